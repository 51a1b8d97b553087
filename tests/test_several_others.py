"""Several other agents (SPEC §3b): ``num_cats`` (Coexistence) and ``num_humans`` (Sharing).

The defaults stay bit-identical: :data:`DEFAULT_DIGESTS` are the digests :func:`default_digests`
gave for the suite before these arguments existed (run this file as a script, with that
version's package first on ``PYTHONPATH``, to print them).
"""

from __future__ import annotations

import hashlib
from typing import Any

import numpy as np
import pytest
from pettingzoo.test import api_test, parallel_api_test, parallel_seed_test

from empathy_zoo import EmpathyWrapper, FixedAgents, coexistence_v0, sharing_v0
from empathy_zoo.actions import NUM_ACTIONS, Action
from empathy_zoo.engine import CoexistenceEngine
from empathy_zoo.engine.sharing import agent_value, battery_value
from empathy_zoo.environments import DEFAULT_POLICIES
from empathy_zoo.grid import torus_distance
from empathy_zoo.vector import VectorEnv

UP, DOWN, LEFT, RIGHT, STAY = (int(a) for a in (Action.UP, Action.DOWN, Action.LEFT, Action.RIGHT, Action.STAY))
ROBOT = "robot_0"
SIZE, VIEW, CENTRE = 7, 5, 12
SEVERAL = [(coexistence_v0, {"num_cats": 3}), (sharing_v0, {"num_humans": 2})]
SEVERAL_IDS = ["coexistence_v0-3-cats", "sharing_v0-2-humans"]

# ---------------------------------------------------------------------------- the defaults, pinned
STEPS = 400
VECTOR_FIELDS = (
    "observations",
    "final_observations",
    "other_swapped",
    "other_seen",
    "other_terminated",
    "rewards",
    "terminated",
    "truncated",
    "episode_over",
    "harmed_by",
    "collected",
    "battery_return",
    "learner_rewards",
    "learner_terminated",
    "learner_truncated",
    "harms",
    "learner_battery_return",
    "other_battery_return",
    "other_rewards",
    "finished",
)
"""What every version's :class:`~empathy_zoo.vector.VectorStep` says, by today's names (the
closest other agent's ``other_*`` read through its properties: each version's digest is the same)."""

DEFAULT_DIGESTS = {
    "coexistence_v0 empathy": "007fef7d3c18e858bc186c092b0e44c25f6c9d5f5387afb6c5dbbbc694b64f99",
    "coexistence_v0 empathy in view": "ad2e8aa0d0a4f849c3a760c37c8c9d9084c79011d4274e9823207a0ba8659f22",
    "coexistence_v0 fixed": "3836eec4270f6e37d3c9ab194d3d9f5db9b87b47880c82f2b3565d316dc89c8e",
    "coexistence_v0 vector": "68b4b2d2a8a017a24c744734e5a88bf58bc33a272917328e4e0cf98467141901",
    "coexistence_v0 vector in view": "274e840480f88a5c189fa9f525c626e2af93e78425719e4d51f3e1d2b0111efb",
    "coexistence_v0 vector two learners": "4fbf0565bd6df4cd4b8550f413369d2bb27bff49baf7d20442f2d11a3812966f",
    "sharing_v0 empathy": "f435595cda5e622cfe2736b70f110e02284ddccb288a58b9e047e1d0bccb1c6a",
    "sharing_v0 empathy in view": "76e8df8d5f0a44fe02590880aff93793ef7ba234c26d8775e9794a5352fee9f3",
    "sharing_v0 fixed": "79bb438e7be83d0ae4fe519fe59b33684656d038c524e1ff01db9cabb1d888d1",
    "sharing_v0 vector": "a8078e30dfa329727ec436e253b59da4bcc66f885f620d78c4dc3d598b918012",
    "sharing_v0 vector in view": "bed2ecff78a8ee80ca1f5395646f667f02f96db03df3c00b33da866e6a393101",
    "sharing_v0 vector two learners": "3eb44c867ecb2826e9f547c99f736b65ca432c6af28482a08a81998af63202ef",
    "sharing_v0 ties": "dee75ff820960f7472088e68aaf39e9786a29ded8241b9a6f641705d7c1f8502",
    "sharing_v0 centre authors": "60e54e7f5e2cac55f477644a816adaac6d6efda484caa37ce7ef5ea653ad7e3e",
}
"""What :func:`default_digests` gave at the last commit before ``num_cats`` / ``num_humans``."""


