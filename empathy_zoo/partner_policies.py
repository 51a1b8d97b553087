"""Fixed agents a trained robot never met: partners for held-out evaluation (:mod:`empathy_zoo.scenarios`).

Each is a :class:`empathy_zoo.policies.FixedPolicy` registered by name in
:data:`empathy_zoo.policies.POLICIES`:

* ``slow_walk`` (:class:`SlowWalk`): steps in a random direction with probability
  ``move_probability`` (0.1), else stays; reads nothing.
* ``chase`` (:class:`Chase`): steps towards the robot along the shorter way round the torus, rows
  first; reads ``positions``.
* ``keep_away`` (:class:`KeepAway`): takes the move that leaves it farthest from the robot; reads
  ``positions``.
* ``nearest_battery`` (:class:`NearestBattery`, Sharing): steps towards the nearest battery in its
  window, else patrols; reads its observation.
* ``noisy`` (:class:`Noisy`): another registered partner that keeps nothing between steps
  (``partner``, e.g. ``chase``), except that on a share ``noise`` of its steps it acts uniformly
  at random; the noisy counterpart of a deterministic partner.
* ``population`` (:class:`Population`): one of several registered partners (``members``), drawn
  afresh at each episode with probabilities ``weights``; a population of partners to train with
  or to hold out.

:class:`Chase`, :class:`KeepAway` and :class:`NearestBattery` are deterministic and keep nothing
between steps (``stateless = True``); :class:`SlowWalk` draws from a counter-based stream of its
seed, as :class:`~empathy_zoo.builtin_policies.RandomWalk` does, and has a batched fast path;
:class:`Noisy` draws from such a stream too, one draw per step; :class:`Population` one per episode.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

import numpy as np

from empathy_zoo.actions import Action
from empathy_zoo.builtin_policies import CounterStream, CounterStreamBatch
from empathy_zoo.limits import MAX_CYCLES
from empathy_zoo.policy_parameters import REGISTRY, AgentName, Members, Parameter, Partner, Share, Weights, Whole, check_arguments
from empathy_zoo.randomness import STREAMS, counter_uniform, derive_key

__all__ = [
    "SlowWalk",
    "Chase",
    "KeepAway",
    "NearestBattery",
    "Noisy",
    "Population",
    "MAX_MEMBERS",
    "BATTERY_VALUE",
    "MOVES_BY_ACTION",
]

BATTERY_VALUE = -1.0
"""How a battery looks in a Sharing observation (SPEC §3: floor 0, battery −1, an agent positive)."""
MOVES_BY_ACTION: tuple[tuple[Action, int, int], ...] = (
    (Action.UP, -1, 0),
    (Action.DOWN, 1, 0),
    (Action.LEFT, 0, -1),
    (Action.RIGHT, 0, 1),
    (Action.STAY, 0, 0),
)
"""Every action and its ``(row, col)`` displacement (SPEC §1), in action order."""
_DIRECTIONS = (Action.UP, Action.DOWN, Action.LEFT, Action.RIGHT)


def _slow_walk_action(draw: float, move_probability: float) -> int:
    """The action of a draw ``u`` in ``[0, 1)``: the ``⌊4u/p⌋``-th move when ``u < p``, else stay."""
    if draw < move_probability:
        return int(_DIRECTIONS[min(int(draw / move_probability * 4), 3)])
    return int(Action.STAY)


class SlowWalk(CounterStream):
    """A cat that rarely moves (one step in ten by default).

    On each step, with probability ``move_probability`` it steps up, down, left or right (each
    equally likely), otherwise it stays. One draw per step from the counter-based stream of its
    seed (the same numbers alone or batched)."""

    needs_observation = False
    parameters: ClassVar[dict[str, Parameter]] = {"move_probability": Share()}
    """Its arguments, their types and ranges (:mod:`empathy_zoo.policy_parameters`)."""

    def __init__(self, move_probability: float = 0.1) -> None:
        check_arguments(type(self).__name__, SlowWalk, {"move_probability": move_probability})
        super().__init__()
        self.move_probability = float(move_probability)

    def act(self, observation: np.ndarray, info: Mapping[str, Any]) -> int:
        key, count = self._take()
        return _slow_walk_action(float(counter_uniform(key, count)[0]), self.move_probability)

    def batched(self, num_envs: int) -> _SlowWalkBatch:
        return _SlowWalkBatch(num_envs, self.move_probability)


class _SlowWalkBatch(CounterStreamBatch):
    needs_observation = False
    state_name = "slow walk"

    def __init__(self, num_envs: int, move_probability: float) -> None:
        super().__init__(num_envs)
        self.move_probability = move_probability

    def act(self, observations: np.ndarray | None, steps: np.ndarray, active: np.ndarray) -> np.ndarray:
        draws = counter_uniform(*self._take(active))
        p = self.move_probability
        with np.errstate(over="ignore"):  # (a tiny p gives inf, capped before the cast: never a wrapped index)
            moves = np.minimum(draws / p * 4, 3).astype(np.int64)
        return np.where(draws < p, np.asarray(_DIRECTIONS, dtype=np.int64)[moves], int(Action.STAY)).astype(np.int64)


def _torus_offset(delta: int, size: int) -> int:
    """The shortest signed displacement ``delta`` on a ring of ``size`` cells (a tie goes forward)."""
    delta %= size
    return delta if delta <= size - delta else delta - size


class Chase:
    """A cat that chases the robot (from the true positions).

    On every ``every``-th step of the episode it steps towards ``target`` along the shorter way
    round the torus, rows first (a tie of the two ways: down, or right); it stays on the other
    steps, once it stands on the target's cell, and when the target is gone. It reads the true
    positions (the target is often outside its window)."""

    needs_state = True
    stateless = True
    parameters: ClassVar[dict[str, Parameter]] = {"target": AgentName(), "every": Whole(1, MAX_CYCLES)}
    """Its arguments, their types and ranges (:mod:`empathy_zoo.policy_parameters`)."""

    def __init__(self, target: str = "robot_0", every: int = 1) -> None:
        check_arguments(type(self).__name__, Chase, {"target": target, "every": every})
        self.target, self.every = target, int(every)

    def reset(self, seed: int | None = None) -> None:
        pass

    def act(self, observation: np.ndarray, info: Mapping[str, Any]) -> int:
        positions, size = info["positions"], info["size"]
        if info["step"] % self.every or self.target not in positions:
            return int(Action.STAY)
        (row, col), (to_row, to_col) = positions[info["agent"]], positions[self.target]
        down, right = _torus_offset(to_row - row, size), _torus_offset(to_col - col, size)
        if down:
            return int(Action.DOWN if down > 0 else Action.UP)
        if right:
            return int(Action.RIGHT if right > 0 else Action.LEFT)
        return int(Action.STAY)


class KeepAway:
    """A cat that keeps away from the robot (from the true positions).

    It takes the action (the four moves or staying) after which its torus distance (the Manhattan
    distance the shorter ways round) to where ``target`` stands now is largest, the first in
    action order on a tie (up, down, left, right, stay); it stays when the target is gone."""

    needs_state = True
    stateless = True
    parameters: ClassVar[dict[str, Parameter]] = {"target": AgentName()}
    """Its argument, its type (:mod:`empathy_zoo.policy_parameters`)."""

    def __init__(self, target: str = "robot_0") -> None:
        check_arguments(type(self).__name__, KeepAway, {"target": target})
        self.target = target

    def reset(self, seed: int | None = None) -> None:
        pass

    def act(self, observation: np.ndarray, info: Mapping[str, Any]) -> int:
        positions, size = info["positions"], info["size"]
        if self.target not in positions:
            return int(Action.STAY)
        (row, col), (to_row, to_col) = positions[info["agent"]], positions[self.target]

        def distance(action: tuple[Action, int, int]) -> int:
            _, d_row, d_col = action
            return abs(_torus_offset(to_row - row - d_row, size)) + abs(_torus_offset(to_col - col - d_col, size))

        return int(max(MOVES_BY_ACTION, key=distance)[0])  # (max keeps the first of equals)


class NearestBattery:
    """A Sharing human that heads for the nearest battery it sees, else patrols.

    It steps towards the nearest battery in its own window (a cell of value −1; the Manhattan
    distance inside the window, the first cell in row-major order on a tie), rows first; with no
    battery in view it patrols as the authors' human does (up on steps 0, ``period``,
    2·``period``, …, right otherwise). It reads only its observation (and the step count), so it
    knows no battery it cannot see."""

    stateless = True
    parameters: ClassVar[dict[str, Parameter]] = {"period": Whole(1, MAX_CYCLES)}
    """Its argument, its type and range (:mod:`empathy_zoo.policy_parameters`)."""

    def __init__(self, period: int = 7) -> None:
        check_arguments(type(self).__name__, NearestBattery, {"period": period})
        self.period = int(period)

    def reset(self, seed: int | None = None) -> None:
        pass

    def act(self, observation: np.ndarray, info: Mapping[str, Any]) -> int:
        window = np.asarray(observation)
        side = round(len(window) ** 0.5)
        if side * side != len(window):
            raise ValueError(f"nearest_battery reads a square window, got an observation of {len(window)} values")
        centre = side // 2
        cells = np.flatnonzero(window == BATTERY_VALUE)
        if cells.size == 0:
            return int(Action.UP if info["step"] % self.period == 0 else Action.RIGHT)
        rows, cols = cells // side - centre, cells % side - centre
        nearest = int(np.argmin(np.abs(rows) + np.abs(cols)))  # (argmin keeps the first of equals)
        down, right = int(rows[nearest]), int(cols[nearest])
        if down:
            return int(Action.DOWN if down > 0 else Action.UP)
        return int(Action.RIGHT if right > 0 else Action.LEFT)


class Noisy(CounterStream):
    """A deterministic partner with noise: on each step, with probability ``noise`` it takes one of
    the five actions uniformly at random, else the action of ``partner``.

    ``partner`` is the registered name of a policy that keeps nothing between steps (``chase``,
    ``keep_away``, ``stay``, ``patrol``, ``nearest_battery``), built with its defaults. One draw
    per step from the counter-based stream of its seed decides both: a draw ``u < noise`` gives
    action ``⌊5u/noise⌋``. It reads what its partner reads."""

    parameters: ClassVar[dict[str, Parameter]] = {"partner": Partner("noisy", stateless=True), "noise": Share()}
    """Its arguments, their types and ranges (:mod:`empathy_zoo.policy_parameters`)."""

    def __init__(self, partner: str = "chase", noise: float = 0.2) -> None:
        check_arguments(type(self).__name__, Noisy, {"partner": partner, "noise": noise})
        base = REGISTRY[partner]()
        super().__init__()
        self.partner, self.noise, self._base = partner, float(noise), base
        self.needs_state = bool(getattr(base, "needs_state", False))

    def reset(self, seed: int | None = None) -> None:
        super().reset(seed)
        self._base.reset(seed)

    def act(self, observation: np.ndarray, info: Mapping[str, Any]) -> int:
        key, count = self._take()
        draw = float(counter_uniform(key, count)[0])
        if draw < self.noise:
            return min(int(draw / self.noise * 5), 4)
        return int(self._base.act(observation, info))


MAX_MEMBERS = 16
"""The most partners a population holds."""
MAX_WEIGHT = 1e9
"""The largest weight of a population's member (their sum stays finite and exact enough)."""


