"""The perspective swap (SPEC §4): the primitive, EmpathyWrapper's infos and the vector env's arrays."""

from __future__ import annotations

import numpy as np
import pytest

from empathy_zoo import EmpathyWrapper, FixedAgents, coexistence_v0, sharing_v0
from empathy_zoo.actions import NUM_ACTIONS, Action
from empathy_zoo.engine.sharing import agent_value
from empathy_zoo.environments import DEFAULT_POLICIES
from empathy_zoo.vector import VectorEnv

MODULES = [coexistence_v0, sharing_v0]
IDS = [module.__name__.rsplit(".", 1)[-1] for module in MODULES]
CENTRE = 12
ROBOT, CAT, HUMAN = "robot_0", "cat_0", "human_0"
UP, DOWN, LEFT, RIGHT, STAY = Action.UP, Action.DOWN, Action.LEFT, Action.RIGHT, Action.STAY


def env_name(module) -> str:
    return module.__name__.rsplit(".", 1)[-1]


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_swapped_observation_is_the_others_own_observation(module):
    env = module.parallel_env()
    rng = np.random.default_rng(0)
    checked = 0
    for seed in range(6):
        obs, _ = env.reset(seed=seed)
        while env.agents:
            live = list(env.agents)
            for viewer in live:
                for other in live:
                    if other != viewer:
                        swapped = env.swapped_observation(viewer, other)
                        assert swapped.dtype == np.float32 and swapped.shape == obs[other].shape
                        np.testing.assert_array_equal(swapped, obs[other])
                        checked += 1
            obs, *_ = env.step({agent: int(rng.integers(NUM_ACTIONS)) for agent in env.agents})
    assert checked > 200


def test_swap_exchanges_inventories_in_sharing():
    env = sharing_v0.parallel_env()
    env.reset(seed=0, options={"positions": {ROBOT: (0, 1), HUMAN: (4, 0)}})
    env.step({ROBOT: int(DOWN), HUMAN: int(STAY)})  # robot collects (1, 1)
    env.step({ROBOT: int(RIGHT), HUMAN: int(STAY)})  # (1, 2)
    obs, _, _, _, info = env.step({ROBOT: int(RIGHT), HUMAN: int(STAY)})  # (1, 3): second battery
    assert info[ROBOT]["batteries"] == 2 and info[HUMAN]["batteries"] == 0
    as_human = env.swapped_observation(ROBOT, HUMAN)
    np.testing.assert_array_equal(as_human, obs[HUMAN])
    assert as_human[CENTRE] == agent_value(0)  # the robot in the human's shoes holds no battery
    as_robot = env.swapped_observation(HUMAN, ROBOT)
    np.testing.assert_array_equal(as_robot, obs[ROBOT])
    assert as_robot[CENTRE] == agent_value(2)
    # the swap leaves the environment alone
    np.testing.assert_array_equal(env.unwrapped.engine.inventory[0], [2, 0])


def test_no_swapped_observation_once_the_cat_left():
    env = coexistence_v0.parallel_env()
    env.reset(seed=0, options={"positions": {ROBOT: (2, 3), CAT: (4, 3)}})
    env.step({ROBOT: int(DOWN), CAT: int(STAY)})  # the robot harms the cat
    assert env.agents == [ROBOT]
    assert env.swapped_observation(ROBOT, CAT) is None
    assert env.swapped_observation(ROBOT, CAT, in_view_only=True) is None
    env.step({ROBOT: int(STAY)})
    assert env.swapped_observation(ROBOT, CAT) is None


