"""Bad input is refused with an error naming the problem (SPEC §1; a ``ValueError``, or the
``RuntimeError`` of a step out of turn), the same on every path that takes it: the PettingZoo env,
FixedAgents, the vector env, the Gymnasium adapter and the training path (fixed policies inside
it, method settings, plug-in names, the command line). That a refused call changes nothing is
tests/test_refused_calls_change_nothing.py."""

from __future__ import annotations

import numpy as np
import pytest
from helpers_policies import AlwaysLeft

from empathy_zoo import FixedAgents, coexistence_v0, make_policy, sharing_v0
from empathy_zoo.actions import NUM_ACTIONS, Action
from empathy_zoo.cli import main
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.gym_adapter import make_single_agent_env
from empathy_zoo.import_names import resolve_name
from empathy_zoo.policies import POLICIES
from empathy_zoo.vector import VectorEnv

MODULES = [coexistence_v0, sharing_v0]
IDS = [module.__name__.rsplit(".", 1)[-1] for module in MODULES]
ROBOT, CAT, HUMAN = "robot_0", "cat_0", "human_0"
HELPERS = AlwaysLeft.__module__  # "helpers_policies", importable because pytest puts tests/ on the path
FLOAT_POLICY = f"{HELPERS}:ReturnsAFloat"


# ------------------------------------------------------------------ actions on the PettingZoo env
@pytest.mark.parametrize("module", MODULES, ids=IDS)
@pytest.mark.parametrize(
    "action, message",
    [
        (NUM_ACTIONS, "outside Discrete"),
        (-1, "outside Discrete"),
        (2.5, "integer"),
        (2.0, "integer"),
        ("a", "integer"),
        (np.float64(1.0), "integer"),
        (np.float32(3), "integer"),
        (None, "integer"),
        (np.array([1]), "integer"),
        (np.int64(7), "outside Discrete"),
    ],
    ids=["5", "-1", "2.5", "2.0", "str", "np.float64", "np.float32", "None", "array", "np.int64(7)"],
)
def test_invalid_action_raises(module, action, message):
    env = module.parallel_env()
    env.reset(seed=0)
    robot_first = env.unwrapped.engine.cells.copy()
    other = env.possible_agents[1]
    with pytest.raises(ValueError, match=message) as error:
        env.step({ROBOT: action, other: int(Action.STAY)})
    assert ROBOT in str(error.value)
    np.testing.assert_array_equal(env.unwrapped.engine.cells, robot_first)  # nothing moved


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_valid_integer_kinds_are_accepted(module):
    env = module.parallel_env()
    other = env.possible_agents[1]
    env.reset(seed=0, options={"positions": {ROBOT: (0, 0), other: (4, 4)}})
    env.step({ROBOT: np.int64(1), other: np.int32(2)})
    env.step({ROBOT: np.array(3), other: np.uint8(4)})
    assert env.unwrapped.engine.pos[0].tolist() == [[1, 1], [4, 3]]


@pytest.mark.parametrize("actions", [[0, 0], (0, 0), np.array([0, 0]), 3, None], ids=["list", "tuple", "array", "int", "None"])
def test_a_joint_action_must_be_a_dict(actions):
    env = coexistence_v0.parallel_env()
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"actions must be a dict \{agent: action\}"):
        env.step(actions)


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_action_for_an_unknown_agent_raises(module):
    env = module.parallel_env()
    env.reset(seed=0)
    other = env.possible_agents[1]
    with pytest.raises(ValueError, match="unknown agent 'dog_0'"):
        env.step({ROBOT: 4, other: 4, "dog_0": 4})


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_missing_action_raises(module):
    env = module.parallel_env()
    env.reset(seed=0)
    other = env.possible_agents[1]
    with pytest.raises(ValueError, match=f"no action given.*{other}"):
        env.step({ROBOT: 4})
    with pytest.raises(ValueError, match="no action given"):
        env.step({})


