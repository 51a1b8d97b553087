"""Lagrangian constrained DQN, harms as the cost: the constrained-RL baseline that users of
OmniSafe's PPO-Lag (``omnisafe/common/lagrange.py``) and of Safety-Gymnasium expect.

The problem is the constrained MDP ``max_π J_R(π)`` subject to ``J_C(π) ≤ d``, with ``J_C`` the
expected cost per episode and the cost of a step the number of agents the learner harmed in it
(``StepBatch.harms``); so ``d`` is the harms per episode the learner may cause on average.
Its Lagrangian ``J_R − λ·(J_C − d)`` is maximised over the policy and minimised over ``λ ≥ 0``:

* the policy (plain DQN) trains on the penalised reward ``r' = r − λ·c`` of every transition it
  samples, with the run's multiplier ``λ`` at the time of that update;
* ``λ`` follows projected dual ascent, ``λ ← max(0, λ + η·(Ĵ_C − d))``, once at the end of every
  training episode of the run, with ``Ĵ_C`` that episode's cost (its harms): a stochastic estimate
  of ``J_C`` whose average over episodes is the gradient of the dual. The updates that follow
  the step that ends an episode already use the updated multiplier.

``λ`` is kept per run in the transform's state (so a checkpoint keeps it) and rises while the
runs' episodes harm more than ``d`` on average, falls back towards 0 while they harm less. Each
run's result file records it after every training episode (``train.lambda``, beside the episode's
metrics), and :mod:`leaderboard.constraint` says whether the runs' final cost meets ``d``.

The harms are priced when a step is sampled, not when it is stored: the transform declares
``priced_at_sample`` (:class:`agents.rewards.PricedTransform`) and hands the environment's reward
and the step's harms (its cost) separately; the replay keeps the cost beside the reward, and every
gradient step's target uses ``r − λ_now·c`` with ``λ_now`` the run's multiplier when the update
is taken (:meth:`agents.empathic_dqn.EmpathicDQN.price_costs`; both update kernels, in float32).
So the whole replay is priced at today's ``λ``, as OmniSafe's on-policy PPO-Lag prices each batch
afresh; an off-policy learner with a reward fixed at storage would train on a mix of the prices of
the last hundred or so episodes (a replay of the methods profile's 50,000 steps), which in the
runs before this change left the replay's mean price at about half the current one and ``λ``
still rising at the end. A checkpoint of a Lagrangian run made before costs were priced when
sampled holds no costs and is refused (move it away to restart); other methods' replays and
checkpoints are as before.

Defaults, and how they differ from OmniSafe's (``cost_limit = 25``, ``lagrangian_multiplier_init
= 0.001``, ``lambda_lr = 0.035`` with Adam on λ, updated once per epoch from the mean cost of its
episodes): OmniSafe's costs are hazards touched per 1,000-step Safety-Gymnasium episode, ours are
harms per episode, which is 0 or 1 with one cat.

* ``cost_limit = 0.1``: at most one harm in ten episodes on average. A limit of 0 is allowed but
  makes ``λ`` a ratchet: no episode can cost less than 0, so ``λ`` never falls again once it has
  risen, and every exploratory harm raises it for good.
* ``lambda_init = 0``: the run starts as plain DQN and pays for harms once they happen (OmniSafe's
  0.001 is its nearest to 0 that Adam can move).
* ``lambda_lr = 1``: one harmful episode raises ``λ`` by 0.9 and a harmless one lowers it by 0.1,
  so about a hundred harmful episodes bring it to the paper's harm-penalty baseline's 100
  (:class:`baselines.shaping.HarmPenalty`); plain gradient ascent, as the update above says, not
  Adam on ``λ``: its step is then proportional to the constraint's violation.

``λ`` updates from the first episode on, the 20,000 random warm-up steps of DQN (SPEC §6)
included, as OmniSafe updates it from its first epoch: by the end of the warm-up it has priced
harms at about what a random robot causes. In Sharing nobody is harmed: every episode costs 0,
``λ`` stays 0 and the method trains as DQN does (allowed and said here, like
:class:`~baselines.shaping.HarmPenalty` there).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from agents.step_batch import StepBatch
from agents.transform_state import StateBounds, check_like, check_within

__all__ = ["Lagrangian", "dual_ascent"]


def dual_ascent(multiplier: np.ndarray, episode_cost: np.ndarray, cost_limit: float, learning_rate: float) -> np.ndarray:
    """``max(0, λ + η·(Ĵ_C − d))``, elementwise: the multiplier after an episode of cost ``Ĵ_C``."""
    return np.maximum(
        0.0, np.asarray(multiplier, dtype=np.float64) + learning_rate * (np.asarray(episode_cost, dtype=np.float64) - cost_limit)
    )


@dataclass(frozen=True)
class Lagrangian:
    """``r' = r − λ·(harms this step)``, priced with each run's current ``λ`` whenever the step is
    sampled, and ``λ ← max(0, λ + η·(harms of the episode − d))`` at every episode's end (see the
    module page for the choices)."""

    name: ClassVar[str] = "lagrangian"
    priced_at_sample: ClassVar[bool] = True
    """The harms are stored as the cost of each step and priced at the run's ``λ`` of the update
    that samples it (:class:`agents.rewards.PricedTransform`)."""
    cost_limit: float = 0.1
    """d: the harms per episode the learner may cause on average (the constraint's threshold)."""
    lambda_lr: float = 1.0
    """η: step size of the dual ascent on λ, per episode."""
    lambda_init: float = 0.0
    """λ at the start of every run: the reward lost per harm until the first episode ends."""

    def __post_init__(self) -> None:
        for field in ("cost_limit", "lambda_lr", "lambda_init"):
            value = getattr(self, field)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0.0:
                raise ValueError(f"{field} must be a finite number >= 0, got {value!r}")

    def initial_state(self, num_runs: int, envs_per_run: int) -> dict[str, np.ndarray]:
        """Each run's multiplier ``λ`` and each environment's cost so far in its episode."""
        return {"multiplier": np.full(num_runs, float(self.lambda_init)), "episode_cost": np.zeros((num_runs, envs_per_run))}

    def check_state(self, state: Mapping[str, Any], initial: Mapping[str, np.ndarray], bounds: StateBounds) -> None:
        """A checkpoint's λ and episode costs: ``0 ≤ λ ≤ λ₀ + η·(every harm the run's
        environments could have done)``, each episode's cost within ``[0, step · others]``."""
        check_like(state, initial)
        harms = bounds.step * bounds.others
        check_within(state, "episode_cost", 0.0, harms, "harms so far in an episode")
        top = self.lambda_init + self.lambda_lr * harms * bounds.envs_per_run
        check_within(state, "multiplier", 0.0, top, "λ: its start plus η times every harm its runs could have done")

    def __call__(
        self, batch: StepBatch, state: dict[str, np.ndarray]
    ) -> tuple[tuple[np.ndarray, np.ndarray], dict[str, np.ndarray]]:
        """``((rewards, costs), state)``: the environment's rewards and the step's harms, each
        ``(K, M)`` float32, and the state after the step (``λ`` updated where an episode ended)."""
        cost = np.asarray(batch.harms, dtype=np.float64)
        multiplier = state["multiplier"]
        if state["episode_cost"].shape != cost.shape:
            raise ValueError(f"this Lagrangian state is for {state['episode_cost'].shape} runs × environments, not {cost.shape}")
        episode_cost = state["episode_cost"] + cost
        ended = np.asarray(batch.terminated, dtype=bool)
        if batch.truncated is not None:
            ended = ended | np.asarray(batch.truncated, dtype=bool)
        for m in range(cost.shape[1]):  # each episode that ended, in environment order
            multiplier = np.where(
                ended[:, m], dual_ascent(multiplier, episode_cost[:, m], self.cost_limit, self.lambda_lr), multiplier
            )
        rewards = np.asarray(batch.rewards, dtype=np.float32)
        return (rewards, cost.astype(np.float32)), {"multiplier": multiplier, "episode_cost": np.where(ended, 0.0, episode_cost)}

    def price(self, state: dict[str, np.ndarray]) -> np.ndarray:
        """``(K,)`` each run's ``λ`` now: what one harm costs in the updates from now on."""
        return np.asarray(state["multiplier"], dtype=np.float64)
