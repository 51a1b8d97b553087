"""Sharing rules (SPEC §3, §3b): a robot and one or more humans collect batteries with
diminishing returns. Several agents ending on one battery in one step: the env's generator gives
it to one of them, uniformly (one number per contested battery, in the order of each battery's
first agent).

Two fidelity options (SPEC §3, constructor keywords; the defaults are the suite's rules):

* ``start``: ``"random"`` draws two distinct battery-free cells from the env's generator;
  ``"centre"`` orders the cells by torus distance from the centre cell ``(size//2, size//2)``
  (ties by row-major index) and puts the robot on the first battery-free one and the human on the
  next (7×7: robot (2, 3), human (3, 2)). It draws nothing, so the generator's first number goes
  to the first battery tie-break: a seed gives another (still deterministic) sequence of
  tie-breaks than with ``"random"``.
* ``inventory_encoding``: an agent holding ``n`` batteries is drawn as ``1 + n``
  (``"count_plus_one"``) or as ``5·(n+1)/100`` (``"authors"``, :func:`authors_agent_value`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import numpy as np

from empathy_zoo.engine.base import GridEngine, StepEvents, check_choice
from empathy_zoo.engine.placement import check_cell, distinct_picks
from empathy_zoo.grid import cells_by_distance
from empathy_zoo.observation_codes import step_value

__all__ = [
    "SharingEngine",
    "battery_value",
    "agent_value",
    "authors_agent_value",
    "battery_cells",
    "FLOOR",
    "BATTERY",
    "STARTS",
    "INVENTORY_ENCODINGS",
]

FLOOR = 0.0
BATTERY = -1.0
STARTS = ("random", "centre")
"""Values of the ``start`` argument (the first is the default)."""
INVENTORY_ENCODINGS = ("count_plus_one", "authors")
"""Values of the ``inventory_encoding`` argument (the first is the default)."""


def battery_cells(size: int) -> np.ndarray:
    """``(size²,)`` bool: the cells that start with a battery (row and column both odd)."""
    rows, cols = np.divmod(np.arange(size * size), size)
    return (rows % 2 == 1) & (cols % 2 == 1)


def battery_value(n: np.ndarray | int) -> np.ndarray:
    """Worth of an agent's ``n``-th battery (n = 1, 2, …): ``1.1 − 0.1·n``."""
    return 1.1 - 0.1 * np.asarray(n, dtype=np.float64)


_ONE = np.array(1)


def agent_value(batteries: np.ndarray | int) -> np.ndarray:
    """Observation value of an agent that holds ``batteries``: ``1 + batteries``."""
    return batteries + _ONE  # (a 0-d array adds faster than the int 1)


def authors_agent_value(batteries: np.ndarray | int) -> np.ndarray:
    """Observation value of an agent that holds ``batteries`` in the authors' encoding:
    ``5·(n+1)/100``, computed as ``np.float32((n + 1) / 20)`` (the replay memory decodes stored
    values with the same arithmetic, :func:`empathy_zoo.observation_codes.step_value`)."""
    return step_value(np.asarray(batteries) + 1)


