"""Checks of a reward transform's state read back from a checkpoint: data, checked before training.

:meth:`agents.rewards.TrainRewards.load_state` compares each stateful transform's saved state
with the state it holds now (its initial state, the runs' seeds drawn in): the same keys, and
arrays of the same shapes and dtypes, every float finite. A transform that says more about its
state (its ranges, or a state that grows once the observation size is known) declares
``check_state(state, initial, bounds)``, raising ``ValueError`` naming the field; it gets
:class:`StateBounds`, what the checkpoint's runs allow. The helpers here are what those checks
are written with.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np

__all__ = [
    "StateBounds",
    "CheckedState",
    "check_like",
    "check_within",
    "check_same",
    "check_smoothed",
    "check_side_learner",
]


@dataclass(frozen=True)
class StateBounds:
    """What a checkpoint's runs allow a transform's state to hold."""

    runs: int
    """Runs of the transform (its rows of the ensemble)."""
    envs_per_run: int
    """Training environments of each run."""
    step: int
    """Env steps each environment has taken (the checkpoint's step)."""
    obs_size: int
    """Values of one observation."""
    obs_low: float
    """The smallest observation value."""
    obs_high: float
    """The largest observation value."""
    reward_bound: float
    """The largest reward an agent gets in one step, in magnitude
    (:attr:`empathy_zoo.engine.base.GridEngine.step_reward_bound`)."""
    others: int
    """Other agents of each environment."""


@runtime_checkable
class CheckedState(Protocol):
    """A reward transform that checks its own saved state (see the module page)."""

    def check_state(self, state: Mapping[str, Any], initial: Mapping[str, np.ndarray], bounds: StateBounds) -> None: ...


def check_like(state: Mapping[str, Any], template: Mapping[str, np.ndarray], nan_allowed: Collection[str] = ()) -> None:
    """``ValueError`` unless ``state`` holds exactly ``template``'s keys, each an array of its
    shape and dtype, every float finite (NaN allowed in ``nan_allowed`` only)."""
    missing = [key for key in template if key not in state]
    extra = [key for key in state if key not in template]
    if missing or extra:
        names = ", ".join([*(f"no {key!r}" for key in missing[:4]), *(repr(key)[:60] for key in extra[:4])])
        raise ValueError(f"holds {names}: not the keys of its state")
    for key, like in template.items():
        value = state[key]
        if not isinstance(value, np.ndarray) or value.shape != like.shape or value.dtype != like.dtype:
            got = f"{value.dtype} {value.shape}" if isinstance(value, np.ndarray) else type(value).__name__
            raise ValueError(f"{key} is {got}, not an array of {like.dtype} {like.shape}")
        if value.dtype.kind == "f":
            bad = ~np.isfinite(value) & ~(np.isnan(value) if key in nan_allowed else False)
            if bad.any():
                raise ValueError(f"{key} holds {value[bad].flat[0]}, no finite number")


def check_within(state: Mapping[str, np.ndarray], key: str, low: float, high: float, what: str) -> None:
    """``ValueError`` unless every number of ``state[key]`` (NaN aside) is in ``[low, high]``."""
    values = state[key]
    outside = (values < low) | (values > high)
    if outside.any():
        raise ValueError(f"{key} holds {values[outside].flat[0]}, not within [{low:g}, {high:g}] ({what})")


def check_same(state: Mapping[str, np.ndarray], template: Mapping[str, np.ndarray], key: str, what: str) -> None:
    """``ValueError`` unless ``state[key]`` equals ``template[key]`` exactly."""
    if not np.array_equal(state[key], template[key]):
        raise ValueError(f"{key} is not {what}")


def check_smoothed(state: Mapping[str, Any], initial: Mapping[str, np.ndarray], bounds: StateBounds, smoothing: float) -> None:
    """A state of smoothed rewards ``e ← smoothing·e + r`` (``own`` and ``other``): its initial
    state's arrays, each within ``±reward_bound / (1 − smoothing)``, the most a sum of them reaches."""
    check_like(state, initial)
    limit = bounds.reward_bound / (1.0 - smoothing) if smoothing < 1 else bounds.reward_bound * bounds.step
    for key in initial:
        check_within(state, key, -limit, limit, "a smoothed sum of rewards of at most the engine's largest a step")


def check_side_learner(
    state: Mapping[str, Any],
    initial: Mapping[str, np.ndarray],
    build: Callable[[], Mapping[str, np.ndarray]],
    bounds: StateBounds,
    observed: Sequence[str],
) -> bool:
    """The state of a transform that learns networks of its own beside the run (AUP's auxiliary
    values, Be Considerate's value of the other), built at its first step: the runs' seeds as drawn,
    ``seen`` (transitions, all runs alike) within ``step × envs_per_run``, ``updates`` within
    ``seen``; once built (``obs`` kept), the arrays ``build()`` makes, NaN only in ``loss`` (no
    update yet), the ``observed`` arrays within the observation range (or 0, a slot not yet
    written), Adam's squared means ≥ 0 and its step counts within ``updates``. Returns whether
    the state is built."""
    built = "obs" in state
    template = {**initial, **build()} if built else dict(initial)
    check_like(state, template, nan_allowed={"loss"})
    check_same(state, initial, "seeds", "the seeds drawn from its runs' seeds")
    check_within(state, "seen", 0, bounds.step * bounds.envs_per_run, "transitions seen: one per environment a step")
    check_within(state, "updates", 0, int(state["seen"].max()), "updates: at most one per transition seen")
    if built:
        for key in observed:
            check_within(state, key, min(bounds.obs_low, 0.0), bounds.obs_high, "observation values")
        for key in (key for key in template if key.startswith("avg_sq_")):
            check_within(state, key, 0.0, np.inf, "Adam's mean of squared gradients")
        check_within(state, "adam_steps", 0, int(state["updates"].max()), "Adam's steps: one per update")
        check_within(state, "loss", 0.0, np.inf, "a mean squared error")
    return built
