"""One validation on every path: what the PettingZoo env refuses, the training path (vector env,
fixed policies inside it, settings, plug-in names) refuses too, with the same kind of message."""

from __future__ import annotations

import numpy as np
import pytest

from empathy_zoo import FixedAgents, coexistence_v0
from empathy_zoo.cli import main
from empathy_zoo.gym_adapter import make_single_agent_env
from empathy_zoo.registry import resolve_name
from empathy_zoo.training.spec import RunSpec
from empathy_zoo.vector import VectorEnv

ROBOT, CAT = "robot_0", "cat_0"
FLOAT_POLICY = "helpers_policies:ReturnsAFloat"


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


@pytest.mark.parametrize(
    "actions", [np.full((2, 1), 1.0), np.full((2, 1), True), np.full((2, 1), 1.5)], ids=["float", "bool", "fraction"]
)
def test_the_vector_env_refuses_actions_that_are_not_integers(actions):
    vector = VectorEnv("coexistence_v0", 2, fixed={CAT: "random_walk"})
    vector.reset(seed=0)
    with pytest.raises(ValueError, match="actions must be integers"):
        vector.step(actions)


@pytest.mark.parametrize("num_envs", [2.5, "2", True, 0, -1])
def test_the_number_of_environments_is_a_positive_int(num_envs):
    with pytest.raises(ValueError, match="num_envs must be a positive int"):
        VectorEnv("coexistence_v0", num_envs)


@pytest.mark.parametrize("seed", [2.5, [1.5, 2], [-1, 2], ["1", 2], True])
def test_vector_seeds_are_not_truncated(seed):
    with pytest.raises(ValueError, match="seed"):
        VectorEnv("coexistence_v0", 2).reset(seed=seed)


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
        RunSpec(method=method, settings={name: value})


def test_the_command_line_refuses_an_infinite_learning_rate(tmp_path, capsys):
    assert main(["train", "--learning-rate", "inf", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "learning_rate must be a finite number" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("actions", [[0, 0], (0, 0), np.array([0, 0]), 3, None], ids=["list", "tuple", "array", "int", "None"])
def test_a_joint_action_must_be_a_dict(actions):
    env = coexistence_v0.parallel_env()
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"actions must be a dict \{agent: action\}"):
        env.step(actions)


@pytest.mark.parametrize("cell", [(float("inf"), 0), (0, float("-inf")), (float("nan"), 1), (10**30, 0)])
def test_a_position_that_is_no_cell_names_the_option(cell):
    with pytest.raises(ValueError, match=r"options\['positions'\]\['robot_0'\]"):
        coexistence_v0.parallel_env().reset(seed=0, options={"positions": {ROBOT: cell}})


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
