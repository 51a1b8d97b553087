"""``VectorEnv.watch_engine``: a watcher sees every engine step of the vector env, with the joint
actions, just before and just after it (before any autoreset); the stepwise inaction baseline
watches this way and leaves the vector env's engine as it is."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from helpers_batches import one_other

from agents.step_batch import StepBatch
from baselines.inaction_baseline import InactionBaseline
from baselines.reachability import RelativeReachability
from empathy_zoo.vector import VectorEnv

STAY = 4


class Recorder:
    """Records what each call of the watch saw."""

    def __init__(self) -> None:
        self.calls: list[tuple[Any, ...]] = []

    def before_engine_step(self, engine: Any, actions: np.ndarray) -> None:
        self.calls.append(("before", actions.copy(), engine.t.copy()))

    def after_engine_step(self, engine: Any, actions: np.ndarray, events: Any) -> None:
        self.calls.append(("after", actions.copy(), engine.t.copy(), engine.observe(0), events.episode_over.copy()))


def test_a_watcher_sees_the_joint_actions_before_and_after_each_engine_step() -> None:
    venv = VectorEnv("coexistence_v0", 3, fixed={"cat_0": "stay"}, max_cycles=2)
    recorder, second = Recorder(), Recorder()
    venv.watch_engine(recorder)
    venv.watch_engine(second)
    venv.reset(seed=0)
    assert recorder.calls == []  # a reset is no step
    rng = np.random.default_rng(0)
    for step in range(4):
        actions = rng.integers(0, 5, size=(3, 1))
        out = venv.step(actions)
        before, after = recorder.calls[-2:]
        assert before[0] == "before" and after[0] == "after"
        for call in (before, after):
            np.testing.assert_array_equal(call[1], np.concatenate([actions, np.full((3, 1), STAY)], axis=1))
        np.testing.assert_array_equal(after[2], before[2] + 1)
        np.testing.assert_array_equal(after[3], out.final_observations[:, 0])  # the end of the step, before the autoreset
        np.testing.assert_array_equal(after[4], out.episode_over)
        assert out.episode_over.all() == (step % 2 == 1)
    assert len(recorder.calls) == 8 and len(second.calls) == 8


def test_something_that_cannot_watch_is_refused() -> None:
    venv = VectorEnv("coexistence_v0", 1)
    with pytest.raises(TypeError, match="before_engine_step"):
        venv.watch_engine(object())  # type: ignore[arg-type]


def test_the_inaction_baseline_watches_without_standing_in_for_the_engine() -> None:
    venv = VectorEnv("coexistence_v0", 2, fixed={"cat_0": "stay"})
    engine = venv.engine
    baseline = InactionBaseline.for_transforms(venv, [RelativeReachability()])
    assert baseline is not None and venv.engine is engine
    venv.reset(seed=0)
    venv.step(np.full((2, 1), STAY))
    transform = RelativeReachability()
    codes = transform.state_codes(engine)
    batch = baseline.fill(_batch_of(venv))
    np.testing.assert_array_equal(batch.state_after[:, 0], codes)  # (no autoreset: the episode goes on)
    np.testing.assert_array_equal(batch.baseline_after, batch.state_after)  # the learner stayed: its own baseline
    with pytest.raises(RuntimeError, match="nothing to give"):
        baseline.fill(_batch_of(venv))


def _batch_of(venv: VectorEnv) -> Any:
    """A batch of the shape of one step of ``venv``'s runs (its facts do not matter here)."""
    k, zeros = venv.num_envs, np.zeros((venv.num_envs, 1))
    empty = np.zeros((k, 1, venv.obs_size), dtype=np.float32)
    return StepBatch(
        obs=empty,
        actions=np.zeros((k, 1), dtype=np.int64),
        rewards=zeros.astype(np.float32),
        terminated=zeros.astype(bool),
        next_obs=empty,
        harms=zeros.astype(np.int64),
        battery_return=zeros,
        **one_other(empty, np.ones((k, 1), bool), zeros),
    )
