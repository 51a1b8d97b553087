"""``empathy-zoo tune``: the search space's specs, tuning seeds kept apart from reporting seeds, a
study that is the same twice (and resumed), its sweep file that reproduces its best trial, and a
pruner hook that changes nothing a run computes. Tiny studies only (300-step runs)."""

from __future__ import annotations

import json
import sys
import tomllib
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("optuna")

from helpers_sweeps import TUNE_SWEEP

from baselines.registry import get_method
from empathy_zoo.cli import main
from empathy_zoo.experiment import load_sweep
from empathy_zoo.experiment.search_space import ParamSpec, parse_param, parse_params, point_runs
from empathy_zoo.training import study_plan, tuning
from empathy_zoo.training.study_plan import select_experiment, tuning_seeds
from empathy_zoo.training.tuning import STUDY_FILE, TUNED_FILE

SWEEP = TUNE_SWEEP

TUNE = [
    "--method",
    "dqn_harm_penalty",
    "--param",
    "penalty=float:-200:-1",
    "--param",
    "learning_rate=log:1e-4:1e-2",
    "--trials",
    "4",
    "--startup-trials",
    "2",
    "--no-progress",
]
"""A 4-trial study: 2 random trials, then 2 that TPE models; the median pruner may stop trial 4."""


@pytest.fixture
def sweep(tmp_path: Path) -> Path:
    path = tmp_path / "tiny.toml"
    path.write_text(SWEEP)
    return path


def _same_study(document: dict[str, Any]) -> dict[str, Any]:
    """A study document without what differs between two runs of one study: the command (its
    --out), wall times and interrupted trials (which do not count)."""
    trials = [
        {key: value for key, value in trial.items() if key not in ("wall_time_s", "number")}
        for trial in document["trials"]
        if trial["state"] != "INTERRUPTED"
    ]
    best = dict(document["best"] or {})
    best.pop("number", None)
    return {**{k: v for k, v in document.items() if k not in ("command", "trials", "best")}, "trials": trials, "best": best}


# ---------------------------------------------------------------------------------- the specs
@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("learning_rate=log:1e-4:1e-2", ParamSpec("learning_rate", "settings", "learning_rate", "log", False, 1e-4, 1e-2)),
        ("gamma=float:0.9:0.999", ParamSpec("gamma", "settings", "gamma", "float", False, 0.9, 0.999)),
        ("batch_size=int:16:128", ParamSpec("batch_size", "settings", "batch_size", "int", True, 16, 128)),
        ("hidden_size=log:8:256", ParamSpec("hidden_size", "settings", "hidden_size", "log", True, 8, 256)),
        ("penalty=float:-200:-1", ParamSpec("penalty", "reward", "penalty", "float", False, -200, -1)),
        (
            "others=choice:closest,mean,min",
            ParamSpec("others", "settings", "others", "choice", choices=("closest", "mean", "min")),
        ),
        ("batch_size=choice:32,64", ParamSpec("batch_size", "settings", "batch_size", "choice", choices=(32, 64))),
    ],
)
def test_a_good_spec_is_parsed_as_written(text: str, expected: ParamSpec) -> None:
    assert parse_param(text, get_method("dqn_harm_penalty")) == expected


def test_a_field_named_like_a_setting_is_reward_dot_field() -> None:
    spec = parse_param("reward.learning_rate=log:1e-4:1e-2", get_method("dqn_aup"))
    assert (spec.part, spec.field) == ("reward", "learning_rate")
    assert parse_param("learning_rate=log:1e-4:1e-2", get_method("dqn_aup")).part == "settings"


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("learning_rate", "expected NAME=KIND:..."),
        ("=log:1:2", "expected NAME=KIND:..."),
        ("learning_rate=uniform:1:2", "unknown kind 'uniform'"),
        ("learning_rate=log", "log needs values after a colon"),
        ("nonsense=log:1e-4:1e-2", "'nonsense' is no setting of method 'dqn_harm_penalty'"),
        ("selfishness=float:0:1", "fixes selfishness = 1.0"),
        ("reward.gamma=float:0.9:0.99", "has no field 'gamma'"),
        ("learning_rate=log:0:1e-2", "a log range needs LOW > 0"),
        ("learning_rate=log:1e-2:1e-4", "LOW must be below HIGH"),
        ("learning_rate=float:0.1:0.1", "LOW must be below HIGH"),
        ("learning_rate=log:1e-4", "takes two bounds"),
        ("learning_rate=log:1e-4:1e-2:1", "takes two bounds"),
        ("learning_rate=float:a:1", "LOW 'a' is not a number"),
        ("learning_rate=float:0:inf", "HIGH 'inf' is not finite"),
        ("batch_size=float:16:64", "batch_size is an int"),
        ("batch_size=int:16:64.5", "HIGH '64.5' is not a whole number"),
        ("learning_rate=int:1:3", "learning_rate is a float"),
        ("others=float:0:1", "not a range of numbers"),
        ("batch_size=choice:32", "give at least two"),
        ("batch_size=choice:32,,64", "an empty value"),
        ("batch_size=choice:32,32", "listed twice"),
        ("batch_size=choice:32,big", "'big' is not a value it takes (int)"),
    ],
)
def test_a_bad_spec_is_refused_naming_the_bad_part(text: str, says: str) -> None:
    with pytest.raises(ValueError, match="--param") as error:
        parse_param(text, get_method("dqn_harm_penalty"))
    assert says in str(error.value)