def feed(digest: Any, value: Any) -> None:
    """Add ``value`` (arrays, numbers, strings, None, dicts in their order, lists) to ``digest``."""
    if isinstance(value, np.ndarray):
        digest.update(f"a{value.dtype.str}{value.shape}".encode())
        digest.update(np.ascontiguousarray(value).tobytes())
    elif isinstance(value, dict):
        digest.update(f"d{len(value)}".encode())
        for key, item in value.items():
            feed(digest, key)
            feed(digest, item)
    elif isinstance(value, (list, tuple)):
        digest.update(f"l{len(value)}".encode())
        for item in value:
            feed(digest, item)
    else:
        digest.update(f"{type(value).__name__}:{value!r};".encode())


def parallel_digest(env: Any, seed: int, action_seed: int) -> str:
    """Digest of everything ``env`` (a ParallelEnv face) returns over :data:`STEPS` random steps,
    resetting without a seed when an episode ends."""
    digest = hashlib.sha256()
    rng = np.random.default_rng(action_seed)
    feed(digest, env.reset(seed=seed))
    for _ in range(STEPS):
        if not env.agents:
            feed(digest, env.reset())
        feed(digest, env.step({agent: int(rng.integers(NUM_ACTIONS)) for agent in env.agents}))
    return digest.hexdigest()


def vector_digest(name: str, fixed: dict | None, in_view_only: bool, seed: int, action_seed: int, **kwargs: Any) -> str:
    """Digest of every :data:`VECTOR_FIELDS` of :data:`STEPS` steps of an 8-environment vector env,
    and of the first learner's swapped observations with every agent."""
    vector = VectorEnv(name, 8, fixed=fixed, in_view_only=in_view_only, **kwargs)
    digest = hashlib.sha256()
    rng = np.random.default_rng(action_seed)
    feed(digest, vector.reset(seed=seed))
    for _ in range(STEPS):
        out = vector.step(rng.integers(NUM_ACTIONS, size=(8, len(vector.learners))))
        feed(digest, [getattr(out, field) for field in VECTOR_FIELDS])
        feed(digest, vector.swapped_observations(vector.learners[0]))
    return digest.hexdigest()


def tie_digest(**kwargs: Any) -> str:
    """Digest of 200 seeded episodes' first step in which the robot and the human reach one
    battery together (the env's generator decides who collects it)."""
    env = EmpathyWrapper(sharing_v0.parallel_env(**kwargs))
    digest = hashlib.sha256()
    for seed in range(200):
        feed(digest, env.reset(seed=seed, options={"positions": {"robot_0": (0, 1), "human_0": (1, 0)}}))
        stay = dict.fromkeys(env.agents, STAY)
        feed(digest, env.step({**stay, "robot_0": DOWN, "human_0": RIGHT}))  # both onto the battery at (1, 1)
        feed(digest, env.step({**stay, "robot_0": RIGHT, "human_0": RIGHT}))
    return digest.hexdigest()


def default_digests(coexistence: dict | None = None, sharing: dict | None = None) -> dict[str, str]:
    """Every digest, by a name saying what it rolled out (``coexistence`` and ``sharing``: keyword
    arguments of each environment, none by default)."""
    out = {}
    for module, kwargs in ((coexistence_v0, coexistence or {}), (sharing_v0, sharing or {})):
        name = module.__name__.rsplit(".", 1)[-1]
        fixed = DEFAULT_POLICIES[name]
        out[f"{name} empathy"] = parallel_digest(EmpathyWrapper(module.parallel_env(**kwargs)), seed=3, action_seed=1)
        out[f"{name} empathy in view"] = parallel_digest(
            EmpathyWrapper(module.parallel_env(**kwargs), in_view_only=True), seed=4, action_seed=2
        )
        out[f"{name} fixed"] = parallel_digest(
            EmpathyWrapper(FixedAgents(module.parallel_env(**kwargs), fixed)), seed=5, action_seed=3
        )
        out[f"{name} vector"] = vector_digest(name, fixed, False, seed=6, action_seed=4, **kwargs)
        out[f"{name} vector in view"] = vector_digest(name, fixed, True, seed=7, action_seed=5, **kwargs)
        out[f"{name} vector two learners"] = vector_digest(name, None, False, seed=8, action_seed=6, **kwargs)
    out["sharing_v0 ties"] = tie_digest(**(sharing or {}))
    out["sharing_v0 centre authors"] = parallel_digest(
        EmpathyWrapper(sharing_v0.parallel_env(start="centre", inventory_encoding="authors", **(sharing or {}))),
        seed=9,
        action_seed=7,
    )
    return out


def test_defaults_are_bit_identical_to_before_several_others():
    assert default_digests() == DEFAULT_DIGESTS


def test_one_other_agent_given_explicitly_is_the_default():
    assert default_digests({"num_cats": 1}, {"num_humans": 1}) == DEFAULT_DIGESTS


