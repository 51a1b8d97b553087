"""Costs priced when sampled: a transition stores its reward and its cost, and the learner's target
uses ``r − λ·c`` with the run's multiplier at the time of the update (both update kernels, bit for
bit on hand-made batches; a run that prices nothing computes what it did before); each
Lagrangian run's result file records λ after every training episode, as the dual ascent
recomputed from its own episode harms gives it, and the checker refuses a negative or NaN λ; the
constraint's verdict (:mod:`leaderboard.constraint`) on hand-made numbers."""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch
from helpers_batches import one_other
from helpers_resume import small_run

from agents import fused_update
from agents.empathic_dqn import EmpathicDQN
from agents.rewards import TrainRewards
from agents.settings import EmpathicDQNSettings
from agents.step_batch import StepBatch
from baselines.lagrangian import Lagrangian, dual_ascent
from empathy_zoo.experiment.result_reader import check_result
from empathy_zoo.result_file import PRICE_COLUMN, ResultFileError
from leaderboard.constraint import constraint_satisfaction

SMALL: dict[str, Any] = {"hidden_size": 32, "replay_capacity": 600, "learning_starts": 32, "target_update_interval": 50}
SHIPPED = Path(__file__).parent.parent / "docs/results/methods/runs/coexistence_v0__dqn_lagrangian-f418807a__s0.json"
"""A shipped Lagrangian run's result file (its λ column is set or removed by :func:`_shipped`)."""


@pytest.fixture(params=["torch", "numba"])
def kernel(request: pytest.FixtureRequest) -> str:
    """Each update kernel (numba where it builds here)."""
    if request.param == "numba":
        pytest.importorskip("numba")
        if not fused_update.numba_available():
            pytest.skip(f"numba kernels do not build here: {fused_update.numba_unavailable_reason()}")
    return request.param


def _transitions(seed: int, n: int = 500, terminal: bool = False) -> dict[str, np.ndarray]:
    """``n`` transitions of one run drawn from ``seed``: rewards and costs (0, 1 or 2 harms)."""
    rng = np.random.default_rng(seed)
    return {
        "obs": rng.integers(-1, 2, size=(n, 25)).astype(np.float32),
        "next_obs": rng.integers(-1, 2, size=(n, 25)).astype(np.float32),
        "swapped": rng.integers(-1, 2, size=(n, 1, 25)).astype(np.float32),
        "action": rng.integers(0, 5, n),
        "reward": rng.standard_normal(n).astype(np.float32),
        "terminated": np.ones(n, bool) if terminal else rng.random(n) < 0.05,
        "present": rng.random((n, 1)) < 0.8,
        "cost": rng.choice(np.array([0.0, 1.0, 2.0], np.float32), size=n, p=[0.7, 0.2, 0.1]),
    }


def _fill(
    learner: EmpathicDQN, runs: list[dict[str, np.ndarray]], rewards: list[np.ndarray] | None = None, costs: bool = True
) -> None:
    """Add the runs' transitions (with ``rewards`` in place of theirs where given; their costs where ``costs``)."""
    n = len(runs[0]["action"])

    def stacked(name: str) -> np.ndarray:
        return np.stack([run[name] for run in runs])

    present = stacked("present")
    reward = np.stack(rewards) if rewards is not None else stacked("reward")
    learner.replay.add(
        stacked("obs"), stacked("next_obs"), stacked("swapped"), stacked("action"), reward, stacked("terminated"),
        present, np.ones_like(present), np.zeros_like(present),
        **({"cost": stacked("cost")} if costs else {}),
    )  # fmt: skip
    assert learner.replay.size == n


def _learner(kernel: str, runs: int = 1, priced: list[bool] | None = None, seeds: list[int] | None = None) -> EmpathicDQN:
    """A DQN learner (β = 1) of ``runs`` runs; pricing its costs for the runs ``priced`` (``None``: none)."""
    seeds = list(range(runs)) if seeds is None else seeds
    learner = EmpathicDQN([EmpathicDQNSettings(selfishness=1.0, **SMALL)] * runs, seeds, 25, update_kernel=kernel)
    if priced is not None:
        learner.price_costs(priced)
    return learner


def _set_prices(learner: EmpathicDQN, values: list[float]) -> None:
    """Set each run's price now (as ``observe`` does from ``StepBatch.prices``)."""
    assert learner.prices is not None
    learner.prices[:] = torch.tensor(values)


