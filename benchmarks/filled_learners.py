"""Learners with filled replay memories, and a CPU timer, for the benchmarks that time updates
alone (shared by the scripts in benchmarks/)."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence

import numpy as np

from agents.empathic_dqn import EmpathicDQN
from agents.settings import EmpathicDQNSettings

PAPER_BETAS = [0.75, 0.5, 0.25] * 5 + [1.0] * 10
"""One env's share of the paper profile: 15 runs with ``Q_emp`` and 10 DQN-type runs."""


def filled_learner(cls: type = EmpathicDQN, betas: Sequence[float] = PAPER_BETAS, seed: int = 0) -> EmpathicDQN:
    """A learner of class ``cls`` with one run per β, every replay memory holding the same 1,000
    random transitions for a given ``seed``; Coexistence's sizes (25 inputs, 5 actions)."""
    settings = [
        EmpathicDQNSettings(selfishness=b, learning_starts=32, replay_capacity=2_000, target_update_interval=50) for b in betas
    ]
    learner = cls(settings, list(range(len(betas))), 25)
    rng, k = np.random.default_rng(seed), len(betas)
    for _ in range(5):
        obs = [rng.integers(-1, 2, size=(k, 200, 25)).astype(np.float32) for _ in range(3)]
        learner.replay.add(
            obs[0],
            obs[1],
            obs[2][:, :, None],  # one other agent
            rng.integers(0, 5, (k, 200)),
            rng.random((k, 200)).astype(np.float32),
            rng.random((k, 200)) < 0.05,
            rng.random((k, 200, 1)) < 0.9,
            np.ones((k, 200, 1), dtype=bool),
            np.zeros((k, 200, 1), dtype=bool),
        )
    return learner


def cpu_ms(fn: Callable[[], object], calls: int) -> float:
    """CPU milliseconds of this process per call of ``fn``, over ``calls`` calls."""
    start = time.process_time()
    for _ in range(calls):
        fn()
    return (time.process_time() - start) / calls * 1e3
