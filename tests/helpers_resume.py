"""Train one run twice, uninterrupted and killed at its first checkpoint then resumed, and return
both result files (for the tests that a stateful reward transform survives a checkpoint)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest


def whole_and_resumed(
    spec: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, checkpoint_interval: int = 250
) -> tuple[dict[str, Any], dict[str, Any]]:
    """The result of ``spec`` trained without checkpoints, and trained again with one every
    ``checkpoint_interval`` steps, killed just after the first is written, then resumed."""
    from empathy_zoo.training import RunnerOptions, ensemble, train_runs

    whole = json.loads(
        train_runs([spec], tmp_path / "whole", RunnerOptions(progress=False, checkpoint_interval=0))[0].read_text()
    )
    real = ensemble.save_checkpoint

    def save_then_die(path, payload):
        real(path, payload)
        raise KeyboardInterrupt

    monkeypatch.setattr(ensemble, "save_checkpoint", save_then_die)
    options = RunnerOptions(progress=False, checkpoint_interval=checkpoint_interval)
    with pytest.raises(KeyboardInterrupt):
        train_runs([spec], tmp_path / "resumed", options)
    monkeypatch.setattr(ensemble, "save_checkpoint", real)
    resumed = json.loads(train_runs([spec], tmp_path / "resumed", options)[0].read_text())
    return whole, resumed


SMALL_SETTINGS = {
    "learning_starts": 64,
    "replay_capacity": 1_000,
    "epsilon_decay_steps": 300,
    "target_update_interval": 50,
    "hidden_size": 16,
}
"""A learner small enough for a 600-step run that still learns something."""


TINY_SETTINGS = {
    "learning_starts": 32,
    "replay_capacity": 300,
    "hidden_size": 8,
    "target_update_interval": 50,
    "epsilon_decay_steps": 200,
}
"""A learner for runs of a few hundred steps whose numbers do not matter (resume, checkpoints, fixed policies)."""


def small_run(method: str, env: str = "coexistence_v0", **spec: Any) -> Any:
    """The ``RunSpec`` of a 600-step run of ``method`` (greedy evaluations at 300 and 600, episodes
    of 40 steps, :data:`SMALL_SETTINGS`); ``spec`` sets other fields (``reward=...``)."""
    from empathy_zoo.experiment.model import RunSpec

    return RunSpec.of(
        env=env,
        method=method,
        steps=600,
        eval_interval=300,
        eval_episodes=2,
        settings=SMALL_SETTINGS,
        env_kwargs={"max_cycles": 40},
        **spec,
    )
