"""An ``evaluations`` folder holds set folders only: ``export``/``analyse separation --out`` never
write into it, a JSON file at its top is refused naming it (it was passed over), and
``leaderboard DIR --evaluations DIR/evaluations`` says the folder is DIR's own, read already
(it named one file as its own duplicate)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from empathy_zoo.cli import main

QUICK = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick"
RUN = "coexistence_v0__dqn_harm_penalty-684a7c7f__s0"


@pytest.fixture()
def results(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """``q``: one quick run with its evaluations; ``q3``: the same run without them; cwd ``tmp_path``."""
    for name in ("q", "q3"):
        (tmp_path / name / "runs").mkdir(parents=True)
        for path in (QUICK / "runs").glob(f"{RUN}.*"):
            shutil.copy(path, tmp_path / name / "runs" / path.name)
    for path in (QUICK / "evaluations").glob(f"*/{RUN}.json"):
        (tmp_path / "q" / "evaluations" / path.parent.name).mkdir(parents=True)
        shutil.copy(path, tmp_path / "q" / "evaluations" / path.parent.name / path.name)
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _refused(capsys: pytest.CaptureFixture[str], argv: list[str], words: str) -> None:
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err, err


def test_export_does_not_write_into_an_evaluations_folder(results: Path, capsys: pytest.CaptureFixture[str]) -> None:
    before = sorted(results.rglob("*"))
    _refused(
        capsys,
        ["export", "--format", "marl-eval", "--out", "q/evaluations/new.json", "q"],
        "lies in a folder of a results directory",
    )
    assert sorted(results.rglob("*")) == before


@pytest.mark.parametrize("given", ["q/evaluations", "q"])
def test_a_json_file_at_the_top_of_an_evaluations_folder_is_refused(
    results: Path, capsys: pytest.CaptureFixture[str], given: str
) -> None:
    (results / "q" / "evaluations" / "stray.json").write_text("{}\n")
    words = "q/evaluations/stray.json lies at the top of the evaluations folder q/evaluations, where no evaluation is read"
    _refused(capsys, ["leaderboard", "q3", "--evaluations", given, "--out", "lb"], words)
    assert not (results / "lb").exists()


def test_a_directorys_own_evaluations_given_again_are_named_its_own(results: Path, capsys: pytest.CaptureFixture[str]) -> None:
    words = "--evaluations q/evaluations is the evaluations folder of the results directory q: it is read beside its runs already"
    _refused(capsys, ["leaderboard", "q", "--evaluations", "q/evaluations", "--out", "lb"], words)


def test_a_link_to_an_evaluations_folder_is_read_as_that_folder(results: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (results / "ev_link").symlink_to(results / "q" / "evaluations")
    capsys.readouterr()
    assert main(["leaderboard", "q3", "--evaluations", "ev_link", "--out", "lb"]) == 0, capsys.readouterr().err
    assert "Held-out partners" in (results / "lb" / "LEADERBOARD.md").read_text(encoding="utf-8")
