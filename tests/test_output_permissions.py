"""Every output (result files, checkpoints, figures, leaderboard pages) gets the permissions an
ordinary file write would give it: 0666 & ~umask for a new file, the old mode for a rewritten one."""

from __future__ import annotations

import os
import stat

import pytest
from helpers_sweeps import TINY_SWEEP

from empathy_zoo.atomic import write_bytes_atomic, write_text_atomic
from empathy_zoo.cli import main

pytestmark = pytest.mark.skipif(os.name != "posix", reason="POSIX permissions")


@pytest.mark.parametrize("umask", [0o022, 0o077, 0o002])
def test_outputs_get_the_permissions_of_an_ordinary_write(tmp_path, umask):
    previous = os.umask(umask)
    try:
        written = write_text_atomic(tmp_path / "atomic.txt", "x")
        (tmp_path / "ordinary.txt").write_text("x")
    finally:
        os.umask(previous)
    mode = stat.S_IMODE(written.stat().st_mode)
    assert mode == 0o666 & ~umask == stat.S_IMODE((tmp_path / "ordinary.txt").stat().st_mode)


def test_rewriting_a_file_keeps_its_permissions(tmp_path):
    path = tmp_path / "kept.txt"
    path.write_text("old")
    path.chmod(0o640)
    write_bytes_atomic(path, b"new")
    assert stat.S_IMODE(path.stat().st_mode) == 0o640 and path.read_bytes() == b"new"


def test_result_files_checkpoints_and_leaderboard_get_ordinary_permissions(tmp_path):
    from empathy_zoo.training.checkpoint import save_checkpoint

    previous = os.umask(0o022)
    try:
        sweep = tmp_path / "tiny.toml"
        sweep.write_text(TINY_SWEEP)
        out = tmp_path / "results"
        assert main(["reproduce", "--profile", str(sweep), "--out", str(out), "--no-progress", "--workers", "1"]) == 0
        save_checkpoint(out / "checkpoints" / "c.pt", {"step": 1})
    finally:
        os.umask(previous)
    outputs = [p for p in out.rglob("*") if p.is_file()]
    assert {p.suffix for p in outputs} >= {".json", ".md", ".csv", ".html", ".png", ".pt"}
    assert {p.name: oct(stat.S_IMODE(p.stat().st_mode)) for p in outputs} == {p.name: "0o644" for p in outputs}
