"""A fixed policy's own state is checkpointed: a killed and resumed sweep with a stateful custom
policy writes the same result files as an uninterrupted one; a policy whose state a checkpoint
would lose is refused when checkpoints are on (and trains without them)."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest
import torch
from helpers_policies import Wanderer
from helpers_resume import TINY_SETTINGS

import empathy_zoo.training.ensemble as ensemble
from empathy_zoo.experiment.sweep_file import parse_sweep
from empathy_zoo.policies import Patrol, RandomWalk
from empathy_zoo.training import RunnerOptions, train_runs
from empathy_zoo.training.checkpoint import from_safe, to_safe
from empathy_zoo.vector import VectorEnv

HELPERS = Wanderer.__module__  # "helpers_policies", importable because pytest puts tests/ on the path
CAT = "cat_0"
SETTINGS = TINY_SETTINGS
UNSTAMPED = ("wall_time_s", "created")
"""Fields of a result file that tell when it was written, not what was trained."""


class Killed(Exception):
    """Stands in for the process being killed."""


def sweep(policy: str = f"{HELPERS}:Wanderer"):
    """Two seeds of Empathic DQN (β = 0.5) on Coexistence with ``policy`` as the cat, built with an argument."""
    return parse_sweep(
        {
            "sweep": {"seeds": 2, "steps": 300, "eval_interval": 150, "eval_episodes": 2},
            "settings": SETTINGS,
            "envs": {"coexistence_v0": {"max_cycles": 40, "fixed": {CAT: {"policy": policy, "repeat": 0.25}}}},
            "methods": [{"method": "empathic_dqn", "selfishness": 0.5}],
        },
        source="stateful.toml",
    )


def options(checkpoint_interval: int = 100) -> RunnerOptions:
    return RunnerOptions(progress=False, checkpoint_interval=checkpoint_interval)


def results(paths) -> dict[str, dict]:
    """Each result file's content but when it was written."""
    return {p.name: {k: v for k, v in json.loads(p.read_text()).items() if k not in UNSTAMPED} for p in paths}


def through_a_checkpoint(state: dict) -> dict:
    """``state`` as a checkpoint stores and loads it."""
    buffer = io.BytesIO()
    torch.save(to_safe(state), buffer)
    buffer.seek(0)
    return from_safe(torch.load(buffer, weights_only=True))


def test_a_killed_and_resumed_sweep_with_a_stateful_policy_writes_the_same_results(tmp_path, monkeypatch):
    uninterrupted = results(train_runs(sweep(), tmp_path / "a", options()))
    real = ensemble.save_checkpoint

    def save_then_die(path, payload):
        real(path, payload)
        if payload["step"] == 200:
            raise Killed

    with monkeypatch.context() as patch:
        patch.setattr(ensemble, "save_checkpoint", save_then_die)
        with pytest.raises(Killed):
            train_runs(sweep(), tmp_path / "b", options())
    loaded = []
    real_load = ensemble.load_checkpoint
    monkeypatch.setattr(ensemble, "load_checkpoint", lambda path: loaded.append(path) or real_load(path))
    resumed = results(train_runs(sweep(), tmp_path / "b", options()))
    assert len(loaded) == 1 and len(resumed) == 2
    assert resumed == uninterrupted


def test_a_policy_that_saves_no_state_is_refused_with_checkpoints_and_trains_without(tmp_path):
    runs = sweep(f"{HELPERS}:WandererWithoutState")
    with pytest.raises(ValueError) as refused:
        train_runs(runs, tmp_path / "with", options(100))
    message = str(refused.value)
    for part in (f"{HELPERS}:WandererWithoutState", CAT, "state()", "load_state", "stateless = True", "--checkpoint-interval 0"):
        assert part in message, message
    assert not list((tmp_path / "with").rglob("*.json")) and not list((tmp_path / "with").rglob("*.pt"))
    paths = train_runs(runs, tmp_path / "without", options(0))
    assert len(paths) == 2 and all(p.exists() for p in paths)


