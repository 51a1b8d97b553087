"""A hostile probe's findings (probe 27), each refused or said where it was once accepted in silence:

* a variant is one environment's table: a result file whose variant is named as another
  environment, a sweep that declares one, and a folder whose variant holds runs of two
  environments are refused (their rows were read in the other environment's table).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from helpers_results import derive_run_id, synthetic_document

from empathy_zoo.experiment.result_reader import check_result
from empathy_zoo.experiment.sweep_file import parse_sweep
from empathy_zoo.experiment.values import SweepConfigError
from empathy_zoo.result_file import ResultFileError
from leaderboard.aggregate import load_results


def _with_variant(env: str, variant: str, seed: int = 0, beta: float = 1.0) -> dict:
    document = synthetic_document(env, "dqn", beta, seed)
    document["variant"] = variant
    document["config"] = {**document["config"], "variant": variant}
    return derive_run_id(document)


def test_a_result_file_s_variant_named_as_another_environment_is_refused() -> None:
    with pytest.raises(ResultFileError, match=r"^forged\.json: field variant: expected a variant of coexistence_v0"):
        check_result(_with_variant("coexistence_v0", "sharing_v0"), "forged.json")
    check_result(_with_variant("coexistence_v0", "coexistence_v0"), "own.json")  # (its own name: the default variant)


def test_a_sweep_variant_named_as_another_environment_is_refused() -> None:
    sweep = {"methods": [{"method": "dqn"}], "envs": {"sharing_v0": {"env": "coexistence_v0"}}}
    with pytest.raises(SweepConfigError, match=r"\[envs\.sharing_v0\] env: 'coexistence_v0', but the variant is named as"):
        parse_sweep(sweep, "s.toml")
    assert parse_sweep({"methods": [{"method": "dqn"}], "envs": {"cats": {"env": "coexistence_v0"}}}, "s.toml")


def test_a_variant_of_two_environments_is_refused_naming_two_runs(tmp_path: Path) -> None:
    runs = tmp_path / "runs"
    runs.mkdir()
    for env, beta in (("coexistence_v0", 1.0), ("sharing_v0", 0.5)):  # (two rows: labels dqn 1.0 and dqn 0.5)
        document = _with_variant(env, "foo", beta=beta)
        (runs / f"{document['run_id']}.json").write_text(json.dumps(document))
    with pytest.raises(ValueError, match=r"are both of variant 'foo' but of two environments \(.*\): a variant is one"):
        load_results(tmp_path)


def _write(directory: Path, documents: list[dict]) -> Path:
    (directory / "runs").mkdir(parents=True, exist_ok=True)
    for document in documents:
        (directory / "runs" / f"{document['run_id']}.json").write_text(json.dumps(document))
    return directory


def _other_world(tmp_path: Path) -> Path:
    """DQN in the default world and Empathic DQN beside a cat that stays: no DQN of its world."""
    dqn = [synthetic_document("coexistence_v0", "dqn", 1.0, seed, harms=0.5) for seed in range(5)]
    stay = [
        synthetic_document("coexistence_v0", "empathic_dqn", 0.5, seed, fixed={"cat_0": "stay"}, harms=0.0) for seed in range(5)
    ]
    return _write(tmp_path / "results", dqn + stay)


def test_a_one_directory_leaderboard_names_a_row_no_dqn_is_compared_with(tmp_path: Path) -> None:
    from leaderboard.report import write_leaderboard

    page = write_leaderboard([_other_world(tmp_path)], tmp_path / "out", command="c")["markdown"].read_text(encoding="utf-8")
    assert "Not compared with DQN (no DQN row of their variant, world and budget): empathic_dqn 0.5." in page


def test_versus_dqn_names_a_row_no_dqn_is_compared_with_and_shows_every_dqn_row(tmp_path: Path) -> None:
    from leaderboard.versus_dqn import versus_dqn_tables

    tables = versus_dqn_tables(load_results(_other_world(tmp_path)))
    assert "Not compared with DQN (no DQN row of their variant, world and budget): empathic_dqn 0.5." in tables
    stay_dqn = [
        derive_run_id({**document, "method_label": "dqn stay"})
        for document in (
            synthetic_document("coexistence_v0", "dqn", 1.0, seed, fixed={"cat_0": "stay"}, harms=0.0) for seed in range(5)
        )
    ]  # (a second DQN row: DQN beside the cat that stays)
    tables = versus_dqn_tables(load_results(_write(tmp_path / "results", stay_dqn)))
    assert "\ndqn stay (5 seeds): " in tables and "\ndqn 1.0 (5 seeds): " in tables and "Not compared" not in tables


def test_train_removes_only_its_own_orphan_list_of_runs(tmp_path: Path) -> None:
    """A list of runs without its checkpoint is removed, and said, only where the suite wrote it:
    its own name and opening; a user's file of the same suffix stays."""
    from empathy_zoo.atomic import write_json_atomic
    from empathy_zoo.training.resume import MANIFEST_FORMAT, plan_ensembles

    checkpoints = tmp_path / "checkpoints"
    checkpoints.mkdir()
    (checkpoints / "notes.runs.json").write_text('{"my": "notes"}')
    (checkpoints / "zz.runs.json").write_text('{\n "format": 2}')  # (the opening, not the name)
    (checkpoints / "coexistence_v0-0123456789abcdef.runs.json").write_text('{"mine": 1}')  # (the name, not the opening)
    own = checkpoints / "coexistence_v0-fedcba9876543210.runs.json"
    write_json_atomic(own, {"format": MANIFEST_FORMAT, "runs": []})
    notes: list[str] = []
    assert plan_ensembles([], tmp_path, 1, notes.append) == []
    assert sorted(path.name for path in checkpoints.iterdir()) == [
        "coexistence_v0-0123456789abcdef.runs.json",
        "notes.runs.json",
        "zz.runs.json",
    ]
    assert notes == [f"removed {own}: a list of runs without its checkpoint (a run killed before its first checkpoint)"]


def test_the_name_a_misnamed_checkpoint_resumes_under_is_that_of_its_runs_environment() -> None:
    from empathy_zoo.training.resume import _AskedRuns, _env_of

    ids = ["coexistence_v0__dqn-33c116fb__s0"]
    assert _env_of(ids, _AskedRuns({}), Path("mymodel.pt")) == "coexistence_v0"  # (not "", the given name's prefix)
    assert _env_of(ids, _AskedRuns({}), Path("sharing_v0-0123.pt")) == "sharing_v0"
    assert _env_of(["cats__dqn-33c116fb__s0"], _AskedRuns({}), Path("mymodel.pt")) == "<environment>"


def test_equivalence_refuses_one_directory_twice_and_says_when_the_sets_are_one(tmp_path: Path) -> None:
    import shutil

    from leaderboard.equivalence import report

    quick = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick"
    with pytest.raises(ValueError, match=r"is given twice .*: its runs would be compared with themselves"):
        report(str(quick), str(quick / "runs" / ".."))
    copy = tmp_path / "copy"
    shutil.copytree(quick / "runs", copy / "runs")
    assert report(str(quick), str(copy)).startswith("Every matched pair of runs (30) is identical column for column")


def test_an_argument_that_is_no_utf8_text_is_refused_before_anything_is_written(tmp_path: Path, capsys) -> None:
    """A path of undecodable bytes (``\\udcff``) cannot go into the command line a page records: one line, exit 2."""
    from empathy_zoo.cli import main

    out = tmp_path / "lb\udcff"
    assert main(["leaderboard", str(Path(__file__).resolve().parents[1] / "docs" / "results" / "quick"), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "is not UTF-8 text" in err and "\\udcff" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()
