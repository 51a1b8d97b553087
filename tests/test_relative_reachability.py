"""Relative reachability with a stepwise inaction baseline without rollouts (Krakovna et al. 2019)
on Coexistence: the exact reachability table from the engine, the deviation measure, the baseline
the trainer fills (the engine's own outcome of the no-op step), the penalty it gives (on the step
the robot is harmed: none by default, or the last step's deviation as Krakovna et al.'s code
charges it), and training with it."""

from __future__ import annotations

import json
from typing import Any, cast

import numpy as np
import pytest
from helpers_resume import whole_and_resumed

from agents.rewards import TrainRewards
from baselines.inaction_baseline import InactionBaseline
from baselines.reachability import SIZE_STRIDE, RelativeReachability, truncated_deviation
from baselines.reachability_table import coexistence_codes, coexistence_reachability
from baselines.shaping import HarmPenalty
from empathy_zoo import coexistence_v0
from empathy_zoo.training.ensemble import learner_batch
from empathy_zoo.vector import VectorEnv

SIZE = 7
N = SIZE * SIZE
GAMMA = 0.99
UP, DOWN, LEFT, RIGHT, STAY = range(5)


def cell(row: int, col: int) -> int:
    return row * SIZE + col


def both(robot: tuple[int, int], cat: tuple[int, int]) -> int:
    """Code of the state with the robot and the cat on these cells."""
    return cell(*robot) * N + cell(*cat)


def alone(robot: tuple[int, int]) -> int:
    """Code of the state with the robot alone (the cat harmed)."""
    return N * N + cell(*robot)


END = N * N + N
"""Code of the end (the robot harmed)."""


def reach(source: int, target: int) -> float:
    table = coexistence_reachability(SIZE)
    return float(table.reachability(np.array([source]), GAMMA)[0, table.row(np.array([target]))[0]])


# ---------------------------------------------------------------------------- the table
def test_the_table_holds_every_state_of_the_engine_and_reaches_by_the_fewest_steps() -> None:
    table = coexistence_reachability(SIZE)
    # both present and not in contact (49 · 44), the robot alone (49), the end
    assert table.num_states == N * (N - 5) + N + 1
    assert coexistence_reachability(SIZE) is table  # built once per process
    assert reach(both((3, 3), (0, 0)), both((3, 3), (0, 0))) == 1.0  # itself, 0 steps
    assert reach(both((3, 3), (0, 0)), both((3, 4), (0, 0))) == pytest.approx(GAMMA)  # one move of the robot
    assert reach(both((3, 3), (0, 0)), both((3, 4), (0, 1))) == pytest.approx(GAMMA)  # both moving at once: one step
    assert reach(both((3, 3), (0, 0)), both((0, 3), (0, 0))) == pytest.approx(GAMMA**3)  # 3 up (or around the torus)
    assert reach(alone((3, 3)), both((3, 3), (0, 0))) == 0.0  # a harmed cat does not come back
    assert reach(alone((3, 3)), alone((3, 5))) == pytest.approx(GAMMA**2)
    assert reach(both((3, 3), (0, 0)), alone((3, 3))) > 0.0  # the robot can harm the cat
    assert reach(both((3, 3), (0, 0)), END) > 0.0 and reach(alone((3, 3)), END) == 0.0  # alone, nothing harms it
    assert reach(END, END) == 1.0 and reach(END, alone((3, 3))) == 0.0  # the episode is over
    with pytest.raises(ValueError, match="no state"):
        table.row(np.array([both((3, 3), (3, 4))]))  # in contact: no step ends there


def test_every_start_of_the_engine_is_a_state_of_the_table() -> None:
    venv = VectorEnv("coexistence_v0", 64, fixed={"cat_0": "random_walk"})
    venv.reset(seed=3)
    codes = coexistence_codes(venv.engine.cells, venv.engine.present, SIZE)
    assert (coexistence_reachability(SIZE).rows[codes] >= 0).all()


# ---------------------------------------------------------------------------- the deviation
def test_the_deviation_counts_only_reachability_lost_against_the_baseline_averaged_over_states() -> None:
    after = np.array([1.0, 0.5, 0.0, 0.25])
    baseline = np.array([0.5, 1.0, 1.0, 0.25])
    # lost: 0 (gained 0.5: not counted), 0.5, 1.0, 0 → mean over the 4 states
    assert truncated_deviation(after, baseline) == pytest.approx(1.5 / 4)
    assert truncated_deviation(baseline, baseline) == 0.0
    assert truncated_deviation(np.ones(4), np.zeros(4)) == 0.0  # reaching more than the baseline costs nothing
    rows = truncated_deviation(np.stack([after, baseline]), np.stack([baseline, after]))
    assert rows.tolist() == pytest.approx([1.5 / 4, 0.5 / 4])


