"""The suite's reward transforms on Stable-Baselines3's learners: SB3 stores and trains on the
shaped reward, the suite scores the environment's events, a sweep file names the composition,
and what cannot run is refused, saying why."""

from __future__ import annotations

import importlib.util
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import pytest

from agents.rewards import TrainRewards
from baselines.lagrangian import Lagrangian
from baselines.methods import BASELINE_METHODS
from baselines.registry import METHODS, get_method
from empathy_zoo.experiment.sweep_file import SweepConfigError, parse_sweep
from empathy_zoo.result_file import check_result
from empathy_zoo.training import RunnerOptions, train_runs
from empathy_zoo.training.ensemble import learner_batch
from empathy_zoo.vector import VectorEnv

from baselines.sb3 import PRICED_AT_SAMPLE_ON_DQN, SB3_DQN, SB3_PPO, SB3Learner, SB3Settings  # isort: skip
from baselines.sb3_transforms import SB3_REFUSED, SB3_TRANSFORM_METHODS, with_transform  # isort: skip

needs_sb3 = pytest.mark.skipif(importlib.util.find_spec("stable_baselines3") is None, reason="stable-baselines3 not installed")

DQN_SMALL: dict[str, Any] = {"buffer_size": 1_000, "learning_starts": 500, "target_update_interval": 40}
PPO_SMALL: dict[str, Any] = {"n_steps": 32, "n_epochs": 1}
OPTIONS = RunnerOptions(progress=False, checkpoint_interval=0)


@dataclass(frozen=True)
class Scaled:
    """``r' = factor · r``: a hand-made transform whose output is known exactly."""

    name: ClassVar[str] = "scaled"
    factor: float = 0.0

    def __call__(self, batch: Any) -> np.ndarray:
        return (self.factor * batch.rewards).astype(np.float32)


def drive(algorithm: str, transform: Any, steps: int, kwargs: dict[str, Any]) -> SB3Learner:
    """``steps`` Coexistence steps of one SB3 run, given what the trainer gives it: the step's
    batch through :class:`TrainRewards` of ``transform`` (episodes long enough not to be truncated)."""
    venv = VectorEnv("coexistence_v0", 1, fixed={"cat_0": "stay"}, max_cycles=500)
    settings = SB3Settings(algorithm=algorithm, algorithm_kwargs=kwargs, batch_size=16)
    learner = SB3Learner([settings], [0], venv.obs_size, venv.num_actions)
    rewards = TrainRewards([transform], seeds=[0])
    if rewards.priced_runs.any():
        learner.price_costs(rewards.priced_runs)
    obs = venv.reset(seed=0)[:, 0]
    for _ in range(steps):
        actions = learner.act(obs[:, None, :])
        result = venv.step(actions.reshape(1, 1))
        learner.observe(rewards(learner_batch(obs, actions, result)))
        obs = result.observations[:, 0]
    return learner


@needs_sb3
@pytest.mark.parametrize("factor", [0.0, -3.0])
def test_ppo_and_dqn_store_the_shaped_reward(factor: float) -> None:
    ppo = drive("ppo", Scaled(factor), 20, PPO_SMALL).models[0].rollout_buffer  # (a rollout of 32: not trained yet)
    dqn = drive("dqn", Scaled(factor), 20, DQN_SMALL).models[0].replay_buffer
    plain = drive("ppo", None, 20, PPO_SMALL).models[0].rollout_buffer
    assert ppo.pos == dqn.pos == plain.pos == 20
    np.testing.assert_array_equal(plain.rewards[:20], 1.0)  # the environment's: +1 a step survived
    np.testing.assert_array_equal(ppo.rewards[:20], np.float32(factor))
    np.testing.assert_array_equal(dqn.rewards[:20], np.float32(factor))


@needs_sb3
def test_ppo_prices_the_lagrangian_cost_when_it_trains_on_the_rollout(monkeypatch: pytest.MonkeyPatch) -> None:
    seen: list[np.ndarray] = []

    def record(self: Any) -> None:  # (SB3's train() replaced: what it would train on)
        seen.append(self.rollout_buffer.rewards.copy())

    from stable_baselines3 import PPO

    monkeypatch.setattr(PPO, "train", record)
    learner = drive("ppo", Lagrangian(lambda_init=7.0), 32, PPO_SMALL)
    run = learner._runs[0]
    np.testing.assert_array_equal(learner.models[0].rollout_buffer.rewards, 1.0)  # stored unpriced, cost beside it
    costs = getattr(run, "costs").copy()
    assert getattr(run, "price") == 7.0  # no episode has ended: λ is its start
    learner.act(np.zeros((1, 1, learner.models[0].observation_space.shape[0]), dtype=np.float32))
    assert len(seen) == 1
    np.testing.assert_array_equal(seen[0], (1.0 - np.float32(7.0) * costs).astype(np.float32))


