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
from empathy_zoo.experiment.result_reader import check_result
from empathy_zoo.experiment.sweep_file import SweepConfigError, parse_sweep
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
    costs = run.costs.copy()
    assert run.price == 7.0  # no episode has ended: λ is its start
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


# ---------------------------------------------------------------------------- cells and distances
def cells_after(env: str, positions: dict, fixed: dict, action: int, **kwargs: Any) -> Any:
    """The learner's batch of one step from hand-placed agents, with the cells the trainer adds."""
    from helpers_placed import placed, step

    from empathy_zoo.training.ensemble import AgentCells

    venv = placed(env, positions, fixed, **kwargs)
    cells = AgentCells(venv)
    return cells.fill(step(venv, action)[1])


@pytest.mark.parametrize(
    "robot, cat, action, after, cat_after, distance",
    [
        ((3, 3), (3, 6), 3, (3, 4), (3, 6), 2),  # right, beside no one
        ((0, 0), (4, 6), 4, (0, 0), (4, 6), 4),  # across both edges of the torus: 3 rows + 1 column
        ((2, 3), (4, 3), 1, (3, 3), (-1, -1), -1),  # down beside the cat: harmed, it has left
    ],
)
def test_the_batch_gives_the_cells_and_torus_distance_at_the_end_of_the_step(robot, cat, action, after, cat_after, distance):
    batch = cells_after("coexistence_v0", {"robot_0": robot, "cat_0": cat}, {"cat_0": "stay"}, action)
    assert batch.position.tolist() == [[list(after)]]
    assert batch.others_position.tolist() == [[[list(cat_after)]]]
    assert batch.others_distance.tolist() == [[[distance]]]
    assert batch.other_distance.tolist() == [[distance]] and batch.other_position.tolist() == [[list(cat_after)]]
    assert int(batch.harms[0, 0]) == (distance == -1)


def test_the_cells_are_taken_before_the_autoreset_and_for_every_other() -> None:
    cut = cells_after("coexistence_v0", {"robot_0": (3, 3), "cat_0": (3, 6)}, {"cat_0": "stay"}, 3, max_cycles=1)
    assert bool(cut.truncated[0, 0]) and cut.position.tolist() == [[[3, 4]]] and cut.others_distance.tolist() == [[[2]]]
    two = cells_after(
        "sharing_v0",
        {"robot_0": (0, 0), "human_0": (0, 2), "human_1": (3, 3)},
        {"human_0": "stay", "human_1": "stay"},
        4,
        env_kwargs={"num_humans": 2},
        batteries=[(5, 5)],
    )
    assert two.others_position.tolist() == [[[[0, 2], [3, 3]]]]
    assert two.others_distance.tolist() == [[[2, 6]]] and two.other_distance.tolist() == [[2]]


@dataclass(frozen=True)
class NeedsCells:
    """Refuses a step without the cells (so a run that finishes was given them every step)."""

    name: ClassVar[str] = "needs_cells"

    def __call__(self, batch: Any) -> np.ndarray:
        assert batch.others_distance is not None and batch.others_distance.shape == (*batch.rewards.shape, 1)
        assert batch.position is not None and ((batch.position >= 0) | (batch.terminated[..., None])).all()
        return batch.rewards


CELLS_PPO = with_transform(SB3_PPO, NeedsCells(), name="sb3_ppo_needs_cells")


@needs_sb3
def test_the_trainer_gives_every_step_the_cells(tmp_path: Path) -> None:
    from empathy_zoo.experiment.model import RunSpec

    spec = RunSpec.of(
        env="coexistence_v0",
        method="test_sb3_transforms:CELLS_PPO",
        settings={"algorithm_kwargs": PPO_SMALL, "batch_size": 16},
        steps=100,
        eval_interval=100,
        eval_episodes=1,
        env_kwargs={"max_cycles": 30},
    )
    (path,) = train_runs([spec], tmp_path, OPTIONS)
    assert len(json.loads(Path(path).read_text())["train"]["survival"]) >= 3


@needs_sb3
def test_a_priced_ppo_run_continues_exactly_from_its_checkpoint() -> None:
    import io

    import torch

    straight = drive("ppo", Lagrangian(lambda_init=3.0), 40, PPO_SMALL)  # mid-rollout: costs kept beside the rewards
    state = io.BytesIO()
    torch.save(straight.state_dict(), state)
    state.seek(0)
    resumed = SB3Learner([SB3Settings(algorithm="ppo", algorithm_kwargs=PPO_SMALL, batch_size=16)], [0], 25, 5)
    resumed.price_costs([True])
    resumed.load_state_dict(torch.load(state, weights_only=True))
    a, b = straight._runs[0], resumed._runs[0]
    np.testing.assert_array_equal(a.costs, b.costs)
    assert a.price == b.price == 3.0
    unpriced = SB3Learner([SB3Settings(algorithm="ppo", algorithm_kwargs=PPO_SMALL, batch_size=16)], [0], 25, 5)
    with pytest.raises(ValueError, match="pricing costs"):
        unpriced.load_state_dict(straight.state_dict())


MARKED = sorted(
    (name, env) for name, method in SB3_TRANSFORM_METHODS.items() for env in method.identical_to if name.startswith("sb3_ppo")
)


@needs_sb3
@pytest.mark.parametrize("name, env", MARKED)
def test_every_mark_of_identity_is_true_seed_for_seed(tmp_path: Path, name: str, env: str) -> None:
    from empathy_zoo.experiment.model import RunSpec

    other, why = SB3_TRANSFORM_METHODS[name].identical_to[env]
    assert other == "sb3_ppo" and why
    reward = {"bonus_starts": 64, "learning_starts": 32} if name.endswith("considerate") else None
    specs = [
        RunSpec.of(
            env=env,
            method=method,
            settings={"algorithm_kwargs": PPO_SMALL, "batch_size": 16},
            reward=reward if method == name else None,
            steps=160,
            eval_interval=160,
            eval_episodes=1,
            env_kwargs={"max_cycles": 40} if env == "coexistence_v0" else {},
            seed=2,
        )
        for method in (name, other)
    ]
    shaped, plain = (json.loads(Path(p).read_text()) for p in train_runs(specs, tmp_path, OPTIONS))
    shaped["train"].pop("lambda", None)
    assert (shaped["train"], shaped["eval"]) == (plain["train"], plain["eval"])


@pytest.mark.parametrize(
    "method, named, says",
    [
        ("sb3_ppo", "harm_penalty", 'write method = "sb3_ppo_harm_penalty"'),
        ("sb3_dqn", "dqn_aup", 'write method = "sb3_dqn_aup"'),
        ("dqn", "lagrangian", 'write method = "dqn_lagrangian"'),
        ("sb3_dqn", "lagrangian", "sb3_dqn_lagrangian is not a method: SB3 DQN cannot"),
        ("sb3_ppo", "envy", "empathy-zoo methods` lists the compositions"),
    ],
)
def test_a_transform_named_beside_a_learner_points_to_the_composed_method(method: str, named: str, says: str) -> None:
    sweep = {"envs": {"coexistence_v0": {}}, "methods": [{"method": method, "reward": named}]}
    with pytest.raises(SweepConfigError, match=r"mine\.toml: \[\[methods\]\] #1 .* reward: a method's reward transform") as error:
        parse_sweep(sweep, source="mine.toml")
    assert says in str(error.value)
