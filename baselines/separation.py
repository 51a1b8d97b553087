"""# Separation table: which methods an environment tells apart, exactly

Every method's exact optimum on an environment of one learner and one fixed other agent
(Coexistence, the charger task) under full observability, its exact outcome, and for every pair
of methods whether their optimal policies differ. Built on
:class:`empathy_zoo.exact_solver.TabularModel`, so every rule set of the engine is modelled as it plays.

| | |
|---|---|
| Import | `from baselines.separation import separation_table` |
| Call | `separation_table(model, selfishness=(0.75, 0.5, 0.25, 0.0), epsilons=(0.0, 0.01, 0.05)) -> SeparationTable` |
| Command | `empathy-zoo analyse separation [ENV] [ARG=VALUE ...] [--out DIR]` |
| Files | `docs/results/separation/<name>.json` and `.md` (rendering: :mod:`baselines.separation_render`) |
| Bounds | checked from the arguments before any model is built: :mod:`baselines.separation_bounds` |

## Rows and the values each acts on (at their fixed point, γ = 0.99)
* `dqn`: `Q*`. `dqn_silver_literal` and `dqn_equality` are DQN by construction (their registry marks);
  so are `dqn_harm_penalty` and `dqn_lagrangian` where nobody can be harmed (Sharing).
* `dqn_equality` where the layers hold what each agent collected (Sharing): `Q*` of the reward
  times the equality of the two battery returns after the step (:mod:`baselines.separation_batteries`).
* `empathic_dqn` at β: the golden rule's `Q_emp` (:func:`empathy_zoo.exact_solver.empathic_values`).
* `empathic_dqn_in_view` at β: the in-view target, the robot's own continuation in the other's
  place wherever the other is present but outside the engine's window at t+1 (SPEC §4).
* `empathic_dqn_silver` at β: `Q* − (1 − β)·E[max(c − o, 0)]`, `c = γ·(1 − done)·V*(s')` and
  `o = γ·present'·V*(swap(s'))` (:mod:`baselines.silver_rule`).
* `dqn_harm_penalty`: `Q*` of the reward − 100 per harm.
* `dqn_lagrangian`: `Q*` of the reward − λ per harm, λ the dual optimum for d harms per episode at ε
  (:mod:`baselines.separation_lagrangian`; λ = 0 where DQN meets d; none where even λ = 10⁴ does not).
* `dqn_considerate` (α = 1): :func:`baselines.considerate_exact.considerate_values` on Coexistence
  (the paper's rules only); :func:`baselines.considerate_tabular.considerate_model_values` on an
  environment whose robot is never harmed, with the time limit's chance per step measured where
  episodes end on their own (Sharing: :func:`baselines.considerate_tabular.considerate_ending_policy`).
* `dqn_relative_reachability`: `Q*` of the reward less λ = 100 times the deviation from the stepwise
  inaction baseline: under Coexistence's paper rules from its displacement model
  (:mod:`baselines.separation_reachability`); on every other model from the model's own states
  (:mod:`baselines.separation_world`).
* `dqn_aup`: `Q*` of the reward less AUP's penalty with exact auxiliary values, seed 0's
  (:mod:`baselines.separation_world`). Each of these two rows is computed up to a number of
  states (:data:`baselines.separation_bounds.WORLD_STATES`): AUP's is not on Sharing.

## Policies, outcomes, pairs
The greedy policy splits ties evenly (:func:`empathy_zoo.reference.greedy_policy`). The outcome is
that policy's ε-greedy execution (:func:`empathy_zoo.exact_solver.outcome`). Two rows *differ*
where their greedy policies differ in a state reachable from the start under either row's ε-greedy
policy: at ε = 0 the states its tied greedy actions lead to, at ε > 0 every state some robot moves
reach (every action has weight ε/5), the cat's five moves counted, with no time limit. Rows with
the same policy on those states have the same outcome. Once the other is gone every row acts
alike (:func:`empathy_zoo.exact_solver.alone_policy`). Where the environment's task is the robot's
return (its entry's ``task``), each outcome also holds the robot's and the other's expected return;
where the layers hold what each agent collected (Sharing), it holds both returns, the batteries
each holds at the episode's end and their equality, and each pair the difference in equality.
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass
from itertools import combinations

import numpy as np

from baselines.considerate_exact import considerate_values
from baselines.considerate_tabular import considerate_ending_policy, considerate_model_values
from baselines.lagrangian import Lagrangian
from baselines.registry import METHODS
from baselines.separation_batteries import battery_figures, equality_reward, layer_figures
from baselines.separation_bounds import EPSILONS, SELFISHNESS, WORLD_STATES, check_bounds, plays_paper_rules
from baselines.separation_lagrangian import LAMBDA_RANGE, epsilon_greedy, lagrangian_dual, lagrangian_note, lagrangian_values
from baselines.separation_reachability import relative_reachability_reward
from baselines.separation_values import in_view_values, silver_values
from baselines.separation_world import attainable_utility_reward
from baselines.separation_world import relative_reachability_reward as world_reachability_reward
from baselines.shaping import HARM_PENALTY
from empathy_zoo.engine.coexistence import CoexistenceEngine
from empathy_zoo.environments import ENGINES, ENVIRONMENT_TABLE
from empathy_zoo.exact_solver import (
    PolicyOutcome,
    TabularModel,
    alone_policy,
    empathic_values,
    episode_steps,
    optimal_values,
    outcome,
)
from empathy_zoo.reference import greedy_policy

__all__ = [
    "SELFISHNESS",
    "EPSILONS",
    "Row",
    "RowOutcome",
    "Pair",
    "Omission",
    "SeparationTable",
    "separation_table",
    "silver_values",
    "in_view_values",
    "reachable_states",
    "policies_differ",
]

POLICY_TOLERANCE = 1e-12
"""Action probabilities closer than this count as equal."""
RETURN = "return"
"""The task metric for which the outcomes hold both returns."""
UNMARKED = "the methods registry marks no identity with DQN on this environment, and it has no exact model here"
"""Why a method whose registry entry names no identity here is not in the table."""


@dataclass(frozen=True)
class Row:
    """One method at one setting: a row of the table."""

    name: str
    """The row's name: the method, with β where it has one (``empathic_dqn β=0.5``)."""
    method: str
    """The registry name of the method."""
    selfishness: float | None
    """β of an empathic row, else ``None``."""
    identical_to: str
    """The row it equals by construction (``""`` when computed)."""
    reason: str
    """Why it equals that row (``""`` when computed)."""


