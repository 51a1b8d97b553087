"""The closest other agent as an index into the others' axis: every per-other array of a step
(``others_*``, ``(X, Y, O, ...)``) and the place ``closest`` (``(X, Y)``) of each learner's
closest other agent on it (SPEC §3b) give that agent's entry, ``(X, Y, ...)``.

:class:`ClosestOther` reads the closest other's entries of the arrays every step record has; the
vector env's :class:`~empathy_zoo.vector.VectorStep` and the learner's
:class:`~agents.step_batch.StepBatch` both read them through it.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

__all__ = ["ClosestOther", "closest_entries"]


def closest_entries(others: np.ndarray, closest: np.ndarray) -> np.ndarray:
    """``others[i, j, closest[i, j]]`` for every ``(i, j)``: the entry at place ``closest`` (an
    ``(X, Y)`` integer array) of the third axis of an ``(X, Y, O, ...)`` array, ``(X, Y, ...)``."""
    if others.ndim < 3 or others.shape[:2] != closest.shape:
        raise ValueError(f"expected an (X, Y, O, ...) array with (X, Y) = {closest.shape}, got shape {others.shape}")
    index = closest.reshape(*closest.shape, *([1] * (others.ndim - 2)))
    return np.take_along_axis(others, index, axis=2)[:, :, 0]


class _OnTheAxis(Protocol):
    """What :class:`ClosestOther` reads of its host."""

    @property
    def closest(self) -> np.ndarray: ...
    @property
    def others_swapped(self) -> np.ndarray: ...
    @property
    def others_present(self) -> np.ndarray: ...
    @property
    def others_unseen(self) -> np.ndarray: ...
    @property
    def others_battery_return(self) -> np.ndarray: ...


class ClosestOther:
    """The closest other agent's entries of a step record's per-other arrays."""

    def of_closest(self: _OnTheAxis, others: np.ndarray) -> np.ndarray:
        """The entry of each learner's closest other agent of an ``(X, Y, O, ...)`` array (an
        ``others_*`` field): ``(X, Y, ...)``."""
        return closest_entries(others, self.closest)

    @property
    def other_swapped(self: _OnTheAxis) -> np.ndarray:
        """(X, Y, V) float32: ``others_swapped`` of the closest other agent."""
        return closest_entries(self.others_swapped, self.closest)

    @property
    def other_present(self: _OnTheAxis) -> np.ndarray:
        """(X, Y) bool: ``others_present`` of the closest other agent."""
        return closest_entries(self.others_present, self.closest)

    @property
    def other_unseen(self: _OnTheAxis) -> np.ndarray:
        """(X, Y) bool: ``others_unseen`` of the closest other agent."""
        return closest_entries(self.others_unseen, self.closest)

    @property
    def other_battery_return(self: _OnTheAxis) -> np.ndarray:
        """(X, Y) float64: ``others_battery_return`` of the closest other agent."""
        return closest_entries(self.others_battery_return, self.closest)