def _priced(reward: np.ndarray, price: float, cost: np.ndarray) -> np.ndarray:
    """``r − λ·c`` in float32, the product rounded first (as both kernels compute it)."""
    return (reward - np.float32(price) * cost).astype(np.float32)


# ---------------------------------------------------------------------------- the learner
def test_a_hand_made_batch_is_priced_with_the_multiplier_of_the_update(kernel: str) -> None:
    """Terminal transitions stored while λ was 1, then λ rises to 7.5: the target of every sampled
    transition is ``r − 7.5·c`` (the first update's targets of the compiled step, the sampled
    batch of the PyTorch one), and the torch and compiled targets are equal bit for bit."""
    data = _transitions(3, terminal=True)
    learner = _learner(kernel, priced=[True])
    _fill(learner, [data])
    _set_prices(learner, [1.0])
    _set_prices(learner, [7.5])  # (λ changed after the transitions were stored)
    index = learner.sample_indices()
    expected = _priced(data["reward"], 7.5, data["cost"])[index.numpy()[0]]
    sampled = learner.sample_batch(index)
    assert "cost" not in sampled and sampled["reward"].dtype == torch.float32
    np.testing.assert_array_equal(sampled["reward"].numpy()[0], expected)
    assert (data["cost"][index.numpy()[0]] > 0).any()  # (λ matters in this batch)
    learner.update()
    if kernel == "numba":
        assert learner._numba is not None
        np.testing.assert_array_equal(learner._numba._targets[0], expected)  # y = r − λ·c + 0 (terminal)


TRIO = {"torch": "torch", "numba": "numba", "split": "numba"}


def test_both_kernels_price_a_batch_alike() -> None:
    """The compiled one-call step, its split path (torch targets in between) and the PyTorch step
    take the same priced targets: 40 updates of each land together (the PyTorch update to float32
    sums), the one-call and split compiled updates bit for bit."""
    pytest.importorskip("numba")
    if not fused_update.numba_available():
        pytest.skip(f"numba kernels do not build here: {fused_update.numba_unavailable_reason()}")
    data = [_transitions(seed) for seed in (5, 6)]
    learners = {name: _learner(kernel, runs=2, priced=[True, True]) for name, kernel in TRIO.items()}
    learners["split"].targets = learners["split"].targets  # type: ignore[method-assign]  # (the split path)
    for learner in learners.values():
        _fill(learner, data)
        _set_prices(learner, [3.25, 0.5])
    for _ in range(40):
        losses = {name: learner.update() for name, learner in learners.items()}
        assert losses["numba"] == losses["split"]
        assert losses["numba"] == pytest.approx(losses["torch"], rel=1e-4)
    for a, b, c in zip(*([p.detach() for p in learners[name].online] for name in ("numba", "split", "torch")), strict=True):
        assert torch.equal(a, b)
        assert float((a - c).abs().max() / c.abs().max()) <= 1e-5


def test_a_priced_learner_trains_as_one_whose_rewards_were_priced_at_that_multiplier(kernel: str) -> None:
    """Stored ``(r, c)`` priced at λ = 4 in every update trains bit for bit as a learner without
    costs whose replay holds ``r − 4·c``: the pricing is that subtraction and nothing else."""
    data = _transitions(7)
    priced, plain = _learner(kernel, priced=[True]), _learner(kernel)
    _fill(priced, [data])
    _set_prices(priced, [4.0])
    _fill(plain, [data], rewards=[_priced(data["reward"], 4.0, data["cost"])], costs=False)
    for _ in range(60):
        assert priced.update() == plain.update()
    for a, b in zip(priced.online + priced.target, plain.online + plain.target, strict=True):
        assert torch.equal(a, b)


def test_a_run_that_prices_nothing_trains_as_it_did_beside_one_that_does(kernel: str) -> None:
    """In an ensemble whose run 0 prices its costs (λ = 9), run 1, which prices none, computes bit
    for bit what it computes in a learner without costs; its replay is the same."""
    data = [_transitions(11), _transitions(12)]
    mixed = _learner(kernel, runs=2, priced=[True, False], seeds=[0, 1])
    _fill(mixed, [data[0], {**data[1], "cost": np.zeros_like(data[1]["cost"])}])
    _set_prices(mixed, [9.0, 0.0])
    alone = _learner(kernel, runs=1, seeds=[1])
    _fill(alone, [data[1]], costs=False)
    for _ in range(60):
        mixed.update()
        alone.update()
    for mine, theirs in zip(mixed.online, alone.online, strict=True):
        assert torch.equal(mine[1:], theirs)
    assert mixed.memory_bytes_of(1) == alone.memory_bytes_of(0)
    assert mixed.memory_bytes_of(0) == alone.memory_bytes_of(0) + 4 * SMALL["replay_capacity"]