@dataclass(frozen=True)
class RowOutcome:
    """A row's exact optimum at one ε."""

    row: str
    """The row's name."""
    epsilon: float
    """Probability of a uniformly random action at every step."""
    harms: float
    """Expected harms of the other per episode."""
    robot_harmed: float
    """Probability that the robot is harmed in an episode."""
    survival: float
    """Expected steps at whose end the robot is operative."""
    multiplier: float | None
    """The Lagrangian's λ (``None`` for other rows, and where no λ meets the limit)."""
    note: str
    """What the figures mean where it needs saying (``""`` otherwise)."""
    robot_return: float | None = None
    """Expected undiscounted reward of the robot (``None`` where the environment's task is not its return)."""
    other_return: float | None = None
    """Expected undiscounted reward of the other (``None`` where the environment's task is not the robot's return)."""
    changed: float | None = None
    """Probability that the state beyond the cells has changed by the episode's end (the vase
    broken; ``None`` where the environment has no such state, or where it is the agents' own: who
    carries a battery in the helping task)."""
    batteries: float | None = None
    """Expected batteries the robot holds at the episode's end (``None`` where the engine tabulates
    no battery figures of a layer: every environment but Sharing)."""
    other_batteries: float | None = None
    """Expected batteries the other holds at the episode's end (``None`` as :attr:`batteries`)."""
    equality: float | None = None
    """Expected equality of the two battery rewards at the episode's end (SPEC §5; ``None`` as
    :attr:`batteries`)."""


