"""The Stable-Baselines3 plug-in: trained by the runner, scored by the suite, learning exactly as
SB3's own ``learn()`` does, checkpointable, and independent of the runs beside it."""

from __future__ import annotations

import importlib.util
import io
import json
import sys

import numpy as np
import pytest
import torch
from helpers_batches import one_other

from agents.base import StepBatch
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.gym_adapter import make_single_agent_env
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.training import RunnerOptions, train_runs

from baselines.sb3 import INSTALL_HINT, SB3_DQN, SB3_PPO, SB3Learner, SB3Settings, make_sb3_model, sb3_seed  # isort: skip

needs_sb3 = pytest.mark.skipif(importlib.util.find_spec("stable_baselines3") is None, reason="stable-baselines3 not installed")

DQN_SMALL = {"algorithm_kwargs": {"buffer_size": 1_000, "learning_starts": 50, "target_update_interval": 40}}
PPO_SMALL = {"algorithm_kwargs": {"n_steps": 64, "n_epochs": 2}, "batch_size": 32}
OPTIONS = RunnerOptions(progress=False, checkpoint_interval=0)


def spec(method: str, settings: dict, seed: int = 0, env: str = "coexistence_v0", steps: int = 300) -> RunSpec:
    return RunSpec.of(
        env=env,
        method=method,
        settings=settings,
        seed=seed,
        steps=steps,
        eval_interval=150,
        eval_episodes=2,
        env_kwargs={"max_cycles": 60},
    )


def read(path) -> dict:
    return json.loads(path.read_text())


@needs_sb3
@pytest.mark.parametrize(
    "method, settings, env",
    [
        ("baselines.sb3:SB3_DQN", DQN_SMALL, "coexistence_v0"),
        ("baselines.sb3:SB3_PPO", PPO_SMALL, "sharing_v0"),
    ],
)
def test_runner_trains_it_and_the_suite_scores_it(tmp_path, method, settings, env):
    reference = {"learning_starts": 50, "replay_capacity": 1_000, "selfishness": 0.5}
    sb3_path, edqn_path = train_runs(
        [spec(method, settings, env=env), spec("empathic_dqn", reference, env=env)], tmp_path, OPTIONS
    )
    sb3, edqn = read(sb3_path), read(edqn_path)
    assert sb3["method_label"] == ("SB3 DQN" if "DQN" in method else "SB3 PPO")
    assert set(sb3["train"]) == set(edqn["train"]) == {"episode_end_step", *METRIC_NAMES}
    assert [set(e) for e in sb3["eval"]] == [set(e) for e in edqn["eval"]] == [{"step", *METRIC_NAMES}] * 2
    train = sb3["train"]
    assert len(train["survival"]) >= 300 // 60
    assert all(0 <= s <= 60 for s in train["survival"])
    if env == "coexistence_v0":  # +1 per operative step: the suite's survival is the unshaped return
        assert train["return"] == [float(s) for s in train["survival"]]
    else:
        assert all(b + o <= 9 for b, o in zip(train["batteries"], train["other_batteries"], strict=True))
    assert sb3["memory_bytes"]["learner_per_run"] > 0


def drive(learner: SB3Learner, env, steps: int, seed: int) -> np.ndarray:
    """Feed ``steps`` adapter steps to a one-run learner as the runner would; returns the next observation."""
    obs, _ = env.reset(seed=seed)
    zero = np.zeros((1, 1))
    for _ in range(steps):
        action = learner.act(obs[None, None])
        next_obs, reward, terminated, truncated, _ = env.step(action[0, 0])
        learner.observe(
            StepBatch(
                obs=obs[None, None],
                actions=action,
                rewards=np.array([[reward]]),
                terminated=np.array([[terminated]]),
                next_obs=next_obs[None, None],
                harms=zero,
                battery_return=zero,
                truncated=np.array([[truncated]]),
                **one_other(np.zeros_like(obs)[None, None], zero.astype(bool), zero),
            )
        )
        obs = env.reset()[0] if terminated or truncated else next_obs
    return obs


@needs_sb3
@pytest.mark.parametrize(
    "algorithm, kwargs, steps",
    [
        ("dqn", DQN_SMALL["algorithm_kwargs"], 250),
        ("ppo", PPO_SMALL["algorithm_kwargs"], 256),  # 4 rollouts, episodes truncated at 30 steps
    ],
)
def test_learns_bit_identically_to_sb3_learn_on_the_gym_adapter(algorithm, kwargs, steps):
    settings = SB3Settings(algorithm=algorithm, algorithm_kwargs=kwargs, batch_size=32, schedule_steps=steps)
    model = make_sb3_model(settings, make_single_agent_env("sharing_v0", max_cycles=30), sb3_seed(7))
    model.learn(steps)
    learner = SB3Learner([settings], [7], 25, 5)
    last = drive(learner, make_single_agent_env("sharing_v0", max_cycles=30), steps, sb3_seed(7))
    if algorithm == "ppo":
        learner.act(last[None, None])  # the last rollout is trained once its next observation is known
    ours = learner.models[0]
    assert (ours.num_timesteps, ours._n_updates) == (model.num_timesteps, model._n_updates)
    assert model._n_updates > 0
    expected = model.policy.state_dict()
    for name, value in ours.policy.state_dict().items():
        assert torch.equal(value, expected[name]), name


