"""Empathy without omniscience: ``empathic_dqn_in_view`` swaps with the cat only while it stands in
the robot's window; it trains apart from omniscient runs, and differs from them."""

from __future__ import annotations

import json

import empathy_zoo.training.ensemble as ensemble
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.training import RunnerOptions, group_specs, train_runs

TINY = {
    "learning_starts": 64,
    "replay_capacity": 2_000,
    "epsilon_decay_steps": 300,
    "target_update_interval": 50,
    "selfishness": 0.5,
}
OPTIONS = RunnerOptions(progress=False, checkpoint_interval=0, threads=1)


def spec(method: str, seed: int = 0) -> RunSpec:
    return RunSpec.of(
        env="coexistence_v0", method=method, settings=TINY, seed=seed, steps=1_200, eval_interval=600, eval_episodes=2
    )


def test_in_view_runs_train_apart_with_an_in_view_swap_and_learn_otherwise(tmp_path, monkeypatch) -> None:
    specs = [spec("empathic_dqn"), spec("empathic_dqn_in_view"), spec("empathic_dqn_in_view", seed=1)]
    assert [len(chunk) for chunk in group_specs(specs, 32)] == [1, 2]
    built = []
    real = ensemble.VectorEnv

    def recording(*args, **kwargs):
        built.append(kwargs.get("in_view_only"))
        return real(*args, **kwargs)

    monkeypatch.setattr(ensemble, "VectorEnv", recording)
    paths = train_runs(specs, tmp_path, OPTIONS)
    assert sorted(built) == [False, True]
    omniscient, in_view = (json.loads(path.read_text()) for path in paths[:2])
    assert omniscient["train"]["episode_end_step"]
    # the same seed, other targets: the greedy policies differ by the end (the training episodes
    # of so short a run may not, since an unseen cat's term is the robot's own continuation)
    assert (in_view["train"], in_view["eval"]) != (omniscient["train"], omniscient["eval"])
