"""``evaluate RESULTS_DIR --out DIR`` refuses a DIR whose readers would take the evaluations for
those of their own runs: another results directory, a ``runs`` folder, an evaluation set's folder
or a folder of result files. Before, ``evaluate A --out B`` wrote A's evaluations into B's set
folder, and B's leaderboard read them as B's. A results directory given as a file is named as one."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from empathy_zoo.cli import main

QUICK = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick"
RUN = "coexistence_v0__dqn_harm_penalty-684a7c7f__s0"


def _tree(root: Path) -> list[tuple[str, int]]:
    return sorted((str(path.relative_to(root)), path.stat().st_size) for path in root.rglob("*"))


@pytest.fixture()
def places(tmp_path: Path) -> Path:
    (tmp_path / "one" / "runs").mkdir(parents=True)
    for path in (QUICK / "runs").glob(f"{RUN}.*"):
        shutil.copy(path, tmp_path / "one" / "runs" / path.name)
    other = tmp_path / "other"
    shutil.copytree(QUICK / "runs", other / "runs")
    (other / "evaluations" / "coexistence_v0").mkdir(parents=True)
    (tmp_path / "flat").mkdir()
    shutil.copy(QUICK / "runs" / f"{RUN}.json", tmp_path / "flat" / f"{RUN}.json")
    return tmp_path


@pytest.mark.parametrize(
    ("out", "words"),
    [
        ("other", "is another results directory (it holds"),
        ("other/runs", "lies in a folder of a results directory"),
        ("other/evaluations/coexistence_v0", "lies in a folder of a results directory"),
        ("one/runs", "lies in a folder of a results directory"),
        ("flat", "lies in a folder of result files"),
    ],
)
def test_evaluations_are_not_written_where_another_directory_reads_them(
    places: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, out: str, words: str
) -> None:
    monkeypatch.chdir(places)
    before = _tree(places)
    capsys.readouterr()
    assert main(["evaluate", "one", "--episodes", "2", "--out", out, "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"the evaluations' folder {out} {words}" in err, err
    assert _tree(places) == before  # (nothing written)


def test_a_folder_of_no_runs_and_the_results_directory_itself_take_evaluations(
    places: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(places)
    for out in ("new", "one", "one/."):
        assert main(["evaluate", "one", "--episodes", "2", "--out", out, "--no-progress"]) == 0
    assert (places / "new" / "evaluations" / "coexistence_v0" / f"{RUN}.json").is_file()
    assert (places / "one" / "evaluations" / "coexistence_v0" / f"{RUN}.json").is_file()


def test_a_results_directory_that_is_a_file_is_named_as_one(places: Path, capsys: pytest.CaptureFixture[str]) -> None:
    afile = places / "afile"
    afile.touch()
    capsys.readouterr()
    assert main(["evaluate", str(afile), "--episodes", "2", "--no-progress"]) == 2
    assert f"results directory {afile} is a file, not a directory" in capsys.readouterr().err


@pytest.mark.parametrize("second", ["coexistence_v0", "FILE", "DOTTED"])
def test_a_scenario_set_given_twice_is_refused(
    places: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, second: str
) -> None:
    from empathy_zoo.scenarios import load_scenario_set

    monkeypatch.chdir(places)
    (places / "sc").mkdir()
    shipped = load_scenario_set("coexistence_v0").source
    (places / "sc" / "coexistence_v0.toml").write_bytes(Path(shipped).read_bytes())
    first = "coexistence_v0" if second == "coexistence_v0" else "sc/coexistence_v0.toml"
    again = {"coexistence_v0": "coexistence_v0", "FILE": "sc/coexistence_v0.toml", "DOTTED": "./sc/../sc/coexistence_v0.toml"}[
        second
    ]
    before = _tree(places)
    capsys.readouterr()
    assert main(["evaluate", "one", "--scenarios", first, "--scenarios", again, "--episodes", "1", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "scenario set 'coexistence_v0' is given twice" in err, err
    assert _tree(places) == before
