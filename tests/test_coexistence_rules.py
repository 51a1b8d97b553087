"""Coexistence rules (SPEC §1-2) on hand-placed scenarios: contact, who harms whom, rewards, ends."""

from __future__ import annotations

import numpy as np
import pytest

from empathy_zoo import coexistence_v0
from empathy_zoo.actions import Action
from empathy_zoo.engine.coexistence import FLOOR, OTHER_AGENT, OWN_CELL
from empathy_zoo.grid import torus_distance

ROBOT, CAT = "robot_0", "cat_0"
UP, DOWN, LEFT, RIGHT, STAY = Action.UP, Action.DOWN, Action.LEFT, Action.RIGHT, Action.STAY
SIZE, VIEW = 7, 5
CENTRE = VIEW * VIEW // 2
LAST = SIZE - 1


def placed(robot: tuple[int, int], cat: tuple[int, int], **kwargs):
    env = coexistence_v0.parallel_env(**kwargs)
    env.reset(seed=0, options={"positions": {ROBOT: robot, CAT: cat}})
    return env


def step(env, robot: int | None = None, cat: int | None = None):
    actions = {agent: int(a) for agent, a in ((ROBOT, robot), (CAT, cat)) if a is not None}
    return env.step(actions)


def positions(env) -> dict[str, tuple[int, int]]:
    engine = env.unwrapped.engine
    return {agent: tuple(int(v) for v in engine.pos[0, i]) for i, agent in enumerate(env.possible_agents)}


def window_slot(viewer: tuple[int, int], other: tuple[int, int], size: int = SIZE, view: int = VIEW) -> int | None:
    """Index of ``other`` in ``viewer``'s flattened window, or None when outside it."""
    half = view // 2
    dr = (other[0] - viewer[0] + half) % size
    dc = (other[1] - viewer[1] + half) % size
    if dr >= view or dc >= view:
        return None
    return dr * view + dc


def expected_observation(viewer: tuple[int, int], other: tuple[int, int] | None) -> np.ndarray:
    obs = np.full(VIEW * VIEW, FLOOR, dtype=np.float32)
    if other is not None and (slot := window_slot(viewer, other)) is not None:
        obs[slot] = OTHER_AGENT
    obs[CENTRE] = OWN_CELL
    return obs


def assert_robot_harms_cat(env, out) -> None:
    _obs, rew, term, trunc, info = out
    assert info[CAT]["harmed_by"] == ROBOT and info[CAT]["harmed"] == []
    assert info[ROBOT]["harmed_by"] is None and info[ROBOT]["harmed"] == [CAT]
    assert term == {ROBOT: False, CAT: True}
    assert trunc == {ROBOT: False, CAT: False}
    assert rew == {ROBOT: 1.0, CAT: 0.0}
    assert env.agents == [ROBOT]


def assert_cat_harms_robot(env, out) -> None:
    _obs, rew, term, trunc, info = out
    assert info[ROBOT]["harmed_by"] == CAT and info[ROBOT]["harmed"] == []
    assert info[CAT]["harmed_by"] is None and info[CAT]["harmed"] == [ROBOT]
    assert term == {ROBOT: True, CAT: False}
    assert trunc == {ROBOT: False, CAT: True}  # the episode ends for the cat too
    assert rew == {ROBOT: 0.0, CAT: 1.0}
    assert env.agents == []


def assert_no_contact(env, out) -> None:
    _obs, rew, term, trunc, info = out
    assert rew == {ROBOT: 1.0, CAT: 1.0}
    assert not any(term.values()) and not any(trunc.values())
    assert all(i["harmed_by"] is None and i["harmed"] == [] for i in info.values())
    assert env.agents == [ROBOT, CAT]