def test_a_field_given_twice_and_no_field_at_all_are_refused() -> None:
    method = get_method("dqn_aup")
    with pytest.raises(ValueError, match="given twice"):
        parse_params(["penalty_weight=float:1:2", "penalty_weight=log:1:3"], method)
    with pytest.raises(ValueError, match="at least one --param"):
        parse_params([], method)


def test_a_bound_the_method_refuses_is_said_before_the_study(sweep: Path, tmp_path: Path, capsys) -> None:
    # (not clipped to what the method takes: refused, naming the spec)
    status = main(["tune", str(sweep), *TUNE[:2], "--param", "gamma=float:0.5:1.5", "--out", str(tmp_path / "o")])
    assert status == 2
    err = capsys.readouterr().err
    assert "--param gamma=float:0.5:1.5" in err and "gamma = 1.5" in err
    assert not (tmp_path / "o").exists()


# ---------------------------------------------------------------------------------- the seeds
def test_tuning_seeds_are_kept_apart_from_reporting_seeds(tmp_path: Path, capsys) -> None:
    assert tuning_seeds(3, [0, 1, 2, 3, 4]) == (10_000, 10_001, 10_002)
    with pytest.raises(ValueError, match=r"overlap the sweep file's reporting seeds \[10001\]"):
        tuning_seeds(2, [0, 10_001])
    reporting_on_them = tmp_path / "high.toml"
    reporting_on_them.write_text(SWEEP.replace("seeds = [0, 1]", "seeds = [3, 10000]"))
    status = main(["tune", str(reporting_on_them), *TUNE, "--out", str(tmp_path / "o")])
    assert status == 2
    assert "overlap the sweep file's reporting seeds [10000]" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_the_experiment_is_chosen_or_the_choices_named() -> None:
    specs = load_sweep("empathy_zoo/profiles/methods.toml")
    with pytest.raises(ValueError, match=r"runs on 2 variants .*choose one with --env"):
        select_experiment(specs, "dqn_social_value")
    with pytest.raises(ValueError, match=r"has 3 experiments there .*choose one with --label"):
        select_experiment(specs, "empathic_dqn", "coexistence_3cats")
    with pytest.raises(ValueError, match="no experiment of method 'sb3_dqn'"):
        select_experiment(specs, "sb3_dqn")
    chosen = select_experiment(specs, "empathic_dqn", "coexistence_3cats", "Empathic DQN, mean (β=0.5)")
    assert chosen.method_settings().others == "mean"


