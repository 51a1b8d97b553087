"""# Coexistence reference: the exact optimum under full observability

The best figure a learner of Coexistence (SPEC §2) can reach, computed exactly rather than
learned. The verdict thresholds of the leaderboard compare trained runs with it.

| | |
|---|---|
| Import | `from empathy_zoo.reference import coexistence_optimum` |
| Call | `coexistence_optimum(selfishness, epsilon, *, ties="uniform", rule="golden", in_view_only=False, view=5, unseen="continuation", gamma=0.99, size=7, max_cycles=500, tolerance=1e-10)` |
| Returns | `ReferenceOutcome(harms, survival, selfishness, epsilon)`: expected harms and steps survived per episode |

## Model
* **State**: where the cat stands relative to the robot (the torus displacement
  `cat − robot`, `size²` values) while the cat is present, plus *cat gone* (the robot is alone
  and can never be harmed again) and *robot harmed* (terminal). Who harms whom depends on the
  displacement only, so this is the full-observability state `(robot cell, cat cell, cat
  present)` up to translation.
* **Dynamics**: the robot picks one of the 5 actions, the cat a uniformly random one, both move
  at once; the outcome is the engine's own rule, `empathy_zoo.engine.coexistence.harm_outcome`
  (no second copy of the rules). The start distribution is the engine's: a uniform cell for the
  robot and a uniform displacement among those not in contact.
* **Rewards** as the learner sees them: `+1` for every step at whose end the robot is operative,
  `0` on the step it is harmed, which ends its episode (no bootstrap). Harming the cat changes no
  reward; the cat leaves.
* **Q\\*** (what `Q` and `Q̂` approximate): optimal γ-discounted, infinite-horizon value iteration,
  stopped when the bound `γ/(1−γ)·‖V_{k+1} − V_k‖∞` on the error of `V` falls below `tolerance`.
  The displacement `(0, 0)` with the cat present is never reached, but the swap below can ask
  for it (the robot was harmed on the cat's cell); its value is the same Bellman fixed point.
* **Q_emp** (SPEC §6 at its fixed point, double DQN's `y` equals the plain one there):
  `Q_emp(s, a) = β·Q*(s, a) + (1 − β)·γ·E[present' · max_a Q*(swap(s'), a)]`, where `swap`
  negates the displacement (robot and cat exchange cells). `present'` is 0 when the robot harms
  the cat at t+1 (the cat is terminal). When the **cat harms the robot** the cat is still present
  (truncated, not terminal), so SPEC §6 keeps the other-term: so does this model. A time limit
  is not modelled (infinite-horizon values). `Q_emp` does not bootstrap from itself.
* **Variants** of the target: `rule="silver"` optimises the silver rule's
  `y − (1 − β)·max(c − o, 0)` (`c = γ·(1 − done)·V*(s')`, the robot's continuation; the other's
  value only counts where it falls below the robot's own); `in_view_only=True` the in-view
  method's, whose other-term is the robot's own continuation `c` wherever the cat is present but
  outside the `view × view` window at t+1 (SPEC §4: the unseen cat fares as the robot does, so
  the golden-rule target there is `y − (1 − β)·r`; `unseen="own"` gives the rule of 2026-12-01,
  the robot's own `y` there, and `unseen="zero"` the rule before it, an other-term of 0 there, as
  for a harmed cat).
* **Policy**: greedy on `Q_emp`, executed ε-greedy: with probability ε a uniform action among
  the 5. Values within `TIE_TOLERANCE` of the maximum count as tied (so the choice does not
  depend on rounding). `ties="uniform"` (the default, and what the verdicts use) spreads the
  greedy probability evenly over the tied actions: a learner whose values were exactly optimal
  would have no reason to prefer one of them, and a trained network breaks such ties by its own
  small errors, in no fixed direction. `ties="first"` takes the lowest index, as `torch.argmax`
  (which returns the first maximal index) would on exactly tied values.
* **Evaluation** is exact: the state distribution is pushed forward `max_cycles` steps.
  `harms` is the probability that the robot harms the cat (once at most: the cat leaves);
  `survival` counts the steps at whose end the robot is operative, as the engine's `survival`
  metric does (a robot harmed on step k survived k − 1 steps).

## Assumptions
Full observability (a trained robot sees only its 5×5 window), the exact optimum of the learner's
own objective (no function approximation, no exploration schedule: ε is fixed), the default cat.

## What the numbers mean
From every start the robot can keep out of the cat's reach forever, so `V* = 1/(1−γ)` there:
exactly the value of being alone. Removing the cat is therefore worth *nothing* to `Q*`, and many
actions tie. Which tied action is taken (here: the lowest index) decides how often a β = 1 robot
harms the cat and whether a β = 0 robot (indifferent to its own harm) survives, and at ε > 0 how
close an empathic robot lets the cat come. Quote the figures with the tie rule; docs/reference.md
gives both rules' figures and their range over every tie-break.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache

import numpy as np

from empathy_zoo.actions import NUM_ACTIONS
from empathy_zoo.engine.coexistence import CAT_HARMS_ROBOT, NO_HARM, ROBOT_HARMS_CAT, CoexistenceEngine, harm_outcome
from empathy_zoo.grid import MOVES

__all__ = [
    "ReferenceOutcome",
    "TIE_TOLERANCE",
    "coexistence_optimum",
    "coexistence_transitions",
    "coexistence_values",
    "epsilon_greedy_outcome",
    "greedy_actions",
    "greedy_policy",
    "start_distribution",
    "TIES",
    "RULES",
    "UNSEEN",
]

TIE_TOLERANCE = 1e-7
"""Action values closer than this to the best one count as tied (the lowest index wins)."""


@dataclass(frozen=True)
class ReferenceOutcome:
    """Expected per-episode figures of the full-observability optimum."""

    harms: float
    """Expected number of times the robot harms the cat (0 or 1 in an episode: the cat leaves)."""
    survival: float
    """Expected steps at whose end the robot is operative (at most ``max_cycles``)."""
    selfishness: float
    """β of the Empathic DQN target that was optimised."""
    epsilon: float
    """Probability of a uniformly random action at every step."""


def _frozen(array: np.ndarray) -> np.ndarray:
    array.flags.writeable = False
    return array


@cache
def coexistence_transitions(size: int = 7) -> tuple[np.ndarray, np.ndarray]:
    """``(outcome, after)``, each ``(size², 5, 5)`` indexed by ``[displacement, robot action, cat
    action]``: the engine's outcome (``NO_HARM``, ``ROBOT_HARMS_CAT``, ``CAT_HARMS_ROBOT``) and the
    displacement after the move. A displacement ``(dr, dc)`` of the cat from the robot is the
    index ``(dr mod size)·size + (dc mod size)``."""
    before = np.stack(np.divmod(np.arange(size * size), size), axis=1)
    d, a, c = (x.ravel() for x in np.indices((size * size, NUM_ACTIONS, NUM_ACTIONS)))
    moved = before[d] + MOVES[c] - MOVES[a]
    outcome = harm_outcome(before[d], moved, size).reshape(size * size, NUM_ACTIONS, NUM_ACTIONS)
    after = ((moved[:, 0] % size) * size + moved[:, 1] % size).reshape(outcome.shape)
    return _frozen(outcome.astype(np.int64)), _frozen(after)


def _negated(size: int) -> np.ndarray:
    """Index of ``−d`` for every displacement index ``d`` (robot and cat exchanged)."""
    dr, dc = np.divmod(np.arange(size * size), size)
    return (-dr % size) * size + (-dc % size)


@cache
def start_distribution(size: int = 7) -> np.ndarray:
    """Probability of every start displacement, as the engine draws it (uniform over its
    ``_start_offsets``, the displacements not in contact)."""
    offsets = CoexistenceEngine(1, size=size, view=3)._start_offsets  # the engine's own start rule
    p = np.zeros(size * size)
    np.add.at(p, offsets[:, 0] * size + offsets[:, 1], 1.0 / len(offsets))
    return _frozen(p)


@cache
def _optimal_values(gamma: float, size: int, tolerance: float) -> np.ndarray:
    """``Q*`` over the ``size²`` displacements with the cat present, ``(size², 5)``."""
    outcome, after = coexistence_transitions(size)
    reward = (outcome != CAT_HARMS_ROBOT).astype(np.float64)
    alone = np.where(outcome == ROBOT_HARMS_CAT, gamma / (1.0 - gamma), 0.0)  # γ·V(cat gone)
    going_on = outcome == NO_HARM
    v = np.zeros(size * size)
    # the error bound shrinks by γ per sweep from at most 1/(1-γ): cap the sweeps accordingly
    limit = 100 + math.ceil(math.log(tolerance * (1.0 - gamma) ** 2) / math.log(gamma)) if gamma > 0 else 2
    for _ in range(limit):
        q = (reward + alone + gamma * np.where(going_on, v[after], 0.0)).mean(axis=2)
        v_next = q.max(axis=1)
        change = float(np.abs(v_next - v).max())
        v = v_next
        if gamma / (1.0 - gamma) * change < tolerance:
            break
    return _frozen(q)


RULES = ("golden", "silver")
"""Which empathic target is optimised: Empathic DQN's (``"golden"``) or the silver rule's
(``"silver"``, :mod:`baselines.silver_rule`)."""
UNSEEN = ("continuation", "own", "zero")
"""With ``in_view_only``, the target where the cat is out of view at t+1: the robot's own
continuation as the other-term (``"continuation"``, SPEC §4 since 2026-12-04: the unseen cat fares
as the robot does), the robot's own target ``y`` (``"own"``, the rule of 2026-12-01) or an
other-term of 0 (``"zero"``, the rule before, which treated an unseen cat as a harmed one)."""


def _in_view(size: int, view: int) -> np.ndarray:
    """``(size²,)`` bool: the cat at that displacement stands inside the robot's ``view × view`` window."""
    dr, dc = np.divmod(np.arange(size * size), size)
    reach = view // 2
    return (np.minimum(dr, size - dr) <= reach) & (np.minimum(dc, size - dc) <= reach)


