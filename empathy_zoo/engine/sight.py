"""What an agent sees: observation windows painted from the engine's state, the perspective
swap (SPEC §4) and the closest other agent.

:class:`Sight` is the part of :class:`~empathy_zoo.engine.base.GridEngine` that paints views
(mixed into it, as :class:`~empathy_zoo.engine.placement.HandPlacement` is); it reads the engine's
state and lookup tables and calls its hooks ``_paint_background``, ``_appearance`` and
``_self_appearance``, where each environment says what its cells and agents look like.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from empathy_zoo.grid import torus_distance

__all__ = ["Sight", "Views", "swap_order", "OUTSIDE"]

OUTSIDE = 1 << 60
"""Window slot of a cell outside the window: larger than any canvas index."""


@dataclass(frozen=True)
class Views:
    """Who looks in each of ``K`` views painted together, with the index arrays :meth:`GridEngine.paint`
    derives from that (build it once with :meth:`GridEngine.views` when the same views are
    painted every step)."""

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
    swapped view draws each agent in the turn of the situation it holds (see :meth:`GridEngine.views`)."""


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


class Sight:
    """Painting views (mixed into :class:`~empathy_zoo.engine.base.GridEngine`, whose state,
    tables and hooks it uses)."""

    if TYPE_CHECKING:  # what the host engine provides (GridEngine.__init__ and its hooks)
        num_envs: int
        num_agents: int
        size: int
        obs_size: int
        other_agents: tuple[np.ndarray, ...]
        cells: np.ndarray
        present: np.ndarray
        inventory: np.ndarray
        _rows: np.ndarray
        _agent_base: np.ndarray
        _spread: np.ndarray
        _spread_centre: np.ndarray
        _window_slot: np.ndarray

        @property
        def pos(self) -> np.ndarray: ...
        def _paint_background(self, env_ids: np.ndarray, centre: np.ndarray, out: np.ndarray) -> None: ...
        def _appearance(self, inventory: np.ndarray, viewer: np.ndarray) -> np.ndarray | float: ...
        def _self_appearance(self, inventory: np.ndarray, viewer: np.ndarray) -> np.ndarray | float: ...

    def views(self, viewer: np.ndarray, order: np.ndarray | None = None) -> Views:
        """The :class:`Views` of agents ``viewer`` (``(K,)`` agent indices); for swapped views, the
        ``(K, A)`` :func:`swap_order` their agents are painted in.

        A swapped view holds the agents in that order (each in the other's situation: cell,
        inventory, presence); each agent is drawn in the turn of the situation it holds, so where
        agents share a cell the one on top is the same as without the swap (the swapped view is the
        other agent's own observation wherever the agents look alike to both)."""
        viewer = np.asarray(viewer, dtype=np.int64)
        k, a = len(viewer), self.num_agents
        own = np.arange(k) * a + viewer
        first = np.repeat(np.arange(k) * self.obs_size, a).reshape(k, a)
        size = k * self.obs_size
        # (with two agents the one besides the viewer is drawn alone: the order cannot matter)
        draw = None if order is None or a <= 2 else np.ascontiguousarray(np.broadcast_to(order, (k, a)))
        return Views(viewer, own, np.repeat(own, a).reshape(k, a), first, size, np.array(size), draw)

    def paint(
        self, env_ids: np.ndarray, cells: np.ndarray, inventory: np.ndarray, present: np.ndarray, views: Views
    ) -> np.ndarray:
        """``(K, obs_size)`` float32 observations of ``K`` views at once.

        View ``k`` is environment ``env_ids[k]`` (its batteries) with the agents on flat
        ``cells[k]`` (``(A,)``), holding ``inventory[k]``, present where ``present[k]``, seen by
        agent ``views.viewer[k]``: the window around the viewer, the other present agents drawn over
        it in agent order (or in ``views.draw``'s), the viewer's own cell drawn last.
        """
        # (operands of equal shape and 0-d constants: numpy's cheapest calls on the small arrays of
        # the one-environment path)
        centre = cells.take(views.own_each)  # (K, A): the viewer's cell, once per agent
        # each agent's index in the flattened canvas; absent or out-of-window agents go to one
        # scratch element past the pictures (so drawing needs no masks)
        slots = self._window_slot.take(self._spread.take(cells) - self._spread_centre.take(centre))
        if np.count_nonzero(present) < present.size:
            slots[~present] = OUTSIDE
        slots += views.first
        np.minimum(slots, views.scratch, out=slots)
        canvas = np.empty(views.size + 1, dtype=np.float32)
        picture = canvas[:-1].reshape(-1, self.obs_size)
        self._paint_background(env_ids, centre[:, 0], picture)
        looks = self._appearance(inventory, views.viewer)
        if views.draw is not None:  # (a swapped view of three or more agents)
            slots = np.take_along_axis(slots, views.draw, axis=1)
            if isinstance(looks, np.ndarray):
                looks = np.take_along_axis(looks, views.draw, axis=1)
        for agent in range(self.num_agents):
            canvas[slots[:, agent]] = looks[:, agent] if isinstance(looks, np.ndarray) else looks
        picture[:, self.obs_size // 2] = self._self_appearance(inventory.take(views.own), views.viewer)
        return picture

    def observe(self, viewer: int, env_ids: np.ndarray | None = None) -> np.ndarray:
        """``(N, obs_size)`` float32 observations of agent ``viewer`` (in ``env_ids``, default all)."""
        if env_ids is None:
            env_ids, cells, inventory, present = self._rows, self.cells, self.inventory, self.present
        else:
            cells, inventory, present = self.cells[env_ids], self.inventory[env_ids], self.present[env_ids]
        return self.paint(env_ids, cells, inventory, present, self.views(np.full(len(env_ids), viewer)))

    def observe_swapped(self, viewer: int, other: int | np.ndarray) -> np.ndarray:
        """What ``viewer`` would observe had it exchanged its situation (cell, inventory, presence)
        with ``other`` (an agent index, or one per environment), in every environment.

        Rows where ``other`` has left the environment are meaningless; see :attr:`present`.
        """
        order = swap_order(self.num_agents, viewer, other)
        views = self.views(np.full(self.num_envs, viewer), order)
        if order.ndim == 1:
            cells, inventory, present = (x.take(order, axis=1) for x in (self.cells, self.inventory, self.present))
        else:
            order = order + self._agent_base  # into the flattened (N, A) arrays
            cells, inventory, present = (x.ravel().take(order) for x in (self.cells, self.inventory, self.present))
        return self.paint(self._rows, cells, inventory, present, views)

    def in_view(self, viewer: int, other: int | np.ndarray) -> np.ndarray:
        """(N,) bool: ``other`` stands inside ``viewer``'s observation window."""
        other_cell = self.cells[self._rows, other] if np.ndim(other) else self.cells[:, other]
        displacement = self._spread[other_cell] - self._spread_centre[self.cells[:, viewer]]
        return self._window_slot[displacement] < self.obs_size

    def closest_other(self, viewer: int) -> tuple[np.ndarray, np.ndarray]:
        """Index of the closest other present agent of ``viewer`` (torus Manhattan distance, ties
        to the lowest index) and a mask of environments where such an agent exists."""
        others = self.other_agents[viewer]
        if len(others) == 1:
            return np.full(self.num_envs, others[0]), self.present[:, others[0]].copy()
        dist = torus_distance(self.pos[:, viewer, None, :], self.pos[:, others, :], self.size).astype(np.float64)
        dist[~self.present[:, others]] = np.inf
        choice = np.argmin(dist, axis=1)
        return np.asarray(others)[choice], np.isfinite(dist[self._rows, choice])
