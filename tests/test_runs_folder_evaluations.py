"""A results directory given as its runs folder (``DIR/runs``) has its evaluations in
``DIR/evaluations``: ``leaderboard DIR/runs`` and ``analyse heldout-verdicts DIR/runs`` read them
there, ``evaluate DIR/runs`` writes them there and never into the runs folder, and an
``evaluations`` folder left inside a runs folder is named in one line rather than passed over.
Copies of two shipped runs of docs/results/quick (with their agent and evaluation files)."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from empathy_zoo.cli import main

ROOT = Path(__file__).resolve().parents[1]
QUICK = ROOT / "docs" / "results" / "quick"
SET = "coexistence_v0"
RUN_IDS = ("coexistence_v0__dqn_harm_penalty-684a7c7f__s0", "coexistence_v0__empathic_dqn-10853fdf__s0")


def copy_runs(results: Path, evaluations: bool) -> Path:
    """``results`` made a results directory of the two shipped runs (result and agent files in
    ``runs/``), with their shipped evaluation files where ``evaluations``."""
    (results / "runs").mkdir(parents=True)
    for run_id in RUN_IDS:
        for path in (QUICK / "runs").glob(f"{run_id}.*"):
            shutil.copy2(path, results / "runs" / path.name)
        if evaluations:
            (results / "evaluations" / SET).mkdir(parents=True, exist_ok=True)
            shutil.copy2(QUICK / "evaluations" / SET / f"{run_id}.json", results / "evaluations" / SET / f"{run_id}.json")
    return results


def tree(directory: Path) -> dict[str, bytes | None]:
    """Every path under ``directory`` with its bytes (``None`` for a folder)."""
    return {
        path.relative_to(directory).as_posix(): None if path.is_dir() else path.read_bytes()
        for path in sorted(directory.rglob("*"))
    }


def one_error_line(capsys: pytest.CaptureFixture[str]) -> str:
    """The one line the command wrote to stderr."""
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err.strip()


def test_results_root_is_the_directory_a_runs_folder_belongs_to(tmp_path: Path, monkeypatch) -> None:
    from empathy_zoo.result_file import results_root

    results = copy_runs(tmp_path / "results", evaluations=False)
    assert results_root(results) == results
    assert results_root(results / "runs") == results
    flat = tmp_path / "mine" / "runs"  # (a user's flat folder of result files, named runs: its parent holds its evaluations)
    flat.mkdir(parents=True)
    assert results_root(flat) == tmp_path / "mine"
    made = tmp_path / "runs"  # (train --out runs: a results directory named runs, its own runs/ inside)
    (made / "runs").mkdir(parents=True)
    assert results_root(made) == made
    assert results_root(tmp_path / "nothing" / "runs") == tmp_path / "nothing" / "runs"  # (no folder: stands for itself)
    os.symlink(results / "runs", tmp_path / "link")
    assert results_root(tmp_path / "link") == results
    monkeypatch.chdir(results / "runs")
    assert results_root(".") == results


def test_leaderboard_of_the_runs_folder_shows_the_held_out_section(tmp_path: Path) -> None:
    results = copy_runs(tmp_path / "results", evaluations=True)
    out = tmp_path / "board"
    assert main(["leaderboard", str(results / "runs"), "--out", str(out)]) == 0
    markdown = (out / "LEADERBOARD.md").read_text(encoding="utf-8")
    assert "## Held-out partners" in markdown and f"### coexistence_v0: scenario set {SET}" in markdown
    assert "cat_stays" in markdown


def test_heldout_verdicts_of_the_runs_folder_reads_its_evaluations(tmp_path: Path, capsys) -> None:
    from leaderboard.heldout_verdicts import heldout_verdicts

    results = copy_runs(tmp_path / "results", evaluations=True)
    assert main(["analyse", "heldout-verdicts", str(results / "runs")]) == 0
    printed = capsys.readouterr().out
    assert "cat_stays" in printed and "changed: 0 of 14" in printed
    assert heldout_verdicts(results / "runs") == heldout_verdicts(results)


def test_evaluate_of_the_runs_folder_writes_beside_it(tmp_path: Path) -> None:
    from empathy_zoo.evaluation_file import evaluation_files

    results = copy_runs(tmp_path / "results", evaluations=False)
    runs_before = tree(results / "runs")
    assert main(["evaluate", str(results / "runs"), "--episodes", "1", "--no-progress"]) == 0
    expected = [results / "evaluations" / SET / f"{run_id}.json" for run_id in RUN_IDS]
    assert all(path.is_file() for path in expected)
    assert not (results / "runs" / "evaluations").exists() and tree(results / "runs") == runs_before
    assert evaluation_files(results) == evaluation_files(results / "runs") == expected
    out = tmp_path / "board"
    assert main(["leaderboard", str(results), "--out", str(out)]) == 0
    assert "## Held-out partners" in (out / "LEADERBOARD.md").read_text(encoding="utf-8")


def test_evaluate_refuses_the_runs_folder_as_its_out(tmp_path: Path, capsys) -> None:
    results = copy_runs(tmp_path / "results", evaluations=False)
    before = tree(results)
    runs = str(results / "runs")
    assert main(["evaluate", runs, "--out", runs, "--episodes", "1", "--no-progress"]) == 2
    line = one_error_line(capsys)
    assert line.startswith("empathy-zoo: error: ") and "lies in a folder of a results directory" in line
    assert tree(results) == before


def test_evaluations_left_inside_the_runs_folder_are_named(tmp_path: Path, capsys) -> None:
    results = copy_runs(tmp_path / "results", evaluations=True)
    (results / "evaluations").rename(results / "runs" / "evaluations")
    before = tree(results)
    for given in (results, results / "runs"):
        out = tmp_path / "board"
        assert main(["leaderboard", str(given), "--out", str(out)]) == 2
        line = one_error_line(capsys)
        assert line.startswith("empathy-zoo: error: ")
        assert f"{results / 'runs' / 'evaluations'} lies inside the runs folder" in line
        assert str(results / "evaluations") in line
        assert not out.exists() and tree(results) == before


def test_the_runs_folder_given_as_evaluations_is_its_results_directory(tmp_path: Path, capsys) -> None:
    results = copy_runs(tmp_path / "results", evaluations=True)
    out = tmp_path / "board"
    assert main(["leaderboard", str(results), "--evaluations", str(results / "runs"), "--out", str(out)]) == 2
    line = one_error_line(capsys)
    assert f"--evaluations {results / 'runs'} is the results directory {results}: " in line
    assert not out.exists()
