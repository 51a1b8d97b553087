"""Result files are read defensively: a name that becomes part of a path (variant, env, run id)
can never point outside the output directory."""

from __future__ import annotations

import os

import pytest
from helpers_results import synthetic_result

from empathy_zoo.atomic import write_json_atomic
from empathy_zoo.cli import main
from empathy_zoo.training.results import result_path
from empathy_zoo.training.spec import RunSpec
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
    bad = synthetic_result("coexistence_v0", "dqn", 1.0, 0)
    bad[field] = name.replace("ABSOLUTE", str(tmp_path / "absolute").lstrip("/"))
    write_runs(results, [synthetic_result("coexistence_v0", "dqn", 1.0, 1), bad])
    before = everything_below(tmp_path)
    assert main(["leaderboard", str(results)]) == 2
    err = capsys.readouterr().err
    assert "run1.json" in err and repr(field) in err and "Traceback" not in err, err
    assert everything_below(tmp_path) == before


def test_plots_confine_figures_to_their_directory(tmp_path):
    run = synthetic_result("coexistence_v0", "dqn", 1.0, 0)
    run["variant"] = "../outside"
    with pytest.raises(ValueError, match="outside"):
        plot_learning_curves([run], tmp_path / "out" / "figures")
    assert not (tmp_path / "out").exists() and not list(tmp_path.glob("*.png"))


@pytest.mark.parametrize("variant", ["../x", "/tmp/x", "a/b", ".x"])
def test_a_run_spec_refuses_a_variant_that_is_not_a_file_name(variant):
    with pytest.raises(ValueError, match=f"variant {variant!r} cannot be part of a file name"):
        RunSpec(variant=variant)


@pytest.mark.parametrize("run_id", ["../x", "/abs", "a/b", os.sep.join(["..", "..", "x"])])
def test_result_path_refuses_a_run_id_that_is_not_a_file_name(tmp_path, run_id):
    with pytest.raises(ValueError, match="run id"):
        result_path(tmp_path, run_id)


def test_a_forged_run_id_is_refused_by_the_leaderboard(tmp_path):
    bad = synthetic_result("coexistence_v0", "dqn", 1.0, 0)
    bad["run_id"] = "../../etc/x"
    write_runs(tmp_path, [bad])
    with pytest.raises(ValueError, match="run0.json.*'run_id'"):
        write_leaderboard(tmp_path)