# (robot start, cat start, robot action, cat action) ------------------------------------------
ROBOT_HARMS = {
    "robot above (robot moves down)": ((2, 3), (4, 3), DOWN, STAY),
    "robot above (cat moves up)": ((2, 3), (4, 3), STAY, UP),
    "robot right (cat moves right)": ((3, 4), (3, 2), STAY, RIGHT),
    "robot right (robot moves left)": ((3, 4), (3, 2), LEFT, STAY),
    "wrap: robot in last row above cat in row 0": ((5, 3), (0, 3), DOWN, STAY),
    "wrap: robot in col 0 right of cat in last col": ((3, 1), (3, LAST), LEFT, STAY),
    "same cell, robot was above": ((2, 3), (4, 3), DOWN, UP),
    "same cell, robot was above (diagonal approach)": ((2, 2), (3, 3), RIGHT, UP),
    "same cell, same row, robot was right": ((3, 4), (3, 2), LEFT, RIGHT),
    "same cell across the wrap, robot was above": ((LAST, 3), (1, 3), DOWN, UP),
    "same cell across the wrap, same row, robot was right": ((3, 0), (3, LAST - 1), LEFT, RIGHT),
}
CAT_HARMS = {
    "cat above (cat moves down)": ((4, 3), (2, 3), STAY, DOWN),
    "cat above (robot moves up)": ((4, 3), (2, 3), UP, STAY),
    "cat right (robot moves right)": ((3, 2), (3, 4), RIGHT, STAY),
    "cat right (cat moves left)": ((3, 2), (3, 4), STAY, LEFT),
    "wrap: cat in last row above robot in row 0": ((0, 3), (5, 3), STAY, DOWN),
    "wrap: cat in col 0 right of robot in last col": ((3, LAST), (3, 1), STAY, LEFT),
    "same cell, cat was above": ((4, 3), (2, 3), UP, DOWN),
    "same cell, cat was above (diagonal approach)": ((3, 3), (2, 2), UP, RIGHT),
    "same cell, same row, cat was right": ((3, 2), (3, 4), RIGHT, LEFT),
    "same cell across the wrap, cat was above": ((1, 3), (LAST, 3), UP, DOWN),
    "same cell across the wrap, same row, cat was right": ((3, LAST - 1), (3, 0), RIGHT, LEFT),
}
NO_CONTACT = {
    "diagonal, standing still": ((2, 2), (3, 3), STAY, STAY),
    "diagonal after a move": ((2, 2), (4, 3), STAY, UP),
    "diagonal across the wrap": ((0, 0), (LAST, LAST - 1), STAY, RIGHT),
    "two apart in a column": ((1, 3), (4, 3), DOWN, STAY),
    "two apart in a row": ((3, 1), (3, 4), RIGHT, STAY),
    "crossing is not contact when they end two apart": ((3, 3), (3, 5), LEFT, RIGHT),
}


@pytest.mark.parametrize("case", ROBOT_HARMS.values(), ids=ROBOT_HARMS.keys())
def test_robot_harms_cat(case):
    robot, cat, robot_action, cat_action = case
    env = placed(robot, cat)
    assert_robot_harms_cat(env, step(env, robot_action, cat_action))


@pytest.mark.parametrize("case", CAT_HARMS.values(), ids=CAT_HARMS.keys())
def test_cat_harms_robot(case):
    robot, cat, robot_action, cat_action = case
    env = placed(robot, cat)
    assert_cat_harms_robot(env, step(env, robot_action, cat_action))


@pytest.mark.parametrize("case", NO_CONTACT.values(), ids=NO_CONTACT.keys())
def test_no_contact(case):
    robot, cat, robot_action, cat_action = case
    env = placed(robot, cat)
    assert_no_contact(env, step(env, robot_action, cat_action))


def test_moves_follow_the_action_table_and_wrap():
    env = placed((0, 0), (3, 3))
    step(env, UP, DOWN)
    assert positions(env) == {ROBOT: (LAST, 0), CAT: (4, 3)}
    step(env, LEFT, RIGHT)
    assert positions(env) == {ROBOT: (LAST, LAST), CAT: (4, 4)}
    step(env, DOWN, UP)
    assert positions(env) == {ROBOT: (0, LAST), CAT: (3, 4)}
    step(env, RIGHT, STAY)
    assert positions(env) == {ROBOT: (0, 0), CAT: (3, 4)}


def test_harm_every_orientation_is_decided_by_the_rule():
    """Around a robot fixed at the centre, the cat steps onto each neighbour: exact outcome of each."""
    expected = {(-1, 0): "cat", (1, 0): "robot", (0, 1): "cat", (0, -1): "robot"}
    for (dr, dc), harmer in expected.items():
        # the cat starts two cells away in that direction and steps towards the robot
        cat = (3 + 2 * dr, 3 + 2 * dc)
        action = {(-1, 0): DOWN, (1, 0): UP, (0, 1): LEFT, (0, -1): RIGHT}[(dr, dc)]
        env = placed((3, 3), cat)
        out = step(env, STAY, action)
        (assert_cat_harms_robot if harmer == "cat" else assert_robot_harms_cat)(env, out)


