"""The twenty-second probe's findings: ``tune`` replaces only files a study wrote, never the
sweep file it reads nor a user's file named like one of its outputs."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("optuna")

from helpers_sweeps import TUNE_SWEEP
from helpers_tune import run_tune, snapshot


def test_tune_never_replaces_the_sweep_file_it_reads(tmp_path: Path, capsys) -> None:
    out = tmp_path / "study"
    out.mkdir()
    sweep = out / "tuned.toml"
    sweep.write_text(TUNE_SWEEP, encoding="utf-8")
    before = snapshot(out)
    capsys.readouterr()
    assert run_tune(sweep, out, 1) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is the sweep file" in err, err
    assert snapshot(out) == before


@pytest.mark.parametrize(
    ("name", "content"),
    [
        ("tuned.toml", "# my notes\nx = 1\n"),
        ("study.json", '{"my": "notes"}'),
        ("trials.png", "not a png"),
        ("study.journal", "notes"),
    ],
)
def test_tune_never_replaces_a_users_file_named_like_its_outputs(tmp_path: Path, capsys, name: str, content: str) -> None:
    sweep = tmp_path / "tiny.toml"
    sweep.write_text(TUNE_SWEEP, encoding="utf-8")
    out = tmp_path / "study"
    out.mkdir()
    (out / name).write_text(content, encoding="utf-8")
    before = snapshot(out)
    capsys.readouterr()
    assert run_tune(sweep, out, 1) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{out / name} exists and is no" in err, err
    assert snapshot(out) == before