# ---------------------------------------------------------------------------------- the study
def test_a_study_is_the_same_twice_and_its_sweep_file_reproduces_its_best_trial(sweep: Path, tmp_path: Path) -> None:
    first, second = tmp_path / "first", tmp_path / "second"
    assert main(["tune", str(sweep), *TUNE, "--out", str(first)]) == 0
    assert main(["tune", str(sweep), *TUNE, "--out", str(second)]) == 0
    study = json.loads((first / STUDY_FILE).read_text())
    assert _same_study(study) == _same_study(json.loads((second / STUDY_FILE).read_text()))
    assert study["trials_done"] == 4 and study["plan"]["tuning_seeds"] == [10_000, 10_001]
    assert (first / "trials.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert {t["state"] for t in study["trials"]} <= {"COMPLETE", "PRUNED"}
    values = [t["params"] for t in study["trials"]]
    assert len({json.dumps(v, sort_keys=True) for v in values}) == 4  # (every trial a point of its own)

    # the sweep file: the best settings, on the reporting seeds and budget, and a label that says so
    text = (first / TUNED_FILE).read_text()
    assert [line for line in text.splitlines() if not line.startswith("#")] == [
        line for line in (second / TUNED_FILE).read_text().splitlines() if not line.startswith("#")
    ]
    specs = load_sweep(first / TUNED_FILE)
    best = study["best"]
    assert [s.seed for s in specs] == [0, 1] and specs[0].steps == 300
    assert specs[0].display_label().endswith(", tuned")
    assert specs[0].method_settings().learning_rate == best["params"]["learning_rate"]
    assert specs[0].reward_transform().penalty == best["params"]["penalty"]
    assert tomllib.loads(text)["methods"][0]["method"] == "dqn_harm_penalty"

    # ... whose runs, trained on the tuning seeds, give the best trial's value again
    from empathy_zoo.training import RunnerOptions, train_runs
    from empathy_zoo.training.study_plan import trial_value

    again = [
        s.__class__(s.variant, s.entry, s.budget, seed) for s, seed in zip(specs, study["plan"]["tuning_seeds"], strict=True)
    ]
    results = [json.loads(p.read_text()) for p in train_runs(again, tmp_path / "again", RunnerOptions(progress=False))]
    assert trial_value([r["eval"][-1] for r in results], "survival")[0] == best["value"]


def test_a_stopped_study_resumes_into_the_study_an_unstopped_one_gives(
    sweep: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    whole = tmp_path / "whole"
    assert main(["tune", str(sweep), *TUNE, "--out", str(whole)]) == 0
    real = tuning.train_trial
    calls = {"n": 0}

    def stopped_in_trial_three(specs, out_dir, options, on_evaluation=None):
        calls["n"] += 1
        if calls["n"] == 3:
            raise KeyboardInterrupt
        return real(specs, out_dir, options, on_evaluation)

    monkeypatch.setattr(tuning, "train_trial", stopped_in_trial_three)
    stopped = tmp_path / "stopped"
    assert main(["tune", str(sweep), *TUNE, "--out", str(stopped)]) == 130
    assert json.loads((stopped / STUDY_FILE).read_text())["trials_done"] == 2  # (the finished ones are kept)
    monkeypatch.setattr(tuning, "train_trial", real)
    assert main(["tune", str(sweep), *TUNE, "--out", str(stopped)]) == 0
    resumed = json.loads((stopped / STUDY_FILE).read_text())
    assert [t["state"] for t in resumed["trials"]].count("INTERRUPTED") == 1
    assert _same_study(resumed) == _same_study(json.loads((whole / STUDY_FILE).read_text()))


def test_a_study_of_another_plan_is_refused_in_the_same_directory(sweep: Path, tmp_path: Path, capsys) -> None:
    out = tmp_path / "o"
    assert main(["tune", str(sweep), *TUNE[:6], "--trials", "1", "--no-progress", "--out", str(out)]) == 0
    capsys.readouterr()
    other = ["--param", "penalty=float:-100:-1", "--trials", "1", "--no-progress", "--out", str(out)]
    assert main(["tune", str(sweep), *TUNE[:2], *other]) == 2
    assert "holds a study of another plan (params differ)" in capsys.readouterr().err


def test_the_pruner_hook_changes_nothing_a_run_computes(sweep: Path, tmp_path: Path) -> None:
    import optuna

    from empathy_zoo.training import RunnerOptions, train_runs
    from empathy_zoo.training.results import stored

    base = load_sweep(sweep)[0]
    params = parse_params(["penalty=float:-200:-1"], base.method_object())
    specs = point_runs(base, params, {"penalty": -50.0}, [10_000, 10_001])
    options = RunnerOptions(progress=False)
    normal = [json.loads(path.read_text()) for path in train_runs(specs, tmp_path / "normal", options)]

    study = optuna.create_study(direction="maximize", pruner=optuna.pruners.MedianPruner(n_startup_trials=0))
    trial = study.ask()
    reported: list[int] = []

    def report(step: int, per_run: list[dict[str, list]]) -> None:
        trial.report(tuning.trial_value(per_run, "survival")[0], step)
        reported.append(step)
        assert not trial.should_prune()

    tuned = [stored(document) for document in tuning.train_trial(specs, tmp_path / "trials", options, report)]
    assert reported == [100, 200, 300]
    for a, b in zip(normal, tuned, strict=True):
        for document in (a, b):
            del document["created"], document["wall_time_s"]
        assert a == b
    assert not list((tmp_path / "trials").rglob("*.json"))  # (a trial writes no result file)


def test_without_optuna_tune_says_which_extra_to_install(sweep: Path, monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    monkeypatch.setitem(sys.modules, "optuna", None)  # (an import of it fails)
    assert main(["tune", str(sweep), *TUNE]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and 'pip install -e ".[tune]"' in err


def test_every_experiment_of_the_methods_profile_is_written_as_a_sweep_file_that_reads_back() -> None:
    from empathy_zoo.experiment.sweep_writer import experiment_sweep

    experiments = {spec.experiment_id: spec for spec in load_sweep("empathy_zoo/profiles/methods.toml")}
    for spec in experiments.values():  # (each checks its own round trip)
        experiment_sweep(spec, [0, 1, 2, 3, 4], label=f"{spec.display_label()}, tuned")


def test_a_value_over_the_curve_is_the_mean_of_its_evaluations_and_over_last_the_last() -> None:
    assert study_plan.curve_value([100.0, 400.0, 500.0], "last") == 500.0
    assert study_plan.curve_value([100.0, 400.0, 500.0], "curve") == pytest.approx(1000.0 / 3)
    # two trials at the same saturated end are told apart by how soon they got there
    assert study_plan.curve_value([500.0, 500.0], "curve") > study_plan.curve_value([200.0, 500.0], "curve")
    with pytest.raises(ValueError, match="at least one greedy evaluation"):
        study_plan.curve_value([], "curve")
    with pytest.raises(ValueError, match="last, curve"):
        study_plan.curve_value([1.0], "area")


def test_ties_at_the_best_value_are_named_and_a_single_best_is_alone() -> None:
    def study(values: list[float | None], states: list[str]) -> dict[str, Any]:
        trials = [{"number": i, "state": s, "value": v} for i, (v, s) in enumerate(zip(values, states, strict=True))]
        finished = [t for t in trials if t["state"] == "COMPLETE"]
        best = max(finished, key=lambda t: t["value"]) if finished else None
        return {"trials": trials, "best": best and {"number": best["number"], "value": best["value"]}}

    assert study_plan.ties_at_best(study([500.0, 320.0, 500.0, None], ["COMPLETE"] * 3 + ["PRUNED"])) == [0, 2]
    assert study_plan.ties_at_best(study([500.0, 320.0], ["COMPLETE", "COMPLETE"])) == [0]
    assert study_plan.ties_at_best(study([None], ["PRUNED"])) == []


def test_a_study_over_the_curve_records_it_and_its_values_are_the_mean_of_each_curve(sweep: Path, tmp_path: Path, capsys) -> None:
    out = tmp_path / "curve"
    assert main(["tune", str(sweep), *TUNE, "--objective-over", "curve", "--no-prune", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    study = json.loads((out / STUDY_FILE).read_text())
    assert study["plan"]["objective"]["over"] == "curve"
    assert "every greedy evaluation" in study["plan"]["objective"]["of"]
    for trial in study["trials"]:
        assert len(trial["curve"]) == 3  # (evaluations at steps 100, 200 and 300)
        assert trial["value"] == pytest.approx(sum(p["value"] for p in trial["curve"]) / 3)
    assert "over every greedy evaluation" in (out / TUNED_FILE).read_text()
    assert "over every greedy evaluation" in printed
    # a study over the last evaluation is another plan: refused in the same directory
    assert main(["tune", str(sweep), *TUNE, "--no-prune", "--out", str(out)]) == 2
    assert "objective" in capsys.readouterr().err


def test_tied_best_trials_are_said_with_the_option_that_tells_them_apart(
    sweep: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys
) -> None:
    monkeypatch.setattr(tuning, "trial_value", lambda per_run, metric: (40.0, [40.0] * len(per_run)))
    assert main(["tune", str(sweep), *TUNE, "--no-prune", "--out", str(tmp_path / "tied")]) == 0
    printed = capsys.readouterr().out
    assert "4 finished trials tie at the best value ([0, 1, 2, 3])" in printed
    assert "--objective-over curve" in printed


def test_the_pruner_waits_until_prune_from_and_a_step_it_would_never_reach_is_refused(
    sweep: Path, tmp_path: Path, capsys
) -> None:
    out = tmp_path / "late"
    assert main(["tune", str(sweep), *TUNE, "--prune-from", "200", "--out", str(out)]) == 0
    study = json.loads((out / STUDY_FILE).read_text())
    assert study["plan"]["pruner"]["n_warmup_steps"] == 200
    assert all(t["steps_trained"] >= 200 for t in study["trials"] if t["state"] == "PRUNED")
    assert main(["tune", str(sweep), *TUNE, "--prune-from", "300", "--out", str(tmp_path / "never")]) == 2
    assert "the pruner would never look: it starts at step 300 and a trial ends at 300" in capsys.readouterr().err
    assert main(["tune", str(sweep), *TUNE, "--prune-from", "-1", "--out", str(tmp_path / "negative")]) == 2
    assert "prune_from must be an int >= 0, got -1" in capsys.readouterr().err
    assert main(["tune", str(sweep), *TUNE, "--prune-from", "100", "--no-prune", "--out", str(tmp_path / "both")]) == 2
    assert "a study without a pruner has no step to start pruning from" in capsys.readouterr().err
