"""Social value orientation (McKee, Gemp, McWilliams, Duéñez-Guzmán, Hughes & Leibo 2020, "Social
diversity and social preferences in mixed-motive reinforcement learning"), for a learner and its
closest other agent:

    Uᵢ = rᵢ − w·|θ − θ*|,    θ = atan2(eⱼ, eᵢ),    eᵗ = γλ·eᵗ⁻¹ + rᵗ

``θ`` is the *reward angle* of the pair: 0 when only the learner is rewarded, 45° when both are
rewarded alike, 90° when only the other is. ``θ*`` is the learner's orientation (45°: prosocial,
caring for both equally; 0°: individualistic) and ``w`` weighs how far the reward angle may stray
from it. Both sides of 45° cost: a learner ahead of the other (θ < 45°) and one behind it
(θ > 45°) are both penalised by ``w`` per radian of the gap.

The angle is taken from temporally smoothed rewards, as McKee et al. do following inequity
aversion (Hughes et al. 2018, :class:`baselines.shaping.InequityAversion`): ``eᵢ`` and ``eⱼ`` are
the smoothed environment rewards of the learner (``StepBatch.rewards``) and of its closest other
agent (``StepBatch.other_rewards``, what the environment reports for that agent), with the same
``γλ = 0.99 · 0.95``, reset at each episode's end. Per step, most rewards come at different times
(a battery for one agent, nothing for the other), so a per-step angle would swing between 0° and
90° on every collection; the smoothed one measures who has been getting what lately.

When both smoothed rewards are 0 (nothing has been earned yet in the episode, or it has all
decayed to 0) the angle is undefined (``atan2(0, 0)`` would say 0°, charging ``w·θ*`` for every
idle step): there is then no distribution to judge, and the learner is charged nothing.

``θ`` ranges over ``(−180°, 180°]`` (``atan2``; negative rewards move it out of the first
quadrant), and the gap ``|θ − θ*|`` is taken as it is, without wrapping round the circle.

Defaults: ``w = 0.5`` per radian, ``θ* = 45°``, ``γλ = 0.99 · 0.95``. In Coexistence the cat and
the robot both earn 1 per step alive, so the angle stays at 45° until one of them is harmed (a
harmed cat's rewards stop and the angle falls towards 0°); in Sharing it follows the batteries.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from agents.step_batch import StepBatch
from agents.transform_state import StateBounds, check_smoothed

__all__ = ["SocialValueOrientation", "reward_angle"]


def reward_angle(own: np.ndarray, other: np.ndarray) -> np.ndarray:
    """The reward angle ``atan2(other, own)`` in radians, and NaN where both are 0 (no angle)."""
    own, other = np.asarray(own, dtype=np.float64), np.asarray(other, dtype=np.float64)
    return np.where((own == 0.0) & (other == 0.0), np.nan, np.arctan2(other, own))


@dataclass(frozen=True)
class SocialValueOrientation:
    """``r' = r − w·|θ − θ*|`` with ``θ`` the reward angle of the smoothed rewards of the learner
    and of its closest other agent; no penalty while both are 0 (see the module page)."""

    name: ClassVar[str] = "social_value_orientation"
    weight: float = 0.5
    """w: reward lost per radian between the reward angle and the target angle."""
    target_angle_degrees: float = 45.0
    """θ*, in degrees: the orientation the learner wants (45 prosocial, 0 individualistic, 90 altruistic)."""
    smoothing: float = 0.99 * 0.95
    """γλ: how much of the smoothed reward carries to the next step."""

    def __post_init__(self) -> None:
        if not (math.isfinite(self.weight) and self.weight >= 0.0):
            raise ValueError(f"weight must be a finite number >= 0, got {self.weight!r}")
        if not (math.isfinite(self.target_angle_degrees) and -180.0 < self.target_angle_degrees <= 180.0):
            raise ValueError(f"target_angle_degrees must be in (-180, 180], got {self.target_angle_degrees!r}")
        if not 0.0 <= self.smoothing < 1.0:
            raise ValueError(f"smoothing must be in [0, 1), got {self.smoothing!r}")

    def initial_state(self, num_runs: int, envs_per_run: int) -> dict[str, np.ndarray]:
        return {side: np.zeros((num_runs, envs_per_run)) for side in ("own", "other")}

    def check_state(self, state: Mapping[str, Any], initial: Mapping[str, np.ndarray], bounds: StateBounds) -> None:
        """A checkpoint's smoothed rewards (:func:`agents.transform_state.check_smoothed`)."""
        check_smoothed(state, initial, bounds, self.smoothing)

    def __call__(self, batch: StepBatch, state: dict[str, np.ndarray]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        if batch.other_rewards is None:
            raise ValueError("social value orientation needs the other agent's rewards (StepBatch.other_rewards)")
        own = self.smoothing * state["own"] + batch.rewards
        other = self.smoothing * state["other"] + batch.other_rewards
        gap = np.abs(reward_angle(own, other) - math.radians(self.target_angle_degrees))
        shaped = batch.rewards - self.weight * np.nan_to_num(gap, nan=0.0)
        ended = batch.terminated | (batch.truncated if batch.truncated is not None else False)
        return shaped.astype(np.float32), {"own": np.where(ended, 0.0, own), "other": np.where(ended, 0.0, other)}
