"""``analyse versus-dqn`` refuses a directory of which no row is compared with DQN: runs with no
DQN row of their variant, world and budget, or DQN runs only. Before, it printed a table with no
mark and exited 0."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from empathy_zoo.cli import main
from leaderboard.aggregate import load_results
from leaderboard.improvement import is_dqn

RUNS = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick" / "runs"


def _directory(root: Path, dqn: bool) -> Path:
    """A results directory of the quick Coexistence runs that are DQN's (``dqn``) or not."""
    (root / "runs").mkdir(parents=True)
    for run in load_results(RUNS):
        if run.env == "coexistence_v0" and is_dqn(run) == dqn:
            shutil.copy(RUNS / f"{run.run_id}.json", root / "runs" / f"{run.run_id}.json")
    return root


@pytest.mark.parametrize(
    ("dqn", "words"), [(False, "holds no DQN row of the variant, world and budget"), (True, "holds DQN runs only")]
)
def test_a_directory_of_nothing_compared_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], dqn: bool, words: str
) -> None:
    results = _directory(tmp_path / "r", dqn)
    capsys.readouterr()
    assert main(["analyse", "versus-dqn", str(results)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and f"{results} {words}" in err, err


def test_a_directory_with_dqn_beside_its_methods_is_tabled(capsys: pytest.CaptureFixture[str]) -> None:
    capsys.readouterr()
    assert main(["analyse", "versus-dqn", str(RUNS.parent)]) == 0
    assert "### coexistence_v0" in capsys.readouterr().out
