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

The exact model (:mod:`empathy_zoo.exact_solver`) reads the state beyond the two cells as a
*layer*: the batteries left and the batteries the robot holds (the human holds the rest of those
taken), every layer one the rules can reach (:func:`tabular_layer_table`). A battery both agents
reach in one step is the step's chance: ``tabular_draws = 2`` equally likely draws, one per winner.
The hooks model one human and the default inventory encoding, and refuse others.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from typing import Any, ClassVar

import numpy as np

from empathy_zoo.engine.base import GridEngine, StepEvents, check_choice
from empathy_zoo.engine.placement import check_cell, distinct_picks
from empathy_zoo.grid import cells_by_distance
from empathy_zoo.metrics import equality
from empathy_zoo.observation_codes import step_value

__all__ = [
    "SharingEngine",
    "battery_value",
    "agent_value",
    "authors_agent_value",
    "battery_cells",
    "battery_return",
    "tabular_layer_table",
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
ROBOT, HUMAN = 0, 1


def battery_cells(size: int) -> np.ndarray:
    """``(size²,)`` bool: the cells that start with a battery (row and column both odd)."""
    rows, cols = np.divmod(np.arange(size * size), size)
    return (rows % 2 == 1) & (cols % 2 == 1)


def battery_value(n: np.ndarray | int) -> np.ndarray:
    """Worth of an agent's ``n``-th battery (n = 1, 2, …): ``1.1 − 0.1·n``."""
    return 1.1 - 0.1 * np.asarray(n, dtype=np.float64)


def battery_return(n: np.ndarray | int) -> np.ndarray:
    """An agent's battery reward for its first ``n`` batteries: ``1.0 + 0.9 + … + (1.1 − 0.1·n)``
    (float64, summed in the engine's order)."""
    n = np.asarray(n, dtype=np.int64)
    top = int(n.max(initial=0))
    sums = np.concatenate([[0.0], np.cumsum(battery_value(np.arange(1, top + 1)))])
    return sums[n]


@functools.lru_cache(maxsize=4)
def tabular_layer_table(batteries: int) -> tuple[np.ndarray, np.ndarray]:
    """``(bitmap, robot)``, one entry per layer of the exact model: which batteries are left
    (bit ``i``: the ``i``-th battery cell in row-major order) and how many the robot holds, every
    pair the rules reach (the robot holds at most the batteries taken; the human the rest of
    them). Ordered by batteries taken, then bitmap from the highest, then the robot's count: layer
    0 is the start, every battery left and none held."""
    bitmap = np.repeat(np.arange(2**batteries, dtype=np.int64), batteries + 1)
    robot = np.tile(np.arange(batteries + 1, dtype=np.int64), 2**batteries)
    taken = batteries - _popcount(bitmap, batteries)
    keep = robot <= taken
    bitmap, robot, taken = bitmap[keep], robot[keep], taken[keep]
    order = np.lexsort((robot, -bitmap, taken))
    bitmap, robot = bitmap[order], robot[order]
    bitmap.flags.writeable = robot.flags.writeable = False
    return bitmap, robot


def _popcount(bitmap: np.ndarray, bits: int) -> np.ndarray:
    """Set bits of each entry of ``bitmap`` (below ``2**bits``)."""
    return ((bitmap[..., None] >> np.arange(bits)) & 1).sum(axis=-1)


@functools.lru_cache(maxsize=4)
def _layer_index(batteries: int) -> np.ndarray:
    """``(2**batteries, batteries + 1)``: the layer of each (bitmap, robot's count), ``-1`` for no layer."""
    bitmap, robot = tabular_layer_table(batteries)
    index = np.full((2**batteries, batteries + 1), -1, dtype=np.int64)
    index[bitmap, robot] = np.arange(len(bitmap))
    index.flags.writeable = False
    return index


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
    tabular_draws: ClassVar[int] = 2
    """Equally likely outcomes of a step's chance (:mod:`empathy_zoo.exact_solver`): a battery the
    robot and the human reach in one step goes to either, with probability ½ each."""

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
        self.step_reward_bound = float(max(abs(battery_value(1)), abs(battery_value(self.num_batteries))))
        """One battery a step at most: the first's worth, or the last's where it is larger in magnitude."""
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
        if not isinstance(cells, (list, tuple, np.ndarray)):  # (never a dict's keys, a set's order or a string's letters)
            raise ValueError(f"options['batteries'] must be a list of (row, col) cells, got {type(cells).__name__}")
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

    # ------------------------------------------------------------------ the exact model's hooks
    @property
    def tabular_layers(self) -> int:
        """Layers of the exact model (:func:`tabular_layer_table`): ``2^(B−1)·(B + 2)`` for ``B``
        batteries, 48 on the 5×5 torus and 2,816 on the 7×7 one."""
        self._check_tabular()
        return 2 ** (self.num_batteries - 1) * (self.num_batteries + 2)

    def _check_tabular(self) -> None:
        """``ValueError`` unless the exact model's hooks model this engine: one human, the default encoding."""
        if self.num_others != 1 or self.inventory_encoding != INVENTORY_ENCODINGS[0]:
            raise ValueError(
                f"the exact model of {self.name} is for one human and inventory_encoding={INVENTORY_ENCODINGS[0]!r}, "
                f"got num_humans={self.num_others} and inventory_encoding={self.inventory_encoding!r}"
            )

    def start_distribution(self) -> np.ndarray:
        """``(cells, cells)``: the probability that an episode starts with the robot on flat cell
        ``i`` and the human on flat cell ``j``, in layer 0 (every battery left, none held): two
        distinct battery-free cells, uniformly, or the fixed cells of ``start="centre"``."""
        self._check_tabular()
        p = np.zeros((self.num_cells, self.num_cells))
        if self.start_order is not None:
            placed = type(self)(1, self.size, self.view, self.max_cycles, start=self.start)
            placed.reset()  # (draws nothing)
            p[placed.cells[0, ROBOT], placed.cells[0, HUMAN]] = 1.0
            return p
        free = self._free_cells
        p[np.ix_(free, free)] = 1.0 / (len(free) * (len(free) - 1))
        p[free, free] = 0.0
        return p

    def tabular_layer(self) -> np.ndarray:
        """``(N,)`` the layer of every environment (:func:`tabular_layer_table`); ``ValueError``
        where its batteries and inventories are no layer (a battery off the odd cells, or counts
        that do not add up to the batteries taken)."""
        self._check_tabular()
        cells = np.flatnonzero(self.initial_batteries)
        left = self.batteries[:, cells]
        robot, human = self.inventory[:, ROBOT], self.inventory[:, HUMAN]
        known = (robot + human + left.sum(axis=1) == len(cells)) & ~self.batteries[:, ~self.initial_batteries].any(axis=1)
        if not known.all():
            raise ValueError(f"environment {int(np.flatnonzero(~known)[0])} is in no layer of the exact model")
        bitmap = left.astype(np.int64) @ (1 << np.arange(len(cells), dtype=np.int64))
        return _layer_index(len(cells))[bitmap, robot]

    def set_tabular_layer(self, layer: np.ndarray) -> None:
        """Set the batteries left and what each agent holds in every environment from ``layer``."""
        self._check_tabular()
        bitmap, robot = tabular_layer_table(self.num_batteries)
        layer = np.asarray(layer)
        bits = (bitmap[layer][:, None] >> np.arange(self.num_batteries)) & 1
        self.batteries[:] = False
        self.batteries[:, np.flatnonzero(self.initial_batteries)] = bits.astype(bool)
        self.inventory[:, ROBOT] = robot[layer]
        self.inventory[:, HUMAN] = self.num_batteries - bits.sum(axis=1) - robot[layer]
        self._draw_batteries(self._rows)

    def swapped_tabular_layer(self, layer: np.ndarray) -> np.ndarray:
        """The layer with the two agents' situations exchanged: the same batteries left, what each
        holds swapped (the swap of SPEC §4 exchanges inventories)."""
        self._check_tabular()
        bitmap, robot = tabular_layer_table(self.num_batteries)
        layer = np.asarray(layer)
        human = self.num_batteries - _popcount(bitmap[layer], self.num_batteries) - robot[layer]
        return _layer_index(self.num_batteries)[bitmap[layer], human]

    def tabular_figures(self, layer: np.ndarray) -> dict[str, np.ndarray]:
        """SPEC §5's battery metrics of an episode that ends in ``layer``: ``batteries``,
        ``other_batteries`` and ``equality`` (of the two battery rewards)."""
        self._check_tabular()
        bitmap, robot = tabular_layer_table(self.num_batteries)
        layer = np.asarray(layer)
        human = self.num_batteries - _popcount(bitmap[layer], self.num_batteries) - robot[layer]
        return {
            "batteries": robot[layer],
            "other_batteries": human,
            "equality": equality(battery_return(robot[layer]), battery_return(human)),
        }

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