class SharingEngine(GridEngine):
    """``robot_0`` and ``human_0 … human_{num_humans-1}`` collect the batteries on every odd
    (row, col) cell."""

    name = "sharing_v0"
    agents = ("robot_0", "human_0")
    symbols = ("R", "H")
    colors = ((40, 110, 220), (200, 60, 60))
    obs_low = -1.0
    extra_arguments: ClassVar[Mapping[str, tuple[str, ...]]] = {"start": STARTS, "inventory_encoding": INVENTORY_ENCODINGS}
    count_argument = "num_humans"
    argument_help: ClassVar[Mapping[str, str]] = {
        "start": "start cells: random, or centre as the authors' code (default: random)",
        "inventory_encoding": "how an agent is drawn: count_plus_one, or authors (default: count_plus_one)",
        "num_humans": "humans (default: 1)",
    }

    def __init__(
        self,
        num_envs: int = 1,
        size: int = 7,
        view: int = 5,
        max_cycles: int = 500,
        *,
        start: str = "random",
        inventory_encoding: str = "count_plus_one",
        num_humans: int = 1,
    ) -> None:
        self.start = check_choice("start", start, STARTS)
        self.inventory_encoding = check_choice("inventory_encoding", inventory_encoding, INVENTORY_ENCODINGS)
        super().__init__(num_envs, size, view, max_cycles, num_others=num_humans)
        self.initial_batteries = battery_cells(self.size)
        self.num_batteries = int(self.initial_batteries.sum())
        self._agent_value: Callable[[np.ndarray | int], np.ndarray]
        """The observation value of an agent holding so many batteries (in :attr:`inventory_encoding`)."""
        if inventory_encoding == "authors":  # a lookup over every count the env can reach
            self._agent_value = authors_agent_value(np.arange(self.num_batteries + 1)).take
        else:
            self._agent_value = agent_value
        self.obs_high = float(self._agent_value(self.num_batteries))
        if start == "centre":
            self.start_order = cells_by_distance(self.size, (self.size // 2, self.size // 2))
        self._free_cells = np.flatnonzero(~self.initial_batteries)
        self.batteries = np.zeros((self.num_envs, self.size * self.size), dtype=bool)
        self._picture = np.zeros(self.batteries.shape, dtype=np.float32)
        """The batteries as observation values (``BATTERY`` or ``FLOOR``), kept in step with
        :attr:`batteries`: painting then reads them with one lookup."""

    def _room_for_others(self) -> tuple[int, str]:
        free = int(np.count_nonzero(~battery_cells(self.size)))
        return (
            free - 1,
            f"the robot and the humans start on distinct cells without a battery: {free} on a {self.size}x{self.size} grid",
        )

    def _draw_batteries(self, env_ids: np.ndarray) -> None:
        self._picture[env_ids] = np.where(self.batteries[env_ids], BATTERY, FLOOR)

    def _reset_extra(self, env_ids: np.ndarray) -> None:
        self.batteries[env_ids] = self.initial_batteries
        self._draw_batteries(env_ids)

    def _blocked_start_cells(self, env_id: int) -> np.ndarray:
        return np.flatnonzero(self.batteries[env_id])

    def _start_conflict(self, agent: int, cell: np.ndarray, other_agent: int, other: np.ndarray) -> bool:
        return False  # only distinct cells are required

    def _apply_options(self, env_id: int, options: Mapping[str, Any]) -> set[str]:
        if "batteries" not in options or options["batteries"] is None:
            return {"batteries"}
        cells = options["batteries"]
        if isinstance(cells, (str, bytes)) or not hasattr(cells, "__iter__"):
            raise ValueError(f"options['batteries'] must be a list of (row, col) cells, got {cells!r}")
        layout = np.zeros(self.size * self.size, dtype=bool)
        for k, cell in enumerate(cells):
            row, col = check_cell(cell, f"options['batteries'][{k}]", self.size)
            if layout[row * self.size + col]:
                raise ValueError(f"options['batteries'] lists {(int(row), int(col))} twice")
            layout[row * self.size + col] = True
        if not layout.any():
            raise ValueError("options['batteries'] must list at least one battery (with none the episode is over)")
        if layout.sum() > self.num_batteries:
            raise ValueError(
                f"options['batteries'] lists {int(layout.sum())} batteries; at most {self.num_batteries} fit this "
                f"{self.size}x{self.size} env (its observation space holds agents with up to {self.num_batteries} batteries)"
            )
        self.batteries[env_id] = layout
        self._draw_batteries(np.array([env_id]))
        return {"batteries"}

    def _random_start(self, env_ids: np.ndarray) -> None:
        picks = distinct_picks(self.streams, env_ids, len(self._free_cells), self.num_agents)
        self.cells[env_ids] = self._free_cells[picks]

    def _resolve(self, previous: np.ndarray, moves: np.ndarray, events: StepEvents) -> None:
        flat = self.cells + self._cell_base if self.num_envs > 1 else self.cells  # into batteries.ravel()
        collects = self.batteries.take(flat)
        if not np.count_nonzero(collects):
            return
        taken = np.sort(flat[collects])  # (flat cells of all environments: distinct across them)
        together = taken[1:] == taken[:-1]
        if np.count_nonzero(together):  # a battery several agents reached
            self._share_out(taken[1:][together], flat, collects)
            taken = flat[collects]
        self.inventory += collects
        value = np.where(collects, battery_value(self.inventory), 0.0)
        events.rewards = value.astype(np.float32)
        events.collected = collects
        self.episode_battery_return += value
        self.batteries.ravel()[taken] = False
        self._picture.ravel()[taken] = FLOOR
        empty = ~np.asarray(self.batteries.any(axis=1))  # (N,): asarray types numpy's "bool or array" as the array
        events.terminated[empty] = True
        events.episode_over = empty

    def _share_out(self, crowded: np.ndarray, flat: np.ndarray, collects: np.ndarray) -> None:
        """Give every battery several agents reached to one of them, uniformly by the env's
        generator (one number per battery, in the order of each battery's first agent): clear the
        others' ``collects``. ``crowded``: those batteries' cells, ``flat``: every agent's cell
        (both counted as in a flattened ``(N, num_cells)`` array)."""
        for env_id in np.unique(crowded // self.num_cells).tolist():
            row = np.where(collects[env_id], flat[env_id], -1).tolist()  # (-1: collects nothing)
            for cell in dict.fromkeys(row):  # each battery once, in the order of its first agent
                contenders = [agent for agent, there in enumerate(row) if there == cell]
                if cell >= 0 and len(contenders) > 1:
                    draw = self.streams.uniform(np.array([env_id])).item()
                    winner = contenders[int(draw * len(contenders))]
                    collects[env_id, contenders] = False
                    collects[env_id, winner] = True

    def reset_info(self, env_id: int, agent: int) -> dict[str, Any]:
        return {"batteries": self.inventory.item(env_id, agent)}

    def step_info(self, events: StepEvents, env_id: int, agent: int) -> dict[str, Any]:
        return {"batteries": self.inventory.item(env_id, agent)}

    def _paint_background(self, env_ids: np.ndarray, centre: np.ndarray, out: np.ndarray) -> None:
        window = self.window.cells.take(centre, 0)
        if self.num_envs > 1:
            window += (env_ids * self.num_cells)[:, None]  # into the flattened picture
        self._picture.take(window, out=out, mode="clip")  # (the indices are valid; "clip" avoids a buffer)

    def _appearance(self, inventory: np.ndarray, viewer: np.ndarray) -> np.ndarray:
        return self._agent_value(inventory)

    def _self_appearance(self, inventory: np.ndarray, viewer: np.ndarray) -> np.ndarray:
        return self._agent_value(inventory)

    def load_state(self, state: Mapping[str, Any]) -> None:
        super().load_state(state)
        self._draw_batteries(self._rows)

    def _state_keys(self) -> tuple[str, ...]:
        return (*super()._state_keys(), "batteries")