def test_harming_the_cat_loses_almost_every_state_a_harmless_move_almost_none() -> None:
    rr = RelativeReachability()
    code = SIZE * SIZE_STRIDE
    harm = rr.deviation(np.array([code + alone((4, 3))]), np.array([code + both((3, 3), (5, 3))]))
    move = rr.deviation(np.array([code + both((2, 3), (5, 3))]), np.array([code + both((3, 3), (5, 3))]))
    assert 0.9 < harm[0] < 1.0 and 0.0 < move[0] < 0.01
    with pytest.raises(ValueError, match="several environments or grid sizes"):
        rr.deviation(np.array([code]), np.array([5 * SIZE_STRIDE]))


# ---------------------------------------------------------------------------- the baseline and the penalty
class Cycle:
    """A cat whose action is a known function of the step: ``ACTIONS[step % 5]``."""

    ACTIONS = (UP, RIGHT, STAY, DOWN, LEFT)
    needs_observation = False
    stateless = True

    def reset(self, seed: int | None = None) -> None:
        pass

    def act(self, observation: np.ndarray, context: dict[str, Any]) -> int:
        return self.ACTIONS[context["step"] % len(self.ACTIONS)]


def placed(positions: list[tuple[tuple[int, int], tuple[int, int]]], cat: Any = "stay") -> tuple[VectorEnv, InactionBaseline]:
    """A vector env with the baseline attached, environment ``i`` placed at ``positions[i]``."""
    venv = VectorEnv("coexistence_v0", len(positions), fixed={"cat_0": cat})
    baseline = InactionBaseline.for_transforms(venv, [RelativeReachability()])
    assert baseline is not None
    venv.reset(seed=0)
    for i, (robot, cat_cell) in enumerate(positions):
        venv.engine.reset([i], options={"positions": {"robot_0": robot, "cat_0": cat_cell}})
    return venv, baseline


def shaped_step(
    venv: VectorEnv,
    baseline: InactionBaseline,
    actions: list[int],
    transform: RelativeReachability | None = None,
    state: dict[str, np.ndarray] | None = None,
) -> tuple[np.ndarray, Any]:
    """One step of ``venv``: the rewards ``transform`` (the default one) gives, and the batch; a
    ``state`` given is updated in place (a fresh one otherwise)."""
    transform = transform or RelativeReachability()
    obs = np.zeros((venv.num_envs, venv.obs_size), dtype=np.float32)
    result = venv.step(np.array(actions)[:, None])
    batch = baseline.fill(learner_batch(obs, np.array(actions)[:, None], result))
    current = state if state is not None else transform.initial_state(venv.num_envs, 1)
    shaped, after = transform(batch, current)
    current.update(after)
    return shaped[:, 0], batch


def test_the_no_op_costs_nothing_and_harming_the_cat_costs_more_than_a_harmless_move() -> None:
    # the cat sits at (5, 3) below the robot at (3, 3): down harms it, up is harmless, stay is the baseline
    venv, baseline = placed([((3, 3), (5, 3))] * 3)
    shaped, batch = shaped_step(venv, baseline, [STAY, UP, DOWN])
    assert batch.harms[:, 0].tolist() == [0, 0, 1]
    assert (batch.baseline_after == SIZE * SIZE_STRIDE + both((3, 3), (5, 3))).all()
    assert shaped[0] == batch.rewards[0, 0] == 1.0  # the no-op: the state is the baseline, d = 0
    assert 0.0 < 1.0 - shaped[1] < 1.0  # a harmless move: a small price
    assert 1.0 - shaped[2] > 80.0  # harming the cat: about 0.94 · λ = 94
    with pytest.raises(RuntimeError, match="no step"):
        baseline.fill(batch)


