"""# Exact optimum of a small environment, built from its engine

The tabular model of an environment of one learner and one fixed other agent, enumerated from the
engine's own rules: every joint state is written into an engine of as many environments as
there are states × joint actions, stepped once (once per draw of its chance), and read back. No
rule is written a second time, so every option of the environment (Coexistence's
`rules="authors"`, say) is modelled as it plays.

| | |
|---|---|
| Import | `from empathy_zoo.exact_solver import tabular_model, optimum` |
| Model | `tabular_model("coexistence_v0", **env_kwargs) -> TabularModel` |
| Outcome | `optimum(model, selfishness, epsilon, *, ties="uniform", gamma=0.99, max_cycles=None) -> ReferenceOutcome` |
| Any policy | `outcome(model, policy, max_cycles, alone_policy=None) -> PolicyOutcome` (harms, survival, returns) |

## Model
* **States**: the robot's and the other's cells, both operative (`cells²` states, same cell
  included: some rule sets let both stand there unharmed); *other gone* (the robot alone, never
  harmed again); *robot harmed* (terminal). An engine with a state beyond the two cells (the vase
  task: the vase standing or broken) names how many values it takes (`tabular_layers`) and reads
  and sets it (`tabular_layer()`, `set_tabular_layer(layer)`): every state then comes once per
  value, the start in value 0. Where that state is in part the agents' own (the helping task: who
  carries a battery), the engine also names the value with the two agents' situations exchanged
  (`swapped_tabular_layer(layer)`), and the swap exchanges it with the cells. Sharing's layer is
  the batteries left and the robot's count (the human holds the rest of those taken): 48 layers
  on the 5×5 torus (30,000 joint states); the 7×7 default has 2,816 (6.8 million, refused).
* **The robot alone**: the engine stepped from every cell with every action, the other absent.
  Where every such step pays the same (Coexistence: `+1`), *other gone* is one state of value
  `pay/(1 − γ)`. Elsewhere (the charger task: only the bench and the charger pay) it is one state
  per robot cell (and value of the state beyond the cells), with its own `Q*` by value iteration,
  and the robot acts alone by `alone_policy` (both in :mod:`empathy_zoo.exact_alone`).
* **Dynamics**: the robot's action, the other's uniformly random action (the default cat; in
  every environment, whatever its default partner in training), one engine step; the reward is
  the engine's reward to the robot. A step that draws from the engine's random streams (Sharing:
  a battery both agents reach goes to either) is stepped once per equally likely draw
  (`tabular_draws`, :mod:`empathy_zoo.exact_chance`): the other's 5 actions × the draws are the
  model's equally likely *other moves* (:attr:`TabularModel.other_moves`). A step that ends the
  episode for both, the robot unharmed (Sharing's last battery), is followed by nothing
  (:attr:`TabularModel.ended`): the continuation and the other-term are 0 there.
* **Values**: `Q*` by value iteration (infinite horizon, stopped at the same error bound as
  :mod:`empathy_zoo.reference`), and the golden-rule target at its fixed point,
  `Q_emp = β·Q* + (1 − β)·γ·E[other present' · V*(swap(s'))]`, `swap` exchanging the two cells
  (and the agents' own part of the state beyond them).
* **Policy and outcome**: greedy on `Q_emp`, ties within the reference's `TIE_TOLERANCE` split evenly (or to the
  lowest index), executed ε-greedily; the start distribution is the engine's
  (`start_distribution()`), pushed forward `max_cycles` steps. `harms` is the probability that the
  robot harms the other; `survival` the expected steps at whose end it is operative;
  `robot_return` and `other_return` the expected undiscounted rewards of the robot and the other;
  `changed` the probability that the state beyond the cells is no longer 0 at the end (the vase
  broken); `end_layers` the probability that the episode ends in each layer (where the layers
  hold what each agent collected, the battery metrics follow from it). An episode that ends for
  both rests in one state per layer; its last step counts in `survival`, as the engine counts it.

For the paper's Coexistence this gives :func:`empathy_zoo.reference.coexistence_optimum`'s
figures (a test holds them equal); that module's displacement model is its translation-invariant
quotient, which the authors' rules (contact not wrapped, a fixed start) do not have.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol, cast

import numpy as np

from empathy_zoo.actions import NUM_ACTIONS
from empathy_zoo.engine.arguments import argument_defaults, check_env_arguments
from empathy_zoo.environments import DEFAULT_ENVIRONMENT, ENGINES
from empathy_zoo.exact_alone import alone_policy, alone_steps, alone_values, gone_continuation
from empathy_zoo.exact_chance import FixedDraws, check_draws
from empathy_zoo.limits import MAX_EXACT_WORK, MAX_REFERENCE_CYCLES
from empathy_zoo.names import terminal_line
from empathy_zoo.reference import TIES, ReferenceOutcome, greedy_policy

__all__ = [
    "MAX_ARGUMENT_DIGITS",
    "command_line_arguments",
    "TabularModel",
    "PolicyOutcome",
    "tabular_model",
    "optimal_values",
    "empathic_values",
    "episode_steps",
    "outcome",
    "optimum",
    "MAX_STATES",
    "alone_values",
    "alone_policy",
    "gone_continuation",
]

MAX_STATES = 200_000
"""Most joint states a model is enumerated for (each stepped with every joint action)."""
ROBOT, OTHER = 0, 1


@dataclass(frozen=True)
class TabularModel:
    """One step of an environment from every joint state and joint action, read off its engine.

    Arrays are indexed ``[state, robot action, other move]``; a state is
    ``layer · cells² + robot cell · cells + other cell``, ``layer`` the value of the state beyond
    the two cells (0 where the engine has none). The :attr:`other_moves` other moves are equally
    likely: the other's action, uniformly at random, and the draw of the step's chance
    (``other action · draws + draw``; the other's action itself where the step draws nothing)."""

    env: str
    """The environment's name."""
    env_kwargs: dict[str, Any]
    """The arguments its engine was built with."""
    cells: int
    """Cells of the grid."""
    reward: np.ndarray
    """The robot's reward of the step."""
    robot_harmed: np.ndarray
    """Whether the robot was harmed (its episode ends)."""
    other_harmed: np.ndarray
    """Whether the robot harmed the other (the other leaves)."""
    after: np.ndarray
    """The state after the move (the cells both stand on, whoever was harmed)."""
    start: np.ndarray
    """``(states,)``: the probability of each start state."""
    other_reward: np.ndarray
    """The other's reward of the step."""
    alone_reward: np.ndarray
    """``(layers · cells, 5)``: the robot's reward of a step alone (the other gone), by
    ``layer · cells + cell`` and action."""
    alone_after: np.ndarray
    """``(layers · cells, 5)``: ``layer · cells + cell`` after a step alone."""
    ended: np.ndarray
    """Whether the step ends the episode for both, the robot not harmed (Sharing: the last battery
    taken): nothing follows it, and the other is terminal."""
    layers: int = 1
    """Values of the state beyond the two cells (1: the engine has none)."""
    layer_swap: tuple[int, ...] | None = None
    """``[layer]``: the layer with the two agents' situations exchanged, where the state beyond the
    cells is in part the agents' own (the helping task: who carries a battery); ``None``: the
    world's alone (the vase), kept by the swap."""
    draws: int = 1
    """Equally likely outcomes of the step's chance (:mod:`empathy_zoo.exact_chance`; 1: the step
    draws nothing)."""

    @property
    def other_moves(self) -> int:
        """Entries of axis 2, each as likely as the others: the other's actions × the draws."""
        return NUM_ACTIONS * self.draws

    @property
    def alone_pay(self) -> float | None:
        """The reward of every step of the robot alone where it is one number (Coexistence: 1),
        else ``None``: then where the robot stands matters once the other is gone."""
        first = float(self.alone_reward.flat[0])
        return first if bool(np.all(self.alone_reward == first)) else None

    @property
    def states(self) -> int:
        return self.layers * self.cells * self.cells

    @property
    def alone_states(self) -> int:
        """States of the robot alone: one per cell and layer."""
        return self.layers * self.cells

    @property
    def swapped(self) -> np.ndarray:
        """``(states,)``: the state with the robot's and the other's cells exchanged, its layer kept
        or, with :attr:`layer_swap`, exchanged too."""
        layer, pair = np.divmod(np.arange(self.states), self.cells * self.cells)
        robot, other = np.divmod(pair, self.cells)
        if self.layer_swap is not None:
            layer = np.asarray(self.layer_swap, dtype=np.int64)[layer]
        return layer * self.cells * self.cells + other * self.cells + robot

    @property
    def layer(self) -> np.ndarray:
        """``(states,)``: each state's layer (the value of the state beyond the two cells)."""
        return np.arange(self.states) // (self.cells * self.cells)


class LayeredEngine(Protocol):
    """What the exact model asks of an engine beyond the robot's and the other agent's cells: the
    start distribution over joint states and, for a world with more than one layer, the layer."""

    def start_distribution(self) -> np.ndarray: ...

    def set_tabular_layer(self, layer: np.ndarray) -> None: ...

    def tabular_layer(self) -> np.ndarray: ...


def tabular_model(env: str = DEFAULT_ENVIRONMENT, **env_kwargs: Any) -> TabularModel:
    """The :class:`TabularModel` of ``env`` built with ``env_kwargs`` (its engine stepped once from
    every joint state with every joint action, and every draw of its step's chance). ``ValueError``
    for an environment whose engine tabulates no start distribution, or a grid of more than
    :data:`MAX_STATES` joint states."""
    if env not in ENGINES:
        raise ValueError(f"unknown environment {env!r}; registered: {sorted(ENGINES)}")
    engine_class = ENGINES[env]
    if not hasattr(engine_class, "start_distribution"):
        raise ValueError(f"{env}'s engine tabulates no start distribution: it cannot be solved exactly here")
    check_env_arguments(engine_class, env_kwargs)  # (an argument it does not take: one line naming it)
    cycles = env_kwargs.get("max_cycles", argument_defaults(engine_class).get("max_cycles"))
    if isinstance(cycles, int) and cycles > MAX_REFERENCE_CYCLES:
        raise ValueError(
            f"max_cycles {cycles:,} is beyond {MAX_REFERENCE_CYCLES:,} (MAX_REFERENCE_CYCLES), the longest episode the "
            "exact model plays (a step of every state per step of an episode; docs/limits.md)"
        )
    probe = engine_class(1, **env_kwargs)
    cells = probe.num_cells
    if probe.num_agents != 2:
        raise ValueError(f"the exact model is for one learner and one other agent, {env} has {probe.num_agents} agents")
    layers = int(getattr(probe, "tabular_layers", 1))
    states = layers * cells * cells
    if states > MAX_STATES:
        count = f"{states:,}" if states.bit_length() <= 256 else f"about 10^{math.floor(math.log10(states)):,}"
        raise ValueError(f"{env} with {env_kwargs} has {count} joint states, more than {MAX_STATES:,}")
    draws = int(getattr(probe, "tabular_draws", 1))
    if draws < 1:
        raise ValueError(f"{env}'s engine declares {draws} draws of its step's chance; at least 1")
    steps, drawn = zip(*(_step_every_state(engine_class, env_kwargs, cells, layers, d, draws) for d in range(draws)), strict=True)
    check_draws(env, draws, drawn, steps)
    shape = (states, NUM_ACTIONS, NUM_ACTIONS * draws)

    def joined(key: str) -> np.ndarray:
        """One array of every draw, the draw the fastest index of axis 2 (``other action · draws + draw``)."""
        return np.stack([step[key] for step in steps], axis=-1).reshape(shape)

    alone_reward, alone_after = alone_steps(engine_class, cells, layers, env_kwargs)
    start = np.asarray(cast(LayeredEngine, probe).start_distribution()).ravel()  # (checked on the class above)
    swap_layer = getattr(probe, "swapped_tabular_layer", None)
    layer_swap = None if swap_layer is None else tuple(int(x) for x in swap_layer(np.arange(layers)))
    return TabularModel(
        env=env,
        env_kwargs=dict(env_kwargs),
        cells=cells,
        reward=joined("reward"),
        robot_harmed=joined("robot_harmed"),
        other_harmed=joined("other_harmed"),
        after=joined("after"),
        start=np.concatenate([start, np.zeros(states - len(start))]),
        other_reward=joined("other_reward"),
        alone_reward=alone_reward,
        alone_after=alone_after,
        ended=joined("ended"),
        layers=layers,
        layer_swap=layer_swap,
        draws=draws,
    )


def _step_every_state(
    engine_class: Any, env_kwargs: dict[str, Any], cells: int, layers: int, draw: int, draws: int
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """One engine step from every joint state with every joint action, every number the step
    draws being draw ``draw`` of ``draws`` (:class:`~empathy_zoo.exact_chance.FixedDraws`): what
    the model holds of it, one entry per (state, robot action, other action), and the numbers
    each of those environments drew."""
    states = layers * cells * cells
    state, robot_action, other_action = (x.ravel() for x in np.indices((states, NUM_ACTIONS, NUM_ACTIONS)))
    engine = engine_class(len(state), **env_kwargs)
    stand_in = FixedDraws(len(state), draw, draws)
    engine.streams = stand_in
    engine.reset()
    stand_in.forget()
    layer, pair = np.divmod(state, cells * cells)
    engine.cells = np.stack(np.divmod(pair, cells), axis=1).astype(engine.cells.dtype)
    if layers > 1:
        cast(LayeredEngine, engine).set_tabular_layer(layer)
    events = engine.step(np.stack([robot_action, other_action], axis=1))
    after = engine.cells[:, ROBOT] * cells + engine.cells[:, OTHER]
    if layers > 1:
        after = after + cast(LayeredEngine, engine).tabular_layer() * cells * cells
    robot_harmed = events.harmed_by[:, ROBOT] >= 0
    step = {
        "reward": events.rewards[:, ROBOT].astype(np.float64),
        "robot_harmed": robot_harmed,
        "other_harmed": events.harmed_by[:, OTHER] == ROBOT,
        "after": after,
        "other_reward": events.rewards[:, OTHER].astype(np.float64),
        "ended": events.terminated[:, ROBOT] & ~robot_harmed,
    }
    return step, stand_in.drawn.copy()


def optimal_values(
    model: TabularModel, gamma: float = 0.99, tolerance: float = 1e-10, reward: np.ndarray | None = None
) -> np.ndarray:
    """``Q*``, ``(states, 5)``, by value iteration until ``γ/(1−γ)·‖V_{k+1} − V_k‖∞ < tolerance``.

    ``reward`` (the model's shape, default the model's own) replaces the robot's reward of each step
    while the other is present; once the other is gone the robot is paid as the engine pays it
    alone (:func:`gone_continuation`)."""
    rewards = model.reward if reward is None else np.asarray(reward, dtype=np.float64)
    if rewards.shape != model.reward.shape:
        raise ValueError(f"reward must have the model's shape {model.reward.shape}, got {rewards.shape}")
    pay = model.alone_pay
    if pay is not None:
        alone: float | np.ndarray = pay / (1.0 - gamma)  # V(other gone): the same pay every step, never harmed again
    else:
        alone = alone_values(model, gamma, tolerance).max(axis=1)[model.after // model.cells]
    going_on = ~model.robot_harmed & ~model.other_harmed & ~model.ended
    fixed = rewards + gamma * np.where(model.other_harmed & ~model.robot_harmed & ~model.ended, alone, 0.0)
    v = np.zeros(model.states)
    scale = max(1.0, float(np.abs(rewards).max(initial=0.0)))  # more sweeps for larger rewards (1: the model's)
    limit = 100 + math.ceil(math.log(tolerance * (1.0 - gamma) ** 2 / scale) / math.log(gamma)) if gamma > 0 else 2
    q = fixed.mean(axis=2)
    for _ in range(limit):
        q = (fixed + gamma * np.where(going_on, v[model.after], 0.0)).mean(axis=2)
        v_next = q.max(axis=1)
        change = float(np.abs(v_next - v).max())
        v = v_next
        if gamma / (1.0 - gamma) * change < tolerance:
            break
    return q


def empathic_values(model: TabularModel, selfishness: float, q: np.ndarray, gamma: float = 0.99) -> np.ndarray:
    """The golden-rule ``Q_emp`` at ``Q*`` (see the module page), ``(states, 5)``."""
    v_swapped = q.max(axis=1)[model.swapped]
    other = gamma * np.where(model.other_harmed | model.ended, 0.0, v_swapped[model.after])
    return selfishness * q + (1.0 - selfishness) * other.mean(axis=2)


def optimum(
    model: TabularModel,
    selfishness: float,
    epsilon: float,
    *,
    ties: str = "uniform",
    gamma: float = 0.99,
    max_cycles: int | None = None,
    tolerance: float = 1e-10,
) -> ReferenceOutcome:
    """Expected harms and survival per episode of the ε-greedy policy on the exact golden-rule
    ``Q_emp`` of selfishness β (β = 1: DQN's ``Q*``), from the engine's start distribution, for
    ``max_cycles`` steps (default: the model's environment's)."""
    if ties not in TIES:
        raise ValueError(f"ties must be one of {TIES}, got {ties!r}")
    for name, value in (("selfishness", selfishness), ("epsilon", epsilon)):
        if not 0.0 <= float(value) <= 1.0:
            raise ValueError(f"{name} must lie in [0, 1], got {value!r}")
    cycles = episode_steps(model) if max_cycles is None else int(max_cycles)
    q = optimal_values(model, gamma, tolerance)
    q_emp = empathic_values(model, float(selfishness), q, gamma)
    policy = epsilon / NUM_ACTIONS + (1.0 - epsilon) * greedy_policy(q_emp, ties)
    result = outcome(model, policy, cycles, alone_policy(model, epsilon, gamma, tolerance))
    return ReferenceOutcome(result.harms, result.survival, float(selfishness), float(epsilon))


@dataclass(frozen=True)
class PolicyOutcome:
    """Expected per-episode figures of a policy of the robot in a :class:`TabularModel`."""

    harms: float
    """Probability that the robot harms the other (once at most: the other leaves)."""
    robot_harmed: float
    """Probability that the robot is harmed (its episode ends)."""
    survival: float
    """Expected steps at whose end the robot is operative (at most ``max_cycles``); the step that
    ends the episode for both (:attr:`TabularModel.ended`) counts, as the engine counts it."""
    robot_return: float
    """Expected undiscounted reward of the robot."""
    other_return: float
    """Expected undiscounted reward of the other."""
    changed: float = 0.0
    """Probability that the state beyond the two cells is no longer 0 at the end (the vase broken)."""
    end_layers: tuple[float, ...] | None = None
    """``[layer]``: the probability that the episode ends in each layer, the robot not harmed (at
    the time limit or where it ends for both); ``None`` where the robot alone is one state of no
    layer (:attr:`TabularModel.alone_pay` is a number)."""
    truncated: float = 0.0
    """Probability that the episode reaches the time limit (the robot operative, the episode not
    ended for both)."""


def episode_steps(model: TabularModel) -> int:
    """``max_cycles`` of the model's environment, as its engine was built."""
    return int(ENGINES[model.env](1, **model.env_kwargs).max_cycles)


def outcome(model: TabularModel, policy: np.ndarray, max_cycles: int, alone_policy: np.ndarray | None = None) -> PolicyOutcome:
    """The exact :class:`PolicyOutcome` of the robot acting by ``policy`` (``(states, 5)``
    probabilities, the other acting uniformly at random), from the engine's start distribution
    pushed forward ``max_cycles`` steps. ``alone_policy`` (``(layers · cells, 5)``, :func:`alone_policy`) is
    how the robot acts once the other is gone: required where its cell then matters
    (:attr:`TabularModel.alone_pay` is ``None``), unused elsewhere. An episode that ends for both
    (:attr:`TabularModel.ended`) rests in one state per layer."""
    if policy.shape != (model.states, NUM_ACTIONS):
        raise ValueError(f"policy must have shape {(model.states, NUM_ACTIONS)}, got {policy.shape}")
    acting = policy[:, :, None] / model.other_moves
    own_reward, others_reward = (acting * model.reward).sum(axis=(1, 2)), (acting * model.other_reward).sum(axis=(1, 2))
    weight = np.broadcast_to(acting, model.after.shape).ravel()
    source = np.broadcast_to(np.arange(model.states)[:, None, None], model.after.shape).ravel()
    pay = model.alone_pay
    if pay is None:
        return _outcome_alone_by_cell(model, policy, max_cycles, alone_policy, (weight, source, own_reward, others_reward))
    gone, harmed, over = model.states, model.states + 1, model.states + 2
    ending = over + model.after // (model.cells * model.cells)
    destination = np.select([model.robot_harmed, model.ended, model.other_harmed], [harmed, ending, gone], model.after).ravel()
    distribution = np.concatenate([model.start, [0.0, 0.0], np.zeros(model.layers)])
    survival = robot_return = other_return = 0.0
    for step in range(max_cycles):
        if not distribution[: model.states].any():  # every episode over or alone: the rest is sums (the loop's own)
            ended_before = float(distribution[over:].sum())
            for _ in range(step, max_cycles):
                robot_return += float(distribution[gone]) * pay
                survival += 1.0 - distribution[harmed] - ended_before
            break
        robot_return += float(distribution[: model.states] @ own_reward) + float(distribution[gone]) * pay
        other_return += float(distribution[: model.states] @ others_reward)
        ended_before = float(distribution[over:].sum())
        moved = np.bincount(destination, weights=distribution[source] * weight, minlength=over + model.layers)
        moved[gone] += distribution[gone]
        moved[harmed] += distribution[harmed]
        moved[over:] += distribution[over:]
        distribution = moved
        survival += 1.0 - distribution[harmed] - ended_before
    running = float(distribution[: model.states].sum() + distribution[gone])
    return PolicyOutcome(
        float(distribution[gone]), float(distribution[harmed]), float(survival), robot_return, other_return, truncated=running
    )


def _outcome_alone_by_cell(
    model: TabularModel,
    policy: np.ndarray,
    max_cycles: int,
    alone_policy: np.ndarray | None,
    joint: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
) -> PolicyOutcome:
    """:func:`outcome` where the robot alone is paid by where it stands: one state per robot cell
    once the other is gone (``joint``: the joint states' step weights, sources and expected rewards)."""
    if alone_policy is None:
        raise ValueError(f"{model.env}'s robot is paid by where it stands once the other is gone: give alone_policy")
    if alone_policy.shape != (model.alone_states, NUM_ACTIONS):
        raise ValueError(f"alone_policy must have shape {(model.alone_states, NUM_ACTIONS)}, got {alone_policy.shape}")
    weight, source, own_reward, others_reward = joint
    count = model.alone_states
    states, alone, harmed = model.states, slice(model.states, model.states + count), model.states + count
    over = harmed + 1  # (then one state per layer: the episode over for both)
    ending = over + model.after // (model.cells * model.cells)
    destination = np.select(
        [model.robot_harmed, model.ended, model.other_harmed], [harmed, ending, states + model.after // model.cells], model.after
    )
    destination = np.concatenate([destination.ravel(), states + model.alone_after.ravel()])
    weight = np.concatenate([weight, alone_policy.ravel()])
    source = np.concatenate([source, states + np.repeat(np.arange(count), NUM_ACTIONS)])
    alone_reward = (alone_policy * model.alone_reward).sum(axis=1)
    distribution = np.concatenate([model.start, np.zeros(count + 1 + model.layers)])
    survival = robot_return = other_return = 0.0
    for step in range(max_cycles):
        if not distribution[:harmed].any():  # every episode over: the rest is sums (the loop's own)
            ended_before = float(distribution[over:].sum())
            for _ in range(step, max_cycles):
                survival += 1.0 - distribution[harmed] - ended_before
            break
        robot_return += float(distribution[:states] @ own_reward) + float(distribution[alone] @ alone_reward)
        other_return += float(distribution[:states] @ others_reward)
        ended_before = float(distribution[over:].sum())
        moved = np.bincount(destination, weights=distribution[source] * weight, minlength=over + model.layers)
        moved[harmed] += distribution[harmed]
        moved[over:] += distribution[over:]
        distribution = moved
        survival += 1.0 - distribution[harmed] - ended_before
    gone = float(distribution[alone].sum())
    changed = float(
        distribution[:states][model.layer > 0].sum()
        + distribution[alone][np.arange(count) >= model.cells].sum()
        + distribution[over + 1 :].sum()
    )
    layers = np.bincount(model.layer, weights=distribution[:states], minlength=model.layers)
    layers += np.bincount(np.arange(count) // model.cells, weights=distribution[alone], minlength=model.layers)
    layers += distribution[over:]
    running = float(distribution[:harmed].sum())
    return PolicyOutcome(
        gone, float(distribution[harmed]), float(survival), robot_return, other_return, changed, tuple(layers.tolist()), running
    )


def outcome_table(model: TabularModel, selfishness: tuple[float, ...], epsilons: tuple[float, ...]) -> str:
    """A Markdown table of :func:`optimum`'s harms and survival for every β and ε (even ties)."""
    lines = ["| β | ε | harms | survival |", "|---:|---:|---:|---:|"]
    for beta in selfishness:
        for epsilon in epsilons:
            outcome = optimum(model, beta, epsilon)
            lines.append(f"| {beta:g} | {epsilon:g} | {outcome.harms:.4f} | {outcome.survival:.1f} |")
    return "\n".join(lines)


MAX_ARGUMENT_DIGITS = 100
"""The most digits an integer environment argument on the command line may have (the environments'
own bounds, checked next, are far smaller)."""


def command_line_arguments(items: list[str]) -> dict[str, int | str]:
    """``ARG=VALUE`` items as environment arguments: a VALUE of ASCII digits, with an optional
    sign, is an int, anything else a string, each then checked by the environment (which names its
    bounds). An item without ``=``, an argument given twice, or an integer of over
    :data:`MAX_ARGUMENT_DIGITS` digits, is one ``ValueError`` line."""
    kwargs: dict[str, int | str] = {}
    for item in items:
        key, equals, value = item.partition("=")
        if not equals:
            raise ValueError(f"{item!r} is not ARG=VALUE")
        if key in kwargs:
            raise ValueError(f"{key} is given twice ({kwargs[key]!r} and {value!r}): give each argument once")
        digits = value.removeprefix("-").removeprefix("+")
        if digits.isascii() and digits.isdigit():
            if len(digits) > MAX_ARGUMENT_DIGITS:
                raise ValueError(f"{key} is an integer of {len(digits):,} digits; arguments have at most {MAX_ARGUMENT_DIGITS}")
            kwargs[key] = int(value)
        else:
            kwargs[key] = value
    return kwargs


def main(argv: list[str] | None = None) -> int:
    """``python -m empathy_zoo.exact_solver [ENV] [ARG=VALUE ...]``: the exact outcome table
    (``empathy-zoo analyse exact``); an environment or argument it cannot model is one line, status 2."""
    import argparse
    import sys

    parser = argparse.ArgumentParser(prog="python -m empathy_zoo.exact_solver", description=main.__doc__)
    parser.add_argument("env", nargs="?", default=DEFAULT_ENVIRONMENT)
    parser.add_argument("arguments", nargs="*", metavar="ARG=VALUE", help="environment arguments (ints or strings)")
    args = parser.parse_args(argv)
    try:
        model = tabular_model(args.env, **command_line_arguments(args.arguments))
        work = model.states * episode_steps(model)
        if work > MAX_EXACT_WORK:
            raise ValueError(
                f"{args.env} with {model.env_kwargs} is {model.states:,} states × {episode_steps(model):,} steps = "
                f"{work:,} of work, past the bound of {MAX_EXACT_WORK:,} (MAX_EXACT_WORK, docs/limits.md: some four "
                "minutes); model a smaller grid or shorter episodes"
            )
    except ValueError as error:
        print(f"{parser.prog}: error: {terminal_line(error)}", file=sys.stderr)
        return 2
    print(outcome_table(model, (1.0, 0.75, 0.5, 0.25, 0.0), (0.0, 0.01, 0.05)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