def test_harmed_cat_leaves_and_robot_goes_on_alone():
    env = placed((2, 3), (4, 3), max_cycles=10)
    obs, *_ = step(env, DOWN, STAY)
    assert env.agents == [ROBOT]
    # the robot's observation no longer shows the cat
    np.testing.assert_array_equal(obs[ROBOT], expected_observation((3, 3), None))
    with pytest.raises(ValueError, match=CAT):
        step(env, STAY, STAY)
    for t in range(2, 10):
        obs, rew, term, trunc, info = step(env, RIGHT)
        assert list(obs) == [ROBOT] and rew == {ROBOT: 1.0}
        assert info[ROBOT] == {"harmed_by": None, "harmed": []}
        assert term == {ROBOT: False} and trunc == {ROBOT: (t == 10)}
    obs, rew, term, trunc, info = step(env, RIGHT)
    assert trunc == {ROBOT: True} and term == {ROBOT: False} and rew == {ROBOT: 1.0}
    assert env.agents == []
    metrics = env.unwrapped.engine.episode_metrics(np.array([0]))
    assert metrics["survival"][0] == 10 and metrics["harms"][0] == 1 and metrics["return"][0] == 10.0
    assert metrics["other_return"][0] == 0.0  # the cat got 0 on the step it was harmed


def test_harmed_robot_ends_the_episode():
    env = placed((4, 3), (2, 3))
    step(env, STAY, STAY)
    step(env, STAY, DOWN)
    assert env.agents == []
    with pytest.raises(RuntimeError):
        step(env, STAY, STAY)
    metrics = env.unwrapped.engine.episode_metrics(np.array([0]))
    assert metrics["survival"][0] == 1 and metrics["harms"][0] == 0 and metrics["return"][0] == 1.0
    assert metrics["other_return"][0] == 2.0


def test_default_max_cycles_is_500():
    env = placed((0, 0), (3, 3))
    for _ in range(499):
        step(env, STAY, STAY)
    assert env.agents == [ROBOT, CAT]
    _, _, _, trunc, _ = step(env, STAY, STAY)
    assert trunc == {ROBOT: True, CAT: True} and env.agents == []


def test_reset_infos():
    env = coexistence_v0.parallel_env()
    _, infos = env.reset(seed=0)
    assert infos == {ROBOT: {"harmed_by": None, "harmed": []}, CAT: {"harmed_by": None, "harmed": []}}


@pytest.mark.parametrize(
    "robot, cat",
    [
        ((3, 3), (1, 2)),  # cat up-left, inside the window
        ((3, 3), (5, 5)),  # window corner
        ((3, 3), (3, 4)),  # would be contact at start; placed diagonally instead below
        ((0, 0), (5, 6)),  # wraps over both edges
        ((0, 6), (1, 1)),  # wraps horizontally
        ((0, 0), (3, 3)),  # outside the window
        ((6, 6), (2, 2)),  # outside the window across the wrap
    ],
)
def test_observation_encoding(robot, cat):
    if torus_distance(np.array(robot), np.array(cat), SIZE) <= 1:
        cat = ((cat[0] + 1) % SIZE, cat[1])  # keep the start legal (diagonal)
    env = coexistence_v0.parallel_env()
    obs, _ = env.reset(seed=0, options={"positions": {ROBOT: robot, CAT: cat}})
    for viewer, other, agent in ((robot, cat, ROBOT), (cat, robot, CAT)):
        assert obs[agent].dtype == np.float32 and obs[agent].shape == (VIEW * VIEW,)
        assert obs[agent][CENTRE] == OWN_CELL
        np.testing.assert_array_equal(obs[agent], expected_observation(viewer, other))


def test_observation_slots_by_hand():
    """A few window indices worked out by hand (row-major 5x5, own cell at index 12)."""
    env = coexistence_v0.parallel_env()
    obs, _ = env.reset(seed=0, options={"positions": {ROBOT: (3, 3), CAT: (1, 2)}})
    assert np.flatnonzero(obs[ROBOT] == OTHER_AGENT).tolist() == [1]  # two up, one left
    assert np.flatnonzero(obs[CAT] == OTHER_AGENT).tolist() == [23]  # two down, one right
    obs, _ = env.reset(seed=0, options={"positions": {ROBOT: (0, 0), CAT: (LAST, LAST - 1)}})
    assert np.flatnonzero(obs[ROBOT] == OTHER_AGENT).tolist() == [5]  # one up, two left (wrapping)
    assert np.flatnonzero(obs[CAT] == OTHER_AGENT).tolist() == [19]