def test_harmed_robot_still_has_its_final_swapped_observation():
    """Like its final observation: the cat is still there (an empathic target needs it)."""
    env = coexistence_v0.parallel_env()
    env.reset(seed=0, options={"positions": {ROBOT: (4, 3), CAT: (2, 3)}})
    obs, *_ = env.step({ROBOT: int(STAY), CAT: int(DOWN)})
    assert env.agents == []
    np.testing.assert_array_equal(env.swapped_observation(ROBOT, CAT), obs[CAT])


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_in_view_only(module):
    other = (env_name(module) == "coexistence_v0" and CAT) or HUMAN
    env = module.parallel_env()
    # far apart (3 rows and 3 columns away): outside the 5x5 window
    obs, _ = env.reset(seed=0, options={"positions": {ROBOT: (0, 0), other: (3, 4)}})
    assert env.swapped_observation(ROBOT, other, in_view_only=True) is None
    assert env.swapped_observation(other, ROBOT, in_view_only=True) is None
    np.testing.assert_array_equal(env.swapped_observation(ROBOT, other), obs[other])  # omniscient default
    # on the window's edge, across the wrap: inside
    obs, _ = env.reset(seed=0, options={"positions": {ROBOT: (0, 0), other: (5, 2)}})
    inside = env.swapped_observation(ROBOT, other, in_view_only=True)
    assert isinstance(inside, np.ndarray)
    np.testing.assert_array_equal(inside, obs[other])


def test_swap_rejects_bad_names():
    env = coexistence_v0.parallel_env()
    env.reset(seed=0)
    with pytest.raises(ValueError, match="dog_0"):
        env.swapped_observation(ROBOT, "dog_0")
    with pytest.raises(ValueError, match="itself"):
        env.swapped_observation(ROBOT, ROBOT)


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_empathy_wrapper_infos_at_reset_and_step(module):
    env = EmpathyWrapper(module.parallel_env())
    a, b = env.possible_agents
    obs, infos = env.reset(seed=3)
    assert set(infos[a]["swapped_obs"]) == {b} and set(infos[b]["swapped_obs"]) == {a}
    np.testing.assert_array_equal(infos[a]["swapped_obs"][b], obs[b])
    np.testing.assert_array_equal(infos[b]["swapped_obs"][a], obs[a])
    rng = np.random.default_rng(1)
    for _ in range(30):
        if not env.agents:
            break
        obs, _, _, _, infos = env.step({agent: int(rng.integers(NUM_ACTIONS)) for agent in env.agents})
        for info in infos.values():
            for other, swapped in info["swapped_obs"].items():
                np.testing.assert_array_equal(swapped, obs[other])
    # the environment's own infos are kept
    key = "harmed_by" if module is coexistence_v0 else "batteries"
    assert all(key in info for info in infos.values())


def test_empathy_wrapper_once_the_cat_left():
    env = EmpathyWrapper(coexistence_v0.parallel_env(max_cycles=4))
    env.reset(seed=0, options={"positions": {ROBOT: (2, 3), CAT: (4, 3)}})
    _, _, _, _, infos = env.step({ROBOT: int(DOWN), CAT: int(STAY)})
    assert infos[ROBOT]["swapped_obs"] == {}
    assert infos[ROBOT]["harmed"] == [CAT]
    _, _, _, _, infos = env.step({ROBOT: int(STAY)})
    assert list(infos) == [ROBOT] and infos[ROBOT]["swapped_obs"] == {}


def test_empathy_wrapper_gives_the_final_step_its_swap():
    """At truncation every agent still gets its swapped observations."""
    env = EmpathyWrapper(coexistence_v0.parallel_env(max_cycles=2))
    env.reset(seed=0, options={"positions": {ROBOT: (0, 0), CAT: (3, 3)}})
    env.step({ROBOT: int(STAY), CAT: int(STAY)})
    obs, _, _, trunc, infos = env.step({ROBOT: int(STAY), CAT: int(STAY)})
    assert all(trunc.values()) and env.agents == []
    np.testing.assert_array_equal(infos[ROBOT]["swapped_obs"][CAT], obs[CAT])
    np.testing.assert_array_equal(infos[CAT]["swapped_obs"][ROBOT], obs[ROBOT])