def test_the_bookkeeping_of_several_pairs_gives_the_one_cat_tables_effects(monkeypatch):
    monkeypatch.setattr(CoexistenceEngine, "one_pair_tables", False)
    env = EmpathyWrapper(coexistence_v0.parallel_env())
    assert parallel_digest(env, seed=3, action_seed=1) == DEFAULT_DIGESTS["coexistence_v0 empathy"]
    vector = vector_digest("coexistence_v0", DEFAULT_POLICIES["coexistence_v0"], False, seed=6, action_seed=4)
    assert vector == DEFAULT_DIGESTS["coexistence_v0 vector"]


def test_several_others_change_the_digests():
    """(the digests see what the arguments change)"""
    several = default_digests({"num_cats": 2}, {"num_humans": 2})
    assert not set(several.values()) & set(DEFAULT_DIGESTS.values())


# ---------------------------------------------------------------------------- API and arguments
@pytest.mark.parametrize("module, kwargs", SEVERAL, ids=SEVERAL_IDS)
def test_parallel_api_and_seed(module, kwargs):
    with pytest.warns(UserWarning, match=r"ignoring unknown reset option\(s\) \['options'\]"):  # (PettingZoo's test passes one)
        parallel_api_test(module.parallel_env(**kwargs), num_cycles=300)
        parallel_seed_test(lambda: module.parallel_env(**kwargs))
        api_test(module.env(**kwargs), num_cycles=100)


@pytest.mark.parametrize("module, kwargs", SEVERAL, ids=SEVERAL_IDS)
def test_agents_are_the_robot_and_numbered_others(module, kwargs):
    ((argument, count),) = kwargs.items()
    env = module.parallel_env(**kwargs)
    kind = "cat" if argument == "num_cats" else "human"
    assert env.possible_agents == [ROBOT] + [f"{kind}_{i}" for i in range(count)]
    observations, _infos = env.reset(seed=0)
    assert list(observations) == env.possible_agents == env.agents


@pytest.mark.parametrize("module, argument, most", [(coexistence_v0, "num_cats", 44), (sharing_v0, "num_humans", 39)])
@pytest.mark.parametrize("bad", [0, -2, "most + 1", 1.5, True, "2", None])
def test_bad_counts_raise_naming_the_argument(module, argument, most, bad):
    value = most + 1 if bad == "most + 1" else bad
    name = module.__name__.rsplit(".", 1)[-1]
    for make in (lambda: module.parallel_env(**{argument: value}), lambda: VectorEnv(name, 2, **{argument: value})):
        with pytest.raises(ValueError, match=argument):
            make()


@pytest.mark.parametrize("module, argument, most", [(coexistence_v0, "num_cats", 44), (sharing_v0, "num_humans", 39)])
def test_as_many_others_as_fit_start_on_distinct_cells(module, argument, most):
    env = module.parallel_env(**{argument: most})
    for seed in range(5):
        env.reset(seed=seed)
        engine = env.unwrapped.engine
        cells = engine.cells[0]
        assert len(set(cells.tolist())) == engine.num_agents
        if module is sharing_v0:
            assert not engine.batteries[0, cells].any()
        else:
            assert (torus_distance(engine.pos[0, :1], engine.pos[0, 1:], SIZE) > 1).all()


def test_the_other_environment_takes_no_count_argument():
    with pytest.raises(TypeError, match="num_humans"):
        coexistence_v0.parallel_env(num_humans=2)
    with pytest.raises(TypeError, match="num_cats"):
        sharing_v0.parallel_env(num_cats=2)


# ---------------------------------------------------------------------------- start placement
@pytest.mark.parametrize("module, kwargs", SEVERAL, ids=SEVERAL_IDS)
def test_random_starts_follow_the_rules(module, kwargs):
    env = module.parallel_env(**kwargs)
    starts = set()
    for seed in range(60):
        env.reset(seed=seed)
        engine = env.unwrapped.engine
        pos = engine.pos[0]
        starts.add(tuple(map(tuple, pos.tolist())))
        assert len(set(engine.cells[0].tolist())) == engine.num_agents
        if module is coexistence_v0:
            assert (torus_distance(pos[:1], pos[1:], SIZE) > 1).all()
        else:
            assert not engine.batteries[0, engine.cells[0]].any()
    assert len(starts) == 60


def test_cats_may_start_side_by_side_but_not_next_to_the_robot():
    env = coexistence_v0.parallel_env(num_cats=2)
    env.reset(seed=0, options={"positions": {ROBOT: (3, 3), "cat_0": (0, 0), "cat_1": (0, 1)}})
    with pytest.raises(ValueError, match="cat_1 at \\(3, 4\\) would start in contact"):
        env.reset(seed=0, options={"positions": {ROBOT: (3, 3), "cat_0": (0, 0), "cat_1": (3, 4)}})
    with pytest.raises(ValueError, match="both placed on"):
        env.reset(seed=0, options={"positions": {ROBOT: (3, 3), "cat_0": (0, 0), "cat_1": (0, 0)}})
    with pytest.raises(ValueError, match="unknown agent 'cat_2'"):
        env.reset(seed=0, options={"positions": {"cat_2": (0, 0)}})


