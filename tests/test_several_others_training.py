"""Several other agents through sweep files, the trainer and result files: every cat gets the
default policy, Empathic DQN aggregates over every other agent when asked, and the methods
profile expands to its runs."""

from __future__ import annotations

import json
import textwrap

import pytest

from empathy_zoo.environments import default_policies
from empathy_zoo.experiment.result_reader import read_result
from empathy_zoo.experiment.sweep_file import profile_path
from empathy_zoo.experiment.values import SweepConfigError
from empathy_zoo.result_file import result_path
from empathy_zoo.training import RunnerOptions, load_sweep, train_runs

SWEEP = """
[sweep]
seeds = 1
steps = 300
eval_interval = 300
eval_episodes = 1

[settings]
learning_starts = 64
replay_capacity = 1_000
epsilon_decay_steps = 100
target_update_interval = 50

[envs.three_cats]
env = "coexistence_v0"
num_cats = 3
max_cycles = 60

[[methods]]
method = "empathic_dqn"
selfishness = 0.5
others = ["closest", "mean", "min"]
label = "Empathic DQN, {others}"
"""


def _write(tmp_path, text: str):
    path = tmp_path / "sweep.toml"
    path.write_text(textwrap.dedent(text))
    return path


def test_every_other_agent_gets_the_default_policy() -> None:
    assert default_policies("coexistence_v0") == {"cat_0": "random_walk"}
    assert default_policies("coexistence_v0", {"num_cats": 3}) == {f"cat_{i}": "random_walk" for i in range(3)}
    humans = default_policies("sharing_v0", {"num_humans": 2})
    assert list(humans) == ["human_0", "human_1"] and humans["human_1"] == humans["human_0"]


def test_a_count_argument_of_another_environment_is_refused(tmp_path) -> None:
    text = SWEEP.replace('env = "coexistence_v0"\nnum_cats = 3', 'env = "sharing_v0"\nnum_cats = 3')
    with pytest.raises(SweepConfigError, match="sharing_v0 takes no argument 'num_cats'"):
        load_sweep(_write(tmp_path, text))


def test_aggregating_runs_train_apart_and_learn_otherwise(tmp_path) -> None:
    specs = load_sweep(_write(tmp_path, SWEEP))
    assert specs[0].fixed_policies() == {f"cat_{i}": "random_walk" for i in range(3)}
    train_runs(specs, tmp_path / "out", RunnerOptions(progress=False, checkpoint_interval=0, threads=1))
    results = [read_result(result_path(tmp_path / "out", s.run_id)) for s in specs]
    assert [r.config.settings["others"] for r in results] == ["closest", "mean", "min"]
    assert all(r.config.env_kwargs["num_cats"] == 3 for r in results)
    trains = [json.dumps(r.to_document()["train"]) for r in results]
    assert len(set(trains)) == 3  # the same seed, three other-terms


def test_the_methods_profile_runs_every_method_on_every_variant() -> None:
    specs = load_sweep(profile_path("methods"))
    assert len(specs) == 280 and {s.seed for s in specs} == set(range(10))
    methods = {(s.variant.label, s.method) for s in specs}
    for method in (
        "dqn_aup",
        "dqn_social_value",
        "dqn_inequity_aversion",
        "empathic_dqn_silver",
        "empathic_dqn_in_view",
        "dqn_considerate",
    ):
        assert ("coexistence_v0", method) in methods and ("sharing_v0", method) in methods
    assert ("coexistence_v0", "dqn_relative_reachability") in methods and ("coexistence_v0", "dqn_lagrangian") in methods
    several = {s.method_settings().others for s in specs if s.variant.label in ("coexistence_3cats", "sharing_2humans")}
    assert several == {"closest", "mean", "min"}


def test_the_vector_env_says_which_others_were_there_when_the_step_began() -> None:
    import numpy as np

    from empathy_zoo.training.ensemble import learner_batch
    from empathy_zoo.vector import VectorEnv

    venv = VectorEnv("coexistence_v0", 1, fixed={"cat_0": "stay", "cat_1": "stay"}, num_cats=2)
    venv.reset(seed=0)
    venv.engine.reset(np.array([0]), options={"positions": {"robot_0": (2, 4), "cat_0": (3, 3), "cat_1": (6, 0)}})
    obs = venv._observe_learners()[:, 0]
    down = np.array([[1]])  # to (3, 4): right of cat_0, which the right one harms
    step = venv.step(down)
    batch = learner_batch(obs, down, step)
    assert step.harmed_by[0, 1] == 0
    assert batch.others_live[0, 0].tolist() == [True, True]  # both were there when the step began
    assert batch.others_present[0, 0].tolist() == [False, True]
    later = venv.step(np.array([[4]]))
    assert later.others_live[0, 0].tolist() == [False, True]  # cat_0 has left: it no longer counts