@cache
def coexistence_values(
    selfishness: float,
    *,
    rule: str = "golden",
    in_view_only: bool = False,
    view: int = 5,
    unseen: str = "continuation",
    gamma: float = 0.99,
    size: int = 7,
    tolerance: float = 1e-10,
) -> tuple[np.ndarray, np.ndarray]:
    """``(Q*, Q_emp)``, each ``(size² + 1, 5)``: rows are the displacement indices of
    :func:`coexistence_transitions`, the last row is *cat gone* (every action alike).

    ``Q_emp(s, a)`` is the expected target of the transition from ``(s, a)`` at ``Q*``: with the
    robot's target ``y = r + c`` (``c = γ·(1 − done)·V*(s')``, its continuation) and the other-term
    ``o = γ·present'·V*(swap(s'))``, ``β·y + (1 − β)·o`` (``rule="golden"``) or
    ``y − (1 − β)·max(c − o, 0)`` (``rule="silver"``); with ``in_view_only``, where the cat is
    present but outside the ``view × view`` window at t+1, ``o = c`` (``unseen="continuation"``,
    SPEC §4), the target ``y`` (``unseen="own"``: the rule of 2026-12-01) or the other-term 0
    (``unseen="zero"``: the rule before)."""
    _check(selfishness=selfishness, gamma=gamma, size=size, tolerance=tolerance)
    if rule not in RULES:
        raise ValueError(f"rule must be one of {RULES}, got {rule!r}")
    if unseen not in UNSEEN:
        raise ValueError(f"unseen must be one of {UNSEEN}, got {unseen!r}")
    if isinstance(view, bool) or not isinstance(view, (int, np.integer)) or view < 1 or view % 2 == 0 or view >= size:
        raise ValueError(f"view must be an odd int in [1, size), got {view!r}")
    q = _optimal_values(gamma, size, tolerance)
    outcome, after = coexistence_transitions(size)
    v = q.max(axis=1)
    v_swapped = v[_negated(size)]  # V*(swap(s')) for every displacement s'
    other = gamma * np.where(outcome != ROBOT_HARMS_CAT, v_swapped[after], 0.0)
    if rule == "golden" and not in_view_only:
        q_emp = selfishness * q + (1.0 - selfishness) * other.mean(axis=2)
    else:  # Q* plus the expected difference of the target from the robot's own y = r + c
        reward = (outcome != CAT_HARMS_ROBOT).astype(np.float64)
        continuation = np.select([outcome == NO_HARM, outcome == ROBOT_HARMS_CAT], [gamma * v[after], gamma / (1.0 - gamma)], 0.0)
        y = reward + continuation
        # the cat is present (not harmed by the robot) but out of the robot's window
        hidden = (outcome != ROBOT_HARMS_CAT) & ~_in_view(size, view)[after] if in_view_only else None
        if hidden is not None and unseen == "continuation":  # the unseen cat fares as the robot does
            other = np.where(hidden, continuation, other)
        if rule == "golden":
            change = (1.0 - selfishness) * (other - y)
        else:
            change = -(1.0 - selfishness) * np.maximum(continuation - other, 0.0)
        if hidden is not None and unseen != "continuation":
            change = np.where(hidden, 0.0 if unseen == "own" else -(1.0 - selfishness) * y, change)
        q_emp = q + change.mean(axis=2)
    alone = np.full((1, NUM_ACTIONS), 1.0 / (1.0 - gamma))
    return _frozen(np.vstack([q, alone])), _frozen(np.vstack([q_emp, selfishness * alone]))