@needs_sb3
def test_a_priced_transform_on_sb3_dqn_is_refused_saying_why() -> None:
    learner = SB3Learner([SB3Settings(algorithm="dqn", algorithm_kwargs=DQN_SMALL)], [0], 25, 5)
    with pytest.raises(ValueError, match="SB3 DQN cannot train a reward transform that prices its costs"):
        learner.price_costs([True])
    with pytest.raises(ValueError, match="replay buffer"):
        get_method("sb3_dqn_lagrangian")
    with pytest.raises(ValueError, match="prices its costs when sampled"):
        with_transform(SB3_DQN, Lagrangian(), name="mine")
    assert with_transform(SB3_PPO, Lagrangian(), name="mine").reward == Lagrangian()
    assert set(SB3_REFUSED) == {"sb3_dqn_lagrangian"} and PRICED_AT_SAMPLE_ON_DQN in SB3_REFUSED["sb3_dqn_lagrangian"]
    sweep = {
        "sweep": {"seeds": 1, "steps": 100},
        "envs": {"coexistence_v0": {}},
        "methods": [{"method": "sb3_dqn_lagrangian"}],
    }
    with pytest.raises(SweepConfigError, match=r"\[\[methods\]\] #1.*sb3_ppo_lagrangian"):
        parse_sweep(sweep, source="mine.toml")


def test_every_transform_baseline_is_registered_on_both_sb3_learners() -> None:
    transforms = [name.removeprefix("dqn_") for name, m in BASELINE_METHODS.items() if m.reward is not None]
    assert {"harm_penalty", "lagrangian", "aup", "relative_reachability", "considerate", "social_value"} <= set(transforms)
    for name in transforms:
        ppo = METHODS[f"sb3_ppo_{name}"]
        assert ppo.reward == BASELINE_METHODS[f"dqn_{name}"].reward and ppo.learner is SB3Learner
        assert ppo.family == "sb3" and not ppo.dqn_reference and ppo.preset == {"algorithm": "ppo"}
        assert (f"sb3_dqn_{name}" in SB3_TRANSFORM_METHODS) != (name == "lagrangian")
    harm = METHODS["sb3_ppo_harm_penalty"]
    assert harm.display_name(harm.make_settings({}), harm.make_reward({"penalty": -10})) == "SB3 PPO + harm penalty (−10)"
    assert harm.identical_to == {"sharing_v0": ("sb3_ppo", "nobody is harmed in Sharing: the penalty is always 0")}


SWEEP = """
[sweep]
seeds = 1
steps = 300
eval_interval = 150
eval_episodes = 2

[envs.coexistence_v0]
max_cycles = 60

[[methods]]
method = "sb3_ppo"
algorithm_kwargs = { n_steps = 64, n_epochs = 2 }
batch_size = 32

[[methods]]
method = "sb3_ppo_harm_penalty"
penalty = -100.0
algorithm_kwargs = { n_steps = 64, n_epochs = 2 }
batch_size = 32

[[methods]]
method = "sb3_ppo_lagrangian"
reward.lambda_init = 5.0
algorithm_kwargs = { n_steps = 64, n_epochs = 2 }
batch_size = 32
"""


@needs_sb3
def test_a_sweep_file_trains_sb3_ppo_with_a_harm_penalty_and_the_lagrangian(tmp_path: Path) -> None:
    path = tmp_path / "sb3_transforms.toml"
    path.write_text(SWEEP)
    from empathy_zoo.experiment.sweep_file import load_sweep

    specs = load_sweep(path)
    assert [s.display_label() for s in specs] == [
        "SB3 PPO",
        "SB3 PPO + harm penalty (−100)",
        "SB3 PPO-Lagrangian (lambda_init=5)",
    ]
    paths = train_runs(specs, tmp_path / "out", OPTIONS)
    plain, harm, lagrangian = (check_result(json.loads(Path(p).read_text()), p) for p in paths)
    assert harm["method"] == "sb3_ppo_harm_penalty" and harm["config"]["reward"] == {"name": "harm_penalty", "penalty": -100.0}
    assert harm["config"]["description"]["family"] == "sb3" and harm["config"]["description"]["reward"]["name"] == "harm_penalty"
    for run in (plain, harm, lagrangian):  # scored on the environment's events: +1 a step survived, never the penalty
        assert run["train"]["return"] == [float(s) for s in run["train"]["survival"]]
        assert len(run["eval"]) == 2
    assert len(lagrangian["train"]["lambda"]) == len(lagrangian["train"]["survival"]) and "lambda" not in harm["train"]
    assert all(value >= 0 for value in lagrangian["train"]["lambda"])