def test_agents_left_out_of_the_options_are_drawn_by_the_rules():
    env = coexistence_v0.parallel_env(num_cats=3)
    for seed in range(20):
        env.reset(seed=seed, options={"positions": {ROBOT: (3, 3), "cat_1": (0, 0)}})
        pos = env.unwrapped.engine.pos[0]
        assert tuple(pos[0]) == (3, 3) and tuple(pos[2]) == (0, 0)
        assert (torus_distance(pos[:1], pos[1:], SIZE) > 1).all() and len({tuple(p) for p in pos.tolist()}) == 4


def test_centre_start_puts_the_humans_on_the_next_cells():
    env = sharing_v0.parallel_env(start="centre", num_humans=2)
    env.reset(seed=0)
    # cells by torus distance from (3, 3), ties row-major, skipping batteries: (2, 3), (3, 2), (3, 4)
    assert env.unwrapped.engine.pos[0].tolist() == [[2, 3], [3, 2], [3, 4]]


# ---------------------------------------------------------------------------- Coexistence scenarios
def cats(count: int, positions: dict[str, tuple[int, int]], **kwargs: Any):
    env = coexistence_v0.parallel_env(num_cats=count, **kwargs)
    env.reset(seed=0, options={"positions": positions})
    return env


def test_robot_harms_two_cats_in_one_step():
    env = cats(3, {ROBOT: (3, 3), "cat_0": (5, 3), "cat_1": (3, 1), "cat_2": (0, 0)})
    # cat_0 ends below the robot, cat_1 left of it: the robot harms both; cat_2 is far away
    _, rewards, terminations, truncations, infos = env.step({ROBOT: STAY, "cat_0": UP, "cat_1": RIGHT, "cat_2": STAY})
    assert infos[ROBOT] == {"harmed_by": None, "harmed": ["cat_0", "cat_1"]}
    assert infos["cat_0"]["harmed_by"] == infos["cat_1"]["harmed_by"] == ROBOT and infos["cat_2"]["harmed_by"] is None
    assert terminations == {ROBOT: False, "cat_0": True, "cat_1": True, "cat_2": False}
    assert not any(truncations.values())
    assert rewards == {ROBOT: 1.0, "cat_0": 0.0, "cat_1": 0.0, "cat_2": 1.0}
    assert env.agents == [ROBOT, "cat_2"]
    assert env.unwrapped.engine.episode_harms[0].tolist() == [2, 0, 0, 0]
    assert env.swapped_observation(ROBOT, "cat_0") is None and env.swapped_observation(ROBOT, "cat_2") is not None


def test_robot_harmed_by_one_cat_while_harming_another():
    env = cats(3, {ROBOT: (3, 3), "cat_0": (5, 3), "cat_1": (1, 3), "cat_2": (0, 0)})
    # cat_0 ends below the robot (the robot harms it), cat_1 above (it harms the robot)
    _, rewards, terminations, truncations, infos = env.step({ROBOT: STAY, "cat_0": UP, "cat_1": DOWN, "cat_2": STAY})
    assert infos[ROBOT]["harmed_by"] == "cat_1" and infos[ROBOT]["harmed"] == ["cat_0"]
    assert infos["cat_0"]["harmed_by"] == ROBOT and infos["cat_1"]["harmed"] == [ROBOT]
    assert terminations == {ROBOT: True, "cat_0": True, "cat_1": False, "cat_2": False}
    assert truncations == {ROBOT: False, "cat_0": False, "cat_1": True, "cat_2": True}
    assert rewards == {ROBOT: 0.0, "cat_0": 0.0, "cat_1": 1.0, "cat_2": 1.0}
    assert env.agents == []
    assert infos[ROBOT]["episode"]["harms"] == 1 and infos[ROBOT]["episode"]["survival"] == 0


def test_two_cats_on_the_robots_cell_each_meet_it_by_the_rule():
    env = cats(2, {ROBOT: (3, 3), "cat_0": (3, 5), "cat_1": (4, 4)})
    # all three end on (3, 4): cat_0 was to the right on the robot's row (it harms the robot);
    # cat_1 was below (the robot harms it); the two cats on one cell do nothing to each other
    _, _, terminations, _, infos = env.step({ROBOT: RIGHT, "cat_0": LEFT, "cat_1": UP})
    assert env.unwrapped.engine.pos[0].tolist() == [[3, 4]] * 3
    assert (infos[ROBOT]["harmed_by"], infos[ROBOT]["harmed"]) == ("cat_0", ["cat_1"])
    assert (infos["cat_0"]["harmed_by"], infos["cat_0"]["harmed"]) == (None, [ROBOT])
    assert infos["cat_1"]["harmed_by"] == ROBOT and terminations == {ROBOT: True, "cat_0": False, "cat_1": True}


