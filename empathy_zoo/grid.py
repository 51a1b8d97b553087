"""Torus geometry shared by every environment: actions, moves and observation windows."""

from __future__ import annotations

from enum import IntEnum

import numpy as np

__all__ = [
    "Action", "MOVES", "NUM_ACTIONS", "window_indices", "window_slots", "signed_offset", "torus_distance",
    "cells_by_distance",
]


class Action(IntEnum):
    """The five actions every agent has (``Discrete(5)``)."""

    UP = 0
    """row - 1"""
    DOWN = 1
    """row + 1"""
    LEFT = 2
    """col - 1"""
    RIGHT = 3
    """col + 1"""
    STAY = 4
    """no-op"""


NUM_ACTIONS = len(Action)

MOVES = np.array([(-1, 0), (1, 0), (0, -1), (0, 1), (0, 0)], dtype=np.int64)
"""``MOVES[action]`` is the (row, col) displacement of an action."""


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


def window_slots(size: int, view: int) -> np.ndarray:
    """Where every cell appears in the window centred on every other cell.

    Returns an int64 array of shape ``(size * size, size * size)``: entry ``[c, x]`` is the index of
    flat cell ``x`` in the flattened window centred on flat cell ``c``, or ``view * view`` when
    ``x`` lies outside that window.
    """
    slots = np.full((size * size, size * size), view * view, dtype=np.int64)
    window = window_indices(size, view)
    centres = np.repeat(np.arange(size * size), view * view)
    slots[centres, window.ravel()] = np.tile(np.arange(view * view), size * size)
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
