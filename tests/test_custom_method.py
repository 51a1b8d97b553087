"""The README's one-file method plugs into the runner by its ``package.module:NAME``."""

from __future__ import annotations

import json

import torch

from baselines.registry import get_method
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.training import RunnerOptions, train_runs

TINY = {"learning_starts": 64, "replay_capacity": 1_000, "epsilon_decay_steps": 300}


def test_the_rawlsian_example_trains_and_is_scored(tmp_path) -> None:
    method = get_method("examples.rawlsian_dqn:RAWLSIAN_DQN")
    assert method.name == "rawlsian_dqn"
    spec = RunSpec.of(
        env="sharing_v0",
        method="examples.rawlsian_dqn:RAWLSIAN_DQN",
        settings=TINY,
        steps=400,
        eval_interval=200,
        eval_episodes=2,
    )
    result = json.loads(train_runs([spec], tmp_path, RunnerOptions(progress=False))[0].read_text())
    assert result["method_label"] == "Rawlsian DQN"
    assert len(result["eval"]) == 2 and len(result["eval"][0]["equality"]) == 2


def test_the_rawlsian_target_is_the_worse_off_value() -> None:
    method = get_method("examples.rawlsian_dqn:RAWLSIAN_DQN")
    learner = method.learner([method.make_settings({**TINY, "gamma": 0.5})], [0], 25)
    batch = {
        "reward": torch.tensor([[1.0, 1.0]]),
        "terminated": torch.tensor([[False, False]]),
        "other_present": torch.tensor([[True, False]]),
    }
    q = torch.tensor([[[0.0, 1.0], [0.0, 1.0]]])
    target_next = torch.tensor([[[2.0, 4.0], [2.0, 4.0]]])  # y = 1 + 0.5 * 4 = 3
    swapped = torch.tensor([[[2.0, 0.0], [100.0, 0.0]]])  # the other's value: 0.5 * 2 = 1, and absent
    y, y_emp = learner.targets(batch, q, target_next, swapped)
    assert y.tolist() == [[3.0, 3.0]]
    assert y_emp.tolist() == [[1.0, 3.0]]
