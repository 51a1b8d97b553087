"""Torus geometry shared by every environment: moves, displacements and observation windows (the
actions themselves: :mod:`empathy_zoo.actions`)."""

from __future__ import annotations

import numpy as np

__all__ = [
    "MOVES",
    "window_indices",
    "spread_ids",
    "displacement_origin",
    "window_slot_by_displacement",
    "signed_offset",
    "torus_distance",
    "cells_by_distance",
]


MOVES = np.array([(-1, 0), (1, 0), (0, -1), (0, 1), (0, 0)], dtype=np.int64)
"""``MOVES[action]`` is the (row, col) displacement of an action (:class:`empathy_zoo.actions.Action`)."""


def window_indices(size: int, view: int) -> np.ndarray:
    """Flat cell ids of the ``view x view`` window centred on every cell of a ``size`` torus.

    Returns an int64 array of shape ``(size * size, view * view)``: row ``c`` lists, row-major,
    the flat ids (``row * size + col``) of the window around flat cell ``c``; its middle entry is
    ``c`` itself.
    """
    half = view // 2
    rows, cols = np.divmod(np.arange(size * size), size)
    offsets = np.arange(-half, half + 1)
    win_rows = (rows[:, None, None] + offsets[None, :, None]) % size
    win_cols = (cols[:, None, None] + offsets[None, None, :]) % size
    return (win_rows * size + win_cols).reshape(size * size, view * view)


def spread_ids(size: int) -> np.ndarray:
    """Every flat cell's id on a grid twice as wide: ``row * 2·size + col`` (int64, ``(size²,)``).

    The difference of two such ids, ``dr · 2·size + dc`` with ``|dr|, |dc| < size``, tells the
    displacement ``(dr, dc)`` between two cells apart (on the plain ``row * size + col`` ids it
    would not), so tables indexed by it hold about ``4·size²`` entries instead of one per pair
    of cells (``size⁴``)."""
    rows, cols = np.divmod(np.arange(size * size, dtype=np.int64), size)
    return rows * (2 * size) + cols


def displacement_origin(size: int) -> int:
    """Where the displacement ``(0, 0)`` sits in a table indexed by
    ``spread_ids[x] - spread_ids[c] + origin`` (whose length is ``2·origin + 1``)."""
    return (size - 1) * (2 * size) + (size - 1)


def window_slot_by_displacement(size: int, view: int) -> np.ndarray:
    """Where a cell appears in the flattened ``view x view`` window centred on another cell,
    indexed by their displacement (see :func:`spread_ids`): ``view * view`` when outside.

    Entry ``spread_ids[x] - spread_ids[c] + displacement_origin(size)`` is the index of flat cell
    ``x`` in the window centred on flat cell ``c`` (the window wraps around the torus)."""
    origin = displacement_origin(size)
    slots = np.full(2 * origin + 1, view * view, dtype=np.int64)
    dr, dc = (d.ravel() for d in np.meshgrid(np.arange(1 - size, size), np.arange(1 - size, size), indexing="ij"))
    half = view // 2
    row, col = (dr + half) % size, (dc + half) % size  # the window's row and column, if < view
    inside = (row < view) & (col < view)
    slots[dr[inside] * (2 * size) + dc[inside] + origin] = row[inside] * view + col[inside]
    return slots


def signed_offset(delta: np.ndarray, size: int) -> np.ndarray:
    """Shortest signed displacement on a ring of ``size`` cells, in ``[-(size-1)//2, size//2]``."""
    return (delta + (size - 1) // 2) % size - (size - 1) // 2


def torus_distance(a: np.ndarray, b: np.ndarray, size: int) -> np.ndarray:
    """Manhattan distance on the torus between cells ``a`` and ``b`` (arrays ``(..., 2)``)."""
    d = np.abs(signed_offset(np.asarray(b) - np.asarray(a), size))
    return d.sum(axis=-1)


def cells_by_distance(size: int, centre: tuple[int, int]) -> np.ndarray:
    """Every flat cell of a ``size`` torus, nearest to ``centre`` first (torus Manhattan distance),
    ties by flat (row-major) index."""
    cells = np.stack(np.divmod(np.arange(size * size), size), axis=1)
    return np.argsort(torus_distance(np.asarray(centre), cells, size), kind="stable")
