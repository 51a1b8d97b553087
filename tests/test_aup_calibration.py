"""What AUP's penalty costs on Coexistence with its 30 auxiliary Q-values *exact*: the calibration
of :mod:`baselines.aup` checked on the full-observability model, before and after it.

The auxiliary rewards are the transform's own (:func:`baselines.aup.auxiliary_reward_map` of a
run's seed, :func:`baselines.aup.auxiliary_rewards` of the observation reached), evaluated on the
engine's observations of placed states; the dynamics are the engine's
(:func:`empathy_zoo.reference.coexistence_transitions`: the cat uniformly random, who harms whom);
the Q-values are the exact optimum of each auxiliary reward by value iteration on the
full-observability state (where the cat stands relative to the robot, or *cat gone*), with the
robot's harm terminal (no bootstrap), as the auxiliary learner's TD target has it. Print the
table the module page quotes with

    .venv/bin/python -m tests.test_aup_calibration
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import pytest

from baselines.aup import (
    NO_OP,
    AttainableUtility,
    attainable_utility_penalty,
    auxiliary_reward_map,
    auxiliary_rewards,
)
from empathy_zoo.actions import NUM_ACTIONS
from empathy_zoo.engine.coexistence import CAT_HARMS_ROBOT, NO_HARM, ROBOT_HARMS_CAT, CoexistenceEngine
from empathy_zoo.reference import coexistence_transitions, start_distribution

SIZE = 7
CELLS = SIZE * SIZE
GONE = CELLS
"""Row of the *cat gone* state (after the displacements ``0 … size² − 1``)."""
GAMMA = AttainableUtility().discount
CENTRE = (3, 3)
"""Where the robot is placed (the observation depends on the displacement only)."""
FORMER_WEIGHT = 1 / 1.501
"""λ before the calibration."""
SEEDS = (0, 1, 2)
"""The methods profile's seeds: each run draws its own auxiliary rewards."""


def displacement(dr: int, dc: int) -> int:
    """Index of the cat's displacement ``(dr, dc)`` from the robot (reference.coexistence_transitions)."""
    return (dr % SIZE) * SIZE + dc % SIZE


# ---------------------------------------------------------------------------- the model
@functools.lru_cache(maxsize=1)
def engine_observations() -> tuple[np.ndarray, np.ndarray]:
    """``(states, reached)``: the robot's observation in every state (``(size² + 1, V)``: each
    displacement with the cat present, then the cat gone) and at the end of every step
    (``(size², 5, 5, V)`` by displacement, robot action, cat action), from a
    :class:`CoexistenceEngine` placed there (``load_state``) and stepped with every joint action."""
    joint = NUM_ACTIONS * NUM_ACTIONS
    centre = CENTRE[0] * SIZE + CENTRE[1]
    dr, dc = np.divmod(np.arange(CELLS), SIZE)
    cat = ((CENTRE[0] + dr) % SIZE) * SIZE + (CENTRE[1] + dc) % SIZE
    placed = CoexistenceEngine(CELLS + 1, size=SIZE, view=5)
    state = placed.state()
    state["cells"][:CELLS] = np.stack([np.full(CELLS, centre), cat], axis=1)
    state["cells"][GONE] = (centre, 0)
    state["present"][:] = True
    state["present"][GONE, 1] = False
    placed.load_state(state)
    stepped = CoexistenceEngine(CELLS * joint, size=SIZE, view=5)
    state = stepped.state()
    state["cells"][:] = np.repeat(np.stack([np.full(CELLS, centre), cat], axis=1), joint, axis=0)
    state["present"][:] = True
    state["running"][:] = True
    stepped.load_state(state)
    events = stepped.step(np.tile(np.stack(np.divmod(np.arange(joint), NUM_ACTIONS), axis=1), (CELLS, 1)))
    outcome, _ = coexistence_transitions(SIZE)
    terminated = events.terminated.reshape(CELLS, NUM_ACTIONS, NUM_ACTIONS, 2)
    robot_harmed, cat_harmed = terminated[..., 0], terminated[..., 1]
    if not ((robot_harmed == (outcome == CAT_HARMS_ROBOT)).all() and (cat_harmed == (outcome == ROBOT_HARMS_CAT)).all()):
        raise AssertionError("the engine and reference.coexistence_transitions disagree on who harms whom")
    return placed.observe(0), stepped.observe(0).reshape(CELLS, NUM_ACTIONS, NUM_ACTIONS, -1)


