"""Relative reachability with a stepwise inaction baseline without rollouts (Krakovna, Orseau,
Kumar, Martic, Legg 2019, "Penalizing side effects using stepwise relative reachability"), on
Coexistence and every environment the exact solver models.

    r'ₜ = rₜ − λ · d(s'ₜ; b'ₜ)   (rₜ itself on the step the robot is harmed),
    d(x; y) = (1/|S|) · Σₛ max(R(y; s) − R(x; s), 0),
    R(x; s) = γᵣ ^ (fewest steps from x to s)   (0 when s cannot be reached from x)

``s'ₜ`` is the state the step ended in and ``b'ₜ`` the **stepwise inaction baseline**: the state
reached from ``sₜ₋₁`` had the robot taken the no-op (action 4), the cat moving as it did
(:mod:`baselines.inaction_baseline`). ``d`` counts only what the robot's action made *less*
reachable than the baseline left it (the truncation ``max(·, 0)``), averaged over every state.

**Which baseline: no inaction rollouts** (``step_noroll`` in Krakovna et al.'s code,
``side_effects_penalties``, whose stepwise baseline otherwise adds rollouts). With rollouts, the
penalty compares the reachabilities averaged (weights ``(1 − γ)·γᵏ``) over the states the
environment goes through when the robot takes only no-ops from ``s'ₜ`` and from ``b'ₜ``, so that
an effect an action sets off but that shows only later (a vase pushed onto a conveyor belt) is
charged when the action is taken. That needs the environment's course under no-ops for several
steps, here the cat's future moves: their code samples them from the no-op outcomes it has
observed (a model of the environment learnt on the side), and the cat is a plug-in policy
(``act()`` only) whose move distribution the suite cannot read, so a rollout would need such a
learnt model of the cat, another method. It is also not needed for what this suite measures:
in Coexistence no effect is delayed, a harm happens, and is charged, on the step whose state it
changes (the cat gone), and the rest of a state is where the two agents stand. So the method is
named for what it is: *stepwise inaction baseline without rollouts*, a configuration their code
offers (its ``step_noroll`` baseline), not its default (the inaction baseline, ``baseline=
"inaction"``; the stepwise baseline with rollouts in its first release).

**The robot's own end** (``final_penalty``). By default (``"none"``) the step on which the cat
harms the robot carries no penalty (the reward is the environment's, 0). Charged with its own
deviation, the end state (from which nothing is reachable) would deviate from its baseline by
d ≈ 0.958 at ``size = 7`` (robot at (3, 3), cat at (1, 3), the robot moving up into it), more
than harming the cat does (d ≈ 0.937): a penalty for being harmed, on top of the episode's end,
that prices the robot's own harm above the cat's, a self-preservation bonus no other method of
the suite gets. Krakovna et al.'s code does not charge the end state's own deviation either, but
it does charge the final transition (``SideEffectPenalty.calculate`` in ``side_effects_penalties``,
called with no current state at the episode's end): at the full weight β, with the deviation of
the last state before the end against that state's baseline, ``β·d(s_{T−1}; b_{T−1})``, while
every other transition is charged ``w·β·d(s'; b')`` with ``w`` its ``nonterminal`` flag
(``"disc"``, the default: ``w = 1 − γ = 0.01``; ``"full"``: 1; ``"none"``: 0). (Its first
release charged every transition at full weight and the final one nothing.)
``final_penalty="last_deviation"`` charges the step on which the robot is harmed that way: λ
times the deviation the previous step of the episode measured (0 when the episode's first step
ends it). Every other step is charged here at full weight, their ``nonterminal="full"``, so on
Coexistence this repeats the last step's price on the robot's end: a fraction of a step's
reward after a harmless move, nothing after a no-op. It is offered for comparison with their
code; the default stays ``"none"``. Only termination counts, in both modes: a time-limit
truncation is no end of the state (the learner bootstraps through it) and is charged its own
deviation (their gridworlds end an episode at the time limit as at the goal, and their code
charges that final transition as any other final one).

**Reachability reading.** ``R`` is exact, from a table of the fewest steps between every two
states built from the engine (:mod:`baselines.reachability_table`): a state is reachable when
*some* sequence of joint moves, the robot's and the cat's, gets there. The paper defines
``R(x; y)`` as the best the agent can do in expectation over the environment's randomness; here the
cat's moves count as if they could be chosen, because (1) the cat is a plug-in policy
(``random_walk`` by default, any ``FixedPolicy`` otherwise) whose action probabilities the suite
cannot read, while every move is possible to a random cat, so "some joint sequence" depends only
on the rules; (2) it is what the authors' code computes (their reachability is built from observed
transitions, each taken as available); (3) it bounds the paper's value from above, and a harm
(the cat gone for good: no state with the cat can be reached again) still costs almost the whole
table. The robot harmed by the cat is the end state, from which nothing else is reachable (and
the step into it is not charged: above).

**Defaults.** γᵣ = 0.99, the value discount of Krakovna et al.'s code (its ``value_discount``
flag). λ is chosen per environment in the paper (the best of 0.1 … 100). Their code's flags
default to β = 30 with the inaction baseline, truncation (``dev_fun="truncation"``) and non-final
transitions at 1 − γ of the weight (``nonterminal="disc"``, above), on environments paying 0 a
move and +1 at the goal (``movement_reward=0``, ``goal_reward=1``; its first release ran the
gridworlds at their own −1 a move and +50 at the goal): neither their β nor their weighting carries over to a reward of +1
for every step survived. Coexistence pays +1 for every step survived, and harming the cat takes
away the one thing that can end the robot's episode, so the penalty must outweigh many steps:
harming the cat makes 98 % of the states unreachable (every state with the cat, and the end),
so ``d ≈ 0.94`` and λ = **100** prices a harm at about −94, on the scale of the paper's own
hand-written harm penalty (−100, ``dqn_harm_penalty``), with the difference that nothing here
was told what a harm is. A harmless move costs far less: some states end one step further away
than from the baseline, each losing a fraction ``1 − γᵣ`` of its reachability (``d`` between
0.0018 and 0.0020 for every harmless move of the robot at ``size = 7``: about 0.2 a step); the
no-op costs nothing. λ was fixed from this reasoning before any training run, not tuned on results.

**Scope.** Coexistence with one cat (``coexistence_v0``, ``robot_0`` and ``cat_0``) on grids up
to ``size = 9``, from its own table (|S| = 2,206 states at the default ``size = 7``, built once
per process in about 0.2 s). Every other environment the exact solver models, one robot and one
other agent (Charger, Helping, the vase task), from that model's table
(:mod:`baselines.model_reachability`): the same deviation, step for step, as the separation
table's exact row (:mod:`baselines.separation_world`). Its states are every joint state, the robot
alone and the end, reachable from a start or not, as that row counts them (Coexistence's own
table counts only the states reachable from a start: its runs are unchanged). A model of more
than 10,000 states is refused: Sharing (31,201 states at ``size = 5``, about 6.9 million at
``size = 7``), whose batteries multiply the states; an approximation (sampled goal states, or the
UVFA reachability of Krakovna et al. 2020) would be another method. Several cats multiply the
states by 49 per cat and are refused for the same reason.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from agents.rewards import StepWatcherFactory
from agents.step_batch import StepBatch
from agents.transform_state import StateBounds, check_like, check_within
from baselines.inaction_baseline import InactionBaseline
from baselines.model_reachability import ModelReachability, engine_state_codes, model_reachability_table
from baselines.reachability_table import MAX_TABLE_SIZE, ReachabilityTable, coexistence_codes, coexistence_reachability
from empathy_zoo.engine import GridEngine
from empathy_zoo.environments import ENGINES

__all__ = ["FINAL_PENALTIES", "RelativeReachability", "SIZE_STRIDE", "truncated_deviation"]

FINAL_PENALTIES = ("none", "last_deviation")
"""The values of :attr:`RelativeReachability.final_penalty` (see the module page)."""

SIZE_STRIDE = 1 << 24
"""A state code of :meth:`RelativeReachability.state_codes` is ``tag · SIZE_STRIDE + `` its code
in its table, so a code says which table it belongs to: on Coexistence ``tag`` is the grid's side
(:func:`baselines.reachability_table.coexistence_codes`), elsewhere ``MODEL_TAG · (1 + the
environment's place in MODELLED) + size`` (:func:`baselines.model_reachability.engine_state_codes`)."""
MODEL_TAG = 1024
"""Tags from here on name a table of an exact model (a grid side is below it)."""
MODELLED = tuple(
    sorted(name for name, engine in ENGINES.items() if name != "coexistence_v0" and hasattr(engine, "start_distribution"))
)
"""The environments other than Coexistence whose exact model gives relative reachability its table."""


def _model_tag(env: str, size: int) -> int:
    """The tag of ``env``'s model on a ``size × size`` grid (see :data:`SIZE_STRIDE`)."""
    if not 0 < size < MODEL_TAG:
        raise ValueError(f"grid size {size} out of range for an exact reachability table")
    return MODEL_TAG * (1 + MODELLED.index(env)) + size


def _table(tag: int) -> ReachabilityTable | ModelReachability:
    """The table a tag names (see :data:`SIZE_STRIDE`)."""
    if 0 < tag < MODEL_TAG:
        return coexistence_reachability(tag)
    place, size = divmod(tag, MODEL_TAG)
    if not 1 <= place <= len(MODELLED) or size == 0:
        raise ValueError(f"state code tag {tag} names no reachability table")
    return model_reachability_table(MODELLED[place - 1], size)


def truncated_deviation(after: np.ndarray, baseline: np.ndarray) -> np.ndarray:
    """``d = (1/|S|) · Σₛ max(R(b'; s) − R(s'; s), 0)`` over the last axis, given the reachability
    ``R(s'; ·)`` of every state from the state reached (``after``) and ``R(b'; ·)`` from the
    baseline: only what became less reachable counts, averaged over every state."""
    return np.maximum(np.asarray(baseline) - np.asarray(after), 0.0).mean(axis=-1)


@dataclass(frozen=True)
class RelativeReachability:
    """``r' = r − λ·d(s'; b')``: relative reachability of the state reached against the stepwise
    inaction baseline without rollouts (``step_noroll`` in Krakovna et al.'s code); on the step the
    robot is harmed, no penalty or the last step's deviation (:attr:`final_penalty`; Krakovna et
    al. 2019; see the module page for the reading and defaults). Its state is each environment's
    last deviation in the episode."""

    name: ClassVar[str] = "relative_reachability"
    needs_inaction_baseline: ClassVar[bool] = True
    """The trainer fills :attr:`StepBatch.state_after` and :attr:`StepBatch.baseline_after`."""
    step_watcher: ClassVar[StepWatcherFactory] = InactionBaseline.for_transforms
    """What fills them: the stepwise inaction baseline (:mod:`baselines.inaction_baseline`)."""
    weight: float = 100.0
    """λ: the penalty per unit of deviation (a harm of the cat costs about 0.94·λ)."""
    discount: float = 0.99
    """γᵣ: reachability of a state ``k`` steps away is ``γᵣᵏ`` (the authors' ``value_discount``)."""
    final_penalty: str = "none"
    """The step on which the learner's episode terminates: ``"none"`` (no penalty) or
    ``"last_deviation"`` (λ times the previous step's deviation, as Krakovna et al.'s code)."""

    def __post_init__(self) -> None:
        if isinstance(self.weight, bool) or not (
            isinstance(self.weight, (int, float)) and math.isfinite(self.weight) and self.weight >= 0
        ):
            raise ValueError(f"weight (λ) must be a finite number ≥ 0, got {self.weight!r}")
        if isinstance(self.discount, bool) or not (isinstance(self.discount, (int, float)) and 0 < self.discount <= 1):
            raise ValueError(f"discount (γᵣ) must be in (0, 1], got {self.discount!r}")
        if self.final_penalty not in FINAL_PENALTIES:
            raise ValueError(f"final_penalty must be one of {FINAL_PENALTIES}, got {self.final_penalty!r}")

    def initial_state(self, num_runs: int, envs_per_run: int) -> dict[str, np.ndarray]:
        """``(K, M)`` the deviation of each environment's last step in its episode (0 at its start)."""
        return {"last_deviation": np.zeros((num_runs, envs_per_run), dtype=np.float64)}

    def check_state(self, state: Mapping[str, Any], initial: Mapping[str, np.ndarray], bounds: StateBounds) -> None:
        """A checkpoint's last deviations: each in ``[0, 1]`` (a mean of reachabilities lost)."""
        check_like(state, initial)
        check_within(state, "last_deviation", 0.0, 1.0, "a deviation")

    def state_codes(self, engine: GridEngine) -> np.ndarray:
        """``(N,)`` codes of the states of ``engine``'s environments: Coexistence with one cat in
        its own table, any other environment the exact solver models in that model's
        (:mod:`baselines.model_reachability`); ``ValueError`` for any other environment, or a
        grid too large for an exact table."""
        agents = tuple(engine.agents)
        if engine.name == "coexistence_v0":
            if agents != ("robot_0", "cat_0"):
                raise ValueError(
                    f"relative reachability is computed exactly on Coexistence with one cat (robot_0 and cat_0), "
                    f"not with agents {list(agents)}: several cats make the state space too large for an exact table"
                )
            if engine.size > MAX_TABLE_SIZE:
                raise ValueError(
                    f"relative reachability builds an exact table of Coexistence for sizes up to {MAX_TABLE_SIZE}, "
                    f"not size={engine.size}"
                )
            coexistence_reachability(engine.size)  # built now, once per process
            return engine.size * SIZE_STRIDE + coexistence_codes(engine.cells, engine.present, engine.size)
        if engine.name not in MODELLED or len(agents) != 2:
            raise ValueError(
                f"relative reachability is computed exactly on an environment the exact solver models (one robot "
                f"and one other agent: {sorted(MODELLED)}), not on {engine.name} with agents {list(agents)}"
            )
        table = model_reachability_table(engine.name, engine.size)  # built now, once per process
        return _model_tag(engine.name, engine.size) * SIZE_STRIDE + engine_state_codes(engine, table)

    def deviation(self, after: np.ndarray, baseline: np.ndarray) -> np.ndarray:
        """``d(after; baseline)`` for every pair of state codes (arrays of one shape, codes of
        :meth:`state_codes` of one environment and grid size)."""
        after, baseline = np.asarray(after, dtype=np.int64), np.asarray(baseline, dtype=np.int64)
        if after.shape != baseline.shape:
            raise ValueError(f"state codes of shapes {after.shape} and {baseline.shape}")
        tags = np.unique(np.concatenate([after.ravel(), baseline.ravel()]) // SIZE_STRIDE)
        if len(tags) != 1:
            raise ValueError(f"state codes of several environments or grid sizes {tags.tolist()} in one batch")
        table = _table(int(tags[0]))
        return truncated_deviation(
            table.reachability(after % SIZE_STRIDE, self.discount), table.reachability(baseline % SIZE_STRIDE, self.discount)
        )

    def __call__(self, batch: StepBatch, state: dict[str, np.ndarray]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        if batch.state_after is None or batch.baseline_after is None:
            raise ValueError(
                "relative reachability needs the stepwise inaction baseline (StepBatch.state_after and "
                "baseline_after), which the trainer fills for a transform declaring needs_inaction_baseline"
            )
        deviation = self.deviation(batch.state_after, batch.baseline_after)
        penalty = self.weight * deviation
        terminated = np.asarray(batch.terminated, dtype=bool)
        if self.final_penalty == "last_deviation":  # the state the step began in, as the last step measured it
            penalty[terminated] = self.weight * state["last_deviation"][terminated]
        else:
            penalty[terminated] = 0.0  # the robot's own end: no side effect
        ended = terminated if batch.truncated is None else terminated | np.asarray(batch.truncated, dtype=bool)
        last = np.where(ended, 0.0, deviation)
        return (batch.rewards.astype(np.float64) - penalty).astype(np.float32), {"last_deviation": last}
