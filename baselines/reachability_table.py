"""Exact reachability between the states of Coexistence, computed from its engine.

A Coexistence state is who is still there and where: the robot's cell and the cat's cell, the
robot's cell alone once the cat has been harmed, or the end (the robot harmed). Its code, on a
``size × size`` grid of ``n = size²`` cells, is ``robot · n + cat`` with both present,
``n² + robot`` without the cat and ``n² + n`` for the end; time is no part of it (the
reachability of Krakovna et al. is between states, whatever the clock says).

:func:`coexistence_reachability` builds, once per grid size and process, the fewest steps
between every two states. Every transition comes from a :class:`CoexistenceEngine`: one
engine environment per state and joint action (robot × cat), placed by loading an engine state,
stepped once, its outcome read back; no rule of the environment is written here. The states are
those the engine can start in (every pair of cells it accepts as ``reset`` positions) and every
state some steps lead to from them; the end has no successor (the episode is over). A step
reaches ``y`` from ``x`` when *some* joint action does: the cat's moves count as if they could be
chosen (see :mod:`baselines.reachability` for why).

The table holds ``|S|²`` bytes: ``|S| = 2,206`` at the default ``size = 7`` (4.9 MB, built in a
fraction of a second), 6,238 at ``size = 9`` (39 MB); larger grids are refused (:data:`MAX_TABLE_SIZE`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from empathy_zoo.actions import NUM_ACTIONS
from empathy_zoo.engine.coexistence import CoexistenceEngine

__all__ = [
    "ReachabilityTable",
    "coexistence_reachability",
    "coexistence_codes",
    "UNREACHABLE",
    "MAX_TABLE_SIZE",
    "check_table_size",
]

ROBOT, CAT = 0, 1
"""Agent indices of Coexistence with one cat (``robot_0``, ``cat_0``)."""
UNREACHABLE = np.iinfo(np.uint8).max
"""Distance of a state that cannot be reached (any real distance is smaller)."""
MAX_TABLE_SIZE = 9
"""Largest grid side an exact table is built for (``size = 10`` would take 92 MB, ``size = 11`` 200 MB)."""


def coexistence_codes(cells: np.ndarray, present: np.ndarray, size: int) -> np.ndarray:
    """``(N,)`` state codes (see the module page) of ``N`` Coexistence environments, given their
    ``(N, 2)`` flat cells and presence (robot, cat)."""
    n = size * size
    robot, cat = cells[:, ROBOT].astype(np.int64), cells[:, CAT].astype(np.int64)
    return np.where(~present[:, ROBOT], n * n + n, np.where(~present[:, CAT], n * n + robot, robot * n + cat))


@dataclass(frozen=True)
class ReachabilityTable:
    """Shortest numbers of steps between the states of Coexistence on one grid size."""

    size: int
    """The grid's side."""
    rows: np.ndarray
    """``(n² + n + 1,)`` int64: each code's row in :attr:`distances`, ``-1`` for a code no step
    ends in (two agents in contact or on one cell)."""
    distances: np.ndarray
    """``(|S|, |S|)`` uint8: ``[x, y]`` the fewest steps from state ``x`` to ``y`` (0 on the
    diagonal), :data:`UNREACHABLE` where no sequence of steps gets there."""
    codes: np.ndarray
    """``(|S|,)`` int64: the code of each row."""

    @property
    def num_states(self) -> int:
        """``|S|``."""
        return len(self.codes)

    def row(self, codes: np.ndarray) -> np.ndarray:
        """Rows of the states ``codes`` (any shape); ``ValueError`` for a code that is no state."""
        codes = np.asarray(codes, dtype=np.int64)
        if codes.size and (codes.min() < 0 or codes.max() >= len(self.rows)):
            raise ValueError(f"state codes must be in [0, {len(self.rows)}) on a {self.size}×{self.size} grid")
        rows = self.rows[codes]
        if np.count_nonzero(rows < 0):
            raise ValueError(f"code {int(codes[rows < 0].flat[0])} is no state a step of Coexistence ends in")
        return rows

    def reachability(self, codes: np.ndarray, discount: float) -> np.ndarray:
        """``(*codes.shape, |S|)`` float64: ``R(x; s) = discount ** distance(x, s)`` (0 where
        unreachable) from each state of ``codes`` to every state ``s``."""
        return _discounted(discount)[self.distances[self.row(codes)]]


@functools.lru_cache(maxsize=8)
def _discounted(discount: float) -> np.ndarray:
    """``(256,)`` read-only: ``discount ** k`` for every distance ``k``, 0 for :data:`UNREACHABLE`."""
    powers = discount ** np.arange(UNREACHABLE + 1, dtype=np.float64)
    powers[UNREACHABLE] = 0.0
    powers.flags.writeable = False
    return powers


