"""Resuming: a checkpointed ensemble resumes whatever the grouping of the next run (another
--max-parallel-runs, other seeds, an ensemble whose results were partly written), says so, and
nothing is left behind: no stale checkpoint, no temporary file of a killed write."""

from __future__ import annotations

import json
import os

import pytest
from helpers_resume import TINY_SETTINGS

import empathy_zoo.training.ensemble as ensemble
from empathy_zoo.atomic import write_bytes_atomic
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.training import RunnerOptions, train_runs
from empathy_zoo.training.resume import CHECKPOINT_DIR

SETTINGS = TINY_SETTINGS


def specs(seeds=(0, 1, 2), betas=(0.5,)):
    return [
        RunSpec.of(
            settings={**SETTINGS, "selfishness": beta},
            seed=seed,
            steps=300,
            eval_interval=150,
            eval_episodes=1,
            env_kwargs={"max_cycles": 40},
        )
        for beta in betas
        for seed in seeds
    ]


def options(k=3):
    return RunnerOptions(progress=False, checkpoint_interval=100, max_parallel_runs=k)


class Killed(Exception):
    """Stands in for the process being killed."""


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """Every run of :func:`specs`, uninterrupted: ``{file name: (train, eval)}``."""
    out = tmp_path_factory.mktemp("reference")
    return contents(train_runs(specs(), out, options()))


def contents(paths):
    return {p.name: (lambda r: (r["train"], r["eval"]))(json.loads(p.read_text())) for p in paths}


def kill_after_checkpoint(monkeypatch, step=200):
    real = ensemble.save_checkpoint

    def save_then_die(path, payload):
        real(path, payload)
        if payload["step"] == step:
            raise Killed

    monkeypatch.setattr(ensemble, "save_checkpoint", save_then_die)


def count_loads(monkeypatch):
    real, loaded = ensemble.load_checkpoint, []
    monkeypatch.setattr(ensemble, "load_checkpoint", lambda path: loaded.append(path.name) or real(path))
    return loaded


def leftovers(out):
    return sorted(p.name for p in out.rglob("*") if p.is_file() and (p.parent.name == CHECKPOINT_DIR or p.name.startswith(".")))


def killed_at_a_checkpoint(monkeypatch, out, runs):
    """Train ``runs`` until the checkpoint at step 200, then die; returns the list of loaded checkpoints
    and the list of notes that the next run fills."""
    with monkeypatch.context() as patch:
        kill_after_checkpoint(patch)
        with pytest.raises(Killed):
            train_runs(runs, out, options())
    return count_loads(monkeypatch), []


def test_another_max_parallel_runs_resumes_the_checkpointed_ensemble(tmp_path, monkeypatch, reference):
    out = tmp_path / "out"
    loaded, notes = killed_at_a_checkpoint(monkeypatch, out, specs())  # one ensemble of 3 runs
    paths = train_runs(specs(), out, options(k=2), on_note=notes.append)
    assert len(loaded) == 1 and any("resuming 3 run(s)" in note for note in notes), notes
    assert contents(paths) == reference
    assert leftovers(out) == []


def test_fewer_seeds_resume_the_ensemble_and_finish_every_run_of_it(tmp_path, monkeypatch, reference):
    out = tmp_path / "out"
    loaded, notes = killed_at_a_checkpoint(monkeypatch, out, specs())
    train_runs(specs(seeds=(0, 1)), out, options(), on_note=notes.append)
    assert len(loaded) == 1
    assert any("not asked for here" in note and "__s2" in note for note in notes), notes
    assert contents(sorted((out / "runs").glob("*.json"))) == reference  # s2 was finished and written too
    assert leftovers(out) == []


def test_more_seeds_resume_the_old_ensemble_and_start_the_new_runs(tmp_path, monkeypatch, reference):
    out = tmp_path / "out"
    loaded, _ = killed_at_a_checkpoint(monkeypatch, out, specs(seeds=(0, 1)))
    assert contents(train_runs(specs(), out, options())) == reference
    assert len(loaded) == 1 and leftovers(out) == []


def test_a_partly_written_ensemble_resumes_without_rewriting_what_was_written(tmp_path, monkeypatch, reference):
    out = tmp_path / "out"
    real_write, written = ensemble.write_result, []

    def write_one_then_die(out_dir, result):
        if written:
            raise Killed
        written.append(real_write(out_dir, result))

    with monkeypatch.context() as patch:
        patch.setattr(ensemble, "write_result", write_one_then_die)
        with pytest.raises(Killed):
            train_runs(specs(), out, options())
    [first] = written
    stamp = first.stat().st_mtime_ns
    loaded, notes = count_loads(monkeypatch), []
    paths = train_runs(specs(), out, options(), on_note=notes.append)
    assert len(loaded) == 1 and any("already finished" in note for note in notes), notes
    assert first.stat().st_mtime_ns == stamp
    assert contents(paths) == reference
    assert leftovers(out) == []


def test_a_checkpoint_of_finished_runs_is_removed(tmp_path, monkeypatch):
    out = tmp_path / "out"
    runs = specs(seeds=(0,))
    killed_at_a_checkpoint(monkeypatch, out, runs)
    [checkpoint] = (out / CHECKPOINT_DIR).glob("*.pt")
    stale = checkpoint.read_bytes()
    train_runs(runs, out, options())
    checkpoint.write_bytes(stale)  # as if a crash had left it behind after the results were written
    notes = []
    train_runs(runs, out, options(), on_note=notes.append)
    assert not checkpoint.exists() and leftovers(out) == []
    assert any("removed" in note and checkpoint.name in note for note in notes), notes


def test_temporary_files_of_killed_writes_are_removed_on_the_next_run(tmp_path):
    out = tmp_path / "out"
    dead = 2**22 + 12345  # above Linux's default pid_max: no such process
    stale = [
        out / "runs" / f".x.json.ezoo-{dead}-abcd1234.tmp",
        out / CHECKPOINT_DIR / f".c.pt.ezoo-{dead}-0badc0de.tmp",
        out / f".ezoo-write-probe-{dead}-0badc0de",
    ]
    live = out / "runs" / f".y.json.ezoo-{os.getpid()}-feedbeef.tmp"  # a write in progress in a live process
    foreign = [out / "runs" / ".x.json.k3j4h5.tmp", out / "runs" / f".x.json.{dead}.abcd1234.tmp"]  # not names the suite makes
    for path in [*stale, live, *foreign]:
        write_bytes_atomic(path, b"half")
    notes = []
    train_runs(specs(seeds=(0,)), out, options(), on_note=notes.append)
    assert [p for p in stale if p.exists()] == [] and live.exists() and all(p.exists() for p in foreign)
    assert any("3 temporary file(s)" in note for note in notes), notes


def test_temporary_files_beside_the_leaderboard_are_removed_when_it_is_written(tmp_path):
    from helpers_results import synthetic_document

    from empathy_zoo.atomic import write_json_atomic
    from leaderboard.report import write_leaderboard

    write_json_atomic(tmp_path / "runs" / "a.json", synthetic_document("coexistence_v0", "dqn", 1.0, 0))
    stale = [
        tmp_path / ".LEADERBOARD.md.ezoo-4194305-0badc0de.tmp",
        tmp_path / "figures" / ".x.png.ezoo-4194305-0badc0de.tmp",
        tmp_path / ".ezoo-write-probe-4194305-0badc0de",
    ]
    for path in stale:
        write_bytes_atomic(path, b"half")
    write_leaderboard(tmp_path)
    assert [p for p in stale if p.exists()] == []