def test_observe_stores_the_cost_and_takes_the_steps_multiplier() -> None:
    """``observe`` stores ``StepBatch.costs`` beside the reward and prices the updates that follow
    with ``StepBatch.prices``; a learner not told to price costs refuses a batch that carries them."""
    learner = _learner("torch", runs=2, priced=[True, True])
    zeros = np.zeros((2, 1))
    batch = StepBatch(
        obs=np.zeros((2, 1, 25), np.float32),
        actions=np.array([[1], [2]]),
        rewards=np.array([[0.5], [-1.0]], np.float32),
        terminated=np.zeros((2, 1), bool),
        next_obs=np.zeros((2, 1, 25), np.float32),
        harms=np.array([[1], [0]]),
        battery_return=zeros,
        costs=np.array([[1.0], [0.0]], np.float32),
        prices=np.array([2.5, 0.0], np.float32),
        **one_other(np.zeros((2, 1, 25), np.float32), np.ones((2, 1), bool), zeros),
    )
    learner.observe(batch)
    assert learner.replay.cost is not None
    assert learner.replay.cost[:, 0].tolist() == [1.0, 0.0] and learner.replay.reward[:, 0].tolist() == [0.5, -1.0]
    assert learner.prices is not None and learner.prices.tolist() == [2.5, 0.0]
    assert learner.sample_batch(torch.zeros((2, 4), dtype=torch.int64))["reward"][:, 0].tolist() == [-2.0, -1.0]
    with pytest.raises(ValueError, match="price"):
        _learner("torch", runs=2).observe(batch)


def test_the_cost_column_is_kept_by_a_checkpoint_and_other_layouts_are_refused(kernel: str) -> None:
    """A priced learner's checkpoint holds the costs and the multipliers and continues exactly; a
    replay saved without costs (another method, or a Lagrangian run of a version that priced
    harms when stored) is refused by a learner that prices them, and the other way round."""
    data = _transitions(9)
    first = _learner(kernel, priced=[True])
    _fill(first, [data])
    _set_prices(first, [2.0])
    for _ in range(30):
        first.update()
    state = copy.deepcopy(first.state_dict())
    assert state["replay"]["cost"].shape == (1, 500)
    resumed = _learner(kernel, priced=[True])
    resumed.load_state_dict(state)
    assert resumed.prices is not None and resumed.prices.tolist() == [2.0]
    for _ in range(30):
        assert first.update() == resumed.update()
    plain = _learner(kernel)
    _fill(plain, [data], costs=False)
    with pytest.raises(ValueError, match="version"):
        _learner(kernel, priced=[True]).load_state_dict(plain.state_dict())
    with pytest.raises(ValueError, match="cost"):
        _learner(kernel).load_state_dict(state)
    assert "cost" not in plain.state_dict()["replay"] and "prices" not in plain.state_dict()


def test_the_memory_estimate_counts_the_cost_column() -> None:
    learner = _learner("torch", priced=[True])
    config = [EmpathicDQNSettings(selfishness=1.0, **SMALL)]
    assert EmpathicDQN.memory_needed(config, 25, priced_costs=True).per_run == learner.memory_bytes_per_run()
    assert EmpathicDQN.memory_needed(config, 25).per_run == _learner("torch").memory_bytes_per_run()