def _start_codes(size: int) -> np.ndarray:
    """Codes of the states the engine may start in: every pair of cells it accepts as positions."""
    engine, starts = CoexistenceEngine(1, size=size, view=1), []
    for robot, cat in np.ndindex(size * size, size * size):
        try:
            engine.reset([0], options={"positions": {"robot_0": divmod(robot, size), "cat_0": divmod(cat, size)}})
        except ValueError:  # (two agents on one cell, or in contact)
            continue
        starts.append(robot * size * size + cat)
    return np.array(starts, dtype=np.int64)


def _successors(size: int) -> tuple[np.ndarray, np.ndarray]:
    """Every code of a state where the robot is present, and ``(C, 25)`` the code each joint
    action (robot action · 5 + cat action) leads to, as the engine steps them."""
    n = size * size
    both = np.arange(n * n)
    codes = np.concatenate([both, n * n + np.arange(n)])
    robot = np.concatenate([both // n, np.arange(n)])
    cat = np.concatenate([both % n, np.zeros(n, dtype=np.int64)])  # (the cell of an absent cat is never read)
    joint = NUM_ACTIONS * NUM_ACTIONS
    engine = CoexistenceEngine(len(codes) * joint, size=size, view=1)
    state = engine.state()
    state["cells"][:] = np.repeat(np.stack([robot, cat], axis=1), joint, axis=0)
    state["present"][:] = True
    state["present"][:, CAT] = np.repeat(codes < n * n, joint)
    state["running"][:] = True
    state["t"][:] = 0
    engine.load_state(state)
    actions = np.tile(np.stack(np.divmod(np.arange(joint), NUM_ACTIONS), axis=1), (len(codes), 1))
    engine.step(actions)
    return codes, coexistence_codes(engine.cells, engine.present, size).reshape(len(codes), joint)


def _shortest_steps(successors: np.ndarray) -> np.ndarray:
    """``(S, S)`` uint8 fewest steps between states ``0 … S-1`` whose ``(S, J)`` successors are
    given (breadth-first from every state at once, on bit-packed reachable sets)."""
    count = len(successors)
    distances = np.full((count, count), UNREACHABLE, dtype=np.uint8)
    np.fill_diagonal(distances, 0)
    reached = np.packbits(distances == 0, axis=1)  # (S, ⌈S/8⌉): within k steps of each state
    steps = 0
    while True:
        steps += 1
        # within k steps of x: x itself, or within k − 1 steps of a successor of x
        grown = reached.copy()
        for column in successors.T:
            grown |= reached[column]
        new = np.unpackbits(grown & ~reached, axis=1, count=count).astype(bool)
        if not np.count_nonzero(new):
            return distances
        if steps >= UNREACHABLE:
            raise ValueError(f"some state is {UNREACHABLE} or more steps from another: too far for this table")
        distances[new] = steps
        reached = grown


def check_table_size(size: int) -> None:
    """Refuse (``ValueError``, one line naming the size and :data:`MAX_TABLE_SIZE`) a grid too large
    for an exact table: what :func:`coexistence_reachability` checks first, and what a caller that
    knows the size from its arguments alone checks before any other work (``analyse separation``)."""
    if size > MAX_TABLE_SIZE:
        raise ValueError(
            f"an exact reachability table of Coexistence on size={size} would hold about "
            f"{(size**2 * (size**2 - 5)) ** 2 / 1e6:.0f} MB; it is built for sizes up to {MAX_TABLE_SIZE}"
        )


@functools.lru_cache(maxsize=4)
def coexistence_reachability(size: int) -> ReachabilityTable:
    """The :class:`ReachabilityTable` of Coexistence (one cat) on a ``size × size`` grid, built
    once per process (see the module page)."""
    check_table_size(size)
    n = size * size
    codes, successors = _successors(size)
    by_code = np.full((n * n + n + 1, successors.shape[1]), n * n + n, dtype=np.int64)  # the end leads nowhere else
    by_code[codes] = successors
    known = np.zeros(n * n + n + 1, dtype=bool)
    frontier = _start_codes(size)
    while frontier.size:  # every state some steps lead to from a start
        known[frontier] = True
        frontier = np.unique(by_code[frontier])
        frontier = frontier[~known[frontier]]
    states = np.flatnonzero(known)
    rows = np.full(n * n + n + 1, -1, dtype=np.int64)
    rows[states] = np.arange(len(states))
    state_successors = rows[by_code[states]]
    distances = _shortest_steps(state_successors)
    for array in (rows, distances, states):
        array.flags.writeable = False
    return ReachabilityTable(size=size, rows=rows, distances=distances, codes=states)