@pytest.mark.parametrize(
    "policy, checkpointable",
    [
        ("random_walk", True),
        ("patrol", True),
        ("stay", True),
        (f"{HELPERS}:Wanderer", True),
        (f"{HELPERS}:Chaser", True),
        (f"{HELPERS}:AlwaysLeft", False),
        (f"{HELPERS}:WandererWithoutState", False),
    ],
)
def test_check_checkpointable_knows_which_policies_save_their_state(policy, checkpointable):
    env = "sharing_v0" if policy == "patrol" else "coexistence_v0"
    agent = "human_0" if policy == "patrol" else CAT
    venv = VectorEnv(env, 2, fixed={agent: policy})
    if checkpointable:
        venv.check_checkpointable()
    else:
        with pytest.raises(ValueError, match=f"fixed policy {policy} of {agent} cannot be checkpointed"):
            venv.check_checkpointable()
        with pytest.raises(ValueError, match="cannot be checkpointed"):
            venv.state()


@pytest.mark.parametrize(
    "env, agent, policy",
    [
        ("coexistence_v0", CAT, "random_walk"),
        ("sharing_v0", "human_0", "patrol"),
        ("coexistence_v0", CAT, "stay"),
        ("coexistence_v0", CAT, f"{HELPERS}:Wanderer"),
        ("sharing_v0", "human_0", f"{HELPERS}:RecorderWithState"),
    ],
)
def test_a_vector_env_loaded_from_a_checkpoint_continues_exactly(env, agent, policy):
    rng = np.random.default_rng(3)
    actions = rng.integers(5, size=(120, 3, 1))
    original = VectorEnv(env, 3, fixed={agent: policy}, max_cycles=25)
    original.reset(seed=[4, 5, 6])
    for step in actions[:50]:
        original.step(step)
    saved = through_a_checkpoint(original.state())
    restored = VectorEnv(env, 3, fixed={agent: policy}, max_cycles=25)
    restored.reset(seed=[7, 8, 9])  # another start: everything must come from the state
    restored.load_state(saved)
    for step in actions[50:]:
        a, b = original.step(step), restored.step(step)
        np.testing.assert_array_equal(a.observations, b.observations)
        np.testing.assert_array_equal(a.rewards, b.rewards)
        np.testing.assert_array_equal(a.episode_over, b.episode_over)


@pytest.mark.parametrize("make", [RandomWalk, lambda: Patrol(period=3)], ids=["random_walk", "patrol"])
def test_a_per_environment_builtin_policy_continues_exactly_from_its_state(make):
    policy = make()
    policy.reset(11)
    for _ in range(7):
        policy.act(np.zeros(25, np.float32), {})
    restored = make()
    restored.reset(12)
    restored.load_state(through_a_checkpoint(policy.state()))
    assert [restored.act(np.zeros(25, np.float32), {}) for _ in range(30)] == [
        policy.act(np.zeros(25, np.float32), {}) for _ in range(30)
    ]


def test_a_state_that_is_not_plain_data_is_refused_naming_the_policy():
    venv = VectorEnv("coexistence_v0", 2, fixed={CAT: f"{HELPERS}:SavesItsGenerator"})
    venv.reset(seed=0)
    with pytest.raises(ValueError, match=f"state\\(\\) of fixed policy {HELPERS}:SavesItsGenerator is not plain data"):
        venv.state()


def test_a_state_of_the_earlier_layout_is_refused_not_misloaded():
    venv = VectorEnv("coexistence_v0", 2, fixed={CAT: "random_walk"})
    venv.reset(seed=0)
    state = venv.state()
    earlier = {
        "engine": state["engine"],
        "observations": state["observations"],
        "policies": {"1": {"keys": np.zeros(2, np.uint64), "counts": np.zeros(2, np.uint64)}},
    }
    with pytest.raises(ValueError, match="written by an earlier version cannot be resumed"):
        venv.load_state(earlier)
