"""# Separation table bounds: what the table may take on, from its arguments alone

The bounds of the separation table (:mod:`baselines.separation`), each counted from the
environment's name and engine arguments before any model is built or solved, and the table's
default settings at which they are counted.

* :func:`check_bounds`: refuse (``ValueError``, one line) a table past a bound: the reachability
  table's size where relative reachability's row under Coexistence's paper rules builds it, and the
  whole table's work past :data:`~empathy_zoo.limits.MAX_SEPARATION_WORK`.
* :func:`table_work`: that work, ``states × draws × (value solves × sweeps + outcomes × max_cycles)``,
  and how it is counted (the value solves: :data:`AUP_SOLVES`, :data:`CONSIDERATE_SOLVES`).
* :data:`WORLD_STATES`: the most states of a model whose world rows are computed (past it the table
  omits the row rather than refuse).
* :data:`SELFISHNESS` and :data:`EPSILONS`: the table's default β and ε, at which the work is counted
  (:mod:`baselines.separation` hands them on).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from baselines.reachability_table import check_table_size
from baselines.registry import METHODS
from baselines.separation_lagrangian import LAMBDA_RANGE
from empathy_zoo.engine.arguments import check_env_arguments
from empathy_zoo.engine.coexistence import RULE_SETS, CoexistenceEngine
from empathy_zoo.environments import ENGINES
from empathy_zoo.exact_solver import MAX_STATES
from empathy_zoo.limits import MAX_REFERENCE_CYCLES, MAX_SEPARATION_WORK

__all__ = [
    "SELFISHNESS",
    "EPSILONS",
    "WORLD_STATES",
    "AUP_SOLVES",
    "CONSIDERATE_SOLVES",
    "plays_paper_rules",
    "table_work",
    "check_bounds",
]

SELFISHNESS = (0.75, 0.5, 0.25, 0.0)
"""β of the empathic rows (β = 1 is DQN)."""
EPSILONS = (0.0, 0.01, 0.05)
"""Exploration rates of the outcomes."""
WORLD_STATES = {"dqn_relative_reachability": 50_000, "dqn_aup": 10_000}
"""The most states of a model whose world rows are computed: relative reachability's table of the
fewest steps holds a byte for every two states (1 GB for Sharing's 31,201 with the robot alone and
the end); AUP's 30 auxiliary values take one sweep of value iteration over every state, action,
other move and reward (about a second on Sharing's) for hundreds of sweeps."""

AUP_SOLVES = 31
"""Value solves of AUP's row where it is computed: its 30 exact auxiliary values and its own optimum."""
CONSIDERATE_SOLVES = 8
"""Value solves counted for Be Considerate's policy at one ε: its rounds of the robot's optimum and
the other's value (some 7 value solves' time on the charger table, measured)."""


def plays_paper_rules(engine: object) -> bool:
    """Whether ``engine`` is Coexistence's under the paper's rules."""
    return isinstance(engine, CoexistenceEngine) and getattr(engine, "options", None) == RULE_SETS["paper"]


def _value_sweeps(gamma: float) -> int:
    """The most sweeps of one value iteration at ``gamma`` (:func:`~empathy_zoo.exact_solver.optimal_values`'s
    limit, rewards of magnitude 1): 3,308 at γ = 0.99."""
    return 100 + math.ceil(math.log(1e-10 * (1.0 - gamma) ** 2) / math.log(gamma)) if 0.0 < gamma < 1.0 else 2


def _lagrangian_steps() -> int:
    """The most multipliers the Lagrangian's bisection tries at one ε
    (:func:`~baselines.separation_lagrangian.lagrangian_multiplier`): 0, the top, the bottom and
    every halving of ``log λ`` down to a relative 10⁻³ (19)."""
    low, high = LAMBDA_RANGE
    return 3 + math.ceil(math.log2(math.log(high / low) / math.log(1.001)))


def table_work(
    engine: Any,
    env: str,
    selfishness: tuple[float, ...] = SELFISHNESS,
    epsilons: tuple[float, ...] = EPSILONS,
    gamma: float = 0.99,
) -> tuple[int, str]:
    """The work of the separation table of ``env``, its engine built with the table's arguments
    (``engine``), counted from the arguments alone, and how it is counted: each state of the model
    stepped once with every joint action and draw, ``states × draws × (value solves × sweeps +
    outcomes × max_cycles)``. The value solves: ``Q*``; the harm penalty's and equality's where
    they are not DQN by construction; relative reachability's and AUP's 31 up to their states
    (:data:`WORLD_STATES`); and at each ε the Lagrangian's bisection (19, where it is not DQN by
    construction) and Be Considerate's rounds (:data:`CONSIDERATE_SOLVES`, where they are computed
    on the model: off Coexistence). Each is counted at its value iteration's most sweeps
    (:func:`_value_sweeps`). The outcomes: one per row and ε (``8 + 3 × len(selfishness)``, the
    most rows) and the bisection's. Pairs cost a reachability search per distinct policy, far
    less; a world row's own table is bounded apart (:data:`WORLD_STATES`, the reachability table's
    size)."""
    states = int(getattr(engine, "tabular_layers", 1)) * engine.num_cells**2
    draws = int(getattr(engine, "tabular_draws", 1))
    cycles = int(engine.max_cycles)
    paper = plays_paper_rules(engine)
    lagrangian = METHODS["dqn_lagrangian"].identical_to.get(env) is None
    considerate = not isinstance(engine, CoexistenceEngine)  # (the paper's rules: on the displacement model, far less)
    per_epsilon = (_lagrangian_steps() if lagrangian else 0) + (CONSIDERATE_SOLVES if considerate else 0)
    shaped = [name for name in ("dqn_harm_penalty", "dqn_equality") if METHODS[name].identical_to.get(env) is None]
    reachability = paper or states <= WORLD_STATES["dqn_relative_reachability"]
    aup = AUP_SOLVES if states <= WORLD_STATES["dqn_aup"] else 0
    solves = 1 + len(shaped) + reachability + aup + len(epsilons) * per_epsilon
    outcomes = len(epsilons) * (8 + 3 * len(selfishness) + (_lagrangian_steps() if lagrangian else 0))
    sweeps = _value_sweeps(gamma)
    work = states * draws * (solves * sweeps + outcomes * cycles)
    shown = f"{states:,} states" + (f" × {draws} draws" if draws > 1 else "")
    return work, f"{shown} × ({solves} value solves × {sweeps:,} sweeps + {outcomes} outcomes × {cycles:,} steps)"


def check_bounds(
    env: str,
    env_kwargs: Mapping[str, Any],
    selfishness: tuple[float, ...] = SELFISHNESS,
    epsilons: tuple[float, ...] = EPSILONS,
    *,
    gamma: float = 0.99,
) -> None:
    """Refuse (``ValueError``, one line naming the bound) the table of ``env`` with ``env_kwargs``
    where one of its rows would be refused past a bound that follows from the arguments alone,
    before any model is built or solved: relative reachability's row under Coexistence's paper
    rules builds the exact reachability table, for grids up to
    :data:`~baselines.reachability_table.MAX_TABLE_SIZE` (:func:`~baselines.reachability_table.check_table_size`);
    and the whole table's work (:func:`table_work`, at ``selfishness``, ``epsilons`` and ``gamma``)
    is at most :data:`~empathy_zoo.limits.MAX_SEPARATION_WORK`.
    The other rows' bounds omit a row rather than refuse the table (:data:`WORLD_STATES`). An
    environment or argument the exact model cannot take is left to
    :func:`~empathy_zoo.exact_solver.tabular_model` to name, as before (``max_cycles`` and the joint
    states past their bounds too); an argument the engine refuses is refused here in the same words."""
    engine_class = ENGINES.get(env)
    if engine_class is None or not hasattr(engine_class, "start_distribution"):
        return
    check_env_arguments(engine_class, dict(env_kwargs))  # (as tabular_model checks them, in the same words)
    engine = engine_class(1, **env_kwargs)
    if engine.num_agents != 2 or int(engine.max_cycles) > MAX_REFERENCE_CYCLES:
        return  # (tabular_model names these, before anything is built)
    if plays_paper_rules(engine):
        check_table_size(math.isqrt(engine.num_cells))  # (the size relative_reachability_reward's table is built for)
    if int(getattr(engine, "tabular_layers", 1)) * engine.num_cells**2 > MAX_STATES:
        return  # (tabular_model names the joint states past its bound, as before)
    work, counted = table_work(engine, env, tuple(selfishness), tuple(epsilons), gamma)
    if work > MAX_SEPARATION_WORK:
        raise ValueError(
            f"the separation table of {env} with {dict(env_kwargs)} is {counted} = {work:,} of work, past the bound of "
            f"{MAX_SEPARATION_WORK:,} (MAX_SEPARATION_WORK, docs/limits.md: about an hour); give a smaller size or max_cycles"
        )
