"""Empathic DQN: exact targets, β = 1 is DQN, shaping, replay size, determinism, ensembles."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch
from helpers_batches import one_other

from agents.base import StepBatch
from agents.empathic_dqn import EmpathicDQN, empathic_targets, linear_epsilon
from agents.replay import StackedReplay
from agents.rewards import TrainRewards
from agents.settings import EmpathicDQNSettings
from baselines.registry import get_method
from baselines.shaping import HARM_PENALTY, EqualityScaling, HarmPenalty
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.training import RunnerOptions, train_runs

TINY = {"learning_starts": 64, "replay_capacity": 2_000, "epsilon_decay_steps": 500, "target_update_interval": 50}


def test_targets_on_a_hand_made_batch() -> None:
    gamma, beta = 0.9, 0.25
    reward = torch.tensor([[1.0, 0.0, 1.0, 2.0]])
    terminated = torch.tensor([[False, True, False, False]])
    # Q picks the action (double DQN); Q̂ values it.
    q_next_online = torch.tensor([[[0.0, 5.0], [1.0, 0.0], [3.0, 2.0], [0.0, 1.0]]])
    q_next_target = torch.tensor([[[10.0, 20.0], [30.0, 40.0], [50.0, 60.0], [7.0, -3.0]]])
    q_swapped_target = torch.tensor([[[1.0, 4.0], [2.0, -1.0], [8.0, 0.0], [100.0, 100.0]]])
    other_present = torch.tensor([[True, True, True, False]])
    y, y_emp = empathic_targets(
        reward,
        terminated,
        q_next_online,
        q_next_target,
        q_swapped_target,
        other_present,
        gamma,
        torch.tensor([[beta]]),
    )
    expected_y = [1.0 + 0.9 * 20.0, 0.0, 1.0 + 0.9 * 50.0, 2.0 + 0.9 * -3.0]
    expected_other = [0.9 * 4.0, 0.9 * 2.0, 0.9 * 8.0, 0.0]  # 0: the other has left
    assert y[0].tolist() == pytest.approx(expected_y)
    assert y_emp[0].tolist() == pytest.approx(
        [beta * a + (1 - beta) * b for a, b in zip(expected_y, expected_other, strict=True)]
    )


def test_beta_one_target_ignores_the_other() -> None:
    args = [torch.rand(2, 8, 5) for _ in range(3)]
    y, y_emp = empathic_targets(
        torch.rand(2, 8), torch.zeros(2, 8, dtype=torch.bool), *args, torch.ones(2, 8, dtype=torch.bool), 0.99, torch.ones(2, 1)
    )
    assert torch.equal(y, y_emp)


def _random_batches(count: int, k: int, seed: int, swapped_noise: bool = False) -> list[StepBatch]:
    rng = np.random.default_rng(seed)
    other = np.random.default_rng(seed + 1000)
    out = []
    for _ in range(count):
        obs = np.repeat(rng.integers(-1, 2, (1, 1, 25)).astype(np.float32), k, 0)
        nxt = np.repeat(rng.integers(-1, 2, (1, 1, 25)).astype(np.float32), k, 0)
        swapped = other.integers(-1, 2, (k, 1, 25)).astype(np.float32) if swapped_noise else nxt
        out.append(
            StepBatch(
                obs=obs,
                actions=np.repeat(rng.integers(0, 5, (1, 1)), k, 0),
                rewards=np.repeat(rng.random((1, 1)), k, 0),
                terminated=np.repeat(rng.random((1, 1)) < 0.1, k, 0),
                next_obs=nxt,
                harms=np.zeros((k, 1)),
                battery_return=np.zeros((k, 1)),
                **one_other(swapped, np.ones((k, 1), bool), np.zeros((k, 1))),
            )
        )
    return out


def _train(method: str, batches: list[StepBatch], seed: int = 3, **settings) -> EmpathicDQN:
    m = get_method(method)
    k = batches[0].obs.shape[0]
    learner = m.learner([m.make_settings({**TINY, **settings})] * k, [seed] * k, 25)
    for batch in batches:
        learner.observe(batch)
    return learner


def test_beta_one_gives_the_same_updates_as_dqn_whatever_the_other_sees() -> None:
    plain = _train("dqn", _random_batches(200, 1, seed=0))
    empathic = _train("empathic_dqn", _random_batches(200, 1, seed=0, swapped_noise=True), selfishness=1.0)
    assert plain.grad_steps > 100
    for a, b in zip(plain.online, empathic.online, strict=True):
        assert torch.equal(a, b)


def test_beta_one_is_standard_dqn_with_one_network() -> None:
    selfish = _train("empathic_dqn", _random_batches(200, 1, seed=0, swapped_noise=True), selfishness=1.0)
    caring = _train("empathic_dqn", _random_batches(200, 1, seed=0, swapped_noise=True), selfishness=0.25)
    assert not selfish.empathic_runs.any() and caring.empathic_runs.all()
    for a, b in zip(selfish.online, caring.online, strict=True):
        assert a.shape[0] == 1 and b.shape[0] == 2  # Q only; Q and Q_emp
        assert torch.equal(a[0], b[0])  # Q is trained on y, which β does not touch
    obs = torch.rand(1, 7, 25)
    assert torch.equal(selfish.q_values(obs, "emp"), selfish.q_values(obs, "self"))  # it acts on Q
    assert not torch.equal(caring.q_values(obs, "emp"), caring.q_values(obs, "self"))


def test_mixed_ensemble_runs_equal_their_solo_runs() -> None:
    """β = 1 runs (Q only) and β < 1 runs (Q and Q_emp) in one ensemble: each run's networks and
    the values it acts on are bit for bit those of the run alone."""
    betas = [1.0, 0.5, 1.0, 0.25]
    m = get_method("empathic_dqn")
    batches = _random_batches(150, len(betas), seed=9, swapped_noise=True)
    mixed = m.learner([m.make_settings({**TINY, "selfishness": b}) for b in betas], list(range(len(betas))), 25)
    for batch in batches:
        mixed.observe(batch)
    assert [p.shape[0] for p in mixed.online] == [6] * 6  # 4 Q + 2 Q_emp
    probe = torch.rand(len(betas), 10, 25)  # as many rows as a greedy evaluation's episodes
    acting = mixed.q_values(probe)
    for run, beta in enumerate(betas):
        solo = m.learner([m.make_settings({**TINY, "selfishness": beta})], [run], 25)
        for batch in batches:
            solo.observe(
                StepBatch(**{name: (None if value is None else value[run : run + 1]) for name, value in vars(batch).items()})
            )
        heads = [run] + ([len(betas) + [1, 3].index(run)] if beta < 1 else [])
        for mine, alone in zip(mixed.online, solo.online, strict=True):
            assert torch.equal(mine[heads], alone)
        solo_values = solo.q_values(probe[run : run + 1])[0]
        assert torch.equal(acting[run], solo_values)
        own = solo.q_values(probe[run : run + 1], "self")[0]
        assert torch.equal(solo_values, own) == (beta == 1.0)  # β = 1 acts on Q itself


def test_ensemble_updates_equal_solo_updates() -> None:
    solo = _train("empathic_dqn", _random_batches(150, 1, seed=5), selfishness=0.5)
    ensemble = _train("empathic_dqn", _random_batches(150, 3, seed=5), selfishness=0.5)
    for a, b in zip(solo.online, ensemble.online, strict=True):
        assert torch.equal(a[0], b[0]) and torch.equal(a[1], b[3])  # Q of run 0 and Q_emp of run 0
        assert torch.equal(b[0], b[1])  # identical runs stay identical


def test_target_network_is_copied_on_schedule() -> None:
    learner = _train("empathic_dqn", _random_batches(64 + 48, 1, seed=1), selfishness=0.5)
    assert learner.grad_steps == 50 - 1
    assert not torch.equal(learner.target[0], learner.online[0][:1])
    learner.observe(_random_batches(1, 1, seed=9)[0])
    assert learner.grad_steps == 50
    for target, online in zip(learner.target, learner.online, strict=True):
        assert torch.equal(target, online[:1])


def test_epsilon_schedule() -> None:
    s = EmpathicDQNSettings(learning_starts=100, epsilon_decay_steps=1000, epsilon_end=0.01)
    assert linear_epsilon(s, 0) == 1.0 and linear_epsilon(s, 99) == 1.0
    assert linear_epsilon(s, 600) == pytest.approx(1.0 - 0.5 * 0.99)
    assert linear_epsilon(s, 1100) == pytest.approx(0.01) and linear_epsilon(s, 10**7) == pytest.approx(0.01)


def test_paper_replay_fits_in_64_mb_per_run() -> None:
    replay = StackedReplay(1, EmpathicDQNSettings().replay_capacity, 25, torch.device("cpu"))
    assert replay.nbytes_per_run() <= 64 * 2**20
    assert replay.nbytes_per_run() == 500_000 * (3 * 25 + 1 + 4 + 1 + 1)


def test_replay_rejects_observations_it_cannot_store_exactly() -> None:
    replay = StackedReplay(1, 10, 2, torch.device("cpu"))
    bad = np.array([[[0.025, 1.0]]], dtype=np.float32)  # not a multiple of 1/20 (0.5 would be stored)
    with pytest.raises(ValueError, match="cannot be stored exactly"):
        one = np.ones((1, 1, 1), bool)  # one other agent, present
        replay.add(bad, bad, bad[:, :, None], np.zeros((1, 1)), np.zeros((1, 1)), np.zeros((1, 1), bool), one, one, ~one)
    assert replay.size == 0


def test_settings_reject_bad_values_and_presets_cannot_be_overridden() -> None:
    with pytest.raises(ValueError, match="selfishness"):
        EmpathicDQNSettings(selfishness=1.5)
    with pytest.raises(ValueError, match="batch_size"):
        EmpathicDQNSettings(batch_size=64, learning_starts=32)
    with pytest.raises(ValueError, match="fixes selfishness"):
        get_method("dqn").make_settings({"selfishness": 0.5})
    with pytest.raises(ValueError, match="unknown setting"):
        get_method("dqn").make_settings({"selfishnes": 1.0})


def test_reward_transforms_shape_only_the_rows_of_their_runs() -> None:
    k = 3
    batch = StepBatch(
        obs=np.zeros((k, 1, 25)),
        actions=np.zeros((k, 1), int),
        rewards=np.full((k, 1), 0.9, dtype=np.float32),
        terminated=np.zeros((k, 1), bool),
        next_obs=np.zeros((k, 1, 25)),
        harms=np.ones((k, 1)),
        battery_return=np.full((k, 1), 1.9),
        **one_other(np.zeros((k, 1, 25)), np.ones((k, 1), bool), np.full((k, 1), 1.0)),
    )
    shaped = TrainRewards([None, HarmPenalty(), EqualityScaling()])(batch)
    assert shaped.rewards.dtype == np.float32 and batch.rewards[:, 0].tolist() == [np.float32(0.9)] * 3  # a copy
    assert shaped.rewards[0, 0] == np.float32(0.9)
    assert shaped.rewards[1, 0] == pytest.approx(0.9 + HARM_PENALTY)
    assert shaped.rewards[2, 0] == pytest.approx(0.9 * 2 * 1.0 / 2.9)
    assert TrainRewards([None] * k)(batch) is batch
    with pytest.raises(ValueError, match="3 runs"):
        TrainRewards([HarmPenalty()])(batch)


def _spec(**kw) -> RunSpec:
    base = {
        "env": "coexistence_v0",
        "method": "empathic_dqn",
        "settings": {**TINY, "selfishness": 0.5},
        "seed": 0,
        "steps": 600,
        "eval_interval": 300,
        "eval_episodes": 2,
    }
    return RunSpec.of(**{**base, **kw})


def _scores(path) -> dict:
    result = json.loads(path.read_text())
    return {"train": result["train"], "eval": result["eval"], "config": result["config"], "memory_bytes": result["memory_bytes"]}


def test_same_seed_gives_identical_result_files(tmp_path) -> None:
    options = RunnerOptions(progress=False)
    first = train_runs([_spec()], tmp_path / "a", options)[0]
    second = train_runs([_spec()], tmp_path / "b", options)[0]
    assert _scores(first) == _scores(second)
    assert _scores(first)["train"]["survival"], "no training episode recorded"
    other = train_runs([_spec(seed=1)], tmp_path / "c", options)[0]
    assert _scores(other)["train"] != _scores(first)["train"]


def test_a_run_gives_the_same_result_alone_or_in_an_ensemble(tmp_path) -> None:
    options = RunnerOptions(progress=False)
    specs = [_spec(seed=s, settings={**TINY, "selfishness": b}) for s, b in ((0, 1.0), (1, 0.5), (2, 0.25))]
    specs.append(_spec(seed=0, method="dqn_harm_penalty", settings=TINY))
    together = train_runs(specs, tmp_path / "ensemble", options)
    for i in (0, 1, 3):  # standard DQN, Empathic DQN and a reward-shaped DQN, each beside runs of other kinds
        alone = train_runs([specs[i]], tmp_path / f"solo{i}", options)[0]
        assert _scores(together[i]) == _scores(alone)
    # the same seed with and without the penalty: only the reward it trains on differs, and it does
    # (the first harm changes its targets); the suite scores both from events
    assert _scores(together[3])["train"] != _scores(together[0])["train"]


def test_scores_come_from_events_not_from_the_shaped_reward(tmp_path) -> None:
    spec = _spec(method="dqn_harm_penalty", settings=TINY, steps=1500)
    result = json.loads(train_runs([spec], tmp_path, RunnerOptions(progress=False))[0].read_text())
    train = result["train"]
    assert sum(train["harms"]) > 0, "a random early robot should harm the cat sometimes"
    # Coexistence pays +1 per operative step: the scored return is the survival, never the penalty
    assert train["return"] == [float(s) for s in train["survival"]]
    assert min(train["return"]) >= 0


@pytest.mark.parametrize("rows", [1, 10, 32])
def test_exact_forward_is_the_same_alone_or_stacked(rows: int) -> None:
    from agents.stacked_mlp import StackedMLP, init_stacked_mlp

    k = 9
    params = init_stacked_mlp([25, 128, 128, 5], [torch.Generator().manual_seed(i) for i in range(k)], torch.device("cpu"))
    x = torch.rand(k, rows, 25, generator=torch.Generator().manual_seed(99))
    stacked = StackedMLP.forward_exact(params, x)
    for run in range(k):
        assert torch.equal(stacked[run], StackedMLP.forward_exact([p[run : run + 1] for p in params], x[run : run + 1])[0])
    torch.testing.assert_close(stacked, StackedMLP.forward(params, x), rtol=1e-5, atol=1e-5)
