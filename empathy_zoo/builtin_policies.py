"""The fixed agents of the paper: the cat's random walk, the human's patrol, and a sitting agent.

Each is a :class:`empathy_zoo.policies.FixedPolicy` with its own batched fast path; they are
registered by name in :data:`empathy_zoo.policies.POLICIES` (``random_walk``, ``patrol``, ``stay``).
"""

from __future__ import annotations

import secrets
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

import numpy as np

from empathy_zoo.actions import NUM_ACTIONS, Action
from empathy_zoo.limits import MAX_CYCLES
from empathy_zoo.policy_parameters import Parameter, Whole, check_arguments
from empathy_zoo.randomness import counter_integer, counter_integers, derive_key

__all__ = ["CounterStream", "CounterStreamBatch", "RandomWalk", "Patrol", "Stay"]


def _fields(state: Any) -> str:
    """What a policy's saved ``state`` holds, for a refusal: its fields, or its start."""
    return str(sorted(map(str, state))) if isinstance(state, Mapping) else f"{state!r:.80}"


def _key_problem(field: str, key: Any, expected: int) -> str | None:
    """``None`` when ``key`` (a saved stream's ``field``) is ``expected``, the key its seed gives."""
    if isinstance(key, (int, np.integer)) and not isinstance(key, bool) and int(key) == expected:
        return None
    return f"{field} is {key!r:.40}, not {expected}, the key its seed gives"


class CounterStream:
    """A policy's own counter-based random stream (:func:`~empathy_zoo.randomness.counter_uniform`):
    ``reset(seed)`` keys it from the episode's seed (a fresh random key without one), and each
    :meth:`_take` gives the key and the number of the next draw; its state is plain data."""

    def __init__(self) -> None:
        self._key: int | None = None
        self._count = 0

    def key_of(self, seed: int) -> int:
        """The key a reset with ``seed`` gives the stream (:func:`~empathy_zoo.randomness.derive_key`
        of it), which it keeps until its next seeded reset."""
        return derive_key(seed)

    def reset(self, seed: int | None = None) -> None:
        if seed is not None:
            self._key, self._count = self.key_of(seed), 0
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

    def saved_key_problem(self, state: Any, seed: int) -> str | None:
        """What is wrong with the key of ``state`` (what :meth:`state` saved) of a stream whose last
        seeded reset was with ``seed``: ``None`` when it is the key that seed gives (:meth:`key_of`,
        rederived: no step changes it), else one line naming the field."""
        return _key_problem("key", state.get("key") if isinstance(state, Mapping) else None, self.key_of(seed))

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

    def key_of(self, seed: int) -> int:
        """The key a reset with ``seed`` gives an environment's stream (as :meth:`CounterStream.key_of`)."""
        return derive_key(seed)

    def reset(self, env_ids: np.ndarray, seeds: Sequence[int | None]) -> None:
        for i, seed in zip(env_ids, seeds, strict=True):
            if seed is not None:
                self.keys[i], self.counts[i] = self.key_of(seed), 0

    def saved_key_problem(self, state: Any, seeds: Sequence[int | None]) -> str | None:
        """What is wrong with the keys of ``state`` (what :meth:`state` saved) of streams whose last
        seeded resets were with ``seeds`` (one per environment; ``None``: never seeded, not judged):
        ``None`` when each is the key its seed gives (:meth:`key_of`, rederived), else one line
        naming the field."""
        keys = state.get("keys") if isinstance(state, Mapping) else None
        if not isinstance(keys, np.ndarray) or keys.dtype != np.uint64 or keys.shape != self.keys.shape:
            return f"keys is no uint64 array of shape {self.keys.shape}"
        for i, seed in enumerate(seeds):
            problem = None if seed is None else _key_problem(f"keys[{i}]", int(keys[i]), self.key_of(seed))
            if problem is not None:
                return problem
        return None

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
    parameters: ClassVar[dict[str, Parameter]] = {}
    """It takes no argument."""

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
    parameters: ClassVar[dict[str, Parameter]] = {
        "period": Whole(1, MAX_CYCLES),
        "first": Whole(0, NUM_ACTIONS - 1, "an action"),
        "then": Whole(0, NUM_ACTIONS - 1, "an action"),
    }
    """Its arguments, their types and ranges (:mod:`empathy_zoo.policy_parameters`)."""

    def __init__(self, period: int = 7, first: int = Action.UP, then: int = Action.RIGHT) -> None:
        check_arguments(type(self).__name__, Patrol, {"period": period, "first": first, "then": then})
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
        t = state.get("t") if isinstance(state, Mapping) and set(state) == {"t"} else None
        if isinstance(t, bool) or not isinstance(t, (int, np.integer)) or not 0 <= t < 2**63:
            raise ValueError(f"a patrol's state holds its step t, an int in [0, 2**63), got {_fields(state)}: {t!r:.80}")
        self._t = int(t)

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
    parameters: ClassVar[dict[str, Parameter]] = {}
    """It takes no argument."""

    def reset(self, seed: int | None = None) -> None:
        pass

    def act(self, observation: np.ndarray, info: Mapping[str, Any]) -> int:
        return int(Action.STAY)