def test_a_robot_harmed_by_two_cats_names_the_first():
    env = cats(2, {ROBOT: (3, 3), "cat_0": (1, 3), "cat_1": (3, 5)})
    _, _, _, _, infos = env.step({ROBOT: STAY, "cat_0": DOWN, "cat_1": LEFT})  # above, and to the right
    assert infos[ROBOT]["harmed_by"] == "cat_0" and infos["cat_0"]["harmed"] == [ROBOT]
    assert env.agents == []


def test_cats_pass_through_each_other():
    env = cats(3, {ROBOT: (5, 5), "cat_0": (0, 0), "cat_1": (0, 1), "cat_2": (1, 0)})
    # cat_0 and cat_1 exchange cells while cat_2 steps onto cat_1's new one; then they stand side
    # by side and on one cell, then cat_0 steps down next to them: nobody is harmed
    for actions in (
        {"cat_0": RIGHT, "cat_1": LEFT, "cat_2": UP},
        {"cat_0": STAY, "cat_1": STAY, "cat_2": STAY},
        {"cat_0": DOWN, "cat_1": STAY, "cat_2": STAY},
    ):
        observations, rewards, terminations, _, infos = env.step({ROBOT: STAY, **actions})
        assert not any(terminations.values()) and set(rewards.values()) == {1.0}
        assert all(info == {"harmed_by": None, "harmed": []} for info in infos.values())
    assert env.agents == env.possible_agents
    assert env.unwrapped.engine.pos[0].tolist() == [[5, 5], [1, 1], [0, 0], [0, 0]]
    seen = observations["cat_0"].reshape(VIEW, VIEW)  # cat_1 and cat_2 on (0, 0), up-left of cat_0
    assert seen[1, 1] == -1.0 and seen[2, 2] == 1.0 and np.count_nonzero(seen) == 2


def test_observations_draw_every_other_agent():
    env = coexistence_v0.parallel_env(num_cats=3)
    positions = {ROBOT: (3, 3), "cat_0": (1, 1), "cat_1": (5, 5), "cat_2": (0, 0)}
    observation = env.reset(seed=0, options={"positions": positions})[0][ROBOT].reshape(VIEW, VIEW)
    expected = np.zeros((VIEW, VIEW), np.float32)
    expected[2, 2] = 1.0
    expected[0, 0] = expected[4, 4] = -1.0  # cat_2 at (0, 0) is outside the window around (3, 3)
    np.testing.assert_array_equal(observation, expected)


# ---------------------------------------------------------------------------- the closest other and the swap
def closest_by_hand(engine: Any, viewer: int) -> int | None:
    """The present agent at the least torus distance from ``viewer``, ties to the lower index."""
    pos, present = engine.pos[0].tolist(), engine.present[0].tolist()
    candidates = [
        (int(torus_distance(np.array(pos[viewer]), np.array(pos[o]), engine.size)), o)
        for o in range(engine.num_agents)
        if o != viewer and present[o]
    ]
    return min(candidates)[1] if candidates else None


def test_closest_other_is_the_nearest_on_the_torus_ties_to_the_lower_index():
    engine = CoexistenceEngine(1, num_cats=3)
    # cat_1 at (6, 6) is 2 away across the edges, as far as cat_2 at (0, 2); cat_0 at (3, 3) is 6 away
    engine.reset(seeds=[0], options={"positions": {ROBOT: (0, 0), "cat_0": (3, 3), "cat_1": (6, 6), "cat_2": (0, 2)}})
    assert engine.closest_other(0)[0].tolist() == [2] and engine.closest_other(0)[1].tolist() == [True]
    engine.reset(seeds=[0], options={"positions": {ROBOT: (0, 0), "cat_0": (6, 6), "cat_1": (3, 3), "cat_2": (0, 2)}})
    assert engine.closest_other(0)[0].tolist() == [1]
    engine.present[0, 1] = False  # cat_0 has left: the next closest
    assert engine.closest_other(0)[0].tolist() == [3]
    engine.present[0, 1:] = False
    assert engine.closest_other(0)[1].tolist() == [False]


