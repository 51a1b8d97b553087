"""Coexistence rules (SPEC §2): a robot and a cat; whoever is above or to the right harms."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from empathy_zoo.engine.base import GridEngine, StepEvents
from empathy_zoo.grid import signed_offset

__all__ = ["CoexistenceEngine", "OWN_CELL", "OTHER_AGENT", "FLOOR"]

OWN_CELL = 1.0
OTHER_AGENT = -1.0
FLOOR = 0.0
ROBOT, CAT = 0, 1


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
        offsets = [
            (dr, dc)
            for dr in range(self.size)
            for dc in range(self.size)
            if not self._in_contact(np.array([dr, dc]))
        ]
        self._start_offsets = np.array(offsets, dtype=np.int64)

    def _in_contact(self, delta: np.ndarray) -> bool:
        return int(np.abs(signed_offset(delta, self.size)).sum()) <= 1

    def _start_conflict(self, cell: np.ndarray, other: np.ndarray) -> bool:
        return self._in_contact(other - cell)

    def _random_start(self, env_ids: np.ndarray) -> None:
        cells = self.size * self.size
        robot = np.floor(self.streams.uniform(env_ids) * cells).astype(np.int64)
        pick = np.floor(self.streams.uniform(env_ids) * len(self._start_offsets)).astype(np.int64)
        robot_rc = np.stack(np.divmod(robot, self.size), axis=1)
        self.pos[env_ids, ROBOT] = robot_rc
        self.pos[env_ids, CAT] = (robot_rc + self._start_offsets[pick]) % self.size

    def _resolve(self, previous: np.ndarray, events: StepEvents) -> None:
        both = self.present[:, ROBOT] & self.present[:, CAT]
        delta = (self.pos[:, CAT] - self.pos[:, ROBOT]) % self.size  # where the cat stands, seen from the robot
        dr, dc = delta[:, 0], delta[:, 1]
        before = signed_offset(previous[:, CAT] - previous[:, ROBOT], self.size)
        same = (dr == 0) & (dc == 0)
        robot_was_above = before[:, 0] > 0
        cat_was_above = before[:, 0] < 0
        level = before[:, 0] == 0
        robot_harms = both & (
            ((dr == 1) & (dc == 0))  # robot directly above the cat
            | ((dr == 0) & (dc == self.size - 1))  # robot directly right of the cat
            | (same & (robot_was_above | (level & (before[:, 1] < 0))))
        )
        cat_harms = both & (
            ((dr == self.size - 1) & (dc == 0))
            | ((dr == 0) & (dc == 1))
            | (same & (cat_was_above | (level & (before[:, 1] > 0))))
        )
        events.harmed_by[robot_harms, CAT] = ROBOT
        events.harmed_by[cat_harms, ROBOT] = CAT
        self.episode_harms[robot_harms, ROBOT] += 1
        self.episode_harms[cat_harms, CAT] += 1
        self.present[robot_harms, CAT] = False
        self.present[cat_harms, ROBOT] = False
        events.terminated[robot_harms, CAT] = True
        events.terminated[cat_harms, ROBOT] = True
        events.truncated[cat_harms, CAT] = True  # the robot fell: the episode ends for the cat too
        events.episode_over |= cat_harms
        events.rewards[:] = np.where(self.present & events.present_before, 1.0, 0.0)

    def reset_info(self, env_id: int, agent: int) -> dict[str, Any]:
        return {"harmed_by": None, "harmed": []}

    def step_info(self, events: StepEvents, env_id: int, agent: int) -> dict[str, Any]:
        by = int(events.harmed_by[env_id, agent])
        victims = np.flatnonzero(events.harmed_by[env_id] == agent)
        return {
            "harmed_by": None if by < 0 else self.agents[by],
            "harmed": [self.agents[v] for v in victims],
        }

    def _paint(self, pos: np.ndarray, inventory: np.ndarray, viewer: int) -> np.ndarray:
        canvas = np.zeros((self.num_envs, self.size * self.size), dtype=np.float32)
        cells = pos[:, :, 0] * self.size + pos[:, :, 1]
        for agent in range(self.num_agents):
            if agent != viewer:
                rows = self._rows[self.present[:, agent]]
                canvas[rows, cells[rows, agent]] = OTHER_AGENT
        canvas[self._rows, cells[:, viewer]] = OWN_CELL
        return canvas