def test_action_for_an_agent_that_left_raises():
    env = coexistence_v0.parallel_env()
    env.reset(seed=0, options={"positions": {ROBOT: (2, 3), CAT: (4, 3)}})
    env.step({ROBOT: int(Action.DOWN), CAT: int(Action.STAY)})  # the cat is harmed and leaves
    assert CAT not in env.agents
    with pytest.raises(ValueError, match=f"{CAT}.*no longer in the environment"):
        env.step({ROBOT: 4, CAT: 4})


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_step_before_reset_and_after_the_end_raises(module):
    env = module.parallel_env(max_cycles=1)
    with pytest.raises(RuntimeError, match="reset"):
        env.step({ROBOT: 4})
    env.reset(seed=0)
    env.step(dict.fromkeys(env.agents, 4))
    assert env.agents == []
    with pytest.raises(RuntimeError, match="reset"):
        env.step({ROBOT: 4})


# ------------------------------------------------------------------ actions on the other faces, and a fixed policy's
def test_fixed_agents_refuses_an_action_for_the_fixed_agent():
    env = FixedAgents(coexistence_v0.parallel_env(), {CAT: "random_walk"})
    env.reset(seed=0)
    with pytest.raises(ValueError, match=CAT):
        env.step({ROBOT: 4, CAT: 4})


@pytest.mark.parametrize(
    "actions, message",
    [
        (np.full((3, 1), 5), "invalid action 5 for robot_0 in env 0"),
        (np.full((3, 1), -2), "invalid action -2 for robot_0"),
        (np.full((3, 1), 1.0), "actions must be integers"),
        (np.full((3, 1), True), "actions must be integers"),
        (np.full((3, 1), 1.5), "actions must be integers"),
        (np.full((3, 1), "a"), "integers"),
        (np.full((3, 2), 1), "shape"),
        (np.full((2, 1), 1), "shape"),
    ],
    ids=["5", "-2", "float", "bool", "fraction", "str", "too many columns", "too few envs"],
)
def test_vector_env_invalid_actions(actions, message):
    vector = VectorEnv("coexistence_v0", 3, fixed={CAT: "random_walk"})
    vector.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        vector.step(actions)


def test_vector_env_step_before_reset():
    with pytest.raises(RuntimeError, match="reset"):
        VectorEnv("sharing_v0", 2, fixed={HUMAN: "patrol"}).step(np.zeros((2, 1), dtype=np.int64))


def test_a_policy_choosing_a_float_is_refused_on_every_path_not_truncated():
    message = r"fixed policy helpers_policies:ReturnsAFloat of cat_0 chose an invalid action: .*got 2\.7"
    env = FixedAgents(coexistence_v0.parallel_env(), {CAT: FLOAT_POLICY})
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.step({ROBOT: 4})
    vector = VectorEnv("coexistence_v0", 2, fixed={CAT: FLOAT_POLICY})
    vector.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        vector.step(np.full((2, 1), 4))
    single = make_single_agent_env("coexistence_v0", fixed={CAT: FLOAT_POLICY})
    single.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        single.step(4)


# ------------------------------------------------------------------ reset options and seeds
@pytest.mark.parametrize("module", MODULES, ids=IDS)
@pytest.mark.parametrize(
    "positions, message",
    [
        ({"dog_0": (0, 0)}, "unknown agent 'dog_0'"),
        ({ROBOT: (7, 0)}, r"\(7, 0\) is off the 7x7 grid"),
        ({ROBOT: (0, -1)}, r"\(0, -1\) is off the 7x7 grid"),
        ({ROBOT: (1, 2, 3)}, "pair of ints"),
        ({ROBOT: 5}, "pair of ints"),
        ({ROBOT: "12"}, "pair of ints"),
        ({ROBOT: (1.5, 2)}, "pair of ints"),
        ({ROBOT: None}, "pair of ints"),
        ({ROBOT: (True, False)}, "pair of ints"),
        ([(0, 0)], "must map agent names"),
    ],
    ids=["unknown agent", "row off grid", "negative col", "triple", "int", "str", "float", "None", "bools", "list"],
)
def test_bad_positions_raise(module, positions, message):
    env = module.parallel_env()
    with pytest.raises(ValueError, match=message):
        env.reset(seed=0, options={"positions": positions})
    assert env.agents == []
    with pytest.raises(RuntimeError):
        env.step({ROBOT: 4})
    env.reset(seed=0)  # a good reset works again
    assert env.agents == env.possible_agents