def test_vector_swaps_with_the_closest_and_with_every_other():
    """A hand-placed state stepped with everyone staying: ``others_swapped`` holds the swap with
    each cat, ``closest`` points at the closest cat (a tie, to the lower index) and
    ``other_swapped`` is its swap."""
    env = coexistence_v0.parallel_env(num_cats=3)
    env.reset(seed=0, options={"positions": {ROBOT: (0, 0), "cat_0": (3, 3), "cat_1": (6, 6), "cat_2": (0, 2)}})
    env.step(dict.fromkeys(env.agents, STAY))
    vector = VectorEnv("coexistence_v0", 1, num_cats=3)
    vector.reset(seed=0)
    vector.engine.load_state(env.unwrapped.engine.state())
    out = vector.step(np.full((1, 4), STAY))
    assert vector.others[0] == ["cat_0", "cat_1", "cat_2"]
    assert out.closest[0, 0] == 1  # cat_1
    np.testing.assert_array_equal(out.other_swapped[0, 0], env.swapped_observation(ROBOT, "cat_1"))
    for k, cat in enumerate(["cat_0", "cat_1", "cat_2"]):
        np.testing.assert_array_equal(out.others_swapped[0, 0, k], env.swapped_observation(ROBOT, cat))
    assert out.others_present[0, 0].tolist() == [True, True, True] and out.other_seen[0, 0]
    assert out.others_swapped.shape == (1, 4, 3, VIEW * VIEW) and out.others_present.shape == (1, 4, 3)


def test_the_swap_exchanges_the_chosen_pair_only():
    env = sharing_v0.parallel_env(num_humans=2)
    env.reset(seed=0, options={"positions": {ROBOT: (0, 1), "human_0": (4, 4), "human_1": (2, 0)}})
    env.step({ROBOT: DOWN, "human_0": STAY, "human_1": UP})  # robot collects (1, 1); human_1 moves to (1, 0)
    env.step({ROBOT: RIGHT, "human_0": STAY, "human_1": STAY})  # robot on (1, 2)
    env.step({ROBOT: RIGHT, "human_0": STAY, "human_1": STAY})  # robot collects (1, 3): holds 2
    observations = env.step({ROBOT: LEFT, "human_0": STAY, "human_1": STAY})[0]  # robot back on (1, 2)
    engine = env.unwrapped.engine
    assert engine.inventory[0].tolist() == [2, 0, 0] and engine.pos[0].tolist() == [[1, 2], [4, 4], [1, 0]]
    swapped = env.swapped_observation(ROBOT, "human_0").reshape(VIEW, VIEW)
    # the robot in human_0's shoes: on (4, 4), empty-handed; human_0 on (1, 2) holding 2; human_1 unmoved
    expected = np.zeros((VIEW, VIEW), np.float32)
    for row, col in ((3, 3), (3, 5), (5, 3), (5, 5)):  # batteries left around (4, 4)
        expected[row - 2, col - 2] = -1.0
    expected[2, 2] = agent_value(0)
    np.testing.assert_array_equal(swapped, expected)  # (1, 2) and (1, 0) are out of this window
    np.testing.assert_array_equal(swapped.ravel(), observations["human_0"])
    # human_0 in the robot's place sees the robot's battery count at the centre and human_1 where it stands
    as_robot = env.swapped_observation("human_0", ROBOT).reshape(VIEW, VIEW)
    np.testing.assert_array_equal(as_robot.ravel(), observations[ROBOT])
    assert as_robot[2, 2] == agent_value(2) and as_robot[2, 0] == agent_value(0)
    # exchanging the robot with human_1 moves human_0's neither cell nor count
    with_one = env.swapped_observation(ROBOT, "human_1").reshape(VIEW, VIEW)
    np.testing.assert_array_equal(with_one.ravel(), observations["human_1"])
    assert with_one[2, 2] == agent_value(0) and with_one[2, 4] == agent_value(2)
    assert engine.inventory[0].tolist() == [2, 0, 0]


@pytest.mark.parametrize("module, kwargs", SEVERAL, ids=SEVERAL_IDS)
def test_every_swapped_observation_is_the_others_own(module, kwargs):
    env = module.parallel_env(**kwargs)
    rng = np.random.default_rng(0)
    checked = 0
    for seed in range(3):
        observations, _ = env.reset(seed=seed)
        while env.agents:
            for viewer in env.agents:
                for other in env.agents:
                    if other != viewer:
                        np.testing.assert_array_equal(env.swapped_observation(viewer, other), observations[other])
                        checked += 1
            observations = env.step({agent: int(rng.integers(NUM_ACTIONS)) for agent in env.agents})[0]
    assert checked > 300


