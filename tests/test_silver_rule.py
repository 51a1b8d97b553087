"""The silver rule (``empathic_dqn_silver``): the other's imagined future counts only where it is
worse than the robot's own continuation, on hand-made numbers, at the exact optimum of
Coexistence, and through the runner."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from agents.empathic_dqn import empathic_targets
from baselines.registry import get_method
from baselines.silver_rule import SilverRuleDQN
from empathy_zoo.engine.coexistence import CAT_HARMS_ROBOT
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.reference import coexistence_optimum, coexistence_transitions, coexistence_values
from empathy_zoo.result_file import result_path
from empathy_zoo.training import RunnerOptions, train_runs

GAMMA = 0.5


class _Learner:
    """The silver rule's ``targets`` on hand-made batches (one run, one transition, 2 actions)."""

    def __init__(self, beta: float) -> None:
        self.config = type("C", (), {"gamma": GAMMA})()
        self.selfishness = torch.tensor([[beta]])
        self.aggregated = False

    targets = SilverRuleDQN.targets
    other_inputs = SilverRuleDQN.other_inputs
    _others_rule = SilverRuleDQN._others_rule


def _targets(
    rule: str, other_value: float, present: bool, beta: float, reward: float = 1.0, terminated: bool = False, unseen: bool = False
):
    # Q(s') prefers action 0 and Q̂(s', 0) = 4: the continuation c = 0.5·4 = 2, y = r + 2
    q_next_online = torch.tensor([[[1.0, 0.0]]])
    q_next_target = torch.tensor([[[4.0, 9.0]]])
    q_swapped = torch.tensor([[[other_value, other_value - 1.0]]])
    batch = {
        "reward": torch.tensor([[reward]]),
        "terminated": torch.tensor([[terminated]]),
        "other_present": torch.tensor([[present]]),
        "other_unseen": torch.tensor([[unseen]]),
    }
    if rule == "golden":
        return empathic_targets(
            batch["reward"],
            batch["terminated"],
            q_next_online,
            q_next_target,
            q_swapped,
            batch["other_present"],
            GAMMA,
            torch.tensor([[beta]]),
            unseen=batch["other_unseen"],
        )
    return _Learner(beta).targets(batch, q_next_online, q_next_target, q_swapped)


def test_an_other_as_well_off_as_the_robot_leaves_the_robots_target() -> None:
    # o = 0.5·4 = 2 = c: the robot's own future and the other's are alike, so nothing is owed; the
    # rule before compared y = 3 with o = 2 and took o (the golden rule's target): this failed
    y, silver = _targets("silver", other_value=4.0, present=True, beta=0.25)
    assert y.item() == 3.0 and silver.item() == 3.0
    _, golden = _targets("golden", other_value=4.0, present=True, beta=0.25)
    assert golden.item() == 0.25 * 3.0 + 0.75 * 2.0


def test_a_worse_off_other_lowers_the_target_by_the_shortfall() -> None:
    y, silver = _targets("silver", other_value=2.0, present=True, beta=0.25)  # o = 1 < c = 2
    assert silver.item() == y.item() - 0.75 * (2.0 - 1.0)


def test_a_better_off_other_does_not_pull_the_target_up() -> None:
    y, silver = _targets("silver", other_value=20.0, present=True, beta=0.25)  # o = 10 > c = 2
    _, golden = _targets("golden", other_value=20.0, present=True, beta=0.25)
    assert silver.item() == y.item() == 3.0
    assert golden.item() == 0.25 * 3.0 + 0.75 * 10.0  # the golden rule would be drawn to it


def test_a_harmed_other_costs_what_it_costs_empathic_dqn() -> None:
    # o = 0: both rules charge (1 − β)·c below the robot's target
    y, silver = _targets("silver", other_value=20.0, present=False, beta=0.5)
    assert silver.item() == y.item() - 0.5 * 2.0


