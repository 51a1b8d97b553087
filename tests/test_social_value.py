"""Social value orientation (McKee et al. 2020) on hand-made numbers: the reward angle of smoothed
rewards, both sides of 45° penalised, no penalty while both rewards are 0, the trace reset at an
episode's end, the other's environment reward read; its state survives a checkpoint."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers_resume import whole_and_resumed
from test_inequity_aversion import step  # one step of hand-made own and other rewards

from agents.base import StepBatch
from agents.rewards import TrainRewards
from baselines.social_value import SocialValueOrientation, reward_angle


def test_the_reward_angle_is_atan2_of_other_over_own_and_undefined_at_zero() -> None:
    angles = reward_angle(np.array([1.0, 1.0, 0.0, 1.0, 0.0]), np.array([1.0, 0.0, 1.0, math.sqrt(3.0), 0.0]))
    assert angles[:4].tolist() == pytest.approx([math.pi / 4, 0.0, math.pi / 2, math.pi / 3])
    assert math.isnan(angles[4])


def test_advantage_and_disadvantage_both_cost_and_both_zero_costs_nothing() -> None:
    svo = SocialValueOrientation(weight=0.5, target_angle_degrees=45.0, smoothing=0.5)
    state = svo.initial_state(5, 1)
    # equal; learner ahead (θ = 0°); learner behind (θ = 90°); θ = 60°; nothing earned by either
    shaped, state = svo(step([1.0, 1.0, 0.0, 1.0, 0.0], [1.0, 0.0, 1.0, math.sqrt(3.0), 0.0]), state)
    quarter = math.pi / 4
    assert shaped[:, 0].tolist() == pytest.approx([1.0, 1.0 - 0.5 * quarter, 0.0 - 0.5 * quarter, 1.0 - 0.5 * math.pi / 12, 0.0])
    # an idle step: the smoothed rewards keep their angle (and its penalty); both-zero stays free
    shaped, state = svo(step([0.0] * 5, [0.0] * 5, ended=[False, False, True, False, False]), state)
    assert shaped[:, 0].tolist() == pytest.approx([0.0, -0.5 * quarter, -0.5 * quarter, -0.5 * math.pi / 12, 0.0])
    assert state["own"][:, 0].tolist() == pytest.approx([0.5, 0.5, 0.0, 0.5, 0.0])
    assert state["other"][2, 0] == 0.0  # run 2's episode ended: its trace starts afresh
    shaped, _ = svo(step([0.0] * 5, [0.0] * 5), state)
    assert shaped[2, 0] == 0.0 and shaped[1, 0] == pytest.approx(-0.5 * quarter)


def test_the_target_angle_is_in_degrees_and_an_individualist_minds_only_being_behind() -> None:
    individualist = SocialValueOrientation(target_angle_degrees=0.0)
    shaped, _ = individualist(step([1.0, 0.0], [0.0, 1.0]), individualist.initial_state(2, 1))
    assert shaped[:, 0].tolist() == pytest.approx([1.0, -0.5 * math.pi / 2])


def test_it_reads_the_others_environment_reward_and_smooths_the_unshaped_own_reward() -> None:
    svo = SocialValueOrientation(smoothing=0.5)
    rewards = TrainRewards([svo, None])
    # the other's battery return says nothing: the angle comes from other_rewards
    batch = step([1.0, 1.0], [1.0, 1.0])
    batch.other_battery_return[:] = 7.0
    assert rewards(batch).rewards[:, 0].tolist() == pytest.approx([1.0, 1.0])
    ahead = rewards(step([1.0, 1.0], [0.0, 0.0]))
    assert ahead.rewards[0, 0] < 1.0 and ahead.rewards[1, 0] == 1.0  # run 1 trains on its own reward
    # the trace holds the environment's rewards (1 + 0.5·1), never the shaped ones
    assert rewards.states[0]["own"][0, 0] == pytest.approx(1.5) and rewards.states[0]["other"][0, 0] == pytest.approx(0.5)
    with pytest.raises(ValueError, match="other_rewards"):
        svo(StepBatch(**{**step([0.0], [0.0]).__dict__, "others_rewards": None}), svo.initial_state(1, 1))


@pytest.mark.parametrize(
    "field, value", [("weight", -1.0), ("weight", float("nan")), ("target_angle_degrees", 270.0), ("smoothing", 1.0)]
)
def test_bad_parameters_are_refused_naming_them(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=field):
        SocialValueOrientation(**{field: value})


def test_a_resumed_social_value_run_equals_an_uninterrupted_one(tmp_path, monkeypatch) -> None:
    from empathy_zoo.experiment.model import RunSpec

    spec = RunSpec.of(
        env="sharing_v0",
        method="dqn_social_value",
        steps=600,
        eval_interval=300,
        eval_episodes=2,
        settings={"learning_starts": 64, "replay_capacity": 1_000, "epsilon_decay_steps": 300, "target_update_interval": 50},
    )
    whole, resumed = whole_and_resumed(spec, tmp_path, monkeypatch)
    assert resumed["train"] == whole["train"] and resumed["eval"] == whole["eval"]
    assert resumed["config"]["reward"] == {
        "name": "social_value_orientation",
        "weight": 0.5,
        "target_angle_degrees": 45.0,
        "smoothing": pytest.approx(0.9405),
    }
