"""``train --out`` (and ``reproduce --out``) refuses a folder whose files a results directory reads
as its own: a results directory's ``runs`` folder, a flat folder of result files, an
``evaluations`` folder. Before, ``train --out DIR/runs`` nested ``runs/`` and ``checkpoints/``
there, and ``DIR/runs`` then read only the nested run, its own result files no longer."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from empathy_zoo.cli import main

QUICK = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick"
RUN = "coexistence_v0__dqn_harm_penalty-684a7c7f__s0"
TRAIN = ["train", "--env", "charger_v0", "--method", "dqn", "--steps", "200", "--eval-interval", "100", "--eval-episodes", "1"]
TRAIN += ["--learning-starts", "50", "--replay-capacity", "300", "--hidden-size", "8", "--max-cycles", "40", "--no-progress"]


@pytest.fixture()
def places(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    for folder in (tmp_path / "q" / "runs", tmp_path / "flat"):
        folder.mkdir(parents=True)
        for path in (QUICK / "runs").glob(f"{RUN}.*"):
            shutil.copy(path, folder / path.name)
    (tmp_path / "q" / "evaluations").mkdir()
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize(
    ("out", "words"),
    [
        ("q/runs", "lies in a folder of result files (q/runs"),
        ("flat", "lies in a folder of result files (flat"),
        ("q/evaluations", "lies in a folder of a results directory"),
    ],
)
def test_train_refuses_a_folder_read_as_results(places: Path, capsys: pytest.CaptureFixture[str], out: str, words: str) -> None:
    before = sorted(places.rglob("*"))
    capsys.readouterr()
    assert main([*TRAIN, "--out", out]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"the output directory {out} {words}" in err, err
    assert sorted(places.rglob("*")) == before


def test_train_takes_its_default_runs_folder_and_a_results_directory(places: Path) -> None:
    assert main([*TRAIN, "--out", "runs"]) == 0  # (train's default: a folder named runs of its own runs/)
    assert main([*TRAIN, "--out", "runs"]) == 0  # (again: finished, nothing to do)
    assert main([*TRAIN, "--out", "q"]) == 0
    assert len(list((places / "q" / "runs").glob("*.json"))) == 2