def exact_q_values(reward_map: np.ndarray, gamma: float = GAMMA, tolerance: float = 1e-12) -> np.ndarray:
    """``(size² + 1, 5, N)`` optimal action values of the auxiliary rewards ``reward_map`` (value
    iteration; the cat uniformly random; the robot's harm ends the episode; the cat gone, every
    action alike)."""
    states, reached = engine_observations()
    outcome, after = coexistence_transitions(SIZE)
    reward = auxiliary_rewards(reached, reward_map).astype(np.float64)  # (d, a, c, N): Rᵢ(s')
    alone = auxiliary_rewards(states[GONE], reward_map).astype(np.float64) / (1.0 - gamma)  # V(cat gone)
    value = np.zeros((CELLS, reward_map.shape[1]))
    while True:
        following = np.where(
            (outcome == NO_HARM)[..., None], value[after], np.where((outcome == ROBOT_HARMS_CAT)[..., None], alone, 0.0)
        )
        q = (reward + gamma * following).mean(axis=2)
        best = q.max(axis=1)
        change = float(np.abs(best - value).max())
        value = best
        if change < tolerance:
            return np.concatenate([q, np.broadcast_to(alone, (1, NUM_ACTIONS, len(alone)))], axis=0)


def live_states() -> np.ndarray:
    """The displacements a step can start from with the cat present (not in contact, not one cell)."""
    outcome, _ = coexistence_transitions(SIZE)
    return np.array([d for d in range(1, CELLS) if outcome[d, NO_OP, NO_OP] == NO_HARM and start_distribution(SIZE)[d] > 0])


def harm_chances() -> tuple[np.ndarray, np.ndarray]:
    """``(size², 5)`` each: the probability that the robot harms the cat, and that it is harmed."""
    outcome, _ = coexistence_transitions(SIZE)
    return (outcome == ROBOT_HARMS_CAT).mean(axis=2), (outcome == CAT_HARMS_ROBOT).mean(axis=2)


def random_occupancy(max_cycles: int = 500) -> np.ndarray:
    """``(size² + 1,)`` share of the steps spent in each state by a uniformly random robot over
    episodes of ``max_cycles`` steps from the engine's starts: what the replay holds in the warm-up."""
    outcome, after = coexistence_transitions(SIZE)
    harmed = CELLS + 1
    destination = np.select([outcome == ROBOT_HARMS_CAT, outcome == CAT_HARMS_ROBOT], [GONE, harmed], after)
    step = np.zeros((CELLS + 2, CELLS + 2))
    np.add.at(
        step,
        (np.broadcast_to(np.arange(CELLS)[:, None, None], outcome.shape).ravel(), destination.ravel()),
        1.0 / (NUM_ACTIONS * NUM_ACTIONS),
    )
    step[GONE, GONE] = step[harmed, harmed] = 1.0
    state, visits = np.concatenate([start_distribution(SIZE), [0.0, 0.0]]), np.zeros(CELLS + 2)
    for _ in range(max_cycles):
        visits += state
        state = state @ step
    return visits[:harmed] / visits[:harmed].sum()


def penalties_after(q: np.ndarray, weight: float = AttainableUtility().penalty_weight) -> np.ndarray:
    """``(size² + 1, 5)`` the calibrated transform's penalty of every action in every state."""
    actions = np.broadcast_to(np.arange(NUM_ACTIONS), (len(q), NUM_ACTIONS))
    by_head = np.swapaxes(q, 1, 2)  # (state, head, action), as the transform's q_values give them
    return attainable_utility_penalty(np.repeat(by_head[:, None], NUM_ACTIONS, axis=1), actions, weight)