@pytest.mark.parametrize("cell", [(float("inf"), 0), (0, float("-inf")), (float("nan"), 1), (10**30, 0)])
def test_a_position_that_is_no_cell_names_the_option(cell):
    with pytest.raises(ValueError, match=r"options\['positions'\]\['robot_0'\]"):
        coexistence_v0.parallel_env().reset(seed=0, options={"positions": {ROBOT: cell}})


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_two_agents_on_one_cell_raise(module):
    other = module.parallel_env().possible_agents[1]
    with pytest.raises(ValueError, match=rf"{ROBOT} and {other} are both placed on \(2, 2\)"):
        module.parallel_env().reset(seed=0, options={"positions": {ROBOT: (2, 2), other: (2, 2)}})


@pytest.mark.parametrize("cat", [(3, 4), (2, 3), (0, 3), (6, 3), (3, 0)], ids=["right", "above", "far", "wrap", "row"])
def test_agents_in_contact_in_coexistence_raise(cat):
    robot = {(0, 3): (6, 3), (6, 3): (0, 3), (3, 0): (3, 6)}.get(cat, (3, 3))
    with pytest.raises(ValueError, match="would start in contact"):
        coexistence_v0.parallel_env().reset(seed=0, options={"positions": {ROBOT: robot, CAT: cat}})


def test_diagonal_start_in_coexistence_is_allowed():
    env = coexistence_v0.parallel_env()
    env.reset(seed=0, options={"positions": {ROBOT: (3, 3), CAT: (4, 4)}})
    assert env.agents == [ROBOT, CAT]


def test_agent_on_a_battery_raises():
    with pytest.raises(ValueError, match=rf"{ROBOT} is placed on a battery at \(1, 1\)"):
        sharing_v0.parallel_env().reset(seed=0, options={"positions": {ROBOT: (1, 1)}})
    with pytest.raises(ValueError, match=rf"{HUMAN} is placed on a battery at \(0, 0\)"):
        sharing_v0.parallel_env().reset(seed=0, options={"positions": {HUMAN: (0, 0)}, "batteries": [(0, 0), (2, 2)]})
    # with a custom layout, an odd cell without a battery is a fine start
    env = sharing_v0.parallel_env()
    env.reset(seed=0, options={"positions": {ROBOT: (1, 1)}, "batteries": [(0, 0)]})
    assert env.agents == [ROBOT, HUMAN]


@pytest.mark.parametrize(
    "batteries, message",
    [
        ([(0, 0), (0, 0)], r"lists \(0, 0\) twice"),
        ([(0, 9)], "off the 7x7 grid"),
        ([(0, 0, 0)], "pair of ints"),
        ("(0, 0)", "list of"),
        (5, "list of"),
        ([], "at least one battery"),
    ],
    ids=["duplicate", "off grid", "triple", "str", "int", "empty"],
)
def test_bad_batteries_raise(batteries, message):
    with pytest.raises(ValueError, match=message):
        sharing_v0.parallel_env().reset(seed=0, options={"batteries": batteries})


def test_a_layout_leaving_no_start_cell_is_refused():
    every_cell = [(r, c) for r in range(7) for c in range(7)]
    with pytest.raises(ValueError, match="at most 9 fit"):
        sharing_v0.parallel_env().reset(seed=0, options={"batteries": every_cell})


def test_a_battery_layout_larger_than_the_default_is_refused() -> None:
    env = sharing_v0.parallel_env()
    cells = [(r, c) for r in range(7) for c in range(7) if (r, c) not in ((0, 0), (0, 1))][:10]
    with pytest.raises(ValueError, match="at most 9"):
        env.reset(seed=0, options={"batteries": cells, "positions": {"robot_0": (0, 0), "human_0": (0, 1)}})


def test_batteries_option_in_coexistence_is_ignored_with_a_warning():
    env = coexistence_v0.parallel_env()
    with pytest.warns(UserWarning, match=r"ignoring unknown reset option\(s\) \['batteries'\] for coexistence_v0"):
        env.reset(seed=0, options={"positions": {ROBOT: (0, 0), CAT: (3, 3)}, "batteries": [(1, 1)]})
    assert env.agents == [ROBOT, CAT]
    assert env.unwrapped.engine.pos[0].tolist() == [[0, 0], [3, 3]]  # the rest of the options still apply


@pytest.mark.parametrize("module", MODULES, ids=IDS)
def test_options_must_be_a_mapping(module):
    with pytest.raises(ValueError, match="options must be a mapping"):
        module.parallel_env().reset(seed=0, options=[("positions", {})])


