"""What an agent sees: the lookup tables of the observation window, the index arrays of views
painted together, and the perspective swap (SPEC §4) as a permutation of agents.

:class:`Window` holds, for a ``view × view`` window on a ``size`` torus, where a cell appears in
the window around another; :class:`Views` says who looks in each of ``K`` views painted at once;
:func:`canvas_slots` and :func:`draw_agents` put agents into such a canvas.
:meth:`GridEngine.paint <empathy_zoo.engine.base.GridEngine.paint>` paints observations with them
and the environment's own looks. Everything here works on the arrays it is given.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from empathy_zoo.grid import displacement_origin, spread_ids, window_indices, window_slot_by_displacement

__all__ = ["Window", "Views", "canvas_slots", "draw_agents", "swap_order", "OUTSIDE"]

OUTSIDE = 1 << 60
"""Window slot of a cell outside the window: larger than any canvas index."""


class Window:
    """The ``view × view`` observation window on a ``size × size`` torus, as lookup tables over
    flat cells (``row * size + col``); each grows with the number of cells, none with its square."""

    def __init__(self, size: int, view: int) -> None:
        self.size = size
        """Side of the torus."""
        self.view = view
        """Side of the window (odd)."""
        self.obs_size = view * view
        """Cells in the window: the length of an observation; its middle one is the centre."""
        self.spread = spread_ids(size)
        """``[cell]``: the cell's id on a grid twice as wide; the difference of two tells their displacement."""
        self.spread_centre = self.spread - displacement_origin(size)
        """``[centre]``: ``spread[centre]`` less the origin of the displacement table :attr:`slot`."""
        slot = window_slot_by_displacement(size, view)
        slot[slot == self.obs_size] = OUTSIDE
        self.slot = slot
        """``[spread[cell] - spread_centre[centre]]``: the window slot of ``cell`` around ``centre``,
        or :data:`OUTSIDE`."""

    @cached_property
    def cells(self) -> np.ndarray:
        """``[centre]``: the flat cells of the window around ``centre``, row-major (``(size², view²)``
        int64; built when first read: only an environment that paints a background reads it)."""
        return window_indices(self.size, self.view)

    def slots(self, cells: np.ndarray, centre: np.ndarray) -> np.ndarray:
        """The window slot of each flat cell of ``cells`` around the matching flat cell of
        ``centre`` (arrays of one shape), or :data:`OUTSIDE`."""
        return self.slot.take(self.spread.take(cells) - self.spread_centre.take(centre))

    def contains(self, cells: np.ndarray, centre: np.ndarray) -> np.ndarray:
        """Bool: each flat cell of ``cells`` is inside the window around the matching ``centre``."""
        return self.slot[self.spread[cells] - self.spread_centre[centre]] < self.obs_size


@dataclass(frozen=True)
class Views:
    """Who looks in each of ``K`` views painted together, with the index arrays painting derives
    from that (build it once with :meth:`Views.of` when the same views are painted every step)."""

    viewer: np.ndarray
    """(K,) the agent whose observation each view is."""
    own: np.ndarray
    """(K,) where the viewer sits in a flattened ``(K, A)`` array."""
    own_each: np.ndarray
    """(K, A) ``own`` repeated for every agent."""
    first: np.ndarray
    """(K, A) where each view starts in a flattened ``(K, obs_size)`` canvas."""
    size: int
    """``K * obs_size``: the index just past the ``K`` pictures in that canvas (its scratch element)."""
    scratch: np.ndarray
    """``size`` as a 0-d array."""
    draw: np.ndarray | None = None
    """(K, A) the agents of each view in the order they are drawn, or ``None``: agent order. A
    swapped view draws each agent in the turn of the situation it holds (see :meth:`Views.of`)."""

    @classmethod
    def of(cls, viewer: np.ndarray, num_agents: int, obs_size: int, order: np.ndarray | None = None) -> Views:
        """The views of agents ``viewer`` (``(K,)`` agent indices) among ``num_agents``, each
        ``obs_size`` long; for swapped views, the ``(K, A)`` :func:`swap_order` their agents are
        painted in.

        A swapped view holds the agents in that order (each in the other's situation: cell,
        inventory, presence); each agent is drawn in the turn of the situation it holds, so where
        agents share a cell the one on top is the same as without the swap (the swapped view is the
        other agent's own observation wherever the agents look alike to both)."""
        viewer = np.asarray(viewer, dtype=np.int64)
        k, a = len(viewer), num_agents
        own = np.arange(k) * a + viewer
        first = np.repeat(np.arange(k) * obs_size, a).reshape(k, a)
        size = k * obs_size
        # (with two agents the one besides the viewer is drawn alone: the order cannot matter)
        draw = None if order is None or a <= 2 else np.ascontiguousarray(np.broadcast_to(order, (k, a)))
        return cls(viewer, own, np.repeat(own, a).reshape(k, a), first, size, np.array(size), draw)


def canvas_slots(window: Window, views: Views, cells: np.ndarray, present: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where each agent of ``K`` views lands in their flattened canvas (``K * obs_size`` pictures
    and one scratch element past them), given the agents' flat ``cells`` and ``present`` (``(K, A)``).

    Returns ``(centre, slots)``, both ``(K, A)`` int64: the viewer's cell once per agent, and each
    agent's canvas index (the scratch element where it is absent or outside the window, so
    drawing needs no masks), its columns in drawing order (:attr:`Views.draw`)."""
    # (operands of equal shape and 0-d constants: numpy's cheapest calls on the small arrays of
    # the one-environment path)
    centre = cells.take(views.own_each)
    slots = window.slots(cells, centre)
    if np.count_nonzero(present) < present.size:
        slots[~present] = OUTSIDE
    slots += views.first
    np.minimum(slots, views.scratch, out=slots)
    if views.draw is not None:  # (a swapped view of three or more agents)
        slots = np.take_along_axis(slots, views.draw, axis=1)
    return centre, slots


def draw_agents(canvas: np.ndarray, slots: np.ndarray, looks: np.ndarray | float, views: Views) -> None:
    """Write each agent's look into ``canvas`` at its ``slots`` (from :func:`canvas_slots`), in
    drawing order, so a later agent covers an earlier one on the same cell; ``looks`` is one
    value for every agent or a ``(K, A)`` array in agent order."""
    if isinstance(looks, np.ndarray):
        if views.draw is not None:
            looks = np.take_along_axis(looks, views.draw, axis=1)
        for agent in range(slots.shape[1]):
            canvas[slots[:, agent]] = looks[:, agent]
    else:
        for agent in range(slots.shape[1]):
            canvas[slots[:, agent]] = looks


def swap_order(num_agents: int, viewer: int, other: int | np.ndarray) -> np.ndarray:
    """The swap (SPEC §4) as a permutation of agent indices: ``arange(num_agents)`` with ``viewer``
    and ``other`` exchanged; ``(A,)`` for one ``other``, ``(N, A)`` for one per environment.
    Indexing every per-agent array (cell, inventory, presence) with it swaps the two situations."""
    other = np.asarray(other, dtype=np.int64)
    if np.count_nonzero(other == viewer):
        raise ValueError("an agent cannot swap places with itself")
    if other.ndim == 0:
        order = np.arange(num_agents, dtype=np.int64)
        order[viewer], order[other] = other, viewer
        return order
    order = np.broadcast_to(np.arange(num_agents, dtype=np.int64), (*other.shape, num_agents)).copy()
    order[..., viewer] = other
    np.put_along_axis(order, other[..., None], viewer, axis=-1)
    return order