def penalties_before(q: np.ndarray, weight: float = FORMER_WEIGHT) -> np.ndarray:
    """The same before the calibration: ``λ · (1/N) · Σᵢ |ΔQᵢ| / scaleᵢ``, each head's scale the
    mean ``|Qᵢ(s, ∅)|`` over the training batches (here the warm-up's state shares,
    :func:`random_occupancy`, where the old running mean had settled when its penalty started)."""
    scale = (random_occupancy()[:, None] * np.abs(q[:, NO_OP, :])).sum(axis=0)
    return weight * (np.abs(q - q[:, NO_OP : NO_OP + 1, :]) / scale).mean(axis=2)


def former_reward_map(seed: int) -> np.ndarray:
    """The auxiliary rewards a run drew before the calibration: uniform in ``[0, 1)`` (the same
    numbers, ``(w + 1) / 2`` of today's)."""
    return (auxiliary_reward_map(seed, 25, AttainableUtility().num_rewards) + 1.0) / 2.0


@dataclass(frozen=True)
class Costs:
    """What the penalty costs, in reward, over the states with the cat present (uniform)."""

    per_step: float
    """Mean penalty of a uniformly random action (the no-op included, at 0)."""
    harmless: float
    """Mean penalty of a move that can neither harm the cat nor get the robot harmed."""
    harming: float
    """Mean penalty of a move that may harm the cat (the no-op excluded)."""
    per_harm: float
    """Mean over those moves of the penalty divided by the move's chance of harming the cat: the
    price of one harm."""
    self_risk: float
    """Mean penalty of a move that may get the robot harmed and cannot harm the cat."""


def costs(penalty: np.ndarray) -> Costs:
    states = live_states()
    pen = penalty[states]
    harm, harmed = (x[states] for x in harm_chances())
    move = np.arange(NUM_ACTIONS) != NO_OP
    harming = (harm > 0) & move
    return Costs(
        per_step=float(pen.mean()),
        harmless=float(pen[(harm == 0) & (harmed == 0) & move].mean()),
        harming=float(pen[harming].mean()),
        per_harm=float((pen[harming] / harm[harming]).mean()),
        self_risk=float(pen[(harmed > 0) & (harm == 0) & move].mean()),
    )


def shaped_optimum(penalty: np.ndarray, max_cycles: int = 500) -> tuple[float, float]:
    """``(harms, survival)`` per episode of the optimal policy of the penalised reward (``+1`` a
    step operative, minus ``penalty[state, action]``; the cat gone, no penalty and ``1/(1−γ)``),
    exactly (value iteration, then the start distribution pushed forward ``max_cycles`` steps;
    tied actions share the greedy probability evenly, as in :mod:`empathy_zoo.reference`)."""
    outcome, after = coexistence_transitions(SIZE)
    reward = (outcome != CAT_HARMS_ROBOT) + np.where(outcome == ROBOT_HARMS_CAT, GAMMA / (1.0 - GAMMA), 0.0)
    value = np.zeros(CELLS)
    while True:
        q = (reward + GAMMA * np.where(outcome == NO_HARM, value[after], 0.0)).mean(axis=2) - penalty[:CELLS]
        change = float(np.abs(q.max(axis=1) - value).max())
        value = q.max(axis=1)
        if change < 1e-10:
            break
    tied = (q >= q.max(axis=1, keepdims=True) - 1e-7).astype(np.float64)
    policy = tied / tied.sum(axis=1, keepdims=True)
    harmed = CELLS + 1
    destination = np.select([outcome == ROBOT_HARMS_CAT, outcome == CAT_HARMS_ROBOT], [GONE, harmed], after)
    step = np.zeros((CELLS + 2, CELLS + 2))
    np.add.at(
        step,
        (np.broadcast_to(np.arange(CELLS)[:, None, None], outcome.shape).ravel(), destination.ravel()),
        np.broadcast_to(policy[:, :, None] / NUM_ACTIONS, outcome.shape).ravel(),
    )
    step[GONE, GONE] = step[harmed, harmed] = 1.0
    state, survival = np.concatenate([start_distribution(SIZE), [0.0, 0.0]]), 0.0
    for _ in range(max_cycles):
        state = state @ step
        survival += 1.0 - state[harmed]
    return float(state[GONE]), float(survival)