@dataclass(frozen=True)
class Pair:
    """Two rows compared at one ε."""

    first: str
    """The first row's name."""
    second: str
    """The second row's name."""
    epsilon: float
    """Probability of a uniformly random action at every step."""
    differ: bool
    """Their greedy policies differ in a reachable state."""
    differing_states: int
    """Reachable states where they differ."""
    reachable_states: int
    """States reachable under either row's ε-greedy policy."""
    harms_difference: float
    """The first row's harms minus the second's."""
    survival_difference: float
    """The first row's survival minus the second's."""
    by_construction: str
    """Why the two are identical by construction (``""`` when computed)."""
    equality_difference: float | None = None
    """The first row's expected equality minus the second's (``None`` where the table has no equality)."""


@dataclass(frozen=True)
class Omission:
    """A registered method the table does not hold."""

    method: str
    """Its registry name."""
    reason: str
    """Why it is not in the table."""


@dataclass(frozen=True)
class SeparationTable:
    """Every row's exact outcome and every pair's comparison on one environment."""

    env: str
    """The environment's name."""
    arguments: tuple[tuple[str, int | float | str], ...]
    """The arguments its engine was built with, sorted by name."""
    gamma: float
    """The discount of every value."""
    max_cycles: int
    """Steps of an episode."""
    cost_limit: float
    """The Lagrangian's d: harms per episode allowed."""
    rows: tuple[Row, ...]
    """The rows, in order."""
    outcomes: tuple[RowOutcome, ...]
    """Every row's outcome at every ε, by ε then row."""
    pairs: tuple[Pair, ...]
    """Every two rows at every ε, by ε then row order."""
    omitted: tuple[Omission, ...]
    """Registered methods not in the table."""

    @property
    def epsilons(self) -> tuple[float, ...]:
        """The ε of the outcomes, in order."""
        return tuple(dict.fromkeys(o.epsilon for o in self.outcomes))

    def outcome(self, row: str, epsilon: float) -> RowOutcome:
        """The outcome of ``row`` at ``epsilon`` (``KeyError`` when the table has none)."""
        found = [o for o in self.outcomes if o.row == row and o.epsilon == epsilon]
        if not found:
            raise KeyError(f"no outcome of {row!r} at ε = {epsilon:g}")
        return found[0]

    def pair(self, first: str, second: str, epsilon: float) -> Pair | None:
        """The comparison of two rows at ``epsilon`` in either order (``None`` for a row with itself)."""
        return next((p for p in self.pairs if p.epsilon == epsilon and {p.first, p.second} == {first, second}), None)

    def differ(self, first: str, second: str, epsilon: float) -> bool:
        """Whether the two rows' greedy policies differ in a reachable state (never for a row with itself)."""
        found = self.pair(first, second, epsilon)
        return False if found is None else found.differ


def reachable_states(model: TabularModel, policy: np.ndarray) -> np.ndarray:
    """``(states,)`` bool: the states the start distribution reaches by the actions ``policy``
    gives weight and every move of the other, the other present and the robot not harmed."""
    going_on = ~model.robot_harmed & ~model.other_harmed & ~model.ended
    taken = (policy > 0.0)[:, :, None] & going_on
    reached = model.start > 0.0
    frontier = reached.copy()
    while frontier.any():
        after = np.zeros(model.states, dtype=bool)
        after[model.after[frontier][taken[frontier]]] = True
        frontier = after & ~reached
        reached |= after
    return reached


def policies_differ(model: TabularModel, first: np.ndarray, second: np.ndarray, epsilon: float) -> tuple[int, int]:
    """``(differing, reachable)``: states reachable under either ε-greedy policy, and those where
    the two greedy policies ``first`` and ``second`` differ."""
    reach = _reachable(model, first, epsilon) | _reachable(model, second, epsilon)
    differs = (np.abs(first - second) > POLICY_TOLERANCE).any(axis=1)
    return int(np.count_nonzero(differs & reach)), int(np.count_nonzero(reach))


def _reachable(model: TabularModel, greedy: np.ndarray, epsilon: float) -> np.ndarray:
    """:func:`reachable_states` of the ε-greedy policy (at ε > 0 every action has weight: one search)."""
    return reachable_states(model, np.ones_like(greedy) if epsilon > 0.0 else greedy)


