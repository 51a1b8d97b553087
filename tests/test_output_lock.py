"""One process at a time on an output directory (empathy_zoo.output_lock): a second ``train`` or
``reproduce`` on the same ``--out``, or a second ``evaluate`` into the same ``evaluations/``, is
refused naming the holder; a holder killed outright leaves nothing locked."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from helpers_heldout import dqn_and_empathic_runs
from helpers_resume import small_run

from empathy_zoo.output_lock import LOCK_NAME, DirectoryInUse, _acquire, hold_output_dir
from empathy_zoo.result_file import RUNS_DIR, result_path
from empathy_zoo.training import RunnerOptions, train_runs
from empathy_zoo.training.heldout import evaluate_results

HOLDER = """
import sys
from empathy_zoo.output_lock import hold_output_dir
with hold_output_dir(sys.argv[1], "the test's holder"):
    print("held", flush=True)
    sys.stdin.read()
"""


def _holder(directory: Path) -> subprocess.Popen[str]:
    """A process holding ``directory`` until its stdin closes (it has said so when this returns)."""
    process = subprocess.Popen(
        [sys.executable, "-c", HOLDER, str(directory)], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )
    assert process.stdout is not None and process.stdout.readline().strip() == "held"
    return process


def test_a_second_process_on_one_out_is_refused_naming_the_holder_and_trains_nothing(tmp_path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    spec = small_run("dqn", seed=0)
    holder = _holder(out)
    try:
        with pytest.raises(DirectoryInUse, match=rf"in use by process {holder.pid} on .*the test's holder"):
            train_runs([spec], out, RunnerOptions(progress=False))
        assert not result_path(out, spec.run_id).exists()
        assert not list((out / RUNS_DIR).glob("*")), "nothing may be written by the refused process"
    finally:
        holder.kill()  # (SIGKILL: the lock must go with the process)
        holder.wait()
    assert holder.returncode == -signal.SIGKILL
    train_runs([spec], out, RunnerOptions(progress=False))  # a holder killed outright leaves nothing locked
    assert result_path(out, spec.run_id).exists()
    assert not (out / LOCK_NAME).exists(), "a clean exit removes its lock file"


def test_the_same_process_cannot_hold_a_directory_twice(tmp_path) -> None:
    with (
        hold_output_dir(tmp_path, "first"),
        pytest.raises(DirectoryInUse, match=rf"in use by process {os.getpid()} .*\(first, since "),
        hold_output_dir(tmp_path, "second"),
    ):
        pass
    with hold_output_dir(tmp_path, "again"):  # released on leaving
        assert (tmp_path / LOCK_NAME).exists()


def test_a_lock_file_replaced_between_open_and_lock_is_not_the_lock(tmp_path) -> None:
    path = tmp_path / LOCK_NAME
    fd = os.open(path, os.O_RDWR | os.O_CREAT)
    try:
        path.unlink()  # (its holder left and removed it) ...
        path.write_text("")  # ... and a third process made a new one
        with pytest.raises(OSError) as error:
            _acquire(path, fd)
        assert error.value.errno == 116
    finally:
        os.close(fd)


def test_a_lock_file_that_is_a_link_is_refused(tmp_path) -> None:
    (tmp_path / "elsewhere").write_text("")
    (tmp_path / LOCK_NAME).symlink_to(tmp_path / "elsewhere")
    with pytest.raises(OSError), hold_output_dir(tmp_path, "x"):
        pass


def test_evaluate_is_refused_beside_another_evaluate_but_not_beside_training(tmp_path) -> None:
    out = tmp_path / "results"
    train_runs(dqn_and_empathic_runs([0], max_cycles=20, eval_episodes=1), out, RunnerOptions(progress=False))
    with hold_output_dir(out, "training goes on"):  # a reproduce on the same directory
        summary = evaluate_results(out, episodes=1, progress=False)
    assert len(summary.written) == 2
    with hold_output_dir(out / "evaluations", "another evaluate"), pytest.raises(DirectoryInUse, match="another evaluate"):
        evaluate_results(out, episodes=1, out_dir=out, progress=False)