@needs_sb3
@pytest.mark.parametrize("algorithm, kwargs", [("dqn", DQN_SMALL["algorithm_kwargs"]), ("ppo", PPO_SMALL["algorithm_kwargs"])])
def test_checkpoint_round_trip_continues_exactly(algorithm, kwargs):
    settings = SB3Settings(algorithm=algorithm, algorithm_kwargs=kwargs, batch_size=32)
    straight = SB3Learner([settings], [3], 25, 5)
    drive(straight, make_single_agent_env("coexistence_v0", max_cycles=40), 100, 11)  # mid-rollout for PPO
    buffer = io.BytesIO()
    torch.save(straight.state_dict(), buffer)
    buffer.seek(0)
    resumed = SB3Learner([settings], [3], 25, 5)
    resumed.load_state_dict(torch.load(buffer, weights_only=True))
    tail = [drive(learner, make_single_agent_env("coexistence_v0", max_cycles=40), 120, 12) for learner in (straight, resumed)]
    np.testing.assert_array_equal(*tail)
    a, b = straight.models[0], resumed.models[0]
    assert a.num_timesteps == b.num_timesteps == 220
    for name, value in a.policy.state_dict().items():
        assert torch.equal(value, b.policy.state_dict()[name]), name
    with pytest.raises(ValueError, match="seeds"):
        SB3Learner([settings], [4], 25, 5).load_state_dict(straight.state_dict())


@needs_sb3
def test_a_run_gives_the_same_result_alone_or_in_an_ensemble(tmp_path):
    alone = read(train_runs([spec("baselines.sb3:SB3_DQN", DQN_SMALL, seed=1, steps=200)], tmp_path / "alone", OPTIONS)[0])
    both = train_runs([spec("baselines.sb3:SB3_DQN", DQN_SMALL, seed=s, steps=200) for s in (0, 1)], tmp_path / "both", OPTIONS)
    together = read(both[1])
    assert together["run_id"] == alone["run_id"]
    assert (together["train"], together["eval"]) == (alone["train"], alone["eval"])
    assert read(both[0])["train"] != together["train"]


def test_settings_are_validated_and_presets_fixed():
    assert SB3Settings(net_arch=[64, 64]).net_arch == (64, 64)
    kwargs = SB3Settings(algorithm="dqn", algorithm_kwargs={"buffer_size": 10}).model_kwargs()
    assert kwargs["buffer_size"] == 10 and kwargs["batch_size"] == 32 and kwargs["learning_rate"] == 1e-3
    assert kwargs["policy_kwargs"] == {"net_arch": [128, 128]}
    assert SB3Settings(algorithm="ppo").model_kwargs()["batch_size"] == 64
    for bad in ({"algorithm": "a2c"}, {"net_arch": ()}, {"algorithm_kwargs": {"gamma": 0.5}}, {"schedule_steps": 0}):
        with pytest.raises(ValueError):
            SB3Settings(**bad)
    assert SB3_DQN.make_settings({}).algorithm == "dqn" and SB3_PPO.make_settings({}).algorithm == "ppo"
    with pytest.raises(ValueError, match="fixes"):
        SB3_DQN.make_settings({"algorithm": "ppo"})
    hash(SB3Settings(algorithm_kwargs={"n_steps": 8}).shared())


def test_missing_sb3_says_how_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "stable_baselines3", None)
    with pytest.raises(ImportError) as error:
        SB3Learner([SB3Settings()], [0], 25, 5)
    assert str(error.value) == INSTALL_HINT and 'pip install -e ".[sb3]"' in INSTALL_HINT


@needs_sb3
@pytest.mark.parametrize(
    "part, name, value, says",
    [
        ("counters", "policy", 0, "unknown SB3 counter 'policy'"),
        ("counters", "num_timesteps", "many", "counter 'num_timesteps' is a str"),
        ("buffer", "observations", np.zeros(3, np.float32), "buffer field 'observations' is not a float32 array of shape"),
        ("buffer", "device", 1, "unknown SB3 buffer field 'device'"),
    ],
)
def test_a_checkpoint_sets_only_the_counters_and_buffer_fields_it_writes(part, name, value, says):
    from empathy_zoo.safe_data import from_safe, to_safe

    settings = SB3Settings(algorithm="dqn", algorithm_kwargs=DQN_SMALL["algorithm_kwargs"], batch_size=32)
    learner = SB3Learner([settings], [3], 25, 5)
    state = learner.state_dict()
    saved = state["runs"][0]
    if part == "counters":
        saved["counters"][name] = value
    else:
        saved["buffer"] = to_safe({**from_safe(saved["buffer"]), name: value})
    with pytest.raises(ValueError, match=says):
        SB3Learner([settings], [3], 25, 5).load_state_dict(state)
