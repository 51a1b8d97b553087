"""Fixed (non-learning) agents: the cat's random walk, the human's patrol, and your own.

A fixed policy is any object with ``reset(seed)`` and ``act(observation, info) -> int``
(:class:`FixedPolicy`). ``reset`` is called at the start of every episode: with a seed it
reseeds, with ``None`` it continues its random stream. Register a new one by name in
:data:`POLICIES`, or name it as ``"package.module:ClassName"`` in a config or on the command
line; :func:`make_policy` resolves both.

A policy may also offer ``batched(num_envs) -> BatchedPolicy`` to act for many environments
with one numpy call (the training fast path); without it, :func:`batched` runs one copy of the
policy per environment, which is correct but slower.
"""

from __future__ import annotations

import copy
import secrets
from collections.abc import Mapping, Sequence
from typing import Any, Protocol, runtime_checkable

import numpy as np

from empathy_zoo.actions import check_action
from empathy_zoo.grid import NUM_ACTIONS, Action
from empathy_zoo.randomness import counter_integer, counter_integers, derive_key
from empathy_zoo.registry import resolve_name

__all__ = [
    "FixedPolicy", "BatchedPolicy", "RandomWalk", "Patrol", "Stay", "POLICIES",
    "DEFAULT_POLICIES", "make_policy", "batched", "checked_policy_action",
]


@runtime_checkable
class FixedPolicy(Protocol):
    """What the suite asks of a non-learning agent."""

    def reset(self, seed: int | None = None) -> None:
        """Start an episode; reseed when ``seed`` is given, else continue the random stream."""

    def act(self, observation: np.ndarray, info: Mapping[str, Any]) -> int:
        """The action (an int in ``[0, 5)``) for this step."""


class BatchedPolicy(Protocol):
    """A fixed policy acting for ``num_envs`` environments at once."""

    needs_observation: bool

    def reset(self, env_ids: np.ndarray, seeds: Sequence[int | None]) -> None:
        """Start episodes in ``env_ids`` (seeded like :meth:`FixedPolicy.reset`)."""

    def act(self, observations: np.ndarray | None, steps: np.ndarray, active: np.ndarray) -> np.ndarray:
        """Actions ``(num_envs,)`` given observations ``(num_envs, obs)``, each env's step count and
        where the agent is present (elsewhere the action is ignored and no stream may advance)."""


class RandomWalk:
    """Uniformly random over the five actions (the cat). Counter-based, so it is reproducible
    per environment whether it acts alone or batched."""

    needs_observation = False

    def __init__(self) -> None:
        self._key: int | None = None
        self._count = 0

    def reset(self, seed: int | None = None) -> None:
        if seed is not None:
            self._key, self._count = derive_key(seed), 0
        elif self._key is None:
            self._key = secrets.randbits(64)

    def act(self, observation: np.ndarray, info: Mapping[str, Any]) -> int:
        if self._key is None:
            self.reset()
        action = counter_integer(self._key, self._count, NUM_ACTIONS)
        self._count += 1
        return action

    def batched(self, num_envs: int) -> _RandomWalkBatch:
        return _RandomWalkBatch(num_envs)


class _RandomWalkBatch:
    needs_observation = False

    def __init__(self, num_envs: int) -> None:
        self.keys = np.array([secrets.randbits(64) for _ in range(num_envs)], dtype=np.uint64)
        self.counts = np.zeros(num_envs, dtype=np.uint64)

    def reset(self, env_ids: np.ndarray, seeds: Sequence[int | None]) -> None:
        for i, seed in zip(env_ids, seeds):
            if seed is not None:
                self.keys[i], self.counts[i] = derive_key(seed), 0

    def act(self, observations: np.ndarray | None, steps: np.ndarray, active: np.ndarray) -> np.ndarray:
        actions = counter_integers(self.keys, self.counts, NUM_ACTIONS)
        self.counts += active.astype(np.uint64)
        return actions


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

    def batched(self, num_envs: int) -> _PatrolBatch:
        return _PatrolBatch(self)


class _PatrolBatch:
    needs_observation = False

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

    def reset(self, seed: int | None = None) -> None:
        pass

    def act(self, observation: np.ndarray, info: Mapping[str, Any]) -> int:
        return int(Action.STAY)


class _PolicyCopies:
    """One copy of a per-environment policy for each environment (the generic, slower path)."""

    needs_observation = True

    def __init__(self, policy: FixedPolicy, num_envs: int, agent: str) -> None:
        self.copies = [copy.deepcopy(policy) for _ in range(num_envs)]
        self.agent = agent

    def reset(self, env_ids: np.ndarray, seeds: Sequence[int | None]) -> None:
        for i, seed in zip(env_ids, seeds):
            self.copies[i].reset(seed)

    def act(self, observations: np.ndarray | None, steps: np.ndarray, active: np.ndarray) -> np.ndarray:
        actions = np.full(len(self.copies), 4, dtype=np.int64)
        for i in np.flatnonzero(active):
            policy = self.copies[i]
            actions[i] = checked_policy_action(policy, self.agent, policy.act(observations[i], {"step": int(steps[i])}))
        return actions


POLICIES: dict[str, type] = {"random_walk": RandomWalk, "patrol": Patrol, "stay": Stay}
"""Fixed policies by name."""

DEFAULT_POLICIES: dict[str, dict[str, str]] = {
    "coexistence_v0": {"cat_0": "random_walk"},
    "sharing_v0": {"human_0": "patrol"},
}
"""The paper's fixed agents for each environment."""


def make_policy(spec: str | FixedPolicy, **kwargs: Any) -> FixedPolicy:
    """A policy from a registered name, a ``package.module:ClassName`` string, or an instance."""
    if not isinstance(spec, str):
        if kwargs:
            raise ValueError("keyword arguments are only accepted with a policy name")
        policy = spec
    else:
        factory = resolve_name(spec, POLICIES, "fixed policy")
        try:
            policy = factory(**kwargs)
        except TypeError as error:
            raise ValueError(f"cannot build fixed policy {spec!r} with {kwargs}: {error}") from error
    if not isinstance(policy, FixedPolicy):
        raise ValueError(f"{spec!r} is not a fixed policy: it needs reset(seed) and act(observation, info)")
    return policy


def checked_policy_action(policy: Any, agent: str, action: Any, num_actions: int = NUM_ACTIONS) -> int:
    """``action`` (what ``policy`` chose for ``agent``) as an ``int``, or a ``ValueError`` naming the
    policy: a fixed policy is held to the same rule as every action (never truncated)."""
    try:
        return check_action(agent, action, num_actions)
    except ValueError as error:
        raise ValueError(f"fixed policy {type(policy).__module__}:{type(policy).__qualname__} of {agent} "
                         f"chose an invalid action: {error}") from None


def batched(policy: FixedPolicy, num_envs: int, agent: str = "a fixed agent") -> BatchedPolicy:
    """The policy acting for ``num_envs`` environments as ``agent`` (its own fast path when it has one)."""
    if hasattr(policy, "batched"):
        return policy.batched(num_envs)
    return _PolicyCopies(policy, num_envs, agent)