def test_observation_with_a_larger_view():
    env = coexistence_v0.parallel_env(size=9, view=7)
    obs, _ = env.reset(seed=0, options={"positions": {ROBOT: (0, 0), CAT: (6, 6)}})
    assert obs[ROBOT].shape == (49,) and obs[ROBOT][24] == OWN_CELL
    assert np.flatnonzero(obs[ROBOT] == OTHER_AGENT).tolist() == [0]  # three up, three left


def test_start_cells_are_distinct_and_never_in_contact():
    env = coexistence_v0.parallel_env()
    robot_cells = set()
    for seed in range(600):
        env.reset(seed=seed)
        cells = positions(env)
        robot_cells.add(cells[ROBOT])
        assert torus_distance(np.array(cells[ROBOT]), np.array(cells[CAT]), SIZE) > 1, (seed, cells)
    assert len(robot_cells) == SIZE * SIZE  # every cell is a possible start


def test_unplaced_agent_is_drawn_out_of_contact():
    env = coexistence_v0.parallel_env()
    for seed in range(200):
        env.reset(seed=seed, options={"positions": {ROBOT: (3, 3)}})
        cells = positions(env)
        assert cells[ROBOT] == (3, 3)
        assert torus_distance(np.array(cells[ROBOT]), np.array(cells[CAT]), SIZE) > 1


def oracle(robot, cat, robot_action, cat_action, size=SIZE):
    """Who harms whom, written out from SPEC §2 in plain Python: 'robot', 'cat' or None."""
    moves = {UP: (-1, 0), DOWN: (1, 0), LEFT: (0, -1), RIGHT: (0, 1), STAY: (0, 0)}

    def move(cell, action):
        return (cell[0] + moves[action][0]) % size, (cell[1] + moves[action][1]) % size

    def shortest(d):
        d %= size
        return d - size if d > size // 2 else d

    r, c = move(robot, robot_action), move(cat, cat_action)
    down, right = (c[0] - r[0]) % size, (c[1] - r[1]) % size  # where the cat is, seen from the robot
    if (down, right) == (1, 0) or (down, right) == (0, size - 1):
        return "robot"  # the robot is directly above, or directly to the right of, the cat
    if (down, right) == (size - 1, 0) or (down, right) == (0, 1):
        return "cat"
    if (down, right) == (0, 0):
        rows, cols = shortest(cat[0] - robot[0]), shortest(cat[1] - robot[1])  # before the move
        if rows != 0:
            return "robot" if rows > 0 else "cat"  # the one that was above
        return "robot" if cols < 0 else "cat"  # the one that was to the right
    return None


@pytest.mark.parametrize("size", [5, 7])
def test_every_start_and_action_pair_against_the_spec(size):
    """All legal start pairs × all 25 action pairs, stepped at once in a batched engine."""
    from empathy_zoo.engine.coexistence import CoexistenceEngine

    cells = [(r, c) for r in range(size) for c in range(size)]
    cases = [
        (robot, cat, a, b)
        for robot in cells
        for cat in cells
        if torus_distance(np.array(robot), np.array(cat), size) > 1
        for a in Action
        for b in Action
    ]
    engine = CoexistenceEngine(len(cases), size=size, view=3)
    engine.reset(seeds=[0] * len(cases))
    engine.cells[:] = [[robot[0] * size + robot[1], cat[0] * size + cat[1]] for robot, cat, _, _ in cases]
    events = engine.step(np.array([[a, b] for _, _, a, b in cases]))
    harmer = np.array([oracle(*case, size=size) or "" for case in cases])
    np.testing.assert_array_equal(events.harmed_by[:, 1] == 0, harmer == "robot")  # the cat harmed by the robot
    np.testing.assert_array_equal(events.harmed_by[:, 0] == 1, harmer == "cat")
    np.testing.assert_array_equal(events.rewards, np.stack([harmer != "cat", harmer != "robot"], axis=1))
    assert (harmer == "robot").any() and (harmer == "cat").any() and (harmer == "").any()
