"""Outputs never land where a results directory reads its own JSON files: ``tune --out`` into a
``runs`` folder or an evaluation set's folder is refused before anything is written."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from helpers_sweeps import TUNE_SWEEP
from helpers_tune import run_tune, snapshot

from empathy_zoo.cli import main

QUICK = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick"


@pytest.mark.parametrize("how", ["a runs folder", "an evaluation set", "a link to a runs folder", "dot-dot into runs"])
def test_tune_out_is_never_a_folder_a_results_directory_reads(tmp_path: Path, capsys, how: str) -> None:
    results = tmp_path / "results"
    (results / "runs" / "sub").mkdir(parents=True)
    (results / "evaluations" / "swap").mkdir(parents=True)
    out = {
        "a runs folder": results / "runs",
        "an evaluation set": results / "evaluations" / "swap",
        "a link to a runs folder": tmp_path / "link",
        "dot-dot into runs": results / "runs" / "sub" / "..",
    }[how]
    if how == "a link to a runs folder":
        os.symlink(results / "runs", out)
    sweep = tmp_path / "tiny.toml"
    sweep.write_text(TUNE_SWEEP)
    before = snapshot(results)
    capsys.readouterr()
    assert run_tune(sweep, out, 1) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "lies in a folder of a results directory" in err and "--out" in err, err
    assert snapshot(results) == before


@pytest.mark.parametrize("below", ["", "deeper"])
def test_an_out_through_a_link_to_nothing_says_so(tmp_path: Path, capsys, below: str) -> None:
    os.symlink(tmp_path / "nowhere", tmp_path / "out")
    capsys.readouterr()
    out = tmp_path / "out" / below if below else tmp_path / "out"
    assert main(["leaderboard", str(QUICK), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    link = f"{tmp_path / 'out'} is a symbolic link to {tmp_path / 'nowhere'}, which does not exist"
    assert err.count("\n") == 1 and link in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]
