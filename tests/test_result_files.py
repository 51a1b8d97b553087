"""Result files are read defensively: a name that becomes part of a path (variant, env, run id)
can never point outside the output directory, and a file of valid JSON with wrong contents is
refused when it is read, in one line naming the file and the field, before anything is written."""

from __future__ import annotations

import copy
import dataclasses
import os
import re

import pytest
from helpers_results import derive_run_id, synthetic_document, synthetic_result

from empathy_zoo.atomic import write_json_atomic
from empathy_zoo.cli import main
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.result_file import result_path
from leaderboard.plots import plot_learning_curves
from leaderboard.report import write_leaderboard


def write_runs(directory, results):
    for i, result in enumerate(results):
        write_json_atomic(directory / "runs" / f"run{i}.json", result)


def everything_below(path):
    return sorted(str(p) for p in path.rglob("*"))


ESCAPES = ["../../x", "../escaped", "/ABSOLUTE", "a/b", "..", ".hidden", ""]


@pytest.mark.parametrize("field", ["variant", "env"])
@pytest.mark.parametrize("name", ESCAPES)
def test_a_result_file_cannot_make_the_leaderboard_write_outside(tmp_path, capsys, field, name):
    sandbox = tmp_path / "sandbox"
    results = sandbox / "results"
    bad = synthetic_document("coexistence_v0", "dqn", 1.0, 0)
    bad[field] = name.replace("ABSOLUTE", str(tmp_path / "absolute").lstrip("/"))
    write_runs(results, [synthetic_document("coexistence_v0", "dqn", 1.0, 1), bad])
    before = everything_below(tmp_path)
    assert main(["leaderboard", str(results)]) == 2
    err = capsys.readouterr().err
    assert "run1.json: field " + field in err and "Traceback" not in err, err
    assert everything_below(tmp_path) == before


def test_plots_confine_figures_to_their_directory(tmp_path):
    run = dataclasses.replace(synthetic_result("coexistence_v0", "dqn", 1.0, 0), variant="../outside")  # (no file can)
    with pytest.raises(ValueError, match="outside"):
        plot_learning_curves([run], tmp_path / "out" / "figures")
    assert not (tmp_path / "out").exists() and not list(tmp_path.glob("*.png"))


@pytest.mark.parametrize("variant", ["../x", "/tmp/x", "a/b", ".x"])
def test_a_run_spec_refuses_a_variant_that_is_not_a_file_name(variant):
    with pytest.raises(ValueError, match=f"variant {variant!r} cannot be part of a file name"):
        RunSpec.of(variant=variant)


@pytest.mark.parametrize("run_id", ["../x", "/abs", "a/b", os.sep.join(["..", "..", "x"])])
def test_result_path_refuses_a_run_id_that_is_not_a_file_name(tmp_path, run_id):
    with pytest.raises(ValueError, match="run id"):
        result_path(tmp_path, run_id)


def test_a_forged_run_id_is_refused_by_the_leaderboard(tmp_path):
    bad = synthetic_document("coexistence_v0", "dqn", 1.0, 0)
    bad["run_id"] = "../../etc/x"
    write_runs(tmp_path, [bad])
    with pytest.raises(ValueError, match=re.escape("run0.json: field run_id")):
        write_leaderboard(tmp_path)


def _set(path, value):
    def mutate(result):
        *parents, last = path
        for key in parents:
            result = result[key]
        if value is DELETE:
            del result[last]
        else:
            result[last] = value

    return mutate