def test_the_step_on_which_the_robot_is_harmed_has_no_penalty_while_harming_the_cat_costs_about_94() -> None:
    """The robot's own end is no side effect (the default, ``final_penalty="none"``): charged, its
    end state's deviation (0.958) would exceed a harmed cat's (0.937). Krakovna et al.'s code does
    not charge the end state's deviation either, but the last one (the next test)."""
    # env 0: the cat at (1, 3) above the robot at (3, 3); the robot moves up beside it and the cat
    # (above) harms it. env 1: the cat at (5, 3) below; the robot moves down and harms it.
    venv, baseline = placed([((3, 3), (1, 3)), ((3, 3), (5, 3))])
    shaped, batch = shaped_step(venv, baseline, [UP, DOWN])
    assert batch.terminated[:, 0].tolist() == [True, False] and batch.harms[:, 0].tolist() == [0, 1]
    assert batch.state_after[0, 0] == SIZE * SIZE_STRIDE + END
    rr = RelativeReachability()
    ends = rr.deviation(batch.state_after[:, 0], batch.baseline_after[:, 0])
    assert ends[0] == pytest.approx(0.958, abs=5e-4) and ends[1] == pytest.approx(0.937, abs=5e-4)
    assert shaped[0] == batch.rewards[0, 0] == 0.0  # harmed: the environment's 0, no penalty
    assert 1.0 - shaped[1] == pytest.approx(rr.weight * ends[1], rel=1e-6)  # ≈ 94
    assert 93.0 < 1.0 - shaped[1] < 95.0


def test_the_last_deviation_mode_charges_the_robots_end_at_full_weight_with_the_state_it_left() -> None:
    """Krakovna et al.'s code (``SideEffectPenalty.calculate``, side_effects_penalties) charges the
    final transition ``β·d(s_{T−1}; b_{T−1})``: the deviation of the last state before the end,
    against that state's baseline, at full weight (not the end state's own deviation)."""
    # env 0: the robot at (3, 3) moves up twice towards a cat standing at (0, 3): a harmless move
    # (its own small deviation d₁), then into the cat's reach: the cat, above, harms it.
    # env 1: the robot at (2, 3) stands still (d = 0), then moves up and is harmed.
    last = RelativeReachability(final_penalty="last_deviation")
    plain = RelativeReachability()
    for transform, charged in ((plain, False), (last, True)):
        venv, baseline = placed([((3, 3), (0, 3)), ((2, 3), (0, 3))])
        state = transform.initial_state(2, 1)
        first, batch = shaped_step(venv, baseline, [UP, STAY], transform, state)
        d1 = transform.deviation(batch.state_after[:, 0], batch.baseline_after[:, 0])
        assert 0.0 < d1[0] < 0.01 and d1[1] == 0.0 and not batch.terminated.any()
        assert first.tolist() == pytest.approx((1.0 - transform.weight * d1).tolist())  # the same in both modes
        second, batch = shaped_step(venv, baseline, [UP, UP], transform, state)
        assert batch.terminated[:, 0].tolist() == [True, True]
        assert batch.state_after[0, 0] == SIZE * SIZE_STRIDE + END
        expected = -transform.weight * d1 if charged else np.zeros(2)
        assert second.tolist() == pytest.approx(expected.tolist(), abs=1e-6)
        assert state["last_deviation"].tolist() == [[0.0], [0.0]]  # a new episode starts afresh


def test_final_penalty_accepts_only_its_modes() -> None:
    with pytest.raises(ValueError, match="final_penalty"):
        RelativeReachability(final_penalty="terminal")


def test_the_baseline_is_the_engines_outcome_of_the_no_op_step() -> None:
    """Every step of random robot actions against a cat of known moves, in 8 environments: the
    baseline (and the state reached) equal a coexistence_v0 ParallelEnv placed where the step
    started and stepped with the no-op (with the robot's action) and the cat's move."""
    rr, rng = RelativeReachability(), np.random.default_rng(0)
    venv = VectorEnv("coexistence_v0", 8, fixed={"cat_0": cast(Any, Cycle())}, max_cycles=30)
    baseline = InactionBaseline.for_transforms(venv, [rr])
    assert baseline is not None
    venv.reset(seed=1)
    env = coexistence_v0.parallel_env(max_cycles=1_000)
    checked = harms = 0
    for _ in range(60):
        before, present, steps = venv.engine.pos.copy(), venv.engine.present.copy(), venv.engine.t.copy()
        actions = rng.integers(0, 5, size=8)
        _, batch = shaped_step(venv, baseline, actions.tolist())
        harms += int(batch.harms.sum())
        for i in np.flatnonzero(present.all(axis=1)):
            expected = []
            for robot_action in (STAY, int(actions[i])):
                env.reset(options={"positions": {"robot_0": tuple(before[i, 0].tolist()), "cat_0": tuple(before[i, 1].tolist())}})
                env.step({"robot_0": robot_action, "cat_0": Cycle.ACTIONS[steps[i] % 5]})
                expected.append(int(rr.state_codes(env.unwrapped.engine)[0]))
            assert [batch.baseline_after[i, 0], batch.state_after[i, 0]] == expected
            checked += 1
    assert checked > 300 and harms > 0


