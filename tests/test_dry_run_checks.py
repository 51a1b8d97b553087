"""``empathy-zoo reproduce --dry-run`` makes every check the same command makes before it trains or
writes anything, and refuses the same way (one line, exit 2), writing nothing: one label one
experiment against the result files already in the output directory, and the output directory's
room. A dry run that passes says which checks it could not make without writing."""

from __future__ import annotations

from collections import namedtuple
from pathlib import Path

import pytest
from helpers_results import synthetic_document
from helpers_sweeps import TINY_SWEEP

import empathy_zoo.atomic as atomic
import empathy_zoo.training.runner as runner
from empathy_zoo.atomic import write_json_atomic
from empathy_zoo.cli import main

TWO_SEEDS = TINY_SWEEP.replace("seeds = 1", "seeds = 2")
"""The tiny sweep (DQN on Coexistence) with seeds 0 and 1."""
assert TWO_SEEDS != TINY_SWEEP
LABEL = "dqn 1.0"
"""The label of a synthetic DQN result (:func:`helpers_results.synthetic_document`), given to the sweep's entry."""


@pytest.fixture
def no_training(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(runner, "train_ensemble", lambda *a, **k: pytest.fail("training started"))


def everything_below(path: Path) -> list[tuple[str, bytes | None, int]]:
    """Every path below ``path`` (the output directory's parent; the sweep file lies beside it), with
    its bytes (a file) and its modification time."""
    return sorted((str(p), p.read_bytes() if p.is_file() else None, p.stat().st_mtime_ns) for p in path.rglob("*"))


def reproduce(out: Path, tmp_path: Path, *more: str, label: str | None = None, sweep_text: str = TWO_SEEDS) -> int:
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(sweep_text + ("" if label is None else f'label = "{label}"\n'))
    return main(["reproduce", "--profile", str(sweep), "--out", str(out), "--no-progress", "--workers", "1", *more])


def error_line(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    assert err.startswith("empathy-zoo: error: ") and err.count("\n") == 1 and "Traceback" not in err, err
    return err


@pytest.fixture
def other_dqn(tmp_path: Path) -> tuple[Path, str]:
    """An output directory holding one DQN result file on coexistence_v0 from another experiment
    (other settings) than the tiny sweep's; its path and run id."""
    out = tmp_path / "work" / "out"
    document = synthetic_document("coexistence_v0", "dqn", 1.0, 0)
    assert document["method_label"] == LABEL and document["env"] == "coexistence_v0"
    path = out / "runs" / f"{document['run_id']}.json"
    path.parent.mkdir(parents=True)
    write_json_atomic(path, document)
    return out, document["run_id"]


def test_dry_run_refuses_a_label_of_two_experiments_as_the_command_does(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], other_dqn: tuple[Path, str], no_training: None
) -> None:
    out, other_id = other_dqn
    before = everything_below(tmp_path / "work")
    assert reproduce(out, tmp_path, "--dry-run", label=LABEL) == 2
    refusal = error_line(capsys)
    assert f"same label {LABEL!r}" in refusal and "two experiments" in refusal
    assert other_id in refusal and str(out / "runs" / f"{other_id}.json") in refusal
    from empathy_zoo.experiment.sweep_file import load_sweep

    ours = [spec.run_id for spec in load_sweep(tmp_path / "sweep.toml")]
    assert any(f"run {run_id} and {out / 'runs'}" in refusal for run_id in ours)  # (the sweep's own run is named too)
    assert everything_below(tmp_path / "work") == before
    assert reproduce(out, tmp_path, label=LABEL) == 2  # the command itself refuses it in the same line
    assert error_line(capsys) == refusal
    assert everything_below(tmp_path / "work") == before


def test_dry_run_on_a_clean_directory_passes_and_says_what_it_did_not_check(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], no_training: None
) -> None:
    out = tmp_path / "work" / "out"
    out.parent.mkdir()
    before = everything_below(tmp_path / "work")
    assert reproduce(out, tmp_path, "--dry-run") == 0
    printed = capsys.readouterr().out
    assert "dry run: nothing is trained or written" in printed
    assert "every check made before training passed, but those that need a write" in printed
    for unchecked in runner.NOT_CHECKED_WITHOUT_WRITING:
        assert unchecked in printed
    assert not out.exists() and everything_below(tmp_path / "work") == before


def test_dry_run_refuses_an_output_directory_without_room_for_a_checkpoint(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, no_training: None
) -> None:
    out = tmp_path / "work" / "out"
    out.mkdir(parents=True)
    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(atomic.shutil, "disk_usage", lambda path: usage(10**6, 10**6 - 1000, 1000))
    before = everything_below(tmp_path / "work")
    big_replay = TWO_SEEDS.replace("replay_capacity = 200", "replay_capacity = 50000")  # (a checkpoint of megabytes)
    assert big_replay != TWO_SEEDS
    assert reproduce(out, tmp_path, "--dry-run", "--checkpoint-interval", "100", sweep_text=big_replay) == 2
    refusal = error_line(capsys)
    assert f"output directory {out}" in refusal and "free, less than the" in refusal
    assert everything_below(tmp_path / "work") == before
    assert reproduce(out, tmp_path, "--checkpoint-interval", "100", sweep_text=big_replay) == 2  # the command too
    assert "free, less than the" in error_line(capsys)
    # (it found that inside the directory's lock, once it wrote a probe: the folder's time changed, not its files)
    assert [entry[:2] for entry in everything_below(tmp_path / "work")] == [entry[:2] for entry in before]


def test_dry_run_refuses_an_output_folder_this_user_cannot_write(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, no_training: None
) -> None:
    out = tmp_path / "work" / "out"
    out.mkdir(parents=True)
    monkeypatch.setattr(atomic.os, "access", lambda path, mode: Path(path) != out)
    before = everything_below(tmp_path / "work")
    assert reproduce(out, tmp_path, "--dry-run") == 2
    refusal = error_line(capsys)
    assert f"output directory {out}" in refusal and "not writable" in refusal
    assert everything_below(tmp_path / "work") == before


def test_dry_run_refuses_a_damaged_checkpoint_it_would_resume(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], no_training: None
) -> None:
    from empathy_zoo.experiment.sweep_file import load_sweep
    from empathy_zoo.training.resume import _checkpoint_file

    out = tmp_path / "work" / "out"
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(TWO_SEEDS)
    ids = sorted(spec.run_id for spec in load_sweep(sweep))
    checkpoint = _checkpoint_file(out, "coexistence_v0", ids)
    checkpoint.parent.mkdir(parents=True)
    checkpoint.write_text("my precious notes\n")
    before = everything_below(tmp_path / "work")
    assert reproduce(out, tmp_path, "--dry-run") == 2
    refusal = error_line(capsys)
    assert f"checkpoint {checkpoint} is corrupted or unreadable" in refusal, refusal
    assert everything_below(tmp_path / "work") == before
