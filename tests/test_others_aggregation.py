"""Empathic DQN with several other agents (SPEC §6): the other-term of the closest other (the
paper's rule, the default), or aggregated over every other agent by mean (utilitarian) or min
(suffering-focused), a terminal other counting 0."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from agents.empathic_dqn import EmpathicDQN, other_term
from agents.settings import EmpathicDQNSettings
from agents.stacked_mlp import StackedMLP
from agents.step_batch import StepBatch

GAMMA = 0.5


def test_mean_and_min_over_every_other_with_a_terminal_one_counting_zero() -> None:
    # one run, one transition, three others whose best swapped values are 4, 8 and 6; the third is terminal
    q = torch.tensor([[[[4.0, 1.0], [2.0, 8.0], [6.0, 0.0]]]])  # (K=1, B=1, N=3, A=2)
    present = torch.tensor([[[True, True, False]]])
    assert other_term(q, present, GAMMA, "mean").item() == pytest.approx(GAMMA * (4.0 + 8.0 + 0.0) / 3)
    assert other_term(q, present, GAMMA, "min").item() == 0.0  # harming one of several is never free
    everyone = torch.ones(1, 1, 3, dtype=torch.bool)
    assert other_term(q, everyone, GAMMA, "min").item() == GAMMA * 4.0
    assert other_term(q, everyone, GAMMA, "mean").item() == pytest.approx(GAMMA * 6.0)
    with pytest.raises(ValueError, match="one swapped value per other agent"):
        other_term(q[:, :, 0], present[:, :, 0], GAMMA, "mean")


def test_only_the_others_there_when_the_step_began_count() -> None:
    q = torch.tensor([[[[4.0, 1.0], [2.0, 8.0], [6.0, 0.0]]]])  # best swapped values 4, 8, 6
    present = torch.tensor([[[True, False, False]]])  # the second harmed in this step, the third gone before
    live = torch.tensor([[[True, True, False]]])
    assert other_term(q, present, GAMMA, "mean", live).item() == pytest.approx(GAMMA * (4.0 + 0.0) / 2)
    assert other_term(q, present, GAMMA, "min", live).item() == 0.0  # the one just harmed is the worst off
    later = torch.tensor([[[True, False, False]]])  # a step later: only the first is left
    assert other_term(q, present, GAMMA, "min", later).item() == GAMMA * 4.0  # the robot still cares for it
    nobody = torch.zeros(1, 1, 3, dtype=torch.bool)
    assert other_term(q, nobody, GAMMA, "min", nobody).item() == 0.0
    assert other_term(q, nobody, GAMMA, "mean", nobody).item() == 0.0


def test_others_setting_is_checked() -> None:
    with pytest.raises(ValueError, match="others must be one of"):
        EmpathicDQNSettings(others="max")


def _batch(rng: np.random.Generator, k: int, n: int, same_swap: bool) -> StepBatch:
    obs = rng.integers(-1, 2, size=(k, 1, 25)).astype(np.float32)
    swapped = rng.integers(-1, 2, size=(k, 1, n, 25)).astype(np.float32)
    if same_swap:
        swapped[:] = swapped[:, :, :1]
    present = rng.random((k, 1, n)) < 0.8
    if same_swap:
        present[:] = present[:, :, :1]
    return StepBatch(
        obs=obs,
        actions=rng.integers(0, 5, (k, 1)),
        rewards=rng.random((k, 1)).astype(np.float32),
        terminated=rng.random((k, 1)) < 0.05,
        next_obs=rng.integers(-1, 2, size=(k, 1, 25)).astype(np.float32),
        closest=np.zeros((k, 1), dtype=np.int64),
        others_swapped=swapped,
        others_present=present,
        others_live=present | (rng.random((k, 1, n)) < 0.5) if not same_swap else np.ones((k, 1, n), dtype=bool),
        others_unseen=np.zeros((k, 1, n), dtype=bool),
        harms=np.zeros((k, 1), dtype=np.int64),
        battery_return=np.zeros((k, 1)),
        others_battery_return=np.zeros((k, 1, n)),
    )


def _learner(others: str, num_others: int) -> EmpathicDQN:
    settings = [
        EmpathicDQNSettings(selfishness=b, others=others, learning_starts=32, replay_capacity=500, target_update_interval=7)
        for b in (0.5, 0.25)
    ]
    return EmpathicDQN(settings, [0, 1], 25, num_others=num_others)


def test_min_over_identical_others_trains_exactly_as_the_closest_rule() -> None:
    closest, aggregated = _learner("closest", 3), _learner("min", 3)
    assert not closest.aggregated and aggregated.aggregated
    rng = np.random.default_rng(0)
    for _ in range(120):
        batch = _batch(rng, 2, 3, same_swap=True)
        closest.observe(batch)
        aggregated.observe(batch)
    assert closest.grad_steps > 50
    for a, b in zip(closest.online, aggregated.online, strict=True):
        assert torch.equal(a, b)


def test_each_others_value_comes_from_its_own_swapped_observation() -> None:
    learner, seen = _learner("mean", 3), {}
    rng = np.random.default_rng(1)
    for _ in range(40):
        batch = _batch(rng, 2, 3, same_swap=False)
        learner.replay.add(
            batch.obs,
            batch.next_obs,
            batch.others_swapped,
            batch.actions,
            batch.rewards,
            batch.terminated,
            batch.others_present,
            batch.others_live,
            batch.others_unseen,
        )

    def capture(batch, q_next, target_next, target_swapped):
        seen.update(batch=batch, target_swapped=target_swapped)
        return EmpathicDQN.targets(learner, batch, q_next, target_next, target_swapped)

    learner.targets = capture
    learner.update()
    swapped = seen["batch"]["others_swapped"]  # (K, B, O, V)
    assert seen["batch"]["others_live"].shape == (2, 32, 3)
    assert (seen["batch"]["others_live"] | ~seen["batch"]["others_present"]).all()  # present implies live
    assert swapped.shape == (2, 32, 3, 25) and seen["target_swapped"].shape == (2, 32, 3, 5)
    for j in range(3):
        expected = StackedMLP.forward(learner.target, swapped[:, :, j])
        assert torch.allclose(seen["target_swapped"][:, :, j], expected)


def test_aggregating_over_another_number_of_others_is_refused() -> None:
    learner = _learner("mean", 3)
    batch = _batch(np.random.default_rng(2), 2, 2, same_swap=False)
    with pytest.raises(ValueError, match="for 3 other agent"):
        learner.observe(batch)


def test_the_closest_rule_keeps_the_closest_others_entries() -> None:
    """With several others and the closest rule, the replay keeps the entries at ``closest``."""
    learner = _learner("closest", 3)
    batch = _batch(np.random.default_rng(3), 2, 3, same_swap=False)
    batch.closest = np.array([[2], [1]])
    learner.observe(batch)
    kept = learner.sample_batch(torch.zeros((2, 1), dtype=torch.long))
    for run, place in enumerate((2, 1)):
        assert torch.equal(kept["other_swapped"][run, 0], torch.from_numpy(batch.others_swapped[run, 0, place]))
        assert bool(kept["other_present"][run, 0]) == batch.others_present[run, 0, place]