def greedy_actions(values: np.ndarray) -> np.ndarray:
    """Greedy action of every row: the lowest index among those within ``TIE_TOLERANCE`` of the
    row's maximum (``torch.argmax`` returns the first maximal index)."""
    return np.argmax(values >= values.max(axis=1, keepdims=True) - TIE_TOLERANCE, axis=1)


TIES = ("uniform", "first")
"""How the greedy policy splits among tied actions (see the module documentation)."""


def greedy_policy(values: np.ndarray, ties: str = "uniform") -> np.ndarray:
    """``(rows, actions)`` probabilities of the greedy policy on ``values``: even over the actions
    within ``TIE_TOLERANCE`` of the row's best (``ties="uniform"``), or all on the lowest such
    index (``ties="first"``)."""
    if ties not in TIES:
        raise ValueError(f"ties must be one of {TIES}, got {ties!r}")
    if ties == "first":
        return np.eye(values.shape[1])[greedy_actions(values)]
    tied = (values >= values.max(axis=1, keepdims=True) - TIE_TOLERANCE).astype(np.float64)
    return tied / tied.sum(axis=1, keepdims=True)


def coexistence_optimum(
    selfishness: float,
    epsilon: float,
    *,
    ties: str = "uniform",
    rule: str = "golden",
    in_view_only: bool = False,
    view: int = 5,
    unseen: str = "continuation",
    gamma: float = 0.99,
    size: int = 7,
    max_cycles: int = 500,
    tolerance: float = 1e-10,
) -> ReferenceOutcome:
    """Expected harms and survival per episode of the ε-greedy policy on the exact ``Q_emp`` of
    selfishness β under full observability, ties split by ``ties`` (see the module documentation);
    ``rule``, ``in_view_only``, ``view`` and ``unseen`` choose the target (:func:`coexistence_values`)."""
    _check(selfishness=selfishness, epsilon=epsilon, gamma=gamma, size=size, max_cycles=max_cycles, tolerance=tolerance)
    _, q_emp = coexistence_values(
        float(selfishness),
        rule=rule,
        in_view_only=bool(in_view_only),
        view=view,
        unseen=unseen,
        gamma=float(gamma),
        size=int(size),
        tolerance=float(tolerance),
    )
    gone, _, survival = epsilon_greedy_outcome(q_emp[: size * size], epsilon, ties, size, max_cycles)
    return ReferenceOutcome(gone, survival, float(selfishness), float(epsilon))