# ---------------------------------------------------------------------------- the transform and the trainer
def test_train_rewards_hand_over_the_reward_the_cost_and_the_multiplier_after_the_step() -> None:
    """The Lagrangian transform leaves the reward as the environment gave it and hands the step's
    harms as its cost, and each run's λ after the step (after the dual ascent of an episode that
    ended in it) as its price; a run without it gets cost 0 at price 0."""
    lagrangian = Lagrangian(cost_limit=0.5, lambda_lr=2.0, lambda_init=1.0)
    rewards = TrainRewards([lagrangian, None], seeds=[0, 1])
    assert rewards.priced_runs.tolist() == [True, False]
    zeros = np.zeros((2, 1))

    def step(harms: list[int], ended: bool) -> StepBatch:
        return StepBatch(
            obs=np.zeros((2, 1, 25), np.float32),
            actions=np.zeros((2, 1), np.int64),
            rewards=np.array([[1.0], [0.25]], np.float32),
            terminated=np.full((2, 1), ended),
            next_obs=np.zeros((2, 1, 25), np.float32),
            harms=np.array(harms)[:, None],
            battery_return=zeros,
            truncated=np.zeros((2, 1), bool),
            **one_other(np.zeros((2, 1, 25), np.float32), np.ones((2, 1), bool), zeros),
        )

    trained = rewards(step([1, 1], False))
    assert trained.costs is not None and trained.prices is not None
    assert trained.rewards.tolist() == [[1.0], [0.25]] and trained.costs.tolist() == [[1.0], [0.0]]
    assert trained.prices.tolist() == [1.0, 0.0] and trained.prices.dtype == np.float32
    trained = rewards(step([2, 0], True))  # the episode ends with 3 harms: λ = 1 + 2·(3 − 0.5)
    assert trained.costs is not None and trained.prices is not None
    assert trained.costs.tolist() == [[2.0], [0.0]] and trained.prices.tolist() == [6.0, 0.0]
    prices = rewards.prices()
    assert prices is not None and prices.tolist() == [6.0, 0.0] and prices.dtype == np.float64
    assert trained.priced_rewards.tolist() == [[1.0 - 12.0], [0.25]]  # (priced at λ of the step, as the tracker logs it)
    assert TrainRewards([None], seeds=[0]).prices() is None


def test_a_lagrangian_run_records_lambda_after_every_training_episode(tmp_path) -> None:
    """A 600-step run's result file holds ``train.lambda``, one value per training episode: the dual
    ascent recomputed from its own ``train.harms`` from ``lambda_init``; plain DQN's holds none."""
    from empathy_zoo.experiment.result_reader import read_result
    from empathy_zoo.training import RunnerOptions, train_runs

    spec = small_run("dqn_lagrangian", reward={"cost_limit": 0.5, "lambda_lr": 2.0, "lambda_init": 0.25})
    [path] = train_runs([spec], tmp_path / "lag", RunnerOptions(progress=False, checkpoint_interval=0))
    train = read_result(path).train
    harms, recorded = train.metrics["harms"], train.column(PRICE_COLUMN)
    assert len(recorded) == len(harms) == len(train.episode_end_step) > 5
    multiplier, expected = np.array([0.25]), []
    for harm in harms:
        multiplier = dual_ascent(multiplier, np.array([float(harm)]), 0.5, 2.0)
        expected.append(float(multiplier[0]))
    assert recorded.tolist() == pytest.approx(expected, abs=1e-6)
    assert 0 in recorded[1:] or min(recorded) < max(recorded)  # (λ moved)
    assert sum(harms) > 0
    [plain] = train_runs([small_run("dqn")], tmp_path / "dqn", RunnerOptions(progress=False, checkpoint_interval=0))
    assert PRICE_COLUMN not in json.loads(plain.read_text())["train"]


# ---------------------------------------------------------------------------- the checker
def _shipped(last: object | None = None, length: int = 0) -> dict:
    """The shipped result document with ``train.lambda``: zeros then ``last`` (``None``: without
    the column), ``length`` more or fewer values than episodes."""
    document = json.loads(SHIPPED.read_text())
    document["train"].pop(PRICE_COLUMN, None)  # (as a file from before λ was recorded)
    if last is not None:
        episodes = len(document["train"]["harms"]) + length
        document["train"][PRICE_COLUMN] = [0.0] * (episodes - 1) + [last]
    return document


@pytest.mark.parametrize("last, length", [(-0.5, 0), (float("nan"), 0), (math.inf, 0), ("2", 0), (1.0, -1), (1.0, 1)])
def test_the_checker_refuses_a_negative_nan_or_misshapen_lambda(last: object, length: int) -> None:
    with pytest.raises(ResultFileError, match=r"train"):
        check_result(_shipped(last, length), SHIPPED)


def test_the_checker_takes_a_lambda_series_and_files_without_one() -> None:
    assert check_result(_shipped(2.5), SHIPPED)["train"][PRICE_COLUMN][-2:] == [0.0, 2.5]
    assert PRICE_COLUMN not in check_result(_shipped(), SHIPPED)["train"]


