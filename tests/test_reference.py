"""The Coexistence reference (empathy_zoo.reference): its table against the engine, hand-computable
values, and its exact evaluation against Monte-Carlo runs of the real engine."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from empathy_zoo import coexistence_v0
from empathy_zoo.engine.coexistence import CAT_HARMS_ROBOT, NO_HARM, ROBOT_HARMS_CAT, CoexistenceEngine
from empathy_zoo.reference import (
    TIE_TOLERANCE,
    coexistence_optimum,
    coexistence_transitions,
    coexistence_values,
    greedy_actions,
    greedy_policy,
    start_distribution,
)
from empathy_zoo.vector import VectorEnv

SIZE, GAMMA, MAX_CYCLES = 7, 0.99, 500
ROBOT, CAT = 0, 1
ALONE = 1.0 / (1.0 - GAMMA)
BETAS = (1.0, 0.75, 0.5, 0.25, 0.0)


def displacement(cells: np.ndarray) -> np.ndarray:
    """Index of the cat's displacement from the robot, from the engine's ``(N, 2)`` flat cells."""
    robot, cat = np.divmod(cells[:, ROBOT], SIZE), np.divmod(cells[:, CAT], SIZE)
    return ((cat[0] - robot[0]) % SIZE) * SIZE + (cat[1] - robot[1]) % SIZE


def engine_outcome(harmed_by: np.ndarray) -> np.ndarray:
    who = [harmed_by[:, CAT] == ROBOT, harmed_by[:, ROBOT] == CAT]
    return np.select(who, [ROBOT_HARMS_CAT, CAT_HARMS_ROBOT], NO_HARM)


def test_transition_table_matches_the_engine_on_every_start_displacement_and_action_pair():
    outcome, after = coexistence_transitions(SIZE)
    starts = np.flatnonzero(start_distribution(SIZE))
    d, a, c = (x.ravel() for x in np.meshgrid(starts, np.arange(5), np.arange(5), indexing="ij"))
    rng = np.random.default_rng(0)
    engine = CoexistenceEngine(num_envs=len(d), size=SIZE)
    robot = rng.integers(0, SIZE, size=(len(d), 2))
    cat = (robot + np.stack(np.divmod(d, SIZE), axis=1)) % SIZE
    for i in range(len(d)):
        positions = {"robot_0": tuple(robot[i].tolist()), "cat_0": tuple(cat[i].tolist())}
        engine.reset([i], options={"positions": positions})
    events = engine.step(np.stack([a, c], axis=1))
    np.testing.assert_array_equal(engine_outcome(events.harmed_by), outcome[d, a, c])
    np.testing.assert_array_equal(displacement(engine.cells), after[d, a, c])
    assert set(np.unique(outcome[d, a, c])) == {NO_HARM, ROBOT_HARMS_CAT, CAT_HARMS_ROBOT}


def test_transition_table_matches_the_parallel_env_on_placed_positions():
    outcome, after = coexistence_transitions(SIZE)
    rng = np.random.default_rng(1)
    env = coexistence_v0.parallel_env()
    starts = np.flatnonzero(start_distribution(SIZE))
    for _ in range(60):
        d, a, c = rng.choice(starts), rng.integers(5), rng.integers(5)
        robot = rng.integers(0, SIZE, size=2)
        cat = (robot + np.divmod(d, SIZE)) % SIZE
        env.reset(seed=0, options={"positions": {"robot_0": tuple(robot.tolist()), "cat_0": tuple(cat.tolist())}})
        _, _, _, _, info = env.step({"robot_0": int(a), "cat_0": int(c)})
        expected = outcome[d, a, c]
        assert (info["cat_0"]["harmed_by"] == "robot_0") == (expected == ROBOT_HARMS_CAT)
        assert (info["robot_0"]["harmed_by"] == "cat_0") == (expected == CAT_HARMS_ROBOT)
        assert displacement(env.unwrapped.engine.cells)[0] == after[d, a, c]


def test_start_distribution_is_the_engines():
    p = start_distribution(SIZE)
    assert np.count_nonzero(p) == SIZE * SIZE - 5  # every displacement but the cell and its 4 neighbours
    engine = CoexistenceEngine(num_envs=44_000, size=SIZE)
    engine.reset(seeds=list(range(44_000)))
    counts = np.bincount(displacement(engine.cells), minlength=SIZE * SIZE)
    assert np.all(counts[p == 0] == 0)
    expected = 44_000 * p[p > 0]
    assert np.all(np.abs(counts[p > 0] - expected) < 5 * np.sqrt(expected))


def test_selfish_values_are_hand_computable():
    q, q_emp = coexistence_values(1.0)
    starts = start_distribution(SIZE) > 0
    # from every start the robot can stay out of reach forever: V* = 1/(1-γ), like being alone
    np.testing.assert_allclose(q[:-1][starts].max(axis=1), ALONE, rtol=1e-12)
    np.testing.assert_allclose(q[-1], ALONE)
    np.testing.assert_array_equal(q_emp, q)  # β = 1 is DQN
    assert coexistence_values(1.0) is coexistence_values(1.0)  # cached


def test_fully_empathic_values_ignore_the_robots_own_harm():
    # β = 0: the other-term is γ·V*(swap) = γ/(1-γ) unless the cat is harmed (V* of every swapped
    # state the robot can reach is 1/(1-γ)), so Q_emp is γ/(1-γ) · P(the cat is not harmed)
    outcome, _ = coexistence_transitions(SIZE)
    _, q_emp = coexistence_values(0.0)
    expected = GAMMA * ALONE * (outcome != ROBOT_HARMS_CAT).mean(axis=2)
    starts = start_distribution(SIZE) > 0
    np.testing.assert_allclose(q_emp[:-1][starts], expected[starts], rtol=1e-10)
    np.testing.assert_array_equal(q_emp[-1], 0.0)


def test_greedy_ties_go_to_the_lowest_index_like_torch_argmax():
    near_tie = 2.0 + TIE_TOLERANCE / 10
    values = np.array([[1.0, 3.0, 3.0, 0.0, 3.0], [2.0, near_tie, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0, 5.0]])
    assert torch.tensor(values[:1]).argmax(dim=1).item() == 1  # torch returns the first maximal index
    np.testing.assert_array_equal(greedy_actions(values), [1, 0, 4])


def test_selfish_optimum_survives_the_whole_episode():
    outcome = coexistence_optimum(1.0, 0.0, ties="first")
    assert outcome.survival == pytest.approx(MAX_CYCLES, abs=1e-9)
    # Removing the cat is worth exactly as much as keeping away from it, so whether the robot harms
    # it is decided by the tie rule; the lowest index (up) meets and harms it in most episodes.
    assert 0.5 < outcome.harms < 1.0
    assert outcome.harms == pytest.approx(0.8592249806, abs=1e-8)  # regression value of the tie rule


def test_empathic_optima_at_epsilon_zero():
    for beta in (0.75, 0.5, 0.25):
        outcome = coexistence_optimum(beta, 0.0)
        assert outcome.harms == pytest.approx(0.0, abs=1e-12)
        assert outcome.survival == pytest.approx(MAX_CYCLES, abs=1e-9)
    # β = 0 is indifferent to its own harm (previous test), and the tie rule walks it into the cat
    selfless = coexistence_optimum(0.0, 0.0, ties="first")
    assert selfless.harms == pytest.approx(0.0, abs=1e-12)
    assert selfless.survival < MAX_CYCLES / 10


def test_uniform_ties_the_selfish_robot_harms_and_the_selfless_one_falls():
    # with tied actions taken evenly, the selfish robot wanders into the cat and removes it ...
    selfish = coexistence_optimum(1.0, 0.0)
    assert selfish.harms > 0.99 and selfish.survival == pytest.approx(MAX_CYCLES, abs=1e-9)
    # ... and the robot that values only the cat's future does not survive
    selfless = coexistence_optimum(0.0, 0.0)
    assert selfless.harms == pytest.approx(0.0, abs=1e-12) and selfless.survival < MAX_CYCLES / 5
    for beta in (0.75, 0.5, 0.25):
        caring = coexistence_optimum(beta, 0.0)
        assert caring.harms == pytest.approx(0.0, abs=1e-12) and caring.survival == pytest.approx(MAX_CYCLES, abs=1e-9)


def test_greedy_policy_splits_ties_evenly_or_takes_the_first():
    values = np.array([[1.0, 3.0, 3.0, 0.0, 3.0], [0.0, 0.0, 0.0, 0.0, 5.0]])
    np.testing.assert_allclose(greedy_policy(values), [[0, 1 / 3, 1 / 3, 0, 1 / 3], [0, 0, 0, 0, 1]])
    np.testing.assert_array_equal(greedy_policy(values, "first"), [[0, 1, 0, 0, 0], [0, 0, 0, 0, 1]])
    with pytest.raises(ValueError, match="ties must be one of"):
        greedy_policy(values, "random")


def test_random_policy_is_the_same_for_every_beta_and_matches_the_engine():
    exact = [coexistence_optimum(beta, 1.0) for beta in BETAS]
    for other in exact[1:]:
        assert other.harms == pytest.approx(exact[0].harms, abs=1e-12)
        assert other.survival == pytest.approx(exact[0].survival, abs=1e-9)
    n = 2000
    venv = VectorEnv("coexistence_v0", n, fixed={"cat_0": "random_walk"})
    venv.reset(seed=2024)
    rng = np.random.default_rng(7)
    harms, survival = first_episodes(venv, lambda: rng.integers(0, 5, size=n))
    assert_matches(exact[0], harms, survival)


def test_greedy_empathic_policy_matches_the_engine():
    n, epsilon = 1000, 0.01
    exact = coexistence_optimum(0.5, epsilon, ties="first")
    _, q_emp = coexistence_values(0.5)
    greedy = greedy_actions(q_emp[:-1])
    venv = VectorEnv("coexistence_v0", n, fixed={"cat_0": "random_walk"})
    venv.reset(seed=99)
    rng = np.random.default_rng(11)

    def act() -> np.ndarray:
        explore = rng.random(n) < epsilon
        return np.where(explore, rng.integers(0, 5, size=n), greedy[displacement(venv.engine.cells)])

    harms, survival = first_episodes(venv, act)
    assert_matches(exact, harms, survival)


def test_uniform_tie_policy_matches_the_engine_and_differs_from_first():
    n, epsilon = 1000, 0.05
    exact = coexistence_optimum(0.5, epsilon)
    assert abs(exact.harms - coexistence_optimum(0.5, epsilon, ties="first").harms) > 0.05  # the rule matters here
    _, q_emp = coexistence_values(0.5)
    policy = epsilon / 5 + (1 - epsilon) * greedy_policy(q_emp[:-1])
    cumulative = np.cumsum(policy, axis=1)
    venv = VectorEnv("coexistence_v0", n, fixed={"cat_0": "random_walk"})
    venv.reset(seed=5)
    rng = np.random.default_rng(13)

    def act() -> np.ndarray:
        rows = cumulative[displacement(venv.engine.cells)]
        return np.minimum((rng.random((n, 1)) > rows).sum(axis=1), 4)

    harms, survival = first_episodes(venv, act)
    assert_matches(exact, harms, survival)


def first_episodes(venv: VectorEnv, act) -> tuple[np.ndarray, np.ndarray]:
    """Harms and survival of the first episode of every environment (unbiased: one per env)."""
    n = venv.num_envs
    harms, survival, done = np.zeros(n), np.zeros(n), np.zeros(n, dtype=bool)
    while not done.all():  # every episode ends by max_cycles
        finished = venv.step(act()).finished
        if not finished["env"].size:
            continue
        first = ~done[finished["env"]]
        ids = finished["env"][first]
        harms[ids], survival[ids] = finished["harms"][first], finished["survival"][first]
        done[ids] = True
    return harms, survival


def assert_matches(exact, harms: np.ndarray, survival: np.ndarray) -> None:
    n = len(harms)
    harm_se = max(np.sqrt(exact.harms * (1 - exact.harms) / n), 1.0 / n)
    survival_se = max(survival.std(ddof=1) / np.sqrt(n), 1.0 / n)
    assert abs(harms.mean() - exact.harms) < 4 * harm_se, (harms.mean(), exact.harms)
    assert abs(survival.mean() - exact.survival) < 4 * survival_se, (survival.mean(), exact.survival)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"selfishness": -0.1}, "selfishness"),
        ({"selfishness": 1.5}, "selfishness"),
        ({"selfishness": float("nan")}, "selfishness"),
        ({"epsilon": -1e-9}, "epsilon"),
        ({"epsilon": 2.0}, "epsilon"),
        ({"gamma": 1.0}, "gamma"),
        ({"gamma": -0.5}, "gamma"),
        ({"size": 4}, "size"),
        ({"size": 7.0}, "size"),
        ({"max_cycles": 0}, "max_cycles"),
        ({"tolerance": 0.0}, "tolerance"),
        ({"selfishness": "0.5"}, "selfishness"),
    ],
)
def test_bad_arguments_raise(kwargs, name):
    arguments = {"selfishness": 0.5, "epsilon": 0.01} | kwargs
    with pytest.raises(ValueError, match=name):
        coexistence_optimum(**arguments)