class Population(CounterStream):
    """A population of partners: at each episode's start one member plays the whole episode.

    ``members`` are registered policy names (built with their defaults), each at most once;
    ``weights`` (default: equal) are their probabilities, normalised. The member is drawn from the
    population's own counter-based stream, keyed by the episode's seed on a seeded reset (stream
    ``population_member`` of :data:`~empathy_zoo.randomness.STREAMS`) and continued otherwise. A
    seeded reset resets every member with its seed, so a member first picked at a later, unseeded
    reset continues a stream of that seed: a run repeats exactly. Its state is its stream's, the member's index and every
    member's own state, so a checkpointed run resumes it exactly."""

    parameters: ClassVar[dict[str, Parameter]] = {
        "members": Members("population", MAX_MEMBERS),
        "weights": Weights("members", MAX_WEIGHT),
    }
    """Its arguments, their types and ranges (:mod:`empathy_zoo.policy_parameters`)."""

    def __init__(self, members: Sequence[str] = ("chase", "keep_away"), weights: Sequence[float] | None = None) -> None:
        check_arguments(type(self).__name__, Population, {"members": members, "weights": weights})
        shares = [1.0] * len(members) if weights is None else weights
        super().__init__()
        total = sum(float(w) for w in shares)
        self.members, self.weights = list(members), [float(w) for w in shares]
        self._cumulative = np.cumsum([float(w) / total for w in shares])
        self._policies = [REGISTRY[name]() for name in members]
        self.needs_state = any(bool(getattr(p, "needs_state", False)) for p in self._policies)
        self.needs_observation = any(bool(getattr(p, "needs_observation", True)) for p in self._policies)
        self.member = 0
        """The index of the member playing this episode."""

    def key_of(self, seed: int) -> int:
        """The key of the draws of members a reset with ``seed`` gives (stream ``population_member``)."""
        return derive_key(seed, STREAMS["population_member"])

    def reset(self, seed: int | None = None) -> None:
        super().reset(seed)
        self.member = self._member_of(*self._take())
        if seed is None:
            self._policies[self.member].reset(None)  # (continues its own stream, keyed at the last seeded reset)
        else:
            for policy in self._policies:  # every member keyed by the seed: one first picked later is too
                policy.reset(seed)

    def _member_of(self, key: int, count: int) -> int:
        """The member the draw ``count`` of the stream ``key`` picks."""
        draw = float(counter_uniform(key, count)[0])
        return min(int(np.searchsorted(self._cumulative, draw, side="right")), len(self.members) - 1)

    def saved_key_problem(self, state: Any, seed: int) -> str | None:
        """As :meth:`CounterStream.saved_key_problem`, for its own key and every member's: a seeded
        reset keys every member with its seed (:meth:`reset`), and an unseeded one continues them."""
        problem = super().saved_key_problem(state, seed)
        members = state.get("members") if isinstance(state, Mapping) else None
        if problem is not None or not isinstance(members, list) or len(members) != len(self.members):
            return problem  # (a list of another length: load_state refuses it)
        for index, (policy, own) in enumerate(zip(self._policies, members, strict=True)):
            judge = getattr(policy, "saved_key_problem", None)
            inner = judge(own, seed) if callable(judge) else None
            if inner is not None:
                return f"members[{index}].{inner}"
        return None

    def act(self, observation: np.ndarray, info: Mapping[str, Any]) -> int:
        return int(self._policies[self.member].act(observation, info))

    def state(self) -> dict[str, Any]:
        states = [p.state() if hasattr(p, "state") else {} for p in self._policies]
        return {**super().state(), "member": self.member, "members": states}

    def load_state(self, state: Mapping[str, Any]) -> None:
        if set(state) != {"key", "count", "member", "members"}:
            raise ValueError(f"population state holds key, count, member and members, got {sorted(state)!r:.120}")
        member, states = state["member"], state["members"]
        if isinstance(member, bool) or not isinstance(member, int) or not 0 <= member < len(self.members):
            raise ValueError(f"population state 'member' must be an index below {len(self.members)}, got {member!r}")
        if not isinstance(states, list) or len(states) != len(self.members):
            raise ValueError(f"population state 'members' must hold {len(self.members)} states, got {states!r}")
        super().load_state({"key": state["key"], "count": state["count"]})
        self.member = member
        for policy, own in zip(self._policies, states, strict=True):
            if hasattr(policy, "load_state"):
                policy.load_state(own)