@pytest.mark.parametrize("seed", [-1, 1.5, "1"])
def test_bad_seed_raises(seed):
    with pytest.raises(ValueError, match="seed"):
        coexistence_v0.parallel_env().reset(seed=seed)


@pytest.mark.parametrize("seed", [2.5, [1.5, 2], [-1, 2], ["1", 2], True])
def test_vector_seeds_are_not_truncated(seed):
    with pytest.raises(ValueError, match="seed"):
        VectorEnv("coexistence_v0", 2).reset(seed=seed)


# ------------------------------------------------------------------ constructor arguments
@pytest.mark.parametrize("module", MODULES, ids=IDS)
@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"view": 4}, "view must be odd"),
        ({"view": 0}, "view must be odd"),
        ({"view": -3}, "view must be odd"),
        ({"view": 7}, "smaller than size=7"),
        ({"view": 9}, "smaller than size=7"),
        ({"size": 9, "view": 9}, "smaller than size=9"),
        ({"size": 2, "view": 1}, "size must be at least"),
        ({"max_cycles": 0}, "max_cycles must be positive"),
        ({"max_cycles": -5}, "max_cycles must be positive"),
        ({"size": 7.0}, "size must be an int"),
        ({"view": "5"}, "view must be an int"),
        ({"max_cycles": True}, "max_cycles must be an int"),
    ],
)
def test_bad_constructor_arguments_raise(module, kwargs, message):
    with pytest.raises(ValueError, match=message):
        module.parallel_env(**kwargs)


def test_coexistence_needs_size_five():
    """With size < 5 'the one above' would be ambiguous for agents two rows apart."""
    with pytest.raises(ValueError, match="size must be at least 5"):
        coexistence_v0.parallel_env(size=4, view=3)
    coexistence_v0.parallel_env(size=5, view=3).reset(seed=0)
    sharing_v0.parallel_env(size=3, view=1).reset(seed=0)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"env": "nope_v0", "num_envs": 2}, "unknown environment 'nope_v0'"),
        ({"env": "coexistence_v0", "num_envs": 2, "fixed": {"dog_0": "stay"}}, "unknown agent"),
        ({"env": "coexistence_v0", "num_envs": 2, "fixed": {ROBOT: "stay", CAT: "stay"}}, "every agent is fixed"),
        ({"env": "coexistence_v0", "num_envs": 2, "fixed": {CAT: "nope"}}, "unknown fixed policy 'nope'"),
        ({"env": "sharing_v0", "num_envs": 2, "view": 6}, "view must be odd"),
    ],
)
def test_bad_vector_env_arguments_raise(kwargs, message):
    with pytest.raises(ValueError, match=message):
        VectorEnv(**kwargs)


@pytest.mark.parametrize("num_envs", [2.5, "2", True, 0, -1])
def test_the_number_of_environments_is_a_positive_int(num_envs):
    with pytest.raises(ValueError, match="num_envs must be a positive int"):
        VectorEnv("coexistence_v0", num_envs)


def test_fixed_agents_with_an_unknown_or_every_agent_raises():
    with pytest.raises(ValueError, match=r"unknown agent.*dog_0"):
        FixedAgents(coexistence_v0.parallel_env(), {"dog_0": "random_walk"})
    with pytest.raises(ValueError, match="every agent is fixed"):
        FixedAgents(coexistence_v0.parallel_env(), {ROBOT: "stay", CAT: "stay"})
    with pytest.raises(ValueError, match="unknown fixed policy"):
        FixedAgents(coexistence_v0.parallel_env(), {CAT: "teleport"})


# ------------------------------------------------------------------ fixed policies and plug-in names
def test_unknown_policy_name_lists_the_registered_ones():
    with pytest.raises(ValueError, match="unknown fixed policy 'teleport'") as error:
        make_policy("teleport")
    for name in POLICIES:
        assert name in str(error.value)
    assert "package.module:ClassName" in str(error.value)


@pytest.mark.parametrize(
    "spec, message",
    [
        ("no_such_module_xyz:Policy", "cannot import module 'no_such_module_xyz'"),
        (f"{HELPERS}:Missing", "has no 'Missing'"),
        (f"{HELPERS}:NotAPolicy", "is not a fixed policy"),
        ("", "non-empty string"),
    ],
)
def test_bad_policy_specs_raise(spec, message):
    with pytest.raises(ValueError, match=message):
        make_policy(spec)


