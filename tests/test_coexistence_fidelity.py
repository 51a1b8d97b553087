"""Coexistence's fidelity options (SPEC §2): the paper's text by default, the authors' public code
with ``rules="authors"``, each option on its own. Every case places the robot and the cat by hand,
gives both actions and checks who is harmed, the rewards and the observation."""

from __future__ import annotations

import numpy as np
import pytest

from empathy_zoo import coexistence_v0
from empathy_zoo.actions import Action
from empathy_zoo.engine.coexistence import FIDELITY_OPTIONS, RULE_SETS, CoexistenceEngine
from empathy_zoo.environments import DEFAULT_ARGUMENTS

UP, DOWN, LEFT, RIGHT, STAY = (int(a) for a in (Action.UP, Action.DOWN, Action.LEFT, Action.RIGHT, Action.STAY))


def play(robot: tuple[int, int], cat: tuple[int, int], robot_action: int, cat_action: int, **kwargs):
    """One step from hand-placed cells: ``(rewards, infos)`` of the parallel env."""
    env = coexistence_v0.parallel_env(**kwargs)
    env.reset(seed=0, options={"positions": {"robot_0": robot, "cat_0": cat}})
    _, rewards, _, _, infos = env.step({"robot_0": robot_action, "cat_0": cat_action})
    return rewards, infos


def who_is_harmed(*args, **kwargs) -> str | None:
    _, infos = play(*args, **kwargs)
    harmed = [agent for agent, info in infos.items() if info["harmed_by"] is not None]
    assert len(harmed) <= 1
    return harmed[0] if harmed else None


# ---------------------------------------------------------------------------- sideways
def test_sideways_the_right_one_harms_in_the_paper_and_the_left_one_in_the_authors_code() -> None:
    # the cat steps left next to the robot: the cat is on the right, the robot on the left
    case = ((3, 3), (3, 5), STAY, LEFT)
    assert who_is_harmed(*case) == "robot_0"
    assert who_is_harmed(*case, sideways="left_harms_right") == "cat_0"
    assert who_is_harmed(*case, rules="authors") == "cat_0"
    # and mirrored: the cat steps in on the left
    case = ((3, 3), (3, 1), STAY, RIGHT)
    assert who_is_harmed(*case) == "cat_0"
    assert who_is_harmed(*case, rules="authors") == "robot_0"


def test_vertically_the_upper_one_harms_under_both_rules() -> None:
    for rules in ("paper", "authors"):
        assert who_is_harmed((3, 3), (1, 3), STAY, DOWN, rules=rules) == "robot_0"  # the cat above
        assert who_is_harmed((3, 3), (5, 3), STAY, UP, rules=rules) == "cat_0"  # the cat below


# ---------------------------------------------------------------------------- the same cell
@pytest.mark.parametrize(
    ("robot", "cat", "robot_action", "cat_action", "paper", "authors"),
    [
        ((4, 4), (2, 4), UP, DOWN, "robot_0", "robot_0"),  # the cat came from above; the robot moved up
        ((2, 4), (4, 4), DOWN, UP, "cat_0", None),  # the robot came from above, moving down: never harmed
        ((3, 3), (3, 5), RIGHT, LEFT, "robot_0", None),  # the cat came from the right; the robot moved right
        ((3, 5), (3, 3), LEFT, RIGHT, "cat_0", "robot_0"),  # the robot came from the right, moving left
    ],
)
def test_on_a_shared_cell(robot, cat, robot_action, cat_action, paper, authors) -> None:
    assert who_is_harmed(robot, cat, robot_action, cat_action) == paper
    assert who_is_harmed(robot, cat, robot_action, cat_action, same_cell="robot_unless_down_or_right") == authors


def test_a_robot_that_came_from_above_is_harmed_in_the_authors_code_unless_it_moved_down_or_right() -> None:
    # the robot steps left from (3, 4), the cat up from (4, 3): they meet on (3, 3). The robot was
    # above, so the paper's rule lets it harm the cat; the authors' code harms the robot (it moved left)
    assert who_is_harmed((3, 4), (4, 3), LEFT, UP) == "cat_0"
    assert who_is_harmed((3, 4), (4, 3), LEFT, UP, rules="authors") == "robot_0"


# ---------------------------------------------------------------------------- the seam
@pytest.mark.parametrize(
    ("robot", "cat", "cat_action", "paper"),
    [
        ((0, 3), (5, 3), DOWN, "robot_0"),  # the cat on row 6, the robot on row 0: above it through the seam
        ((3, 6), (3, 1), LEFT, "robot_0"),  # the cat on column 0, the robot on column 6: right of it through the seam
    ],
)
def test_contact_through_the_seam_counts_only_when_wrapped(robot, cat, cat_action, paper) -> None:
    assert who_is_harmed(robot, cat, STAY, cat_action) == paper
    assert who_is_harmed(robot, cat, STAY, cat_action, seam_contact="not_wrapped") is None
    assert who_is_harmed(robot, cat, STAY, cat_action, rules="authors") is None


