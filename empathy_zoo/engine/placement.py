"""Start cells: agents (and, in Sharing, batteries) placed by hand, checked as they are placed,
and distinct random picks for the agents placed at random.

:class:`HandPlacement` is the part of :class:`~empathy_zoo.engine.base.GridEngine` that applies
``reset(options={"positions": {...}, ...})`` to one environment: every cell is checked (on the
grid, a pair of ints, not taken, not blocked, not in conflict with another agent), and agents left
out are placed by the environment's own rule (drawn from its stream, or its start order). A bad
option raises ``ValueError``; the engine's ``reset`` then undoes what was placed.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from empathy_zoo.randomness import EnvStreams

__all__ = ["HandPlacement", "distinct_picks"]


def distinct_picks(streams: EnvStreams, env_ids: np.ndarray, choices: int, count: int) -> np.ndarray:
    """``(len(env_ids), count)`` int64: ``count`` distinct indices below ``choices`` in each of
    ``env_ids``, drawn in turn from its stream, each uniform over the indices still free (one
    number per pick: the ``k``-th is ``floor(u·(choices − k))``, then moved past the earlier picks)."""
    picks = np.empty((len(env_ids), count), dtype=np.int64)
    for k in range(count):
        pick = np.floor(streams.uniform(env_ids) * (choices - k)).astype(np.int64)
        for earlier in (picks[:, :k] if k < 2 else np.sort(picks[:, :k], axis=1)).T:  # ascending: skip each taken one
            pick += pick >= earlier
        picks[:, k] = pick
    return picks


class HandPlacement:
    """Placing agents by hand at reset (mixed into :class:`~empathy_zoo.engine.base.GridEngine`,
    whose state and hooks it uses)."""

    if TYPE_CHECKING:  # what the host engine provides (GridEngine.__init__ and its hooks)
        name: ClassVar[str]
        agents: tuple[str, ...]
        size: int
        num_agents: int
        num_cells: int
        cells: np.ndarray
        start_order: np.ndarray | None
        streams: EnvStreams
        _cell_rc: np.ndarray

        def flat_cell(self, row: int, col: int) -> int: ...
        def _blocked_start_cells(self, env_id: int) -> np.ndarray: ...
        def _start_conflict(self, agent: int, cell: np.ndarray, other_agent: int, other: np.ndarray) -> bool: ...
        def _apply_options(self, env_id: int, options: Mapping[str, Any]) -> set[str]: ...

    def _reset_with_options(self, env_id: int, options: Mapping[str, Any]) -> None:
        if not isinstance(options, Mapping):
            raise ValueError(f"options must be a mapping, got {type(options).__name__}")
        consumed = self._apply_options(env_id, options) | {"positions"}
        unknown = set(options) - consumed
        if unknown:  # PettingZoo's own API test passes foreign options; ignore them loudly
            warnings.warn(
                f"ignoring unknown reset option(s) {sorted(unknown)} for {self.name}; known: {sorted(consumed)}",
                stacklevel=4,
            )
        positions = {} if options.get("positions") is None else options["positions"]
        if not isinstance(positions, Mapping):
            raise ValueError(f"options['positions'] must map agent names to (row, col), got {positions!r}")
        placed: dict[int, np.ndarray] = {}
        for agent, cell in positions.items():
            if agent not in self.agents:
                raise ValueError(f"options['positions'] names unknown agent {agent!r}; agents are {list(self.agents)}")
            placed[self.agents.index(agent)] = self._check_cell(cell, f"options['positions'][{agent!r}]")
        blocked = set(self._blocked_start_cells(env_id).tolist())
        for index, cell in placed.items():
            if int(cell[0] * self.size + cell[1]) in blocked:
                raise ValueError(f"{self.agents[index]} is placed on a battery at {tuple(cell.tolist())}")
        indices = sorted(placed)
        for x in range(len(indices)):
            for y in range(x + 1, len(indices)):
                a, b = indices[x], indices[y]
                if np.array_equal(placed[a], placed[b]):
                    raise ValueError(f"{self.agents[a]} and {self.agents[b]} are both placed on {tuple(placed[a].tolist())}")
                if self._start_conflict(a, placed[a], b, placed[b]):
                    raise ValueError(
                        f"{self.agents[a]} at {tuple(placed[a].tolist())} and {self.agents[b]} at "
                        f"{tuple(placed[b].tolist())} would start in contact"
                    )
        env = np.array([env_id])
        missing = [index for index in range(self.num_agents) if index not in placed]
        if self.start_order is not None:
            placed = self._ordered_start(env_id, placed, missing)
            missing = []
        for index in missing:
            if not any(
                flat not in blocked and not self._taken(index, self._cell_rc[flat], placed) for flat in range(self.num_cells)
            ):
                raise ValueError(f"no free start cell is left for {self.agents[index]} with these options")
            while True:  # rejection sampling from the environment's own stream
                flat = int(np.floor(self.streams.uniform(env)[0] * self.size * self.size))
                cell = np.array(divmod(flat, self.size), dtype=np.int64)
                if flat in blocked or self._taken(index, cell, placed):
                    continue
                placed[index] = cell
                break
        for index, cell in placed.items():
            self.cells[env_id, index] = self.flat_cell(*cell)

    def _ordered_start(self, env_id: int, placed: Mapping[int, np.ndarray], missing: Iterable[int]) -> dict[int, np.ndarray]:
        """``placed`` (agent index -> (row, col)) plus a cell for every agent in ``missing``, in
        turn: the first cell of :attr:`start_order` that is not blocked in ``env_id`` and neither
        taken by nor in conflict with an agent placed before it."""
        if self.start_order is None:
            raise RuntimeError(f"{self.name}: no start order (GridEngine.__init__ sets it)")
        blocked = set(self._blocked_start_cells(env_id).tolist())
        placed = dict(placed)
        order = self.start_order.tolist()
        for index in missing:
            for flat in order:
                cell = self._cell_rc[flat]
                if flat in blocked or self._taken(index, cell, placed):
                    continue
                placed[index] = cell
                break
            else:
                raise ValueError(f"no free start cell is left for {self.agents[index]} with these options")
        return placed

    def _taken(self, index: int, cell: np.ndarray, placed: Mapping[int, np.ndarray]) -> bool:
        """Whether agent ``index`` may not start on ``cell`` given the agents ``placed`` so far:
        one of them stands there or would start in conflict with it."""
        return any(
            np.array_equal(cell, other) or self._start_conflict(index, cell, agent, other) for agent, other in placed.items()
        )

    def _check_cell(self, cell: Any, where: str) -> np.ndarray:
        try:
            if isinstance(cell, (str, bytes)) or any(isinstance(v, (str, bytes, bool, np.bool_)) for v in cell):
                raise TypeError  # "12" or (True, False) would otherwise pass for a cell
            row, col = (int(v) for v in cell)
            if any(float(v) != int(v) for v in cell):
                raise TypeError
        except (TypeError, ValueError, OverflowError):  # (inf: OverflowError)
            raise ValueError(f"{where} must be a (row, col) pair of ints, got {cell!r}") from None
        if not (0 <= row < self.size and 0 <= col < self.size):
            raise ValueError(f"{where} = {(row, col)} is off the {self.size}x{self.size} grid")
        return np.array([row, col], dtype=np.int64)
