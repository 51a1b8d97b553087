"""No method trains as another without saying so: every registered DQN-family method (empathic
ones at β = 0.5) is trained beside DQN on both environments, seed for seed. A method equal to DQN
in every column on every environment fails unless its registry entry says so
(``Method.identical_to``), and wherever an entry says so the runs must be equal. (A short run can
equal DQN's by chance on one environment, e.g. before AUP's auxiliary values move: that alone is
no failure.)"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from baselines.registry import METHODS
from empathy_zoo.environments import ENVIRONMENT_TABLE
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.training import RunnerOptions, train_runs

ENVS = ("coexistence_v0", "sharing_v0")
SETTINGS = {"learning_starts": 64, "replay_capacity": 2_000, "epsilon_decay_steps": 300, "target_update_interval": 50}
STEPS = 600
DQN_FAMILY = [name for name, method in METHODS.items() if method.family in ("dqn", "empathic_dqn") and name != "dqn"]
COLUMNS = ("train", "eval")
ENV_KWARGS = {"coexistence_v0": {"max_cycles": 40}, "sharing_v0": {}}
"""Short Coexistence episodes (many reach the time limit); Sharing at its default length, as the marks say."""
REWARD_WARM_UPS = {
    "dqn_aup": {"learning_starts": 64, "penalty_starts": 200},
    "dqn_considerate": {"learning_starts": 32, "bonus_starts": 64},
}
"""Reward transforms whose own warm-up would outlast these short runs, started within them."""


def spec(method: str, env: str) -> RunSpec:
    empathic = METHODS[method].family == "empathic_dqn"  # (at β = 1 it is DQN by definition: the profiles' β)
    return RunSpec.of(
        env=env,
        method=method,
        settings={**SETTINGS, **({"selfishness": 0.5} if empathic else {})},
        reward=REWARD_WARM_UPS.get(method),
        steps=STEPS,
        eval_interval=STEPS,
        eval_episodes=2,
        env_kwargs=ENV_KWARGS[env],
        seed=3,
    )


@pytest.fixture(scope="module")
def columns(tmp_path_factory) -> dict[tuple[str, str], dict]:
    """``{(method, env): {column: ...}}`` of one short run of every method and DQN on both environments."""
    out = tmp_path_factory.mktemp("identical")
    options = RunnerOptions(progress=False, checkpoint_interval=0)
    found = {}
    for method in ["dqn", *DQN_FAMILY]:
        for env in ENVS:
            try:
                (path,) = train_runs([spec(method, env)], out / f"{method}-{env}", options)
            except ValueError:  # (a method that does not run on that environment: relative reachability on Sharing)
                continue
            result = json.loads(Path(path).read_text())
            found[method, env] = {column: result[column] for column in COLUMNS}
    return found


def _without_extra_columns(columns: dict) -> dict:
    """The columns every method records (a method's own extra training column, λ, left out)."""
    train = {key: value for key, value in columns["train"].items() if key != "lambda"}
    return {"train": train, "eval": columns["eval"]}


@pytest.mark.parametrize("method", DQN_FAMILY)
def test_no_method_trains_as_dqn_everywhere_and_every_mark_is_true(columns, method) -> None:
    marked = METHODS[method].identical_to
    same = {
        env: _without_extra_columns(columns[method, env]) == _without_extra_columns(columns["dqn", env])
        for env in ENVS
        if (method, env) in columns
    }
    for env, (other, why) in marked.items():
        if env not in ENVS:
            continue  # (the newer tasks' marks: test_every_mark_on_the_newer_tasks_is_true)
        assert other == "dqn" and why, f"{method}: a mark names the method and why"
        assert same.get(env), f"{method} says it is DQN on {env} ({why}), but its runs differ"
    unmarked = [env for env, equal in same.items() if equal and env not in marked]
    assert len(unmarked) < len(ENVS), f"{method} trains as DQN on every environment and says so on none"


def test_the_methods_and_envs_commands_say_it(capsys) -> None:
    from empathy_zoo.cli import main

    assert main(["methods"]) == 0
    lines = {line.split()[0]: line for line in capsys.readouterr().out.splitlines()}
    assert "[≡ dqn on sharing_v0:" in lines["dqn_considerate"] and "≡" not in lines["empathic_dqn"]
    assert main(["envs"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("coexistence_v0") and "sharing_v0" in out and "rules='paper'" in out


def test_the_leaderboard_marks_a_row_identical_by_construction(tmp_path) -> None:
    from dataclasses import replace

    from helpers_results import synthetic_result

    from leaderboard.report import write_leaderboard
    from leaderboard.row_names import IDENTICAL_MARK, identical_row_names

    runs = [synthetic_result("sharing_v0", method, 1.0, seed) for method in ("dqn", "dqn_considerate") for seed in (0, 1)]
    runs = [replace(run, method_label={"dqn": "DQN", "dqn_considerate": "Be Considerate"}[run.method]) for run in runs]
    assert identical_row_names(runs) == {("sharing_v0", "Be Considerate"): "Be Considerate" + IDENTICAL_MARK}
    out = tmp_path / "runs"
    out.mkdir()
    for run in runs:
        (out / f"{run.run_id}.json").write_text(json.dumps(run.to_document()))
    page = write_leaderboard(tmp_path, tmp_path / "board")["markdown"].read_text(encoding="utf-8")
    assert "| Be Considerate ≡ DQN |" in page and "train as DQN by construction" in page


def test_a_runs_summary_names_only_its_environments_metrics() -> None:
    from helpers_results import synthetic_result

    from empathy_zoo.cli.common import run_summary

    coexistence = run_summary(synthetic_result("coexistence_v0", "dqn", 1.0, 0, survival=400.0, harms=0.5))
    sharing = run_summary(synthetic_result("sharing_v0", "dqn", 1.0, 0, batteries=4.0, equality=0.9))
    assert "harms" in coexistence and "batteries" not in coexistence and "equality" not in coexistence
    assert "batteries" in sharing and "equality" in sharing and "harms" not in sharing


def test_reproduce_dry_run_plans_and_writes_nothing(tmp_path, capsys) -> None:
    from empathy_zoo.cli import main

    out = tmp_path / "plan"
    assert main(["reproduce", "--profile", "quick", "--out", str(out), "--dry-run"]) == 0
    printed = capsys.readouterr().out
    assert "dry run: nothing is trained or written" in printed and "900,000 env steps left" in printed
    assert "no estimate of the time" in printed and not out.exists()


def test_a_row_whose_runs_equal_dqns_is_marked_though_not_by_construction(tmp_path) -> None:
    from helpers_results import derive_run_id, edited, record, synthetic_document, synthetic_result

    from empathy_zoo.experiment.records import RunResult
    from leaderboard.report import write_leaderboard
    from leaderboard.row_names import SAME_RUNS_MARK, same_runs_row_names

    def row(method: str, label: str, survival: float = 400.0, seeds: tuple[int, ...] = (0, 1, 2, 3)) -> list[RunResult]:
        made = [synthetic_document("coexistence_v0", method, 1.0, seed, survival=survival) for seed in seeds]
        for run in made:
            run["method_label"] = label
        return [record(derive_run_id(run)) for run in made]

    dqn, considerate = row("dqn", "DQN"), row("dqn_considerate", "Be Considerate")
    assert same_runs_row_names(dqn + considerate) == {("coexistence_v0", "Be Considerate"): "Be Considerate" + SAME_RUNS_MARK}
    # one differing value, a seed DQN lacks, or another budget: not the same runs
    differs = row("dqn_considerate", "Be Considerate")

    def one_less(document: dict) -> None:
        document["eval"][0]["survival"][0] -= 1.0

    differs[2] = edited(differs[2], one_less)
    assert same_runs_row_names(dqn + differs) == {}
    assert same_runs_row_names(dqn + row("dqn_considerate", "Be Considerate", seeds=(0, 1, 2, 7))) == {}
    longer = [edited(run, lambda document: document.update(steps=40000)) for run in row("dqn_considerate", "Be Considerate")]
    assert same_runs_row_names(dqn + longer) == {}
    # a row marked by construction keeps that mark (Be Considerate in Sharing)
    sharing = [synthetic_result("sharing_v0", m, 1.0, s) for m in ("dqn", "dqn_considerate") for s in (0, 1)]
    assert same_runs_row_names(sharing) == {}
    out = tmp_path / "runs"
    out.mkdir()
    for run in dqn + considerate:
        (out / f"{run.run_id}.json").write_text(json.dumps(run.to_document()))
    page = write_leaderboard(tmp_path, tmp_path / "board")["markdown"].read_text(encoding="utf-8")
    assert f"| Be Considerate{SAME_RUNS_MARK} |" in page and "on these runs the method trained as DQN" in page


NEW_TASKS = [env for env in ENVIRONMENT_TABLE if env not in ENVS]
MARKED_ON_NEW_TASKS = [(name, env) for name in DQN_FAMILY for env in METHODS[name].identical_to if env in NEW_TASKS]


def test_the_environment_facts_mark_methods_on_the_newer_tasks() -> None:
    """The marks the environments' facts give: no negative rewards anywhere, no batteries on the
    charger and vase tasks (so the literal silver rule and equality scaling are DQN there)."""
    assert set(MARKED_ON_NEW_TASKS) == {
        *(("dqn_silver_literal", env) for env in NEW_TASKS),
        ("dqn_equality", "charger_v0"),
        ("dqn_equality", "vase_v0"),
    }


@pytest.mark.parametrize(("method", "env"), MARKED_ON_NEW_TASKS)
def test_every_mark_on_the_newer_tasks_is_true(tmp_path, method, env) -> None:
    """Where a newer task's facts mark a method as DQN, its short run equals DQN's, column for column."""
    options = RunnerOptions(progress=False, checkpoint_interval=0)
    found = {}
    for name in (method, "dqn"):
        spec = RunSpec.of(env=env, method=name, settings=SETTINGS, steps=STEPS, eval_interval=STEPS, eval_episodes=2, seed=3)
        (path,) = train_runs([spec], tmp_path / name, options)
        found[name] = _without_extra_columns(json.loads(Path(path).read_text()))
    assert found[method] == found["dqn"]