@pytest.mark.parametrize("module, kwargs", SEVERAL, ids=SEVERAL_IDS)
def test_in_view_only_swaps_with_the_others_in_view(module, kwargs):
    env = EmpathyWrapper(module.parallel_env(**kwargs), in_view_only=True)
    engine = env.unwrapped.engine
    rng = np.random.default_rng(1)
    _, infos = env.reset(seed=2)
    kinds = set()
    for _ in range(150):
        if not env.agents:
            _, infos = env.reset()
        for agent, info in infos.items():
            v = env.possible_agents.index(agent)
            expected = [
                o
                for o in env.possible_agents
                if o != agent
                and engine.present[0, env.possible_agents.index(o)]
                and engine.in_view(v, env.possible_agents.index(o))[0]
            ]
            assert list(info["swapped_obs"]) == expected
            kinds.add(len(expected))
        infos = env.step({agent: int(rng.integers(NUM_ACTIONS)) for agent in env.agents})[4]
    assert len(kinds) >= 2


# ---------------------------------------------------------------------------- Sharing scenarios
def test_a_battery_three_agents_reach_goes_to_one_of_them_uniformly():
    env = sharing_v0.parallel_env(num_humans=2)
    wins = {ROBOT: 0, "human_0": 0, "human_1": 0}
    for seed in range(600):
        env.reset(seed=seed, options={"positions": {ROBOT: (0, 1), "human_0": (1, 0), "human_1": (2, 1)}})
        _, rewards, _, _, infos = env.step({ROBOT: DOWN, "human_0": RIGHT, "human_1": UP})  # all onto (1, 1)
        winners = [agent for agent, info in infos.items() if info["batteries"] == 1]
        assert len(winners) == 1 and rewards[winners[0]] == pytest.approx(battery_value(1))
        assert sum(rewards.values()) == rewards[winners[0]] and not env.unwrapped.engine.batteries[0, 8]
        wins[winners[0]] += 1
    assert all(150 <= count <= 250 for count in wins.values()), wins  # 200 each expected


def test_two_humans_alone_on_a_battery_share_it_by_a_fair_draw():
    env = sharing_v0.parallel_env(num_humans=2)
    wins = {"human_0": 0, "human_1": 0}
    for seed in range(400):
        env.reset(seed=seed, options={"positions": {ROBOT: (4, 4), "human_0": (1, 0), "human_1": (2, 1)}})
        _, _, _, _, infos = env.step({ROBOT: STAY, "human_0": RIGHT, "human_1": UP})
        assert infos[ROBOT]["batteries"] == 0 and infos["human_0"]["batteries"] + infos["human_1"]["batteries"] == 1
        wins["human_0"] += infos["human_0"]["batteries"]
        wins["human_1"] += infos["human_1"]["batteries"]
    assert all(160 <= count <= 240 for count in wins.values()), wins


def test_the_same_seed_gives_the_same_winners():
    def winners(seed: int) -> list[str]:
        env = sharing_v0.parallel_env(num_humans=2)
        env.reset(seed=seed, options={"positions": {ROBOT: (0, 1), "human_0": (1, 0), "human_1": (2, 1)}})
        infos = env.step({ROBOT: DOWN, "human_0": RIGHT, "human_1": UP})[4]
        return [agent for agent, info in infos.items() if info["batteries"]]

    assert [winners(seed) for seed in range(30)] == [winners(seed) for seed in range(30)]
    assert len({tuple(winners(seed)) for seed in range(30)}) == 3


def test_sharing_metrics_sum_over_the_others_and_compare_with_their_mean():
    env = sharing_v0.parallel_env(num_humans=2)
    env.reset(
        seed=0,
        options={"positions": {ROBOT: (0, 1), "human_0": (0, 3), "human_1": (5, 5)}, "batteries": [(1, 1), (1, 3), (2, 3)]},
    )
    env.step({ROBOT: DOWN, "human_0": DOWN, "human_1": STAY})  # robot (1, 1), human_0 (1, 3)
    _, _, terminations, _, infos = env.step({ROBOT: STAY, "human_0": DOWN, "human_1": STAY})  # human_0 (2, 3)
    assert all(terminations.values())
    robot, human = infos[ROBOT]["episode"], infos["human_0"]["episode"]
    assert robot["batteries"] == 1 and robot["other_batteries"] == 2
    assert robot["return"] == pytest.approx(1.0) and robot["other_return"] == pytest.approx(1.0 + 0.9)
    assert robot["equality"] == pytest.approx(2 * min(1.0, 1.9 / 2) / (1.0 + 1.9 / 2))
    assert human["batteries"] == 2 and human["other_batteries"] == 1 and human["other_return"] == pytest.approx(1.0)
    assert infos["human_1"]["episode"]["equality"] == pytest.approx(0.0)  # it collected nothing, the others 2.9