DELETE = object()
MALFORMED = {
    "eval entry without step": (_set(["eval", 0, "step"], DELETE), "eval[0].step: missing"),
    "step as a string": (_set(["eval", 0, "step"], "4000"), "eval[0].step: expected an int"),
    "step past the run": (_set(["eval", 0, "step"], 10**9), "eval[0].step: expected a step <= steps"),
    "string in a train column": (_set(["train", "survival", 3], "12"), "train.survival[3]: expected a number"),
    "fractional end step": (_set(["train", "episode_end_step", 0], 1.5), "train.episode_end_step[0]: expected an integer"),
    "eval metric not a list": (_set(["eval", 0, "harms"], 3), "eval[0].harms: expected an array"),
    "eval without a metric": (_set(["eval", 0, "equality"], DELETE), "eval[0].equality: missing"),
    "train without a metric": (_set(["train", "harms"], DELETE), "train.harms: missing"),
    "columns of different lengths": (_set(["train", "harms"], [0.0]), "train: columns of different lengths"),
    "no config": (_set(["config"], DELETE), "config: missing"),
    "config not an object": (_set(["config"], "paper"), "config: expected an object"),
    "config without settings": (_set(["config", "settings"], DELETE), "config.settings: missing"),
    "a setting of the wrong type": (
        _set(["config", "settings", "selfishness"], "half"),
        "config.settings: expected settings of dqn",
    ),
    "an unknown setting": (_set(["config", "settings", "speed"], 2), "config.settings: expected settings of dqn"),
    "a fixed policy not a string": (_set(["config", "fixed", "cat_0"], 3), "config.fixed.cat_0"),
    "seed as a string": (_set(["seed"], "0"), "seed: expected an int >= 0"),
    "negative seed": (_set(["seed"], -1), "seed: expected an int >= 0"),
    "steps as a bool": (_set(["steps"], True), "steps: expected an int >= 1"),
    "label not a string": (_set(["method_label"], 3), "method_label: expected a non-empty one-line string"),
    "eval not an array": (_set(["eval"], {}), "eval: expected an array"),
    "train not an object": (_set(["train"], []), "train: expected an object"),
    "another schema": (_set(["schema"], 4), "schema: this suite reads result schemas 1, 2 and 3, got 4"),
    "a list, not an object": (lambda result: None, None),
}


def malformed(case):
    result = copy.deepcopy(synthetic_document("coexistence_v0", "dqn", 1.0, 0))  # (it shares DEFAULT_POLICIES)
    mutate, expected = MALFORMED[case]
    if expected is None:
        return [result], "(the whole file): expected an object"
    mutate(result)
    return result, expected


