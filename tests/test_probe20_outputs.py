"""Outputs never land where a results directory reads its own JSON files: ``tune --out`` into a
``runs`` folder or an evaluation set's folder is refused before anything is written."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from helpers_sweeps import TUNE_SWEEP
from helpers_tune import run_tune, snapshot


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