def test_coexistence_metrics_count_every_cat_harmed():
    env = cats(3, {ROBOT: (3, 3), "cat_0": (5, 3), "cat_1": (3, 1), "cat_2": (0, 0)}, max_cycles=3)
    env.step({ROBOT: STAY, "cat_0": UP, "cat_1": RIGHT, "cat_2": STAY})
    env.step({ROBOT: STAY, "cat_2": STAY})
    infos = env.step({ROBOT: STAY, "cat_2": STAY})[4]
    assert env.agents == []
    metrics = infos[ROBOT]["episode"]
    assert metrics["harms"] == 2 and metrics["survival"] == 3 and metrics["return"] == 3.0
    assert metrics["other_return"] == 3.0  # cat_0 and cat_1: 0 (harmed on the first step); cat_2: 3


# ---------------------------------------------------------------------------- the vector env
def fixed_others(name: str, kwargs: dict) -> dict[str, str]:
    """Every other agent with the paper's fixed policy of the first one."""
    (policy,) = DEFAULT_POLICIES[name].values()
    agents = VectorEnv(name, 1, **kwargs).agents
    return dict.fromkeys(agents[1:], policy)


@pytest.mark.parametrize("in_view_only", [False, True], ids=["omniscient", "in-view"])
@pytest.mark.parametrize("module, kwargs", SEVERAL, ids=SEVERAL_IDS)
def test_vector_swaps_equal_the_parallel_envs(module, kwargs, in_view_only):
    """Step for step, ``others_swapped``, ``others_present`` and the closest other agent's
    ``other_*`` are what the ParallelEnvs (in FixedAgents) say of every other agent and of the
    closest other agent when the step began."""
    name = module.__name__.rsplit(".", 1)[-1]
    fixed = fixed_others(name, kwargs)
    seeds = [0, 1, 2]
    envs = [FixedAgents(module.parallel_env(**kwargs), fixed) for _ in seeds]
    vector = VectorEnv(name, len(seeds), fixed=fixed, in_view_only=in_view_only, **kwargs)
    vector.reset(seed=seeds)
    for env, seed in zip(envs, seeds, strict=True):
        env.reset(seed=seed)
    others = vector.others[0]
    rng = np.random.default_rng(3)
    ended = closest_kinds = 0
    for _ in range(250):
        actions = rng.integers(NUM_ACTIONS, size=(len(seeds), 1))
        out = vector.step(actions)
        for i, env in enumerate(envs):
            closest = closest_by_hand(env.unwrapped.engine, 0)  # chosen when the step begins (SPEC §3b)
            env.step({ROBOT: int(actions[i, 0])})
            base = env.unwrapped
            for k, other in enumerate(others):
                swapped = base.swapped_observation(ROBOT, other, in_view_only=in_view_only)
                expected = np.zeros(VIEW * VIEW, np.float32) if swapped is None else swapped
                np.testing.assert_array_equal(out.others_swapped[i, 0, k], expected)
                index = k + 1
                terminal = bool(out.terminated[i, index])
                assert out.others_present[i, 0, k] == (swapped is not None and not terminal)
            if closest is not None:
                closest_kinds |= 1 << closest
                swapped = base.swapped_observation(ROBOT, base.possible_agents[closest], in_view_only=in_view_only)
                assert out.closest[i, 0] == closest - 1  # (its place among the others: the robot is agent 0)
                assert out.other_seen[i, 0] == (swapped is not None)
                if swapped is not None:
                    np.testing.assert_array_equal(out.other_swapped[i, 0], swapped)
                assert out.other_terminated[i, 0] == out.terminated[i, closest]
            else:
                assert not out.other_seen[i, 0]
            if not env.agents:
                ended += 1
                env.reset()
    assert ended >= 2 and bin(closest_kinds).count("1") >= 2


@pytest.mark.parametrize("module", [coexistence_v0, sharing_v0], ids=["coexistence_v0", "sharing_v0"])
def test_vector_fields_with_one_other_are_the_closest_ones(module):
    name = module.__name__.rsplit(".", 1)[-1]
    vector = VectorEnv(name, 4, fixed=DEFAULT_POLICIES[name])
    vector.reset(seed=0)
    rng = np.random.default_rng(0)
    for _ in range(100):
        out = vector.step(rng.integers(NUM_ACTIONS, size=(4, 1)))
        assert out.closest.tolist() == [[0]] * 4 and out.others_swapped.shape == (4, 1, 1, VIEW * VIEW)
        np.testing.assert_array_equal(out.others_swapped[:, :, 0], out.other_swapped)
        np.testing.assert_array_equal(out.others_present[:, :, 0], out.other_seen & ~out.other_terminated)
        np.testing.assert_array_equal(out.others_rewards[:, :, 0], out.rewards[:, 1:])
        np.testing.assert_array_equal(out.other_battery_return, out.battery_return[:, 1:])


if __name__ == "__main__":
    for key, value in default_digests().items():
        print(f"    {key!r}: {value!r},")
