"""A results directory given twice is refused however it is written: ``DIR`` and ``DIR/runs`` are
one directory (their result files are the same files), for every command that compares two
directories. ``analyse tuning-effect`` of a tuned directory with no tuned method is refused, not
read as "changed by tuning: 0 of 0"."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from empathy_zoo.cli import main

QUICK = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick"

TWICE = {
    "leaderboard": ["leaderboard", "A", "A/runs", "--out", "OUT"],
    "compare-runs": ["analyse", "compare-runs", "A", "A/runs"],
    "compare-runs of one path": ["analyse", "compare-runs", "A", "A"],
    "equivalence": ["analyse", "equivalence", "A", "A/runs"],
    "tuning-effect": ["analyse", "tuning-effect", "A", "A/runs"],
    "population-reading": ["analyse", "population-reading", "A", "A/runs"],
}


@pytest.fixture(scope="module")
def copied(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The quick profile's results (runs and evaluations) in a folder of their own."""
    root = tmp_path_factory.mktemp("quick") / "A"
    shutil.copytree(QUICK / "runs", root / "runs")
    return root


@pytest.mark.parametrize("args", list(TWICE.values()), ids=list(TWICE))
def test_a_directory_and_its_runs_folder_are_one_directory(copied, tmp_path, capsys, args) -> None:
    filled = [str(copied) + arg[1:] if arg.startswith("A") else str(tmp_path / "out") if arg == "OUT" else arg for arg in args]
    status = main(filled)
    err = capsys.readouterr().err
    assert status == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert "twice" in err or "one directory" in err, err
    assert not (tmp_path / "out").exists()


def test_the_read_folder_is_the_runs_folder_where_there_is_one(copied, tmp_path) -> None:
    from empathy_zoo.result_file import read_folder

    assert read_folder(copied) == read_folder(copied / "runs") == (copied / "runs").resolve()
    (tmp_path / "flat").mkdir()
    assert read_folder(tmp_path / "flat") == (tmp_path / "flat").resolve()
    (tmp_path / "link").symlink_to(copied)
    assert read_folder(tmp_path / "link") == read_folder(copied)


def test_tuning_effect_refuses_a_tuned_directory_of_no_tuned_row(copied, tmp_path, capsys) -> None:
    other = tmp_path / "copy"
    shutil.copytree(copied, other)
    assert main(["analyse", "tuning-effect", str(copied), str(other)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no tuned method to compare" in err and "<label>, tuned" in err, err
