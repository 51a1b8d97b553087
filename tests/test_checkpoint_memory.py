"""Checkpoints cost no second copy of what they save: a full replay memory is written as it is,
the file is streamed (never assembled in memory), a resumed ensemble drops the loaded checkpoint
once restored — and runs resumed after their replay memory filled end exactly as uninterrupted
ones. (The paper profile's replay memories are ≈ 1 GB per ensemble; the peaks are measured by
``benchmarks/checkpoint_memory.py``.)"""

from __future__ import annotations

import gc
import pickle
import tracemalloc
import weakref

import numpy as np
import pytest
import torch
from helpers_resume import whole_and_resumed

from agents.replay import StackedReplay
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.training import RunnerOptions, ensemble, train_runs
from empathy_zoo.training.checkpoint import load_checkpoint, save_checkpoint


def _filled(capacity: int, adds: int, seed: int = 0) -> StackedReplay:
    rng = np.random.default_rng(seed)
    k, v = 2, 25
    replay = StackedReplay(k, capacity, v, torch.device("cpu"))
    for _ in range(adds):
        obs = rng.integers(-1, 11, (k, 1, 3, v)).astype(np.float32)
        replay.add(
            obs[:, :, 0],
            obs[:, :, 1],
            obs[:, :, 2:],
            rng.integers(0, 5, (k, 1)),
            rng.normal(size=(k, 1)),
            rng.random((k, 1)) < 0.1,
            rng.random((k, 1, 1)) < 0.9,
            np.ones((k, 1, 1), bool),
            np.zeros((k, 1, 1), bool),
        )
    return replay


@pytest.mark.parametrize("adds", [5, 8, 11], ids=["partly filled", "just full", "wrapped around"])
def test_a_replay_memory_restores_exactly_from_a_saved_checkpoint(tmp_path, adds) -> None:
    replay = _filled(capacity=8, adds=adds)
    save_checkpoint(tmp_path / "c.pt", {"replay": replay.state_dict()})
    restored = StackedReplay(2, 8, 25, torch.device("cpu"))
    restored.load_state_dict(load_checkpoint(tmp_path / "c.pt")["replay"])
    assert (restored.size, restored.position) == (replay.size, replay.position)
    index = torch.from_numpy(np.random.default_rng(1).integers(0, replay.size, (2, 20)))
    for name, value in replay.sample(index).items():
        assert torch.equal(restored.sample(index)[name], value), name


def test_the_state_of_a_full_replay_memory_is_its_buffers_not_a_copy() -> None:
    full, partial = _filled(capacity=8, adds=9), _filled(capacity=8, adds=3)
    state = full.state_dict()
    for name in ("observations", "flags", "reward"):
        assert state[name].data_ptr() == getattr(full, name).data_ptr(), name
        assert partial.state_dict()[name].shape[1] == 3, name  # only the filled part of a partial one


def test_a_checkpoint_is_streamed_to_its_file_not_assembled_in_memory(tmp_path) -> None:
    tensor = torch.arange(5_000_000, dtype=torch.int32)  # 20 MB (torch's memory: not traced below)
    tracemalloc.start()
    try:
        save_checkpoint(tmp_path / "c.pt", {"big": tensor})
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 2_000_000, peak  # Python-side buffers: far below the file's 20 MB
    assert torch.equal(load_checkpoint(tmp_path / "c.pt")["big"], tensor)


def test_a_checkpoint_that_fails_mid_write_leaves_the_previous_one_and_no_temporary_file(tmp_path) -> None:
    path = tmp_path / "c.pt"
    save_checkpoint(path, {"step": 1})
    # (what pickle raises for a function it cannot find by name: PicklingError, or AttributeError for a local one)
    with pytest.raises((pickle.PicklingError, AttributeError)):
        save_checkpoint(path, {"step": 2, "unsaveable": lambda: None})
    assert load_checkpoint(path)["step"] == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.pt"]


def _spec() -> RunSpec:
    """A run whose replay memory (100 transitions) is full long before its checkpoint at step 250."""
    return RunSpec.of(
        env="coexistence_v0",
        seed=3,
        steps=500,
        eval_interval=250,
        eval_episodes=2,
        settings={"selfishness": 0.5, "learning_starts": 32, "replay_capacity": 100},
    )


def test_a_run_resumed_after_its_replay_memory_filled_ends_as_the_uninterrupted_run(tmp_path, monkeypatch) -> None:
    whole, resumed = whole_and_resumed(_spec(), tmp_path, monkeypatch)
    for key in ("train", "eval", "memory_bytes"):
        assert resumed[key] == whole[key], key


def test_a_resumed_ensemble_does_not_keep_the_loaded_checkpoint(tmp_path, monkeypatch) -> None:
    options = RunnerOptions(progress=False, checkpoint_interval=200)
    real_save, real_load = ensemble.save_checkpoint, ensemble.load_checkpoint

    def save_then_die(path, payload):
        real_save(path, payload)
        raise KeyboardInterrupt

    with monkeypatch.context() as patch:
        patch.setattr(ensemble, "save_checkpoint", save_then_die)
        with pytest.raises(KeyboardInterrupt):
            train_runs([_spec()], tmp_path, options)

    loaded: list[weakref.ref] = []
    alive_at_next_checkpoint: list[bool] = []

    def load_and_watch(path):
        payload = real_load(path)
        loaded.append(weakref.ref(payload["learner"]["replay"]["observations"]))
        return payload

    def save_and_check(path, payload):
        gc.collect()
        alive_at_next_checkpoint.append(loaded[0]() is not None)
        real_save(path, payload)

    monkeypatch.setattr(ensemble, "load_checkpoint", load_and_watch)
    monkeypatch.setattr(ensemble, "save_checkpoint", save_and_check)
    train_runs([_spec()], tmp_path, options)
    assert len(loaded) == 1 and alive_at_next_checkpoint == [False]