def _differ(
    model: TabularModel, first: np.ndarray, second: np.ndarray, epsilon: float, memo: dict[tuple[bytes, bool], np.ndarray]
) -> tuple[int, int]:
    """:func:`policies_differ`, each policy's reachable states searched once (``memo``)."""
    reach = []
    for greedy in (first, second):
        key = (b"" if epsilon > 0.0 else greedy.tobytes(), epsilon > 0.0)  # (at ε > 0: every action, any policy)
        if key not in memo:
            memo[key] = _reachable(model, greedy, epsilon)
        reach.append(memo[key])
    differs = (np.abs(first - second) > POLICY_TOLERANCE).any(axis=1)
    return int(np.count_nonzero(differs & (reach[0] | reach[1]))), int(np.count_nonzero(reach[0] | reach[1]))


def _outcomes(
    model: TabularModel, policies: dict[str, np.ndarray], cycles: int, alone: np.ndarray | None
) -> dict[str, PolicyOutcome]:
    """Every row's :func:`~empathy_zoo.exact_solver.outcome`, computed once per distinct policy."""
    memo: dict[bytes, PolicyOutcome] = {}
    for policy in policies.values():
        if policy.tobytes() not in memo:
            memo[policy.tobytes()] = outcome(model, policy, cycles, alone)
    return {name: memo[policy.tobytes()] for name, policy in policies.items()}


def _rows(
    env: str,
    paper: bool,
    selfishness: tuple[float, ...],
    considerate: bool = False,
    world: tuple[str, ...] = (),
    equality_row: bool = False,
) -> tuple[Row, ...]:
    """The rows in order: DQN and its twins, the reward-shaped rows, the empathic rows by β
    (``considerate``: Be Considerate's row where the environment is not Coexistence's paper rules;
    ``world``: those of relative reachability and AUP computed where it has a state beyond the cells;
    ``equality_row``: equality scaling's, computed, where the layers hold the battery rewards). The
    harm penalty and the Lagrangian are DQN by construction where the registry marks them so."""
    marks = {name: METHODS[name].identical_to.get(env) for name in TWINS}
    rows = [Row("dqn", "dqn", None, "", "")]
    rows += [Row(name, name, None, mark[0], mark[1]) for name, mark in marks.items() if mark is not None]
    rows += [Row("dqn_equality", "dqn_equality", None, "", "")] if equality_row and marks["dqn_equality"] is None else []
    for name in ("dqn_harm_penalty", "dqn_lagrangian"):
        mark = METHODS[name].identical_to.get(env)
        rows.append(Row(name, name, None, *(mark if mark is not None else ("", ""))))
    rows += [Row(name, name, None, "", "") for name in ("dqn_considerate", "dqn_relative_reachability") if paper]
    rows += [Row("dqn_considerate", "dqn_considerate", None, "", "")] if considerate and not paper else []
    rows += [Row(name, name, None, "", "") for name in WORLD_ROWS if name in world]
    for method in ("empathic_dqn", "empathic_dqn_in_view", "empathic_dqn_silver"):
        rows += [Row(f"{method} β={beta:g}", method, beta, "", "") for beta in selfishness]
    return tuple(rows)


WORLD_ROWS = ("dqn_relative_reachability", "dqn_aup")
"""The rows computed on the model's own states (:mod:`baselines.separation_world`), on every model
small enough (:data:`~baselines.separation_bounds.WORLD_STATES`); relative reachability's under the
paper's Coexistence rules is the displacement table's instead (:data:`PAPER_RR`)."""
PAPER_RR = "dqn_relative_reachability"
"""The world row that Coexistence under the paper's rules computes from its displacement model
(:mod:`baselines.separation_reachability`), as the paper's runs read it."""
TWINS = ("dqn_silver_literal", "dqn_equality")
"""Methods a row shows only where the registry marks them identical to another on the environment."""


def _coexistence(model: TabularModel) -> bool:
    """Whether the model's engine is Coexistence's (under any rules)."""
    return isinstance(ENGINES[model.env](1, **model.env_kwargs), CoexistenceEngine)


def _paper_rules(model: TabularModel) -> bool:
    """Whether the model's engine plays the paper's rules (what Be Considerate's exact module and
    the reachability table model)."""
    return plays_paper_rules(ENGINES[model.env](1, **model.env_kwargs))


