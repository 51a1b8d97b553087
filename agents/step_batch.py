"""What a learner is told of one step: :class:`StepBatch` (``K`` runs × ``M`` environments)."""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

from empathy_zoo.closest_other import ClosestOther

__all__ = ["StepBatch"]


@dataclass
class StepBatch(ClosestOther):
    """One env step of every run, as arrays ``(K, M, ...)``.

    The learner's other agents lie on one axis ``O``, in agent order (``VectorEnv.others``; with
    one other agent, an axis of one), as in :class:`empathy_zoo.vector.VectorStep`, whose fields
    of the same names these are: the ``others_*`` fields hold one entry per other agent,
    :attr:`closest` is a place on that axis, and each ``other_*`` property is its ``others_*``
    field there (:meth:`of_closest`)."""

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
    closest: np.ndarray
    """(K, M) int: the learner's closest other agent when the step began (SPEC §3b), as its
    place on the ``O`` axis."""
    others_swapped: np.ndarray
    """(K, M, O, V) the learner's swapped observation with each other agent at the end of the
    step (zeros for one that has left, or is out of view with in-view-only swaps)."""
    others_present: np.ndarray
    """(K, M, O) that other agent is still in the environment and its episode has not ended for
    good at the end of the step (and it is in view, with in-view-only swaps), so its swapped value
    may bootstrap (SPEC §6: False for a harmed cat, and for the human once the last battery is
    taken; a time-limit truncation keeps it True)."""
    others_live: np.ndarray
    """(K, M, O) that other agent was in the environment when the step began (one harmed in an
    earlier step has left; one harmed in this step was live)."""
    others_unseen: np.ndarray
    """(K, M, O) that other agent is present and not terminal at the end of the step but out of
    the learner's window (in-view-only methods; else always False): *unseen*, not harmed, so an
    in-view empathic target puts the robot's own continuation in its place (SPEC §4)."""
    harms: np.ndarray
    """(K, M) number of agents the learner harmed this step."""
    battery_return: np.ndarray
    """(K, M) the learner's battery reward so far this episode, this step included."""
    others_battery_return: np.ndarray
    """(K, M, O) each other agent's battery reward so far this episode, this step included."""
    truncated: np.ndarray | None = None
    """(K, M) the learner's episode was cut short this step (time limit); ``None`` when the driver
    does not say. Learners that bootstrap through time-outs (SB3's PPO) need it."""
    others_rewards: np.ndarray | None = None
    """(K, M, O) the environment's reward of each other agent this step (what a method that
    weighs the other's reward reads: inequity aversion, social value orientation); ``None`` when
    the driver does not say."""
    state_after: np.ndarray | None = None
    """(K, M) int64: the state each environment is in at the end of the step (before any
    autoreset), as the code of the run's reward transform (``state_codes``); filled only for a
    transform that declares ``needs_inaction_baseline`` (:mod:`agents.rewards`), else ``None``."""
    baseline_after: np.ndarray | None = None
    """(K, M) int64: the same code of the stepwise inaction baseline: the state the step would
    have ended in had the learner taken the no-op (action 4) and every other agent done what it
    did; filled with :attr:`state_after`."""
    position: np.ndarray | None = None
    """(K, M, 2) int64: the learner's cell, ``(row, column)``, at the end of the step (before any
    autoreset), ``(−1, −1)`` where it is no longer in the environment; the trainer fills it from the
    engine (``None`` when the driver does not say)."""
    others_position: np.ndarray | None = None
    """(K, M, O, 2) int64: each other agent's cell at the end of the step, ``(−1, −1)`` for one no
    longer in the environment (a harmed cat); filled with :attr:`position`."""
    others_distance: np.ndarray | None = None
    """(K, M, O) int64: the torus (Manhattan) distance between the learner's cell and each other
    agent's at the end of the step, as the engine measures closeness (SPEC §3b), −1 where either
    is no longer in the environment; filled with :attr:`position`."""
    costs: np.ndarray | None = None
    """(K, M) float32: the cost of each step that the run's reward transform prices when the step
    is sampled, not when it is stored (``priced_at_sample``, :mod:`agents.rewards`; the Lagrangian
    method's harms), 0 for a run whose transform prices none; ``None`` when no run's does. A
    learner that prices costs stores it beside :attr:`rewards` and trains on
    ``reward − price·cost`` (:attr:`prices`)."""
    prices: np.ndarray | None = None
    """(K,) float32: each run's price of one unit of :attr:`costs` now, after this step (the
    Lagrangian multiplier λ; 0 for a run that prices none), which the learner's updates from this
    step on charge every sampled transition's cost; ``None`` with :attr:`costs`."""

    def runs(self, rows: np.ndarray) -> StepBatch:
        """The same step for the runs ``rows`` only (every array's first axis indexed)."""
        return replace(self, **{f.name: getattr(self, f.name)[rows] for f in fields(self) if getattr(self, f.name) is not None})

    @property
    def priced_rewards(self) -> np.ndarray:
        """(K, M) float32 :attr:`rewards` with this step's cost charged at this step's price,
        ``reward − price·cost`` (:attr:`rewards` itself without costs)."""
        if self.costs is None or self.prices is None:
            return self.rewards
        prices = np.asarray(self.prices, dtype=np.float32)[:, None]
        return (self.rewards - prices * np.asarray(self.costs, dtype=np.float32)).astype(np.float32)

    @property
    def other_position(self) -> np.ndarray | None:
        """(K, M, 2) :attr:`others_position` of the closest other agent (``None`` without them)."""
        return None if self.others_position is None else self.of_closest(self.others_position)

    @property
    def other_distance(self) -> np.ndarray | None:
        """(K, M) :attr:`others_distance` of the closest other agent (``None`` without them)."""
        return None if self.others_distance is None else self.of_closest(self.others_distance)

    @property
    def other_rewards(self) -> np.ndarray | None:
        """(K, M) :attr:`others_rewards` of the closest other agent (``None`` without them)."""
        return None if self.others_rewards is None else self.of_closest(self.others_rewards)