def test_the_robots_own_harm_is_not_consoled_by_the_others_future() -> None:
    y, silver = _targets("silver", other_value=20.0, present=True, beta=0.5, reward=0.0, terminated=True)
    _, golden = _targets("golden", other_value=20.0, present=True, beta=0.5, reward=0.0, terminated=True)
    assert y.item() == 0.0 and silver.item() == 0.0
    assert golden.item() == 0.5 * 10.0


def test_beta_one_is_selfish_and_an_unseen_other_gives_the_robots_target() -> None:
    y, selfish = _targets("silver", other_value=-5.0, present=True, beta=1.0)
    assert selfish.item() == y.item()
    y, unseen = _targets("silver", other_value=0.0, present=False, beta=0.25, unseen=True)
    assert unseen.item() == y.item()


# ---------------------------------------------------------------------------- the exact optimum
@pytest.mark.parametrize("beta", [0.25, 0.5, 0.75])
def test_at_the_optimum_the_rules_differ_by_a_constant_where_the_robot_is_safe(beta: float) -> None:
    """Q_silver − Q_emp = (1 − β) on every action that cannot get the robot harmed (the same choice
    among them), and more than that where it can (the silver robot minds its own harm more)."""
    _, golden = coexistence_values(beta)
    _, silver = coexistence_values(beta, rule="silver")
    outcome, _ = coexistence_transitions()
    cells = outcome.shape[0]
    risky = (outcome == CAT_HARMS_ROBOT).any(axis=2)
    reachable = np.arange(cells) != 0  # the displacement (0, 0) with the cat present is never reached
    difference = (silver - golden)[:cells]
    np.testing.assert_allclose(difference[~risky & reachable[:, None]], 1.0 - beta, atol=1e-9)
    assert (difference[risky & reachable[:, None]] < 1.0 - beta - 1e-6).all()


@pytest.mark.parametrize("ties", ["uniform", "first"])
def test_the_exact_optimum_equals_empathic_dqns_where_it_must_and_differs_where_it_must(ties: str) -> None:
    """For 0 < β ≤ 1 both rules forbid the same harms and the robot can always avoid both: the same
    policy. At β = 0 Empathic DQN gives up the robot's own survival for the cat's value, the
    silver rule does not."""
    for epsilon in (0.0, 0.01, 0.05):
        for beta in (1.0, 0.75, 0.5, 0.25, 0.1):
            golden = coexistence_optimum(beta, epsilon, ties=ties)
            silver = coexistence_optimum(beta, epsilon, ties=ties, rule="silver")
            assert silver.harms == pytest.approx(golden.harms, abs=1e-9)
            assert silver.survival == pytest.approx(golden.survival, abs=1e-6)
        golden, silver = (coexistence_optimum(0.0, epsilon, ties=ties, rule=r) for r in ("golden", "silver"))
        assert golden.survival < 100 and silver.survival > 300
        assert silver.survival == pytest.approx(coexistence_optimum(0.5, epsilon, ties=ties).survival, abs=1e-6)


def test_reference_refuses_an_unknown_rule() -> None:
    with pytest.raises(ValueError, match="rule must be one of"):
        coexistence_values(0.5, rule="bronze")


def test_silver_rule_trains_through_the_runner_and_learns_otherwise(tmp_path) -> None:
    assert get_method("empathic_dqn_silver").learner is SilverRuleDQN
    settings = {
        "learning_starts": 64,
        "replay_capacity": 2_000,
        "selfishness": 0.25,
        "target_update_interval": 20,
        "epsilon_decay_steps": 200,
    }
    specs = [
        RunSpec.of(
            env="coexistence_v0",
            method=m,
            seed=3,
            steps=400,
            eval_interval=400,
            eval_episodes=1,
            settings=settings,
            env_kwargs={"max_cycles": 40},
        )
        for m in ("empathic_dqn", "empathic_dqn_silver")
    ]
    train_runs(specs, tmp_path, RunnerOptions(progress=False, checkpoint_interval=0))
    golden, silver = (json.loads(result_path(tmp_path, s.run_id).read_text()) for s in specs)
    assert silver["config"]["method"] == "empathic_dqn_silver"
    assert silver["train"]["episode_end_step"] and silver["train"] != golden["train"]  # same seed, other targets