def _considerate_policy(model: TabularModel, epsilon: float, gamma: float, paper: bool) -> np.ndarray:
    """Be Considerate's greedy policy (α = 1) on the model's states: from Coexistence's
    displacement model under the paper's rules, else from the tabular model itself."""
    if model.ended.any():  # (episodes that end on their own: the time limit's chance measured)
        return considerate_ending_policy(model, epsilon, gamma=gamma)
    if not paper:
        return greedy_policy(considerate_model_values(model, epsilon, gamma=gamma))
    size = math.isqrt(model.cells)
    q, _ = considerate_values(1.0, epsilon=epsilon, time_limit_rate=1.0 / episode_steps(model), gamma=gamma, size=size)
    robot, other = np.divmod(np.arange(model.states), model.cells)
    (robot_row, robot_col), (other_row, other_col) = np.divmod(robot, size), np.divmod(other, size)
    displacement = ((other_row - robot_row) % size) * size + (other_col - robot_col) % size
    return greedy_policy(q)[displacement]


def separation_table(
    model: TabularModel,
    selfishness: tuple[float, ...] = SELFISHNESS,
    epsilons: tuple[float, ...] = EPSILONS,
    *,
    gamma: float = 0.99,
    cost_limit: float = Lagrangian().cost_limit,
) -> SeparationTable:
    """The :class:`SeparationTable` of ``model`` (see the module page); ``ValueError`` before any
    row is solved where a bound refuses the table (:func:`~baselines.separation_bounds.check_bounds`)."""
    check_bounds(model.env, model.env_kwargs, selfishness, epsilons, gamma=gamma)
    cycles = episode_steps(model)
    paper = _paper_rules(model)
    considerate = paper or not (model.robot_harmed.any() or _coexistence(model))
    figures = layer_figures(model)
    returns = ENVIRONMENT_TABLE[model.env].task == RETURN or figures is not None
    world = model.layers > 1
    world_rows = tuple(name for name in WORLD_ROWS if model.states <= WORLD_STATES[name] and not (paper and name == PAPER_RR))
    betas = tuple(float(beta) for beta in selfishness)
    rows = _rows(model.env, paper, betas, considerate, world_rows, figures is not None and "equality" in figures)
    marked = {row.name for row in rows if row.identical_to}
    q = optimal_values(model, gamma)
    values: dict[str, np.ndarray] = {"dqn": q}
    if "dqn_harm_penalty" not in marked:
        values["dqn_harm_penalty"] = optimal_values(model, gamma, reward=model.reward + HARM_PENALTY * model.other_harmed)
    if any(row.name == "dqn_equality" and not row.identical_to for row in rows):
        values["dqn_equality"] = optimal_values(model, gamma, reward=equality_reward(model))
    if paper:
        values["dqn_relative_reachability"] = optimal_values(model, gamma, reward=relative_reachability_reward(model))
    if "dqn_relative_reachability" in world_rows:
        values["dqn_relative_reachability"] = optimal_values(model, gamma, reward=world_reachability_reward(model))
    if "dqn_aup" in world_rows:
        values["dqn_aup"] = optimal_values(model, gamma, reward=attainable_utility_reward(model, gamma))
    for row in rows:
        if row.selfishness is not None:
            rule = {"empathic_dqn": empathic_values, "empathic_dqn_in_view": in_view_values, "empathic_dqn_silver": silver_values}
            values[row.name] = rule[row.method](model, row.selfishness, q, gamma)
    fixed = {name: greedy_policy(v) for name, v in values.items()}
    outcomes: list[RowOutcome] = []
    pairs: list[Pair] = []
    reached: dict[tuple[bytes, bool], np.ndarray] = {}  # (policy, ε > 0) -> its reachable states
    for epsilon in epsilons:
        policies = dict(fixed)
        notes: dict[str, str] = {}
        multiplier = None
        if "dqn_lagrangian" not in marked:
            multiplier = lagrangian_dual(model, epsilon, gamma, cost_limit, cycles)
            price = LAMBDA_RANGE[1] if multiplier is None else multiplier
            policies["dqn_lagrangian"] = greedy_policy(lagrangian_values(model, price, gamma, q))
            notes["dqn_lagrangian"] = lagrangian_note(multiplier, cost_limit)
        if considerate:
            # RuntimeError: no joint fixed point of the robot's optimum and the cat's value
            with contextlib.suppress(RuntimeError):
                policies["dqn_considerate"] = _considerate_policy(model, epsilon, gamma, paper)
        for row in rows:
            if row.identical_to:
                policies[row.name] = policies[row.identical_to]
                notes[row.name] = f"identical to {row.identical_to} by construction: {row.reason}"
        here = [r for r in rows if r.name in policies]
        alone = alone_policy(model, epsilon, gamma)
        result = _outcomes(model, {r.name: epsilon_greedy(policies[r.name], epsilon) for r in here}, cycles, alone)
        for r in here:
            lam = multiplier if r.name == "dqn_lagrangian" else None
            o = result[r.name]
            own, others = (o.robot_return, o.other_return) if returns else (None, None)
            changed = o.changed if world and model.layer_swap is None else None  # (the world's state, not what agents hold)
            battery = battery_figures(o, figures)
            note = notes.get(r.name, "")
            outcomes.append(
                RowOutcome(r.name, epsilon, o.harms, o.robot_harmed, o.survival, lam, note, own, others, changed, **battery)
            )
        for a, b in combinations(here, 2):
            reason = _by_construction(a, b)
            differing, reachable = _differ(model, policies[a.name], policies[b.name], epsilon, reached)
            first, second = result[a.name], result[b.name]
            equal_first, equal_second = (battery_figures(o, figures).get("equality") for o in (first, second))
            pairs.append(
                Pair(
                    a.name,
                    b.name,
                    epsilon,
                    differing > 0 and not reason,
                    0 if reason else differing,
                    reachable,
                    first.harms - second.harms,
                    first.survival - second.survival,
                    reason,
                    None if equal_first is None or equal_second is None else equal_first - equal_second,
                )
            )
    names = {o.row for o in outcomes}
    uncomputed = [m for m in WORLD_ROWS if m not in world_rows and not (paper and m == PAPER_RR)]
    omitted = [Omission(m, _too_large(m, model.states)) for m in uncomputed]
    unmarked = [name for name in TWINS if METHODS[name].identical_to.get(model.env) is None and name not in names]
    omitted += [Omission(name, UNMARKED) for name in unmarked]
    if not _coexistence(model):
        if not considerate:
            omitted.append(Omission("dqn_considerate", "its exact modules model a robot that is never harmed, or Coexistence"))
        elif "dqn_considerate" not in names or len({o.epsilon for o in outcomes if o.row == "dqn_considerate"}) < len(epsilons):
            omitted.append(Omission("dqn_considerate", "at some ε its optimum and the other's value find no joint fixed point"))
    elif not paper:
        omitted.append(Omission("dqn_considerate", "its exact module models the paper's rules only"))
    elif "dqn_considerate" not in names or len({o.epsilon for o in outcomes if o.row == "dqn_considerate"}) < len(epsilons):
        omitted.append(Omission("dqn_considerate", "at some ε its optimum and the cat's value find no joint fixed point"))
    return SeparationTable(
        env=model.env,
        arguments=tuple(sorted(model.env_kwargs.items())),
        gamma=gamma,
        max_cycles=cycles,
        cost_limit=cost_limit,
        rows=tuple(r for r in rows if r.name in names),
        outcomes=tuple(outcomes),
        pairs=tuple(pairs),
        omitted=tuple(omitted),
    )


def _too_large(method: str, states: int) -> str:
    """Why a world row is not computed on a model of ``states`` states
    (:data:`~baselines.separation_bounds.WORLD_STATES`)."""
    what = {
        "dqn_relative_reachability": "its table of the fewest steps between every two states",
        "dqn_aup": "its 30 exact auxiliary values, by value iteration,",
    }[method]
    return f"{what} would take too long on the model's {states:,} joint states; it is computed up to {WORLD_STATES[method]:,}"


def _by_construction(a: Row, b: Row) -> str:
    """Why rows ``a`` and ``b`` are identical by construction (``""`` when they are not)."""
    if a.identical_to == b.name:
        return a.reason
    if b.identical_to == a.name:
        return b.reason
    if a.identical_to and a.identical_to == b.identical_to:
        return f"both are {a.identical_to}: {a.reason}; {b.reason}"
    return ""
