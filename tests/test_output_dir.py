"""An unusable output directory (a file, one that cannot be created or written) is refused before
any training starts, by ``train``, ``reproduce``, ``leaderboard`` and the ``train_runs`` API."""

from __future__ import annotations

import os

import pytest
from helpers_sweeps import TINY_SWEEP, TINY_TRAIN

import empathy_zoo.training.runner as runner
from empathy_zoo import atomic
from empathy_zoo.cli import main
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.training import RunnerOptions, train_runs


@pytest.fixture
def no_training(monkeypatch):
    """Fail the test if any ensemble starts training."""
    started = []

    def refuse(*args, **kwargs):
        started.append(args)
        raise AssertionError("training started although the output directory is unusable")

    monkeypatch.setattr(runner, "train_ensemble", refuse)
    return started


def unusable_outputs(tmp_path):
    """An existing file, and a directory that cannot be created (below a file)."""
    a_file = tmp_path / "a_file"
    a_file.write_text("not a directory")
    return {"file": a_file, "below a file": a_file / "sub"}


@pytest.mark.parametrize("kind, expected", [("file", "is a file"), ("below a file", "cannot create")])
def test_train_refuses_an_unusable_out_before_training(tmp_path, capsys, no_training, kind, expected):
    out = unusable_outputs(tmp_path)[kind]
    assert main(["train", "--out", str(out), *TINY_TRAIN]) == 2
    err = capsys.readouterr().err
    assert err.startswith("empathy-zoo: error: ") and str(out) in err and expected in err, err
    assert "--out" in err and "Traceback" not in err
    assert no_training == []


@pytest.mark.parametrize("kind, expected", [("file", "is a file"), ("below a file", "cannot create")])
def test_reproduce_refuses_an_unusable_out_before_training(tmp_path, capsys, no_training, kind, expected):
    sweep = tmp_path / "tiny.toml"
    sweep.write_text(TINY_SWEEP)
    out = unusable_outputs(tmp_path)[kind]
    assert main(["reproduce", "--profile", str(sweep), "--out", str(out), "--no-progress", "--workers", "1"]) == 2
    err = capsys.readouterr().err
    assert str(out) in err and expected in err and "Traceback" not in err, err
    assert no_training == []


def test_train_runs_refuses_a_directory_it_cannot_write(tmp_path, monkeypatch, no_training):
    """The write probe fails (as on a read-only mount, or without permission): refused up front."""
    real = atomic.write_bytes_atomic

    def read_only(path, data):
        if "probe" in path.name:
            raise PermissionError(13, "Permission denied", str(path))
        return real(path, data)

    monkeypatch.setattr(atomic, "write_bytes_atomic", read_only)
    spec = RunSpec.of(steps=200, eval_interval=200, eval_episodes=1, settings={"learning_starts": 32})
    with pytest.raises(ValueError, match=r"not writable.*Permission denied.*choose another") as error:
        train_runs([spec], tmp_path / "out", RunnerOptions(progress=False))
    assert str(tmp_path / "out") in str(error.value)
    assert no_training == []
    assert list((tmp_path / "out").rglob("*probe*")) == []


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="needs POSIX permissions and a non-root user")
def test_a_read_only_directory_is_refused(tmp_path, no_training):
    out = tmp_path / "read_only"
    out.mkdir()
    out.chmod(0o500)
    try:
        spec = RunSpec.of(steps=200, eval_interval=200, eval_episodes=1, settings={"learning_starts": 32})
        with pytest.raises(ValueError, match=str(out)):
            train_runs([spec], out, RunnerOptions(progress=False))
    finally:
        out.chmod(0o700)


def test_the_leaderboard_refuses_an_unusable_out(tmp_path, capsys):
    from helpers_results import synthetic_document

    from empathy_zoo.atomic import write_json_atomic

    results = tmp_path / "results"
    write_json_atomic(results / "runs" / "a.json", synthetic_document("coexistence_v0", "dqn", 1.0, 0))
    out = unusable_outputs(tmp_path)["file"]
    assert main(["leaderboard", str(results), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert str(out) in err and "is a file" in err and "Traceback" not in err, err