# ---------------------------------------------------------------------------- the constraint's verdict
def test_the_constraint_verdict_on_hand_made_numbers() -> None:
    """Three seeds of 20 training episodes each (the final 10 %: their last two) and two greedy
    episodes each: the per-seed means, their mean, the t interval, and where d lies."""
    train = [[1.0] * 18 + [0.0, 0.0], [1.0] * 18 + [0.0, 1.0], [1.0] * 18 + [1.0, 1.0]]
    greedy = [[0.0, 0.0], [0.0, 0.0], [0.0, 0.0]]
    verdict = constraint_satisfaction(train, greedy, cost_limit=0.1)
    final = verdict.final_training
    assert final.per_seed == (0.0, 0.5, 1.0) and final.mean == pytest.approx(0.5)
    half = 6.205346816570682 * 0.5 / math.sqrt(3)  # t(0.9875, 2)·s/√n, s = 0.5: the leaderboard's 95 % interval
    assert (final.low, final.high) == (0.0, pytest.approx(0.5 + half))  # (no cost below 0)
    assert final.limit_lies == "inside"  # d = 0.1 within [0, 2.29]
    assert verdict.greedy.mean == 0.0 and verdict.greedy.limit_lies == "above"  # met: every seed harms 0 < d
    assert constraint_satisfaction([[0.3] * 10] * 4, [[0.0]] * 4, cost_limit=0.1).final_training.limit_lies == "below"
    assert verdict.cost_limit == 0.1 and verdict.seeds == 3 and verdict.confidence == 0.95
    tight = constraint_satisfaction([[0.0] * 9 + [0.2], [0.0] * 9 + [0.25]], [[0.0]] * 2, cost_limit=0.5)
    assert tight.final_training.per_seed == (0.2, 0.25) and tight.final_training.limit_lies == "inside"
    assert constraint_satisfaction([[0.2]] * 3, [[0.0]] * 3, cost_limit=0.5).final_training.limit_lies == "above"


def test_the_constraint_verdict_needs_runs_and_says_so() -> None:
    with pytest.raises(ValueError, match="run"):
        constraint_satisfaction([], [], cost_limit=0.1)
    with pytest.raises(ValueError, match="greedy"):
        constraint_satisfaction([[1.0]], [[0.0], [1.0]], cost_limit=0.1)
    one = constraint_satisfaction([[1.0, 0.0, 0.0]], [[0.0]], cost_limit=0.1)
    assert one.final_training.mean == 0.0 and one.final_training.low == one.final_training.high == 0.0  # one seed: a point


def test_a_lagrangian_checkpoint_from_before_costs_were_priced_when_sampled_is_refused(tmp_path, monkeypatch) -> None:
    """A Lagrangian run's checkpoint whose replay holds no costs (as one written before they were
    priced when sampled) is refused, saying it is from another version; the same checkpoint with
    its costs resumes."""
    from empathy_zoo.training import RunnerOptions, ensemble, train_runs
    from empathy_zoo.training.checkpoint import CheckpointError, load_checkpoint, save_checkpoint
    from empathy_zoo.training.resume import checkpoint_path

    spec = small_run("dqn_lagrangian", reward={"cost_limit": 0.5, "lambda_lr": 2.0})
    real = ensemble.save_checkpoint

    def save_then_die(path, payload):  # type: ignore[no-untyped-def]
        real(path, payload)
        raise KeyboardInterrupt

    monkeypatch.setattr(ensemble, "save_checkpoint", save_then_die)
    options = RunnerOptions(progress=False, checkpoint_interval=250)
    with pytest.raises(KeyboardInterrupt):
        train_runs([spec], tmp_path, options)
    monkeypatch.setattr(ensemble, "save_checkpoint", real)
    path = checkpoint_path(tmp_path, [spec])
    saved = load_checkpoint(path)
    assert PRICE_COLUMN in saved["logs"][0] and "cost" in saved["learner"]["replay"]
    old = copy.deepcopy(saved)
    del old["learner"]["replay"]["cost"], old["learner"]["prices"]
    save_checkpoint(path, {key: value for key, value in old.items() if key != "format"})
    with pytest.raises(CheckpointError, match="another method, or by a version that priced costs when they were stored"):
        train_runs([spec], tmp_path, options)
    save_checkpoint(path, {key: value for key, value in saved.items() if key != "format"})
    [result] = train_runs([spec], tmp_path, options)
    assert len(json.loads(result.read_text())["train"][PRICE_COLUMN]) > 0
