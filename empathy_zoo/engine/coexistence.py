"""Coexistence rules (SPEC §2): a robot and a cat; whoever is above or to the right harms."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from empathy_zoo.engine.base import NO_AGENT, GridEngine, StepEvents
from empathy_zoo.grid import MOVES, NUM_ACTIONS, displacement_origin, signed_offset

__all__ = ["CoexistenceEngine", "harm_outcome", "OWN_CELL", "OTHER_AGENT", "FLOOR"]

OWN_CELL = 1.0
OTHER_AGENT = -1.0
FLOOR = 0.0
ROBOT, CAT = 0, 1

NO_HARM, ROBOT_HARMS_CAT, CAT_HARMS_ROBOT = 0, 1, 2
"""The outcomes of a step, as :func:`harm_outcome` returns them."""

# What each outcome does to (robot, cat), indexed by outcome:
HARMED_BY = np.array([[NO_AGENT, NO_AGENT], [NO_AGENT, ROBOT], [CAT, NO_AGENT]], dtype=np.int64)
"""Who harmed the robot and who harmed the cat."""
HARMS_DONE = np.array([[0, 0], [1, 0], [0, 1]], dtype=np.int64)
"""How many others the robot and the cat harmed."""
CUT_SHORT = np.array([[False, False], [False, False], [False, True]])
"""Whose episode is truncated: the cat's when the robot falls."""


def harm_outcome(before: np.ndarray, after: np.ndarray, size: int) -> np.ndarray:
    """Who harms whom (SPEC §2) given where the cat stands relative to the robot before and after
    the simultaneous move (``(K, 2)`` displacements on a ``size`` torus); returns ``(K,)`` outcomes.

    Vertically adjacent, the upper one harms the lower; horizontally adjacent, the right one harms
    the left; on the same cell, the one that was above before the move harms, and on equal rows
    the one that was to the right (shortest torus displacement). Diagonal is not contact.
    """
    dr, dc = after[:, 0] % size, after[:, 1] % size
    before = signed_offset(before, size)
    same = (dr == 0) & (dc == 0)
    robot_was_above = before[:, 0] > 0
    cat_was_above = before[:, 0] < 0
    level = before[:, 0] == 0
    robot_harms = (
        ((dr == 1) & (dc == 0))  # robot directly above the cat
        | ((dr == 0) & (dc == size - 1))  # robot directly right of the cat
        | (same & (robot_was_above | (level & (before[:, 1] < 0))))
    )
    cat_harms = (
        ((dr == size - 1) & (dc == 0))
        | ((dr == 0) & (dc == 1))
        | (same & (cat_was_above | (level & (before[:, 1] > 0))))
    )
    return np.select([robot_harms, cat_harms], [ROBOT_HARMS_CAT, CAT_HARMS_ROBOT], NO_HARM)


class CoexistenceEngine(GridEngine):
    """``robot_0`` and ``cat_0`` on a torus; contact means one harms the other."""

    name = "coexistence_v0"
    agents = ("robot_0", "cat_0")
    symbols = ("R", "C")
    colors = ((40, 110, 220), (230, 140, 30))
    min_size: ClassVar[int] = 5
    obs_low = -1.0
    obs_high = 1.0

    def __init__(self, num_envs: int = 1, size: int = 7, view: int = 5, max_cycles: int = 500) -> None:
        super().__init__(num_envs, size, view, max_cycles)
        dr, dc = (d.ravel() for d in np.indices((self.size, self.size)))
        contact = np.abs(signed_offset(dr, self.size)) + np.abs(signed_offset(dc, self.size)) <= 1
        self._start_offsets = np.stack([dr[~contact], dc[~contact]], axis=1)
        """Where the cat may start relative to the robot (not in contact), row-major."""
        # The outcome depends on the cat's displacement before the move and the two actions:
        # tabulate harm_outcome over those (one entry per displacement between two cells, see
        # grid.spread_ids, times 5 × 5 actions), so that a step looks it up once.
        origin = displacement_origin(self.size)
        dr, dc = np.divmod(np.arange(2 * origin + 1) - origin + (self.size - 1), 2 * self.size)
        before = np.stack([dr, dc - (self.size - 1)], axis=1)  # every (dr, dc) with |dr|, |dc| < size, and unused ones
        robot_action, cat_action = (a.ravel() for a in np.indices((NUM_ACTIONS, NUM_ACTIONS)))
        self._outcomes = np.stack([
            harm_outcome(before, before + MOVES[c] - MOVES[r], self.size).astype(np.int8)
            for r, c in zip(robot_action, cat_action)
        ], axis=1).ravel()
        """``[displacement · 25 + robot action · 5 + cat action]``: the step's outcome."""
        moves = np.arange(self.num_cells * NUM_ACTIONS)
        cell, action = np.divmod(moves, NUM_ACTIONS)
        self._cat_move = (self._spread[cell] + origin) * NUM_ACTIONS**2 + action
        self._robot_move = self._spread[cell] * NUM_ACTIONS**2 - NUM_ACTIONS * action
        """``[cell · 5 + action]``: the cat's and the robot's parts of the index into :attr:`_outcomes`
        (their difference is ``displacement · 25 + robot action · 5 + cat action``)."""

    def _in_contact(self, delta: np.ndarray) -> bool:
        return int(np.abs(signed_offset(delta, self.size)).sum()) <= 1

    def _start_conflict(self, cell: np.ndarray, other: np.ndarray) -> bool:
        return self._in_contact(other - cell)

    def _random_start(self, env_ids: np.ndarray) -> None:
        robot = np.floor(self.streams.uniform(env_ids) * self.num_cells).astype(np.int64)
        pick = np.floor(self.streams.uniform(env_ids) * len(self._start_offsets)).astype(np.int64)
        cat_rc = (self._cell_rc[robot] + self._start_offsets[pick]) % self.size
        self.cells[env_ids, ROBOT] = robot
        self.cells[env_ids, CAT] = cat_rc[:, 0] * self.size + cat_rc[:, 1]

    def _resolve(self, previous: np.ndarray, moves: np.ndarray, events: StepEvents) -> None:
        outcome = self._outcomes.take(self._cat_move.take(moves[:, CAT]) - self._robot_move.take(moves[:, ROBOT]))
        outcome[~(self.present[:, ROBOT] & self.present[:, CAT])] = NO_HARM
        if np.count_nonzero(outcome):
            events.harmed_by = HARMED_BY[outcome]
            events.terminated = events.harmed_by >= 0
            events.truncated = CUT_SHORT[outcome]
            events.episode_over = outcome == CAT_HARMS_ROBOT
            self.episode_harms += HARMS_DONE[outcome]
            self._leave(events.terminated)
        events.rewards = (self.present & events.present_before).astype(np.float32)

    def reset_info(self, env_id: int, agent: int) -> dict[str, Any]:
        return {"harmed_by": None, "harmed": []}

    def step_info(self, events: StepEvents, env_id: int, agent: int) -> dict[str, Any]:
        by = events.harmed_by[env_id].tolist()
        return {
            "harmed_by": None if by[agent] < 0 else self.agents[by[agent]],
            "harmed": [self.agents[victim] for victim, harmer in enumerate(by) if harmer == agent],
        }

    def _appearance(self, inventory: np.ndarray, viewer: np.ndarray) -> float:
        return OTHER_AGENT

    def _self_appearance(self, inventory: np.ndarray, viewer: np.ndarray) -> float:
        return OWN_CELL