@pytest.mark.parametrize("case", sorted(MALFORMED))
def test_a_malformed_result_file_is_one_line_naming_file_and_field(tmp_path, capsys, case):
    document, expected = malformed(case)
    write_runs(tmp_path, [synthetic_document("coexistence_v0", "dqn", 1.0, 1), document])
    before = everything_below(tmp_path)
    assert main(["leaderboard", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert str(tmp_path / "runs" / "run1.json") in err and expected in err, err
    assert everything_below(tmp_path) == before
    assert main(["reproduction", str(tmp_path)]) == 2
    assert expected in capsys.readouterr().err
    assert everything_below(tmp_path) == before


def test_reading_a_result_checks_its_schema(tmp_path):
    from empathy_zoo.experiment.result_reader import read_result

    document, expected = malformed("eval entry without step")
    write_json_atomic(tmp_path / "r.json", document)
    with pytest.raises(ValueError, match=f"r.json: field {expected}".replace("[", r"\[").replace("]", r"\]")):
        read_result(tmp_path / "r.json")


def test_reproduce_refuses_a_malformed_result_file_before_training(tmp_path, capsys, monkeypatch):
    from helpers_sweeps import TINY_SWEEP

    import empathy_zoo.training.runner as runner

    monkeypatch.setattr(runner, "train_ensemble", lambda *a, **k: pytest.fail("training started"))
    sweep = tmp_path / "tiny.toml"
    sweep.write_text(TINY_SWEEP)
    out = tmp_path / "out"
    document, expected = malformed("no config")
    write_runs(out, [document])
    before = everything_below(tmp_path)
    assert main(["reproduce", "--profile", str(sweep), "--out", str(out), "--no-progress", "--workers", "1"]) == 2
    err = capsys.readouterr().err
    assert expected in err and "run0.json" in err and "Traceback" not in err, err
    assert everything_below(tmp_path) == before


# ---------------------------------------------------------------------------- two experiments, one label
def test_a_second_train_differing_only_in_a_setting_is_refused_when_it_starts(tmp_path, capsys, monkeypatch):
    from helpers_sweeps import TINY_TRAIN

    out = tmp_path / "out"
    assert main(["train", "--out", str(out), *TINY_TRAIN, "--learning-rate", "0.001"]) == 0
    [first] = (out / "runs").glob("*.json")
    capsys.readouterr()
    import empathy_zoo.training.runner as runner

    monkeypatch.setattr(runner, "train_ensemble", lambda *a, **k: pytest.fail("training started"))
    for seed in ("0", "1"):  # the same seed, or another: the tables would mix the two experiments
        assert main(["train", "--out", str(out), *TINY_TRAIN, "--learning-rate", "0.002", "--seed", seed]) == 2
        err = capsys.readouterr().err
        assert str(first) in err and "same label 'Empathic DQN (β=1)'" in err and "--label" in err, err
        assert "Traceback" not in err
    assert list((out / "runs").glob("*.json")) == [first]
    monkeypatch.undo()
    assert main(["train", "--out", str(out), *TINY_TRAIN, "--learning-rate", "0.002", "--label", "lr 0.002"]) == 0
    assert main(["leaderboard", str(out)]) == 0


def test_train_runs_refuses_two_experiments_with_one_label_in_one_call(tmp_path):
    from empathy_zoo.training import RunnerOptions, train_runs

    specs = [RunSpec.of(steps=100, settings={"learning_rate": lr, "learning_starts": 32}) for lr in (1e-3, 2e-3)]
    with pytest.raises(ValueError, match="same label 'Empathic DQN"):
        train_runs(specs, tmp_path, RunnerOptions(progress=False))
    assert not (tmp_path / "runs").exists()


def test_the_leaderboard_names_two_experiments_with_one_label(tmp_path):
    a = synthetic_document("coexistence_v0", "dqn", 1.0, 0)
    b = copy.deepcopy(synthetic_document("coexistence_v0", "dqn", 1.0, 1))
    b["config"]["settings"]["learning_rate"] = 0.0005  # (another experiment: its id is its config's)
    derive_run_id(b)
    write_runs(tmp_path, [a, b])
    with pytest.raises(ValueError, match=r"run1\.json.*same label 'dqn 1\.0' on coexistence_v0.*other settings"):
        write_leaderboard(tmp_path)


@pytest.mark.parametrize("command", ["leaderboard", "reproduction"])
@pytest.mark.parametrize("layout", ["empty", "empty runs/", "only temporary files"])
def test_a_directory_without_result_files_is_refused_alike(tmp_path, capsys, command, layout):
    if layout != "empty":
        (tmp_path / "runs").mkdir()
    if layout == "only temporary files":
        (tmp_path / "runs" / ".x.json.1.abcd0123.tmp").write_text("{")
    before = everything_below(tmp_path)
    assert main([command, str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err == f"empathy-zoo: error: no result files (*.json) in {tmp_path}: run a sweep first\n"
    assert everything_below(tmp_path) == before


def test_schema_1_files_are_read_with_their_shaping_as_the_reward_transform() -> None:
    """Files of empathy-zoo 0.1 (schema 1) carried shaping as settings; they read as schema 3."""
    from pathlib import Path

    from empathy_zoo.atomic import read_json
    from empathy_zoo.experiment.result_reader import read_result
    from empathy_zoo.result_file import SCHEMA

    runs = Path(__file__).resolve().parent / "data" / "schema_1"  # files the paper profile of 0.1.0 wrote
    expected = {
        "dqn_harm_penalty": {"name": "harm_penalty", "penalty": -100.0},
        "dqn_equality": {"name": "equality_scaling"},
        "empathic_dqn": None,
    }
    seen = set()
    for path in sorted(runs.glob("*__s0.json")):
        raw = read_json(path)
        assert raw["schema"] == 1 and "harm_penalty" in raw["config"]["settings"]
        result = read_result(path)
        assert result.schema == SCHEMA == 3 and result.run_id == raw["run_id"]
        assert "harm_penalty" not in result.config.settings and "equality_shaping" not in result.config.settings
        assert result.config.reward == expected[result.method]
        seen.add(result.method)
    assert seen == set(expected)
