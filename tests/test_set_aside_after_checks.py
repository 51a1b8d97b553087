"""``train`` changes ``checkpoints/`` (a list of runs that cannot be read set aside, an orphan list
of runs or a stale temporary file removed) only once every input is checked and it goes ahead: a
refused command leaves the output directory as it was, byte for byte."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import pytest
from test_probe24_set_aside import _dead_pid

TRAIN = [
    "train",
    "--steps",
    "200",
    "--eval-interval",
    "100",
    "--eval-episodes",
    "1",
    "--learning-starts",
    "50",
    "--replay-capacity",
    "300",
    "--hidden-size",
    "8",
    "--max-cycles",
    "40",
    "--no-progress",
    "--seeds",
    "0",
    "1",
    "--checkpoint-interval",
    "100",
]
"""A short ``train`` of two runs in one ensemble, checkpointed."""


def _tree(root: Path) -> list[tuple[str, str, int, bytes]]:
    """Every entry under ``root``: its path, kind, size and contents (a link's target)."""
    entries = []
    for folder, dirs, files in os.walk(root):
        for name in sorted([*dirs, *files]):
            path = Path(folder) / name
            if path.is_symlink():
                entries.append((str(path.relative_to(root)), "link", 0, os.readlink(path).encode()))
            elif path.is_dir():
                entries.append((str(path.relative_to(root)), "dir", 0, b""))
            else:
                entries.append((str(path.relative_to(root)), "file", path.stat().st_size, path.read_bytes()))
    return sorted(entries)


def test_a_refused_train_leaves_an_unreadable_list_of_runs_where_it_was(tmp_path: Path, capsys) -> None:
    """The probe's case: finished runs, a checkpoint of their ensemble that is a user's text and a
    list of runs beside it that cannot be read: refused (the checkpoint), and the list is not set aside."""
    from empathy_zoo.cli import main
    from empathy_zoo.training.resume import _checkpoint_file

    out = tmp_path / "out"
    assert main([*TRAIN, "--out", str(out)]) == 0
    ids = sorted(path.name.removesuffix(".json") for path in (out / "runs").glob("*.json"))
    assert [run_id[-3:] for run_id in ids] == ["_s0", "_s1"]
    checkpoint = _checkpoint_file(out, "coexistence_v0", ids)
    checkpoint.parent.mkdir(exist_ok=True)
    checkpoint.write_text("my precious notes\n")
    manifest = checkpoint.with_name(checkpoint.stem + ".runs.json")
    manifest.write_text('{"mine":1}\n')
    before = _tree(out)
    capsys.readouterr()
    assert main([*TRAIN, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"empathy-zoo: error: checkpoint {checkpoint} is corrupted or unreadable"), err
    assert "set aside" not in err and err.count("\n") == 1, err
    assert _tree(out) == before


def test_a_refused_train_removes_no_orphan_list_or_stale_temporary_file(tmp_path: Path) -> None:
    """A checkpoint that resumes (its list of runs readable) but is damaged is refused before the
    orphan list of runs and the stale temporary file beside it are removed."""
    from empathy_zoo.experiment.model import RunSpec
    from empathy_zoo.training import RunnerOptions, train_runs
    from empathy_zoo.training.checkpoint import CheckpointError
    from empathy_zoo.training.resume import checkpoint_path, write_manifest

    out = tmp_path / "out"
    tiny = {"learning_starts": 32, "replay_capacity": 300, "hidden_size": 8}
    specs = [RunSpec.of(steps=100, eval_interval=100, eval_episodes=1, seed=0, settings=tiny)]
    checkpoint = checkpoint_path(out, specs)
    checkpoint.parent.mkdir(parents=True)
    write_manifest(checkpoint, specs)
    checkpoint.write_bytes(b"PK\x03\x04 not a checkpoint")
    orphan_specs = [RunSpec.of(steps=100, eval_interval=100, eval_episodes=1, seed=7, settings=tiny)]
    write_manifest(checkpoint_path(out, orphan_specs), orphan_specs)  # (removed when a train goes ahead)
    (checkpoint.parent / f".x.pt.ezoo-{_dead_pid()}-abcd1234.tmp").write_bytes(b"half")  # (likewise)
    before = _tree(out)
    with pytest.raises(CheckpointError, match=f"checkpoint {checkpoint} is corrupted or unreadable"):
        train_runs(specs, out, RunnerOptions(progress=False, checkpoint_interval=100), on_note=lambda _: None)
    assert _tree(out) == before


def test_survey_changes_nothing_and_apply_sets_aside(tmp_path: Path) -> None:
    """``survey_ensembles`` only reads; its plan's changes (the unreadable list set aside under a
    free name, never over a user's file) are made by ``apply``."""
    from empathy_zoo.experiment.model import RunSpec
    from empathy_zoo.training.checkpoint import save_checkpoint
    from empathy_zoo.training.resume import checkpoint_path, survey_ensembles

    out = tmp_path / "out"
    todo = [RunSpec.of(steps=100, eval_interval=100, eval_episodes=1, seed=0)]
    checkpoint = checkpoint_path(out, todo)
    save_checkpoint(checkpoint, {"run_ids": [spec.run_id for spec in todo]})
    manifest = checkpoint.with_name(checkpoint.stem + ".runs.json")
    manifest.write_text("{")
    users = manifest.with_name(manifest.name + ".unreadable")
    users.write_text("mine")
    before = _tree(out)
    plan = survey_ensembles(todo, out, 1)
    assert _tree(out) == before and plan.chunks == [todo]
    notes: list[str] = []
    assert plan.apply(notes.append) == [todo]
    assert users.read_text() == "mine" and manifest.with_name(manifest.name + ".unreadable.2").read_text() == "{"
    assert not manifest.exists() and checkpoint.exists()
    assert len(notes) == 1 and notes[0].startswith(f"set aside {manifest} as {manifest.name}.unreadable.2:"), notes


def test_a_train_that_goes_ahead_sets_an_unreadable_list_aside_and_resumes(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from empathy_zoo.experiment.model import RunSpec
    from empathy_zoo.training import RunnerOptions, ensemble, train_runs
    from empathy_zoo.training.resume import checkpoint_path

    specs = [
        RunSpec.of(
            steps=200,
            eval_interval=100,
            eval_episodes=1,
            seed=seed,
            settings={"learning_starts": 32, "replay_capacity": 300, "hidden_size": 8},
            env_kwargs={"max_cycles": 40},
        )
        for seed in (0, 1)
    ]
    out = tmp_path / "out"
    options = RunnerOptions(progress=False, checkpoint_interval=100)
    real = ensemble.save_checkpoint

    def save_then_die(path: Path, payload: Any) -> None:
        real(path, payload)
        raise KeyboardInterrupt

    monkeypatch.setattr(ensemble, "save_checkpoint", save_then_die)
    with pytest.raises(KeyboardInterrupt):
        train_runs(specs, out, options, on_note=lambda _: None)
    monkeypatch.setattr(ensemble, "save_checkpoint", real)
    checkpoint = checkpoint_path(out, specs)
    manifest = checkpoint.with_name(checkpoint.stem + ".runs.json")
    assert checkpoint.is_file() and manifest.is_file()
    manifest.write_text('{"mine":1}\n')
    notes: list[str] = []
    results = train_runs(specs, out, options, on_note=notes.append)
    assert all(path.is_file() for path in results)
    aside = manifest.with_name(manifest.name + ".unreadable")
    assert aside.read_text() == '{"mine":1}\n' and not manifest.exists() and not checkpoint.exists()
    assert any(note.startswith(f"set aside {manifest} as {aside.name}:") for note in notes), notes