def test_empathy_wrapper_in_view_only():
    env = EmpathyWrapper(coexistence_v0.parallel_env(), in_view_only=True)
    _, infos = env.reset(seed=0, options={"positions": {ROBOT: (0, 0), CAT: (3, 2)}})
    assert infos[ROBOT]["swapped_obs"] == {} and infos[CAT]["swapped_obs"] == {}
    obs, _, _, _, infos = env.step({ROBOT: int(DOWN), CAT: int(UP)})  # (1, 0) and (2, 2): in view
    assert set(infos[ROBOT]["swapped_obs"]) == {CAT}
    np.testing.assert_array_equal(infos[ROBOT]["swapped_obs"][CAT], obs[CAT])


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_empathy_over_fixed_agents_swaps_with_the_fixed_agent(module):
    name = env_name(module)
    fixed = DEFAULT_POLICIES[name]
    (other,) = fixed
    env = EmpathyWrapper(FixedAgents(module.parallel_env(), fixed))
    obs, infos = env.reset(seed=2)
    assert list(obs) == [ROBOT] and list(infos[ROBOT]["swapped_obs"]) == [other]
    base = env.unwrapped
    np.testing.assert_array_equal(infos[ROBOT]["swapped_obs"][other], base.engine.observe(1)[0])


def test_swap_follows_the_definition_when_it_differs_from_the_others_observation():
    """An engine whose picture depends on who is who: the swap exchanges cells and inventories only."""
    from empathy_zoo.engine.sharing import SharingEngine

    class Tagged(SharingEngine):
        """Draws each agent as ``10·(index + 1) + inventory``, to itself too."""

        def _appearance(self, inventory, viewer):
            return 10 * (np.arange(self.num_agents) + 1) + inventory

        def _self_appearance(self, inventory, viewer):
            return 10 * (viewer + 1) + inventory

    engine = Tagged(1)
    engine.reset(seeds=[0], options={"positions": {ROBOT: (3, 3), HUMAN: (3, 4)}, "batteries": [(0, 0)]})
    engine.inventory[0] = [2, 5]
    swapped = engine.observe_swapped(0, 1)[0]
    # the robot (tag 10) now stands on (3, 4) holding 5, the human (tag 20) on (3, 3) holding 2
    assert swapped[CENTRE] == 10 + 5 and swapped[CENTRE - 1] == 20 + 2
    own = engine.observe(1)[0]
    assert own[CENTRE] == 20 + 5 and not np.array_equal(swapped, own)


@pytest.mark.parametrize("in_view_only", [False, True], ids=["omniscient", "in_view_only"])
@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_vector_swapped_agrees_with_the_parallel_primitive(module, in_view_only):
    name = env_name(module)
    fixed = DEFAULT_POLICIES[name]
    (other,) = fixed
    seeds = [0, 1, 2]
    envs = [FixedAgents(module.parallel_env(), fixed) for _ in seeds]
    vector = VectorEnv(name, len(seeds), fixed=fixed, in_view_only=in_view_only)
    vector.reset(seed=seeds)
    for env, seed in zip(envs, seeds, strict=True):
        env.reset(seed=seed)
    rng = np.random.default_rng(3)
    valid_seen, invalid_seen = 0, 0
    for _ in range(600):
        actions = rng.integers(NUM_ACTIONS, size=(len(seeds), 1))
        out = vector.step(actions)
        for i, env in enumerate(envs):
            env.step({ROBOT: int(actions[i, 0])})
            expected = env.unwrapped.swapped_observation(ROBOT, other, in_view_only=in_view_only)
            assert bool(out.other_seen[i, 0]) == (expected is not None)
            if expected is None:
                invalid_seen += 1
                np.testing.assert_array_equal(out.other_swapped[i, 0], 0.0)
            else:
                valid_seen += 1
                np.testing.assert_array_equal(out.other_swapped[i, 0], expected)
            if not env.agents:
                env.reset()
        _all_swaps, mask = vector.swapped_observations(ROBOT)
        assert not mask[:, 0].any()
    assert valid_seen > 30
    if in_view_only or module is coexistence_v0:
        assert invalid_seen > 10


def test_the_swap_permutation_exchanges_exactly_the_two_agents():
    from empathy_zoo.engine.sight import swap_order

    assert swap_order(3, 0, 2).tolist() == [2, 1, 0]
    per_env = swap_order(3, 1, np.array([0, 2, 0]))
    assert per_env.tolist() == [[1, 0, 2], [0, 2, 1], [1, 0, 2]]
    assert (np.take_along_axis(per_env, per_env, axis=1) == np.arange(3)).all()  # swapping twice is no swap
    with pytest.raises(ValueError, match="itself"):
        swap_order(2, 1, np.array([0, 1]))