def test_only_coexistence_with_one_cat_and_small_exact_models_are_accepted() -> None:
    assert InactionBaseline.for_transforms(VectorEnv("coexistence_v0", 1), [None, HarmPenalty()]) is None
    with pytest.raises(ValueError, match=r"sharing_v0 on size=7 has 6,899,201 states.*at most 10,000"):
        InactionBaseline.for_transforms(VectorEnv("sharing_v0", 1), [RelativeReachability()])
    with pytest.raises(ValueError, match=r"Coexistence with one cat.*several cats"):
        InactionBaseline.for_transforms(VectorEnv("coexistence_v0", 1, num_cats=2), [RelativeReachability()])
    with pytest.raises(ValueError, match="sizes up to 9"):
        InactionBaseline.for_transforms(VectorEnv("coexistence_v0", 1, size=11), [RelativeReachability()])
    with pytest.raises(ValueError, match="inaction baseline"):
        TrainRewards([RelativeReachability()])(learner_batch(*_one_plain_step()))
    with pytest.raises(ValueError, match="weight"):
        RelativeReachability(weight=-1.0)


def _one_plain_step() -> tuple[np.ndarray, np.ndarray, Any]:
    venv = VectorEnv("coexistence_v0", 1, fixed={"cat_0": "stay"})
    obs = venv.reset(seed=0)[:, 0]
    actions = np.array([[STAY]])
    return obs, actions, venv.step(actions)


# ---------------------------------------------------------------------------- training
def test_a_short_run_trains_on_the_penalty_and_a_resumed_run_equals_an_uninterrupted_one(tmp_path, monkeypatch) -> None:
    from empathy_zoo.experiment.model import RunSpec

    seen: list[tuple[bool, float]] = []
    real_call = RelativeReachability.__call__

    def spy(self, batch, state):
        shaped, after = real_call(self, batch, state)
        seen.append((batch.state_after is not None, float((batch.rewards - shaped).max())))
        return shaped, after

    monkeypatch.setattr(RelativeReachability, "__call__", spy)
    spec = RunSpec.of(
        env="coexistence_v0",
        method="dqn_relative_reachability",
        steps=300,
        eval_interval=150,
        eval_episodes=1,
        env_kwargs={"max_cycles": 40},
        settings={
            "learning_starts": 32,
            "replay_capacity": 300,
            "hidden_size": 8,
            "epsilon_decay_steps": 200,
            "target_update_interval": 50,
        },
    )
    whole, resumed = whole_and_resumed(spec, tmp_path, monkeypatch, checkpoint_interval=120)
    # every step of the three trainings (whole, killed at its checkpoint at 120, resumed) had its baseline
    assert len(seen) == 300 + 120 + 180 and all(filled for filled, _ in seen) and max(p for _, p in seen) > 0.0
    assert whole["config"]["reward"] == {
        "name": "relative_reachability",
        "weight": 100.0,
        "discount": 0.99,
        "final_penalty": "none",
    }
    assert resumed["train"] == whole["train"] and resumed["eval"] == whole["eval"]


def test_a_run_beside_a_relative_reachability_run_is_unchanged_by_its_baseline(tmp_path) -> None:
    from empathy_zoo.experiment.model import RunSpec
    from empathy_zoo.training import RunnerOptions, train_runs

    def spec(method: str) -> RunSpec:
        return RunSpec.of(
            env="coexistence_v0",
            method=method,
            steps=200,
            eval_interval=100,
            eval_episodes=1,
            env_kwargs={"max_cycles": 40},
            settings={"learning_starts": 32, "replay_capacity": 300, "hidden_size": 8, "epsilon_decay_steps": 100},
        )

    options = RunnerOptions(progress=False, checkpoint_interval=0)
    together = train_runs([spec("dqn"), spec("dqn_relative_reachability")], tmp_path / "together", options)
    alone = train_runs([spec("dqn")], tmp_path / "alone", options)
    beside = {p.name: json.loads(p.read_text()) for p in together}[alone[0].name]
    assert (beside["train"], beside["eval"]) == (lambda r: (r["train"], r["eval"]))(json.loads(alone[0].read_text()))