def test_registered_names_and_keyword_arguments():
    assert isinstance(make_policy("random_walk"), POLICIES["random_walk"])
    patrol = make_policy("patrol", period=3)
    assert patrol.period == 3
    with pytest.raises(ValueError, match="cannot build fixed policy 'patrol'"):
        make_policy("patrol", speed=2)
    with pytest.raises(ValueError, match="period must be an int in \\[1, "):
        make_policy("patrol", period=0)
    with pytest.raises(ValueError, match="keyword arguments"):
        make_policy(AlwaysLeft(), period=3)


def test_module_colon_class_policy_drives_the_fixed_agent():
    policy = make_policy(f"{HELPERS}:AlwaysLeft")
    assert isinstance(policy, AlwaysLeft)
    env = FixedAgents(coexistence_v0.parallel_env(), {CAT: f"{HELPERS}:AlwaysLeft"})
    env.reset(seed=0, options={"positions": {ROBOT: (0, 0), CAT: (3, 3)}})
    for col in (2, 1, 0, 6):
        env.step({ROBOT: int(Action.STAY)})
        assert env.unwrapped.engine.pos[0, 1].tolist() == [3, col]


def test_user_policy_gives_the_same_trajectories_on_both_faces():
    """A plug-in policy without a batched form runs one copy per environment in the vector env."""
    spec = f"{HELPERS}:UpWhenCrowded"
    seeds = [3, 4]
    envs = [FixedAgents(coexistence_v0.parallel_env(), {CAT: spec}) for _ in seeds]
    vector = VectorEnv("coexistence_v0", len(seeds), fixed={CAT: spec})
    observations = vector.reset(seed=seeds)
    for i, (env, seed) in enumerate(zip(envs, seeds, strict=True)):
        np.testing.assert_array_equal(env.reset(seed=seed)[0][ROBOT], observations[i, 0])
    rng = np.random.default_rng(0)
    for _ in range(300):
        actions = rng.integers(NUM_ACTIONS, size=(len(seeds), 1))
        out = vector.step(actions)
        for i, env in enumerate(envs):
            obs, rew, *_ = env.step({ROBOT: int(actions[i, 0])})
            np.testing.assert_array_equal(out.final_observations[i, 0], obs[ROBOT])
            assert out.rewards[i, 0] == rew[ROBOT]
            if not env.agents:
                np.testing.assert_array_equal(env.reset()[0][ROBOT], out.observations[i, 0])


@pytest.mark.parametrize(
    "spec, message",
    [
        ("..x:Y", "'..x:Y' is not a valid 'package.module:Name'"),
        (".x:Y", "is not a valid 'package.module:Name'"),
        ("x:", "is not a valid 'package.module:Name'"),
        (":Y", "is not a valid 'package.module:Name'"),
        ("a b:C", "is not a valid 'package.module:Name'"),
        ("x:Y:Z", "is not a valid 'package.module:Name'"),
        ("helpers_broken_module:X", "importing module 'helpers_broken_module' .* raised RuntimeError: this module is broken"),
    ],
)
def test_a_bad_plugin_name_is_a_clear_error(spec, message):
    with pytest.raises(ValueError, match=message):
        resolve_name(spec, {}, "method")


@pytest.mark.parametrize("option", ["--method", "--fixed"])
def test_the_command_line_refuses_a_bad_plugin_name(tmp_path, capsys, option):
    value = "..x:Y" if option == "--method" else "cat_0=..x:Y"
    assert main(["train", option, value, "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "is not a valid 'package.module:Name'" in err and "Traceback" not in err, err


# ------------------------------------------------------------------ method settings
@pytest.mark.parametrize(
    "method, name, value",
    [
        ("empathic_dqn", "learning_rate", float("inf")),
        ("empathic_dqn", "learning_rate", float("nan")),
        ("dqn", "gamma", float("nan")),
        ("empathic_dqn", "epsilon_end", float("-inf")),
        ("baselines.sb3:SB3_DQN", "learning_rate", float("inf")),
    ],
)
def test_a_setting_must_be_a_finite_number(method, name, value):
    with pytest.raises(ValueError, match=f"{name} must be a finite number"):
        RunSpec.of(method=method, settings={name: value})


def test_the_command_line_refuses_an_infinite_learning_rate(tmp_path, capsys):
    assert main(["train", "--learning-rate", "inf", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "learning_rate must be a finite number" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()
