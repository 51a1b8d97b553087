"""A results directory may be a folder of result files itself (no ``runs`` folder): every JSON file
in it is read as a result. ``export --out``, ``analyse separation --out`` and ``tune --out`` into
such a folder are refused in one line before anything is written, as into a ``runs`` folder; a
folder of other JSON files is written to as before."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from helpers_sweeps import TUNE_SWEEP
from helpers_tune import run_tune, snapshot

from empathy_zoo.cli import main
from empathy_zoo.evaluation_file import check_not_read_folder

ROOT = Path(__file__).resolve().parents[1]
QUICK = ROOT / "docs" / "results" / "quick"


def _flat(directory: Path) -> Path:
    """The quick profile's result files (without their agents) in ``directory`` itself."""
    directory.mkdir()
    for path in sorted((QUICK / "runs").glob("*.json"))[:3]:
        shutil.copyfile(path, directory / path.name)
    return directory


def _run(command: str, flat: Path, tmp_path: Path) -> int:
    if command == "tune":
        sweep = tmp_path / "tiny.toml"
        sweep.write_text(TUNE_SWEEP)
        return run_tune(sweep, flat, 1)
    if command == "export":
        return main(["export", str(QUICK), "--format", "marl-eval", "--out", str(flat / "e.json")])
    return main(["analyse", "separation", "coexistence_v0", "max_cycles=5", "--out", str(flat)])


@pytest.mark.parametrize("command", ["export", "separation", "tune"])
def test_no_output_lands_in_a_folder_of_result_files(tmp_path: Path, capsys, command: str) -> None:
    flat = _flat(tmp_path / "flat")
    before = snapshot(flat)
    status = _run(command, flat, tmp_path)
    err = capsys.readouterr().err
    assert status == 2 and err.count("\n") == 1 and "folder of result files" in err and str(flat) in err, err
    assert snapshot(flat) == before


def test_only_a_folder_holding_a_result_files_name_is_one(tmp_path: Path) -> None:
    from empathy_zoo.evaluation_file import RESULT_FILE_NAME

    assert all(RESULT_FILE_NAME.fullmatch(path.name) for path in (QUICK / "runs").glob("*.json"))
    other = tmp_path / "other"
    other.mkdir()
    (other / "notes.json").write_text("{}")
    check_not_read_folder(other, "--out")  # (JSON files of no result's name: written to as before)
    with_runs = _flat(tmp_path / "with_runs")
    (with_runs / "runs").mkdir()
    check_not_read_folder(with_runs, "--out")  # (its runs folder holds its results: the rest is not read)
    with pytest.raises(ValueError, match="folder of result files"):
        check_not_read_folder(_flat(tmp_path / "flat"), "--out")