def test_positions_still_wrap_when_contact_does_not() -> None:
    env = coexistence_v0.parallel_env(rules="authors")
    env.reset(seed=0, options={"positions": {"robot_0": (0, 3), "cat_0": (3, 0)}})
    env.step({"robot_0": UP, "cat_0": LEFT})
    assert env.engine.pos[0].tolist() == [[6, 3], [3, 6]]


# ---------------------------------------------------------------------------- start, observation, reward
@pytest.mark.parametrize("size", [5, 7, 9])
def test_the_authors_start_the_robot_in_the_centre_and_the_cat_in_the_corner(size) -> None:
    env = coexistence_v0.parallel_env(size=size, view=3, rules="authors")
    for seed in (0, 1):
        env.reset(seed=seed)
        assert env.engine.pos[0].tolist() == [[size // 2, size // 2], [0, 0]]
    env = coexistence_v0.parallel_env(size=size, view=3, start="centre_corner", num_cats=2)
    env.reset(seed=0)
    assert env.engine.pos[0].tolist() == [[size // 2, size // 2], [0, 0], [0, 1]]


def test_the_authors_draw_every_agent_as_five_hundredths() -> None:
    env = coexistence_v0.parallel_env(rules="authors")
    observations, _ = env.reset(seed=0, options={"positions": {"robot_0": (3, 3), "cat_0": (1, 2)}})
    expected = np.zeros((5, 5), dtype=np.float32)
    expected[2, 2] = expected[0, 1] = np.float32(0.05)
    assert np.array_equal(observations["robot_0"].reshape(5, 5), expected)
    paper, _ = coexistence_v0.parallel_env().reset(seed=0, options={"positions": {"robot_0": (3, 3), "cat_0": (1, 2)}})
    assert paper["robot_0"].reshape(5, 5)[2, 2] == 1.0 and paper["robot_0"].reshape(5, 5)[0, 1] == -1.0


def test_the_authors_pay_the_step_on_which_an_agent_is_harmed() -> None:
    case = ((3, 3), (1, 3), STAY, DOWN)  # the cat lands above the robot and harms it
    rewards, infos = play(*case)
    assert infos["robot_0"]["harmed_by"] == "cat_0" and rewards["robot_0"] == 0.0 and rewards["cat_0"] == 1.0
    rewards, _ = play(*case, harmed_step_reward="paid")
    assert rewards == {"robot_0": 1.0, "cat_0": 1.0}


# ---------------------------------------------------------------------------- the options as arguments
def test_rules_set_every_option_and_an_option_given_replaces_it() -> None:
    assert CoexistenceEngine().options == RULE_SETS["paper"]
    assert CoexistenceEngine(rules="authors").options == RULE_SETS["authors"]
    engine = CoexistenceEngine(rules="authors", sideways="right_harms_left")
    assert engine.options == {**RULE_SETS["authors"], "sideways": "right_harms_left"}
    assert set(FIDELITY_OPTIONS) == set(RULE_SETS["paper"]) == set(RULE_SETS["authors"])


@pytest.mark.parametrize(("name", "value"), [("rules", "author"), ("sideways", "left"), ("seam_contact", True)])
def test_an_unknown_value_is_refused_naming_the_argument(name, value) -> None:
    with pytest.raises(ValueError, match=name):
        coexistence_v0.parallel_env(**{name: value})


def test_the_environment_table_holds_every_option_at_its_default() -> None:
    arguments = DEFAULT_ARGUMENTS["coexistence_v0"]
    assert arguments["rules"] == "paper" and all(arguments[name] == "rules" for name in FIDELITY_OPTIONS)


def test_the_defaults_play_exactly_as_the_paper_rules_given_explicitly() -> None:
    default, explicit = coexistence_v0.parallel_env(), coexistence_v0.parallel_env(rules="paper", **RULE_SETS["paper"])
    rng = np.random.default_rng(0)
    for env in (default, explicit):
        env.reset(seed=7)
    for _ in range(400):
        if not default.agents:
            for env in (default, explicit):
                env.reset()
        actions = {agent: int(rng.integers(5)) for agent in default.agents}
        a, b = default.step(actions), explicit.step(actions)
        assert a[0].keys() == b[0].keys() and all(np.array_equal(a[0][agent], b[0][agent]) for agent in a[0])
        assert [dict(part) for part in a[1:]] == [dict(part) for part in b[1:]]