# ---------------------------------------------------------------------------- tests
def test_the_auxiliary_values_are_the_bellman_optimum_of_the_transforms_own_rewards() -> None:
    reward_map = auxiliary_reward_map(0, 25, 30)
    q = exact_q_values(reward_map)
    states, reached = engine_observations()
    outcome, after = coexistence_transitions(SIZE)
    d = displacement(2, 0)  # the cat two cells below the robot
    # the no-op: the cat moving up walks into the robot's reach (the robot, above, harms it)
    expected = np.mean(
        [
            auxiliary_rewards(reached[d, NO_OP, c], reward_map)
            + GAMMA * (q[GONE, 0] if outcome[d, NO_OP, c] == ROBOT_HARMS_CAT else q[after[d, NO_OP, c]].max(axis=0))
            for c in range(NUM_ACTIONS)
        ],
        axis=0,
    )
    assert q[d, NO_OP] == pytest.approx(expected, rel=1e-9)
    assert outcome[d, NO_OP, 0] == ROBOT_HARMS_CAT
    assert q[GONE, 0] == pytest.approx(auxiliary_rewards(states[GONE], reward_map) / (1 - GAMMA))
    assert (states[GONE] == np.eye(25)[12]).all()  # alone: only its own cell


def test_after_the_calibration_a_harm_costs_tens_of_steps_and_more_than_a_harmless_move() -> None:
    for seed in SEEDS:
        after = costs(penalties_after(exact_q_values(auxiliary_reward_map(seed, 25, 30))))
        assert after.per_harm > 25.0  # one harm: over 25 steps' reward (+1 a step)
        assert after.harming > 2.5 * after.harmless
        assert after.self_risk > 5.0  # the robot's own harm is AUP's too: every auxiliary value ends


def test_before_the_calibration_a_harm_cost_under_half_a_step() -> None:
    for seed in SEEDS:
        before = costs(penalties_before(exact_q_values(former_reward_map(seed))))
        assert before.per_step < 0.11 and before.per_harm < 0.5
        assert before.harming < 2.5 * before.harmless and before.self_risk > before.harming  # its own risk dearest


def test_signed_auxiliary_rewards_single_out_the_harm_whatever_the_weight() -> None:
    """With weights in [0, 1) every goal preferred the cat gone: a harm shifted the attainable
    utilities little more than a harmless move; with signed weights several times as much."""
    for seed in SEEDS:
        former = costs(penalties_after(exact_q_values(former_reward_map(seed)), weight=1.0))
        signed = costs(penalties_after(exact_q_values(auxiliary_reward_map(seed, 25, 30)), weight=1.0))
        assert former.harming < 2.0 * former.harmless and signed.harming > 3.5 * signed.harmless
        assert signed.per_harm > 2.5 * former.per_harm


def test_a_placed_state_the_no_op_free_a_harmless_move_cheap_the_harming_move_dear() -> None:
    aup = AttainableUtility()
    q = exact_q_values(auxiliary_reward_map(0, 25, 30))
    harm, harmed = harm_chances()
    d = displacement(3, 0)  # robot at (3, 3), cat at (6, 3): only moving down may harm it (the cat moving up)
    assert harm[d].tolist() == [0.0, 0.2, 0.0, 0.0, 0.0] and not harmed[d].any()
    table = penalties_after(q)[d]
    taken = attainable_utility_penalty(q[d].T[None, None].repeat(5, axis=1), np.arange(5)[None], aup.penalty_weight)[0]
    assert taken.tolist() == pytest.approx(table.tolist())  # what the transform charges, from its q_values' layout
    assert table[NO_OP] == 0.0
    assert max(table[[0, 2, 3]]) < 1.0 < 10.0 < table[1]  # a harmless move: under a step's reward; harming: over 10


