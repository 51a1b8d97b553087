"""What a learner is told of one step: :class:`StepBatch` (``K`` runs × ``M`` environments)."""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

__all__ = ["StepBatch"]


@dataclass
class StepBatch:
    """One env step of every run, as arrays ``(K, M, ...)``."""

    obs: np.ndarray
    """(K, M, V) observations the actions were chosen on."""
    actions: np.ndarray
    """(K, M) actions taken."""
    rewards: np.ndarray
    """(K, M) float32: the reward each run trains on: the environment's reward of the learner, or
    what the run's method's :class:`RewardTransform` made of it (the suite never scores it)."""
    terminated: np.ndarray
    """(K, M) the learner's episode ended for good (truncation is not termination)."""
    next_obs: np.ndarray
    """(K, M, V) observations at the end of the step (before any autoreset)."""
    swapped_next_obs: np.ndarray
    """(K, M, V) the learner's swapped observation at the end of the step with its closest other
    agent when the step began (SPEC §3b)."""
    other_present: np.ndarray
    """(K, M) that other agent is still in the environment and its episode has not ended for good
    at the end of the step, so its swapped value may bootstrap (SPEC §6: False for a harmed cat,
    and for the human once the last battery is taken; a time-limit truncation keeps it True)."""
    harmed_other: np.ndarray
    """(K, M) number of agents the learner harmed this step."""
    battery_return: np.ndarray
    """(K, M) the learner's battery reward so far this episode, this step included."""
    other_battery_return: np.ndarray
    """(K, M) the other agent's battery reward so far this episode, this step included."""
    truncated: np.ndarray | None = None
    """(K, M) the learner's episode was cut short this step (time limit); ``None`` when the driver
    does not say. Learners that bootstrap through time-outs (SB3's PPO) need it."""
    other_rewards: np.ndarray | None = None
    """(K, M) the environment's reward of the closest other agent this step (what a method that
    weighs the other's reward reads: inequity aversion, social value orientation); ``None`` when the
    driver does not say."""
    state_after: np.ndarray | None = None
    """(K, M) int64: the state each environment is in at the end of the step (before any
    autoreset), as the code of the run's reward transform (``state_codes``); filled only for a
    transform that declares ``needs_inaction_baseline`` (:mod:`agents.rewards`), else ``None``."""
    baseline_after: np.ndarray | None = None
    """(K, M) int64: the same code of the stepwise inaction baseline: the state the step would
    have ended in had the learner taken the no-op (action 4) and every other agent done what it
    did; filled with :attr:`state_after`."""
    swapped_next_obs_all: np.ndarray | None = None
    """(K, M, N, V) the learner's swapped observation with each of the N other agents, in agent
    order, at the end of the step (zeros for one that has left); ``None`` when the driver does not
    say. What a learner aggregating over every other agent reads (``others="mean"`` / ``"min"``)."""
    others_present: np.ndarray | None = None
    """(K, M, N) each other agent is present and not terminal at the end of the step (as
    :attr:`other_present` is for the closest); ``None`` when the driver does not say."""
    others_live: np.ndarray | None = None
    """(K, M, N) each other agent was in the environment when the step began (one harmed in an
    earlier step has left); ``None`` when the driver does not say."""
    other_unseen: np.ndarray | None = None
    """(K, M) the closest other agent is present and not terminal at the end of the step but out
    of the learner's window (in-view-only methods): *unseen*, not harmed, so an in-view empathic
    target uses no other-term at all (SPEC §4); ``None`` (never unseen) when the driver does not say."""
    others_unseen: np.ndarray | None = None
    """(K, M, N) the same for each other agent; ``None`` when the driver does not say."""

    def runs(self, rows: np.ndarray) -> StepBatch:
        """The same step for the runs ``rows`` only (every array's first axis indexed)."""
        return replace(self, **{f.name: getattr(self, f.name)[rows] for f in fields(self) if getattr(self, f.name) is not None})