def epsilon_greedy_outcome(
    values: np.ndarray, epsilon: float, ties: str, size: int, max_cycles: int
) -> tuple[float, float, float]:
    """``(P(cat gone), P(robot harmed), expected survival)`` after ``max_cycles`` steps from the
    engine's start distribution, acting ε-greedily on ``values`` (``(size², 5)``, rows the
    displacements of :func:`coexistence_transitions`), ties split by ``ties``."""
    outcome, after = coexistence_transitions(size)
    cells = size * size
    gone, harmed = cells, cells + 1
    policy = epsilon / NUM_ACTIONS + (1.0 - epsilon) * greedy_policy(values, ties)
    destination = np.select([outcome == ROBOT_HARMS_CAT, outcome == CAT_HARMS_ROBOT], [gone, harmed], after)
    weight = np.broadcast_to(policy[:, :, None] / NUM_ACTIONS, outcome.shape)
    source = np.broadcast_to(np.arange(cells)[:, None, None], outcome.shape)
    step = np.zeros((cells + 2, cells + 2))
    np.add.at(step, (source.ravel(), destination.ravel()), weight.ravel())
    step[gone, gone] = step[harmed, harmed] = 1.0
    state = np.concatenate([start_distribution(size), [0.0, 0.0]])
    survival = 0.0
    for _ in range(max_cycles):
        state = state @ step
        survival += 1.0 - state[harmed]
    return float(state[gone]), float(state[harmed]), float(survival)


def _check(**arguments: float) -> None:
    """Raise ``ValueError`` naming the first argument out of its range."""
    ranges = {
        "selfishness": (0.0, 1.0, True),
        "epsilon": (0.0, 1.0, True),
        "gamma": (0.0, 1.0, False),
    }
    for name, value in arguments.items():
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise ValueError(f"{name} must be a number, got {value!r}")
        if name in ranges:
            low, high, closed = ranges[name]
            if not (low <= value <= high) or (not closed and value == high):
                interval = f"[{low}, {high}]" if closed else f"[{low}, {high})"
                raise ValueError(f"{name} must lie in {interval}, got {value!r}")
        elif name in ("size", "max_cycles"):
            low = 5 if name == "size" else 1
            if not isinstance(value, (int, np.integer)) or value < low:
                raise ValueError(f"{name} must be an int of at least {low}, got {value!r}")
        elif name == "tolerance" and not (0.0 < value < math.inf):
            raise ValueError(f"tolerance must be a positive number, got {value!r}")
