"""The silver rule (``empathic_dqn_silver``): the other's imagined value counts only where it is
worse than the robot's own target, on hand-made numbers and through the runner."""

from __future__ import annotations

import json

import torch

from agents.empathic_dqn import empathic_targets, other_term
from baselines.registry import get_method
from baselines.silver_rule import SilverRuleDQN, silver_targets
from empathy_zoo.result_file import result_path
from empathy_zoo.training import RunnerOptions, train_runs
from empathy_zoo.training.spec import RunSpec

GAMMA = 0.5


def _targets(rule: str, other_value: float, present: bool, beta: float, reward: float = 1.0):
    # one run, one transition, 2 actions; Q(s') prefers action 0, Q̂(s', 0) = 4 -> y = r + 0.5·4 = 3
    q_next_online = torch.tensor([[[1.0, 0.0]]])
    q_next_target = torch.tensor([[[4.0, 9.0]]])
    q_swapped = torch.tensor([[[other_value, other_value - 1.0]]])
    args = (torch.tensor([[reward]]), torch.tensor([[False]]), q_next_online, q_next_target, q_swapped,
            torch.tensor([[present]]), GAMMA, torch.tensor([[beta]]))
    y, golden = empathic_targets(*args)
    if rule == "golden":
        return y, golden
    return y, silver_targets(y, other_term(q_swapped, torch.tensor([[present]]), GAMMA), torch.tensor([[beta]]))


def test_the_other_counts_only_where_it_fares_worse() -> None:
    y, silver = _targets("silver", other_value=2.0, present=True, beta=0.25)  # o = 0.5·2 = 1 < y = 3
    assert y.item() == 3.0
    assert silver.item() == 0.25 * 3.0 + 0.75 * 1.0  # the shortfall counts, as in Empathic DQN
    _, golden = _targets("golden", other_value=2.0, present=True, beta=0.25)
    assert golden.item() == silver.item()


def test_a_better_off_other_does_not_pull_the_target_up() -> None:
    y, silver = _targets("silver", other_value=20.0, present=True, beta=0.25)  # o = 10 > y = 3
    _, golden = _targets("golden", other_value=20.0, present=True, beta=0.25)
    assert silver.item() == y.item() == 3.0
    assert golden.item() == 0.25 * 3.0 + 0.75 * 10.0  # the golden rule would be drawn to it


def test_a_harmed_other_lowers_the_target_and_beta_one_is_selfish() -> None:
    y, silver = _targets("silver", other_value=20.0, present=False, beta=0.5)  # o = 0
    assert silver.item() == 0.5 * y.item()
    y, selfish = _targets("silver", other_value=-5.0, present=True, beta=1.0)
    assert selfish.item() == y.item()


def test_silver_rule_trains_through_the_runner_and_learns_otherwise(tmp_path) -> None:
    assert get_method("empathic_dqn_silver").learner is SilverRuleDQN
    settings = {"learning_starts": 64, "replay_capacity": 2_000, "selfishness": 0.25, "target_update_interval": 20,
                "epsilon_decay_steps": 200}
    specs = [RunSpec(env="coexistence_v0", method=m, seed=3, steps=400, eval_interval=400, eval_episodes=1,
                     settings=settings, env_kwargs={"max_cycles": 40}) for m in ("empathic_dqn", "empathic_dqn_silver")]
    train_runs(specs, tmp_path, RunnerOptions(progress=False, checkpoint_interval=0))
    golden, silver = (json.loads(result_path(tmp_path, s.run_id).read_text()) for s in specs)
    assert silver["config"]["method"] == "empathic_dqn_silver"
    assert silver["train"]["episode_end_step"] and silver["train"] != golden["train"]  # same seed, other targets
