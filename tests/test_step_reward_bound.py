"""Every engine's declared :attr:`~empathy_zoo.engine.base.GridEngine.step_reward_bound` holds:
no agent gets a larger reward in one step, so no episode return exceeds ``t`` times it (what a
checkpoint's returns are checked against)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from empathy_zoo.environments import ENGINES

VARIANTS: list[tuple[str, dict[str, Any]]] = [
    *((name, {}) for name in sorted(ENGINES)),
    ("sharing_v0", {"size": 5, "view": 3, "num_humans": 3}),
    ("sharing_v0", {"size": 11}),
    ("coexistence_v0", {"num_cats": 3}),
]


@pytest.mark.parametrize(("env", "kwargs"), VARIANTS, ids=[f"{e}-{k}" for e, k in VARIANTS])
def test_no_step_pays_more_than_the_bound_and_no_return_exceeds_t_times_it(env: str, kwargs: dict[str, Any]) -> None:
    engine = ENGINES[env](64, max_cycles=60, **kwargs)
    bound = engine.step_reward_bound
    rng = np.random.default_rng(0)
    engine.reset(seeds=list(range(64)))
    largest = 0.0
    for _ in range(400):
        events = engine.step(rng.integers(0, engine.num_actions, size=(engine.num_envs, engine.num_agents)))
        largest = max(largest, float(np.abs(events.rewards).max()))
        assert np.all(np.abs(events.rewards) <= bound)
        assert np.all(np.abs(engine.episode_return) <= engine.t[:, None] * bound)
        assert np.all(np.abs(engine.episode_battery_return) <= engine.t[:, None] * bound)
        over = np.flatnonzero(events.episode_over)
        if over.size:
            engine.reset(over)
    assert largest > 0.0, "some step paid something"
