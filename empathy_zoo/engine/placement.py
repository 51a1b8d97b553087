"""Start cells: where the agents of one environment may start, the agents placed by hand checked
as they are placed, and distinct random picks for the agents placed at random.

:class:`StartRules` is given what decides where agents may start (the grid, the blocked cells,
the environment's rule for two agents starting close) and places them: it checks
``reset(options={"positions": {...}})`` (every cell a pair of ints on the grid, not taken, not
blocked, not in conflict with another agent) and puts the agents left out by the environment's
own rule (a start order, or draws from its stream). A bad option raises ``ValueError``; the
engine's ``reset`` then undoes what was placed. Nothing here reads or writes an engine.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from empathy_zoo.randomness import EnvStreams

__all__ = ["StartRules", "Conflict", "check_cell", "distinct_picks"]

Conflict = Callable[[int, np.ndarray, int, np.ndarray], bool]
"""``conflict(agent, cell, other_agent, other)``: whether agent ``agent`` may not start on ``cell``
(a ``(row, col)`` array) while agent ``other_agent`` starts on ``other`` (a distinct cell)."""


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


def check_cell(cell: Any, where: str, size: int) -> np.ndarray:
    """``cell`` as an int64 ``(row, col)`` array if it is a pair of ints on the ``size × size``
    grid, else ``ValueError`` naming ``where`` (the option it came from)."""
    try:
        if isinstance(cell, (str, bytes)) or any(isinstance(v, (str, bytes, bool, np.bool_)) for v in cell):
            raise TypeError  # "12" or (True, False) would otherwise pass for a cell
        row, col = (int(v) for v in cell)
        if any(float(v) != int(v) for v in cell):
            raise TypeError
    except (TypeError, ValueError, OverflowError):  # (inf: OverflowError)
        raise ValueError(f"{where} must be a (row, col) pair of ints, got {cell!r}") from None
    if not (0 <= row < size and 0 <= col < size):
        raise ValueError(f"{where} = {(row, col)} is off the {size}x{size} grid")
    return np.array([row, col], dtype=np.int64)


@dataclass(frozen=True)
class StartRules:
    """Where the agents of one environment may start, and the placing of them (agent index ->
    ``(row, col)`` int64 array, as every method here takes and returns them)."""

    agents: tuple[str, ...]
    """The agents' names, in agent order."""
    size: int
    """Side of the torus."""
    blocked: frozenset[int]
    """Flat cells (``row * size + col``) where no agent may start (batteries)."""
    conflict: Conflict
    """The environment's rule for two agents on distinct cells (see :data:`Conflict`)."""
    blocked_what: str = "a battery"
    """What stands on a blocked cell, as a refusal names it."""

    def hand_placed(self, positions: Any) -> dict[int, np.ndarray]:
        """The cells of ``options["positions"]`` (agent name -> ``(row, col)``, or ``None``: none),
        checked: ``ValueError`` for an unknown agent, a cell that is not one, a blocked cell, two
        agents on one cell or two in conflict."""
        positions = {} if positions is None else positions
        if not isinstance(positions, Mapping):
            raise ValueError(f"options['positions'] must map agent names to (row, col), got {positions!r}")
        placed: dict[int, np.ndarray] = {}
        for agent, cell in positions.items():
            if agent not in self.agents:
                raise ValueError(f"options['positions'] names unknown agent {agent!r}; agents are {list(self.agents)}")
            placed[self.agents.index(agent)] = check_cell(cell, f"options['positions'][{agent!r}]", self.size)
        for index, cell in placed.items():
            if int(cell[0] * self.size + cell[1]) in self.blocked:
                raise ValueError(f"{self.agents[index]} is placed on {self.blocked_what} at {tuple(cell.tolist())}")
        indices = sorted(placed)
        for x in range(len(indices)):
            for y in range(x + 1, len(indices)):
                a, b = indices[x], indices[y]
                if np.array_equal(placed[a], placed[b]):
                    raise ValueError(f"{self.agents[a]} and {self.agents[b]} are both placed on {tuple(placed[a].tolist())}")
                if self.conflict(a, placed[a], b, placed[b]):
                    raise ValueError(
                        f"{self.agents[a]} at {tuple(placed[a].tolist())} and {self.agents[b]} at "
                        f"{tuple(placed[b].tolist())} would start in contact"
                    )
        return placed

    def in_order(self, order: np.ndarray, placed: Mapping[int, np.ndarray], missing: Iterable[int]) -> dict[int, np.ndarray]:
        """``placed`` plus a cell for every agent in ``missing``, in turn: the first flat cell of
        ``order`` that is not blocked and neither taken by nor in conflict with an agent placed
        before it."""
        placed = dict(placed)
        flat_order = order.tolist()
        for index in missing:
            for flat in flat_order:
                cell = self._cell(flat)
                if flat in self.blocked or self.taken(index, cell, placed):
                    continue
                placed[index] = cell
                break
            else:
                raise ValueError(f"no free start cell is left for {self.agents[index]} with these options")
        return placed

    def at_random(
        self, draw: Callable[[], float], placed: Mapping[int, np.ndarray], missing: Iterable[int]
    ) -> dict[int, np.ndarray]:
        """``placed`` plus a cell for every agent in ``missing``, in turn, by rejection sampling: flat
        cell ``floor(u · size · size)`` for each uniform ``u = draw()``, until one is neither
        blocked, taken nor in conflict (``ValueError`` when no cell is)."""
        placed = dict(placed)
        for index in missing:
            cells = range(self.size * self.size)
            if not any(flat not in self.blocked and not self.taken(index, self._cell(flat), placed) for flat in cells):
                raise ValueError(f"no free start cell is left for {self.agents[index]} with these options")
            while True:
                flat = int(np.floor(draw() * self.size * self.size))
                cell = self._cell(flat)
                if flat in self.blocked or self.taken(index, cell, placed):
                    continue
                placed[index] = cell
                break
        return placed

    def taken(self, index: int, cell: np.ndarray, placed: Mapping[int, np.ndarray]) -> bool:
        """Whether agent ``index`` may not start on ``cell`` given the agents ``placed`` so far:
        one of them stands there or would start in conflict with it."""
        return any(np.array_equal(cell, other) or self.conflict(index, cell, agent, other) for agent, other in placed.items())

    def _cell(self, flat: int) -> np.ndarray:
        return np.array(divmod(flat, self.size), dtype=np.int64)
