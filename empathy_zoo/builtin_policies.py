"""The fixed agents of the paper: the cat's random walk, the human's patrol, and a sitting agent.

Each is a :class:`empathy_zoo.policies.FixedPolicy` with its own batched fast path; they are
registered by name in :data:`empathy_zoo.policies.POLICIES` (``random_walk``, ``patrol``, ``stay``).
"""

from __future__ import annotations

import secrets
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from empathy_zoo.actions import NUM_ACTIONS, Action
from empathy_zoo.randomness import counter_integer, counter_integers, derive_key

__all__ = ["CounterStream", "CounterStreamBatch", "RandomWalk", "Patrol", "Stay"]


def _fields(state: Any) -> str:
    """What a policy's saved ``state`` holds, for a refusal: its fields, or its start."""
    return str(sorted(map(str, state))) if isinstance(state, Mapping) else f"{state!r:.80}"


class CounterStream:
    """A policy's own counter-based random stream (:func:`~empathy_zoo.randomness.counter_uniform`):
    ``reset(seed)`` keys it from the episode's seed (a fresh random key without one), and each
    :meth:`_take` gives the key and the number of the next draw; its state is plain data."""

    def __init__(self) -> None:
        self._key: int | None = None
        self._count = 0

    def reset(self, seed: int | None = None) -> None:
        if seed is not None:
            self._key, self._count = derive_key(seed), 0
        elif self._key is None:
            self._key = secrets.randbits(64)

    def _take(self) -> tuple[int, int]:
        """The key and the number of this step's draw (the next one after it)."""
        if self._key is None:
            self.reset()
        assert self._key is not None  # reset() draws one
        count = self._count
        self._count += 1
        return self._key, count

    def state(self) -> dict[str, Any]:
        return {"key": self._key, "count": self._count}

    def load_state(self, state: Mapping[str, Any]) -> None:
        if not isinstance(state, Mapping) or set(state) != {"key", "count"}:
            raise ValueError(f"a counter stream's state holds key and count, got {_fields(state)}")
        key, count = state["key"], state["count"]
        if key is not None and (isinstance(key, bool) or not isinstance(key, (int, np.integer)) or not 0 <= key < 2**64):
            raise ValueError(f"a counter stream's key is a 64-bit unsigned int or null, got {key!r:.80}")
        if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or not 0 <= count < 2**63:
            raise ValueError(f"a counter stream's count is an int in [0, 2**63), got {count!r:.80}")
        self._key = None if key is None else int(key)
        self._count = int(count)


class CounterStreamBatch:
    """:class:`CounterStream` for ``num_envs`` environments at once: one key and one count each,
    a count advancing only where its environment's agent is active."""

    state_name = "counter stream"
    """What a state error calls the policy."""

    def __init__(self, num_envs: int) -> None:
        self.keys = np.array([secrets.randbits(64) for _ in range(num_envs)], dtype=np.uint64)
        self.counts = np.zeros(num_envs, dtype=np.uint64)

    def reset(self, env_ids: np.ndarray, seeds: Sequence[int | None]) -> None:
        for i, seed in zip(env_ids, seeds, strict=True):
            if seed is not None:
                self.keys[i], self.counts[i] = derive_key(seed), 0

    def _take(self, active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The keys and the numbers of this step's draws (the counts of the active ones advance)."""
        counts = self.counts.copy()
        self.counts += active.astype(np.uint64)
        return self.keys, counts

    def state(self) -> dict[str, Any]:
        return {"keys": self.keys.copy(), "counts": self.counts.copy()}

    def load_state(self, state: Mapping[str, Any]) -> None:
        if not isinstance(state, Mapping) or set(state) != {"keys", "counts"}:
            raise ValueError(f"{self.state_name} state holds keys and counts, got {_fields(state)}")
        for name in ("keys", "counts"):
            value = np.asarray(state[name])
            current = getattr(self, name)
            if value.shape != current.shape:
                raise ValueError(f"{self.state_name} state {name!r} has shape {value.shape}, expected {current.shape}")
            if value.dtype != np.uint64:
                raise ValueError(f"{self.state_name} state {name!r} is {value.dtype}, expected uint64")
            current[...] = value


class RandomWalk(CounterStream):
    """Uniformly random over the five actions (the cat). Counter-based, so it is reproducible
    per environment whether it acts alone or batched."""

    needs_observation = False

    def act(self, observation: np.ndarray, info: Mapping[str, Any]) -> int:
        key, count = self._take()
        return counter_integer(key, count, NUM_ACTIONS)

    def batched(self, num_envs: int) -> _RandomWalkBatch:
        return _RandomWalkBatch(num_envs)


class _RandomWalkBatch(CounterStreamBatch):
    needs_observation = False
    state_name = "random walk"

    def act(self, observations: np.ndarray | None, steps: np.ndarray, active: np.ndarray) -> np.ndarray:
        keys, counts = self._take(active)
        return counter_integers(keys, counts, NUM_ACTIONS)


class Patrol:
    """The human of Sharing: on steps t = 0, period, 2·period, … move ``first``, otherwise ``then``.

    Defaults follow the original code: up every 7th step (from t = 0), right otherwise.
    """

    needs_observation = False

    def __init__(self, period: int = 7, first: int = Action.UP, then: int = Action.RIGHT) -> None:
        if period < 1:
            raise ValueError(f"period must be positive, got {period}")
        for name, action in (("first", first), ("then", then)):
            if not 0 <= int(action) < NUM_ACTIONS:
                raise ValueError(f"{name} must be an action in [0, {NUM_ACTIONS}), got {action}")
        self.period, self.first, self.then = int(period), int(first), int(then)
        self._t = 0

    def reset(self, seed: int | None = None) -> None:
        self._t = 0

    def act(self, observation: np.ndarray, info: Mapping[str, Any]) -> int:
        action = self.first if self._t % self.period == 0 else self.then
        self._t += 1
        return action

    def state(self) -> dict[str, Any]:
        return {"t": self._t}

    def load_state(self, state: Mapping[str, Any]) -> None:
        self._t = int(state["t"])

    def batched(self, num_envs: int) -> _PatrolBatch:
        return _PatrolBatch(self)


class _PatrolBatch:
    needs_observation = False
    stateless = True
    """Its step count is the environment's."""

    def __init__(self, patrol: Patrol) -> None:
        self.patrol = patrol

    def reset(self, env_ids: np.ndarray, seeds: Sequence[int | None]) -> None:
        pass  # the step count comes from the environment

    def act(self, observations: np.ndarray | None, steps: np.ndarray, active: np.ndarray) -> np.ndarray:
        p = self.patrol
        return np.where(steps % p.period == 0, p.first, p.then).astype(np.int64)


class Stay:
    """Never moves (a sitting target; handy in tests and as a control)."""

    needs_observation = False
    stateless = True

    def reset(self, seed: int | None = None) -> None:
        pass

    def act(self, observation: np.ndarray, info: Mapping[str, Any]) -> int:
        return int(Action.STAY)