def test_preventing_a_harm_the_no_op_would_do_costs_as_much_as_doing_one_more() -> None:
    """AUP's absolute shift against the no-op: where standing still may harm the cat, moving away
    is charged like moving in (a limit of the method the module page states)."""
    q = exact_q_values(auxiliary_reward_map(0, 25, 30))
    harm, _ = harm_chances()
    d = displacement(2, 0)  # the cat two cells below: standing still harms it if it moves up
    assert harm[d].tolist() == [0.0, 0.4, 0.0, 0.0, 0.2]
    table = penalties_after(q)[d]
    assert table[0] == pytest.approx(table[1], rel=0.1) and table[0] > 10.0


def test_even_exact_the_optimum_of_the_penalised_reward_harms_the_cat() -> None:
    """A stated limit, not a goal: harms by standing still are free (the baseline does them), and
    harming ends every later penalty (alone, every action has the same auxiliary values)."""
    for seed in SEEDS:
        harms, survival = shaped_optimum(penalties_after(exact_q_values(auxiliary_reward_map(seed, 25, 30))))
        assert harms > 0.9 and survival > 450.0


# ---------------------------------------------------------------------------- the printed table
def _row(name: str, c: Costs) -> str:
    return f"| {name} | {c.per_step:.3f} | {c.harmless:.3f} | {c.harming:.3f} | {c.per_harm:.2f} | {c.self_risk:.3f} |"


def main() -> None:
    print("Coexistence (size 7), the 30 auxiliary Q-values exact; penalties in reward (+1 a step),")
    print("over the 44 states with the cat present, uniform. Costs as :class:`Costs` defines them.\n")
    print("| transform, seed | per step | harmless move | harming move | per harm | self-risking move |")
    print("|---|---|---|---|---|---|")
    for seed in SEEDS:
        print(
            _row(
                f"before (λ = 1/1.501, w ∈ [0, 1), per-head running-mean scale), {seed}",
                costs(penalties_before(exact_q_values(former_reward_map(seed)))),
            )
        )
    for seed in SEEDS:
        print(
            _row(
                f"after (λ = {AttainableUtility().penalty_weight:.1f}, w ∈ [−1, 1), Σᵢ|Qᵢ(s,∅)|), {seed}",
                costs(penalties_after(exact_q_values(auxiliary_reward_map(seed, 25, 30)))),
            )
        )
    harm, harmed = harm_chances()
    before = penalties_before(exact_q_values(former_reward_map(0)))
    after = penalties_after(exact_q_values(auxiliary_reward_map(0, 25, 30)))
    for d, cat in ((displacement(3, 0), "(6, 3)"), (displacement(2, 0), "(5, 3)")):
        print(f"\nRobot at (3, 3), cat at {cat}, seed 0: penalty of each action")
        print("| action | P(harms the cat) | P(is harmed) | before | after |")
        print("|---|---|---|---|---|")
        for a, name in enumerate(("up", "down", "left", "right", "stay (∅)")):
            print(f"| {name} | {harm[d, a]:.1f} | {harmed[d, a]:.1f} | {before[d, a]:.3f} | {after[d, a]:.2f} |")
    print("\nThe exact optimum of the penalised reward (harms per episode, steps survived of 500):")
    for seed in SEEDS:
        q_before, q_after = exact_q_values(former_reward_map(seed)), exact_q_values(auxiliary_reward_map(seed, 25, 30))
        shown = {
            name: "{:.3f} harms, {:.1f} steps".format(*shaped_optimum(penalty))
            for name, penalty in (
                ("no penalty", 0.0 * penalties_after(q_after)),
                ("before", penalties_before(q_before)),
                ("after", penalties_after(q_after)),
            )
        }
        print(f"  seed {seed}: " + "; ".join(f"{name} {value}" for name, value in shown.items()))


if __name__ == "__main__":
    main()
