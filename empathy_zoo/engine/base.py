"""The part of the rules both gridworlds share: torus, moves, resets, state, observations and the
swap.

A :class:`GridEngine` holds the state of ``num_envs`` environments as numpy arrays and steps them
all at once. Subclasses add what differs (who harms whom, batteries, observation values). The
PettingZoo ``ParallelEnv`` is this engine with ``num_envs = 1``; :mod:`empathy_zoo.vector` is the
same engine with many environments. Where agents may start is decided by
:class:`~empathy_zoo.engine.placement.StartRules`; the observation window's lookup tables and the
painting of views are in :mod:`empathy_zoo.engine.sight`.
"""

from __future__ import annotations

import difflib
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from empathy_zoo.actions import NUM_ACTIONS, Action, check_action_array
from empathy_zoo.engine.arguments import (
    GRID_ARGUMENTS,
    MAX_SIZE,
    check_agent_count,
    check_choice,
    check_env_arguments,
    check_grid_arguments,
    table_bytes,
)
from empathy_zoo.engine.placement import StartRules
from empathy_zoo.engine.sight import Views, Window, canvas_slots, draw_agents, swap_order
from empathy_zoo.grid import MOVES, torus_distance
from empathy_zoo.metrics import equality
from empathy_zoo.randomness import EnvStreams, check_seed

__all__ = [
    "GridEngine",
    "StepEvents",
    "GRID_ARGUMENTS",
    "MAX_SIZE",
    "check_grid_arguments",
    "check_choice",
    "check_env_arguments",
    "table_bytes",
]

NO_AGENT = -1
MISSPELT_OPTION_RATIO = 0.9
"""How alike (``difflib`` ratio) an unknown reset option must be to a known one to be refused as
its misspelling (``position`` for ``positions``); other unknown keys are ignored with a warning, as
PettingZoo's API test passes ``{"options": 1}``."""
STAY = int(Action.STAY)


@dataclass
class StepEvents:
    """What happened in one step of every environment (arrays over ``(N,)`` or ``(N, A)``)."""

    rewards: np.ndarray
    """(N, A) float32: the environment's reward of each agent this step (0 for absent agents)."""
    terminated: np.ndarray
    """(N, A) bool: the agent's episode ended for good this step."""
    truncated: np.ndarray
    """(N, A) bool: the agent's episode was cut short this step (time limit, or the robot fell)."""
    harmed_by: np.ndarray
    """(N, A) int64: index of the agent that harmed this agent this step, else -1."""
    collected: np.ndarray
    """(N, A) bool: the agent collected a battery this step."""
    present_before: np.ndarray
    """(N, A) bool: the agent was in the environment when the step began."""
    episode_over: np.ndarray
    """(N,) bool: the episode ended this step (the environment needs a reset)."""


class GridEngine:
    """State and shared rules of ``num_envs`` gridworlds on a ``size x size`` torus."""

    name: ClassVar[str]
    agents: tuple[str, ...]
    """The agents' names: the class gives the default roster (the learner, then one other agent);
    an engine with :attr:`count_argument` set to ``N`` holds the learner and ``N`` others alike,
    named ``<kind>_0 … <kind>_{N-1}`` after the default other (``cat_0``)."""
    symbols: tuple[str, ...]
    """One character per agent for the text render (the others share one)."""
    colors: tuple[tuple[int, int, int], ...]
    """One RGB colour per agent for the image render (the others share one)."""
    min_size: ClassVar[int] = 3
    num_actions: ClassVar[int] = NUM_ACTIONS
    """Actions of every agent (up, down, left, right, stay)."""
    obs_low: ClassVar[float]
    obs_high: float
    step_reward_bound: float = 1.0
    """The largest reward any agent gets in one step, in magnitude (every reward of the suite's
    engines is ≥ 0 but Sharing's late batteries); a checkpoint's episode returns are checked
    against ``t`` times it. An engine whose rewards can be larger sets it."""
    """The largest observation value: the class gives it, or an engine whose values depend on its
    arguments sets it per instance (Sharing: the value of an agent holding every battery)."""
    extra_arguments: ClassVar[Mapping[str, tuple[str, ...]]] = {}
    """Environment-specific keyword arguments of the constructor and their allowed values (the
    first one is the default); every face and the sweep files accept exactly these."""
    count_argument: ClassVar[str | None] = None
    """The constructor keyword giving how many other agents (after the first) the environment
    holds, default 1 (``num_cats``), or ``None`` when the number is fixed."""
    argument_help: ClassVar[Mapping[str, str]] = {}
    """One line for each of its own arguments (:attr:`extra_arguments`, :attr:`count_argument`):
    the command line's help."""

    def __init__(self, num_envs: int = 1, size: int = 7, view: int = 5, max_cycles: int = 500, num_others: int = 1) -> None:
        check_grid_arguments(size, view, max_cycles, self.min_size)
        if isinstance(num_envs, bool) or not isinstance(num_envs, (int, np.integer)) or num_envs < 1:
            raise ValueError(f"num_envs must be a positive int, got {num_envs!r}")
        self.num_envs = int(num_envs)
        self.size = int(size)
        self.view = int(view)
        self.max_cycles = int(max_cycles)
        if self.count_argument is None:
            if num_others != 1:
                raise ValueError(f"{self.name} holds exactly one other agent, got num_others={num_others!r}")
        else:
            num_others = check_agent_count(self.count_argument, num_others, *self._room_for_others())
            kind = type(self).agents[-1].rsplit("_", 1)[0]
            self.agents = (self.agents[0], *(f"{kind}_{i}" for i in range(num_others)))
            self.symbols = (self.symbols[0],) + (self.symbols[-1],) * num_others
            self.colors = (self.colors[0],) + (self.colors[-1],) * num_others
        self.num_others = int(num_others)
        """How many agents besides the first (the learner) the environment holds."""
        self.num_agents = len(self.agents)
        self.other_agents = tuple(np.array([j for j in range(self.num_agents) if j != i]) for i in range(self.num_agents))
        """``[agent]``: the indices of every agent but ``agent``, in agent order (int arrays, read-only)."""
        for other_indices in self.other_agents:
            other_indices.flags.writeable = False
        self.obs_size = self.view * self.view
        self.num_cells = self.size * self.size
        # lookup tables over flat cells (row * size + col), so a step is a few 1-D numpy lookups;
        # every table grows with the number of cells, none with its square
        rows, cols = np.divmod(np.arange(self.num_cells), self.size)
        self._cell_rc = np.stack([rows, cols], axis=1)
        self._cell_rc.flags.writeable = False
        destination = (self._cell_rc[:, None, :] + MOVES[None, :, :]) % self.size
        self._next_cell = (destination[..., 0] * self.size + destination[..., 1]).ravel()
        """``[cell * NUM_ACTIONS + action]``: the cell an agent on ``cell`` reaches with ``action``."""
        self.window = Window(self.size, self.view)
        """The observation window's lookup tables (see :meth:`paint`)."""
        self.streams = EnvStreams(self.num_envs)
        n, a = self.num_envs, self.num_agents
        self.cells = np.zeros((n, a), dtype=np.int64)
        """(N, A) int64: the flat cell (``row * size + col``) of every agent (see :attr:`pos`)."""
        self.present = np.zeros((n, a), dtype=bool)
        self.inventory = np.zeros((n, a), dtype=np.int64)
        self.t = np.zeros(n, dtype=np.int64)
        self.running = np.zeros(n, dtype=bool)
        # what happened so far this episode (the metrics are computed from these, never from rewards)
        self.episode_return = np.zeros((n, a), dtype=np.float64)
        self.episode_battery_return = np.zeros((n, a), dtype=np.float64)
        self.episode_harms = np.zeros((n, a), dtype=np.int64)
        self.left_at = np.zeros((n, a), dtype=np.int64)
        """(N, A) int64: steps the agent was operative before it left (where it is absent)."""
        self._clear_of_timeouts = 0
        self._rows = np.arange(n)
        self._nobody_harmed = np.full((n, a), NO_AGENT, dtype=np.int64)
        self._agent_base = (self._rows * a)[:, None]
        self._cell_base = np.repeat(self._rows * self.num_cells, a).reshape(n, a)
        """(N, A): where each environment's cells start in a flattened ``(N, num_cells)`` array."""
        # 0-d arrays: cheaper ufunc operands than Python ints on the small arrays of one environment
        self._num_actions = np.array(NUM_ACTIONS)
        self._one, self._time_limit = np.array(1), np.array(self.max_cycles)
        self.start_order: np.ndarray | None = None
        """Flat cells in the order agents take them at reset (each agent the first one not blocked,
        taken or in conflict), or ``None``: start cells are drawn at random (:meth:`_random_start`)."""

    @property
    def pos(self) -> np.ndarray:
        """(N, A, 2) int64, read-only: the ``(row, col)`` of every agent (from :attr:`cells`)."""
        pos = self._cell_rc[self.cells]
        pos.flags.writeable = False  # a copy: writing to it would move nobody
        return pos

    def flat_cell(self, row: int, col: int) -> int:
        """The flat id of cell ``(row, col)``."""
        return int(row) * self.size + int(col)

    # ------------------------------------------------------------------ hooks for subclasses
    def _room_for_others(self) -> tuple[int, str]:
        """The most other agents the grid can start (besides the first) and why, for the
        ``ValueError`` of a larger :attr:`count_argument`."""
        return self.size * self.size - 1, f"the {self.size}x{self.size} grid has {self.size * self.size} cells"

    def _reset_extra(self, env_ids: np.ndarray) -> None:
        """Reset environment-specific state (batteries) of ``env_ids``."""

    def _blocked_start_cells(self, env_id: int) -> np.ndarray:
        """Flat cells where no agent may start (batteries)."""
        return np.zeros(0, dtype=np.int64)

    def _random_start(self, env_ids: np.ndarray) -> None:
        """Draw start cells for every agent of ``env_ids`` from their streams."""
        raise NotImplementedError

    def _start_conflict(self, agent: int, cell: np.ndarray, other_agent: int, other: np.ndarray) -> bool:
        """Whether agent ``agent`` may not start on ``cell`` while agent ``other_agent`` starts on
        ``other`` (distinct cells)."""
        raise NotImplementedError

    def _apply_options(self, env_id: int, options: Mapping[str, Any]) -> set[str]:
        """Apply environment-specific options; return the option keys consumed."""
        return set()

    def _resolve(self, previous: np.ndarray, moves: np.ndarray, events: StepEvents) -> None:
        """Apply the environment's rules after everyone moved, filling ``events`` (including
        ``episode_over`` where the rules end the episode). ``previous`` holds the cells before the
        move and ``moves`` each agent's ``cell * NUM_ACTIONS + action`` (``STAY`` when absent)."""
        raise NotImplementedError

    def _paint_background(self, env_ids: np.ndarray, centre: np.ndarray, out: np.ndarray) -> None:
        """Fill ``out`` (``(K, obs_size)`` float32) with the window around flat cell ``centre[k]`` of
        environment ``env_ids[k]``, without agents. Floor is 0 unless a subclass says otherwise."""
        out.fill(0.0)

    def _appearance(self, inventory: np.ndarray, viewer: np.ndarray) -> np.ndarray | float:
        """How each agent holding ``inventory`` (``(K, A)``) looks to ``viewer`` (``(K,)``): a
        scalar (all look alike) or a ``(K, A)`` array."""
        raise NotImplementedError

    def _self_appearance(self, inventory: np.ndarray, viewer: np.ndarray) -> np.ndarray | float:
        """How its own cell looks to ``viewer`` (``(K,)``) holding ``inventory`` (``(K,)``)."""
        raise NotImplementedError

    # ------------------------------------------------------------------ reset
    def reset(
        self,
        env_ids: Sequence[int] | np.ndarray | None = None,
        seeds: Sequence[int | None] | None = None,
        options: Mapping[str, Any] | None = None,
    ) -> None:
        """Start new episodes in ``env_ids`` (all when ``None``), reseeding those given a seed.

        Bad seeds or options raise ``ValueError`` and leave every environment as it was."""
        ids = self._rows if env_ids is None else np.asarray(env_ids, dtype=np.int64)
        if seeds is not None:
            if len(seeds) != len(ids):
                raise ValueError(f"got {len(seeds)} seeds for {len(ids)} environments")
            for s in seeds:
                check_seed(s)
        if options:
            if len(ids) != 1:
                raise ValueError("reset options place one environment at a time")
            before = self.state()  # placing agents by hand is checked as it goes: undo it on an error
            try:
                self._reset(ids, seeds, options)
            except BaseException:
                self.load_state(before)
                raise
        else:
            self._reset(ids, seeds, options)

    def _reset(self, ids: np.ndarray, seeds: Sequence[int | None] | None, options: Mapping[str, Any] | None) -> None:
        if seeds is not None:
            for i, s in zip(ids, seeds, strict=True):
                if s is not None:
                    self.streams.seed(int(i), s)
        self.streams.ensure_seeded(ids)
        self.t[ids] = 0
        self.present[ids] = True
        self.inventory[ids] = 0
        self.running[ids] = True
        for array in (self.episode_return, self.episode_battery_return, self.episode_harms, self.left_at):
            array[ids] = 0
        self._reset_extra(ids)
        if options:
            self._reset_with_options(int(ids[0]), options)
        elif self.start_order is None:
            self._random_start(ids)
        else:  # no randomness drawn; without options every environment has the same layout
            placed = self._start_rules(int(ids[0])).in_order(self.start_order, {}, range(self.num_agents))
            self.cells[ids] = [self.flat_cell(*placed[index]) for index in range(self.num_agents)]

    def _start_rules(self, env_id: int) -> StartRules:
        """Where agents may start in environment ``env_id`` (its blocked cells as they are now)."""
        return StartRules(self.agents, self.size, frozenset(self._blocked_start_cells(env_id).tolist()), self._start_conflict)

    def _reset_with_options(self, env_id: int, options: Mapping[str, Any]) -> None:
        """Apply ``reset(options=...)`` to environment ``env_id``: the environment's own options,
        then the agents placed by hand (checked), then every other agent by the environment's
        rule (its start order, or drawn from its stream)."""
        if not isinstance(options, Mapping):
            raise ValueError(f"options must be a mapping, got {type(options).__name__}")
        consumed = self._apply_options(env_id, options) | {"positions"}
        unknown = set(options) - consumed
        for key in sorted(unknown, key=str):  # a misspelt option is refused, never ignored
            close = difflib.get_close_matches(str(key), sorted(consumed), n=1, cutoff=MISSPELT_OPTION_RATIO)
            if close:
                raise ValueError(
                    f"unknown reset option {key!r} for {self.name}: did you mean {close[0]!r}? known: {sorted(consumed)}"
                )
        if unknown:  # PettingZoo's own API test passes foreign options; ignore them loudly
            warnings.warn(
                f"ignoring unknown reset option(s) {sorted(unknown)} for {self.name}; known: {sorted(consumed)}",
                stacklevel=4,
            )
        rules = self._start_rules(env_id)
        placed = rules.hand_placed(options.get("positions"))
        missing = [index for index in range(self.num_agents) if index not in placed]
        if self.start_order is not None:
            placed = rules.in_order(self.start_order, placed, missing)
        else:
            env = np.array([env_id])
            placed = rules.at_random(lambda: self.streams.uniform(env)[0], placed, missing)
        for index, cell in placed.items():
            self.cells[env_id, index] = self.flat_cell(*cell)

    # ------------------------------------------------------------------ step
    def check_actions(self, actions: np.ndarray) -> np.ndarray:
        """Validate an ``(N, A)`` integer action array; raise ``ValueError`` naming the problem."""
        return check_action_array(actions, (self.num_envs, self.num_agents), self.agents, self.present)

    def step(self, actions: np.ndarray) -> StepEvents:
        """Move every present agent simultaneously, then apply the rules; returns the events."""
        # (np.count_nonzero instead of .all()/.any(): a third of the cost on the one-environment path)
        if np.count_nonzero(self.running) < self.num_envs:
            raise RuntimeError("step() called on an environment whose episode is over; reset it first")
        actions = self.check_actions(actions)
        if np.count_nonzero(self.present) < self.present.size:
            actions = np.where(self.present, actions, STAY)  # absent agents' actions are ignored
        return self.step_checked(actions)

    def step_checked(self, actions: np.ndarray) -> StepEvents:
        """:meth:`step` for an ``(N, A)`` int64 array already known valid, with ``STAY`` for absent
        agents, in environments whose episodes are running (a face that guarantees this skips
        the checks)."""
        n, a = self.num_envs, self.num_agents
        present = self.present.copy()
        previous = self.cells
        moves = previous * self._num_actions + actions
        self.cells = self._next_cell[moves]
        terminated, truncated, collected = np.zeros((3, n, a), dtype=bool)  # one allocation
        events = StepEvents(
            rewards=np.zeros((n, a), dtype=np.float32),
            terminated=terminated,
            truncated=truncated,
            harmed_by=self._nobody_harmed.copy(),
            collected=collected,
            present_before=present,
            episode_over=np.zeros(n, dtype=bool),
        )
        self._resolve(previous, moves, events)
        self.t += self._one
        self.episode_return += events.rewards
        # No environment can reach max_cycles for the next _clear_of_timeouts steps (resets only
        # lower t), so the time limit is checked only when that count runs out.
        self._clear_of_timeouts -= 1
        if self._clear_of_timeouts <= 0:
            ending = self.t >= self._time_limit
            if np.count_nonzero(ending):
                events.truncated |= ending[:, None] & self.present & ~events.terminated
                events.episode_over |= ending
            self._clear_of_timeouts = self.max_cycles - int(self.t.max())
        if np.count_nonzero(events.episode_over):
            self.running &= ~events.episode_over
        return events

    def _leave(self, gone: np.ndarray) -> None:
        """Take the agents where ``gone`` (``(N, A)`` bool) out of their environments."""
        self.left_at = np.where(gone, self.t[:, None], self.left_at)
        self.present &= ~gone

    # ------------------------------------------------------------------ observations
    def views(self, viewer: np.ndarray, order: np.ndarray | None = None) -> Views:
        """The :class:`~empathy_zoo.engine.sight.Views` of agents ``viewer`` (``(K,)`` agent indices);
        for swapped views, the ``(K, A)`` :func:`~empathy_zoo.engine.sight.swap_order` their agents
        are painted in (see :meth:`Views.of <empathy_zoo.engine.sight.Views.of>`)."""
        return Views.of(viewer, self.num_agents, self.obs_size, order)

    def paint(
        self, env_ids: np.ndarray, cells: np.ndarray, inventory: np.ndarray, present: np.ndarray, views: Views
    ) -> np.ndarray:
        """``(K, obs_size)`` float32 observations of ``K`` views at once.

        View ``k`` is environment ``env_ids[k]`` (its batteries) with the agents on flat
        ``cells[k]`` (``(A,)``), holding ``inventory[k]``, present where ``present[k]``, seen by
        agent ``views.viewer[k]``: the window around the viewer, the other present agents drawn over
        it in agent order (or in ``views.draw``'s), the viewer's own cell drawn last.
        """
        centre, slots = canvas_slots(self.window, views, cells, present)
        canvas = np.empty(views.size + 1, dtype=np.float32)
        picture = canvas[:-1].reshape(-1, self.obs_size)
        self._paint_background(env_ids, centre[:, 0], picture)
        draw_agents(canvas, slots, self._appearance(inventory, views.viewer), views)
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
        return self.window.contains(other_cell, self.cells[:, viewer])

    def closest_other(self, viewer: int) -> tuple[np.ndarray, np.ndarray]:
        """Index of the closest other present agent of ``viewer`` (torus Manhattan distance, ties
        to the lowest index) and a mask of environments where such an agent exists."""
        other_indices = self.other_agents[viewer]
        if len(other_indices) == 1:
            return np.full(self.num_envs, other_indices[0]), self.present[:, other_indices[0]].copy()
        dist = torus_distance(self.pos[:, viewer, None, :], self.pos[:, other_indices, :], self.size).astype(np.float64)
        dist[~self.present[:, other_indices]] = np.inf
        choice = np.argmin(dist, axis=1)
        return np.asarray(other_indices)[choice], np.isfinite(dist[self._rows, choice])

    # ------------------------------------------------------------------ infos
    harm_infos: ClassVar[bool] = False
    """Whether an agent's infos say who harmed it and whom it harmed (``harmed_by``, ``harmed``):
    an environment where agents harm one another sets it."""

    def reset_info(self, env_id: int, agent: int) -> dict[str, Any]:
        """The ``infos[agent]`` entry after a reset (nobody harmed yet, with :attr:`harm_infos`)."""
        return {"harmed_by": None, "harmed": []} if self.harm_infos else {}

    def step_info(self, events: StepEvents, env_id: int, agent: int) -> dict[str, Any]:
        """The ``infos[agent]`` entry after a step: with :attr:`harm_infos`, the agent that harmed
        ``agent`` this step (``None``: none) and the agents ``agent`` harmed."""
        if not self.harm_infos:
            return {}
        by = events.harmed_by[env_id].tolist()
        return {
            "harmed_by": None if by[agent] < 0 else self.agents[by[agent]],
            "harmed": [self.agents[victim] for victim, harmer in enumerate(by) if harmer == agent],
        }

    # ------------------------------------------------------------------ metrics
    def episode_metrics(self, env_ids: np.ndarray, learner: int = 0) -> dict[str, np.ndarray]:
        """Episode metrics of ``learner`` (SPEC §5) in ``env_ids``, from what happened so far.

        With several other agents, ``harms`` counts every one harmed, ``other_batteries`` and
        ``other_return`` are summed over the others, and ``equality`` compares the learner's
        battery reward with the others' mean (1 when the learner took exactly its share); with one
        other agent each is that agent's own figure."""
        other_indices = self.other_agents[learner]
        if len(other_indices) == 1:  # (that agent's own figures, read at once)

            def summed_over_others(array: np.ndarray) -> np.ndarray:
                return array[env_ids, other_indices[0]]
        else:

            def summed_over_others(array: np.ndarray) -> np.ndarray:
                return array[env_ids[:, None], other_indices].sum(axis=1)

        own_b = self.episode_battery_return[env_ids, learner]
        return {
            "survival": np.where(self.present[env_ids, learner], self.t[env_ids], self.left_at[env_ids, learner]),
            "harms": self.episode_harms[env_ids, learner].copy(),
            "batteries": self.inventory[env_ids, learner].copy(),
            "other_batteries": summed_over_others(self.inventory),
            "equality": equality(own_b, summed_over_others(self.episode_battery_return) / len(other_indices)),
            "return": self.episode_return[env_ids, learner].copy(),
            "other_return": summed_over_others(self.episode_return),
            "length": self.t[env_ids].copy(),
        }

    # ------------------------------------------------------------------ checkpoint
    def state(self) -> dict[str, Any]:
        """A copy of the whole state (for checkpoints)."""
        return {key: getattr(self, key).copy() for key in self._state_keys()} | {"streams": self.streams.state()}

    def load_state(self, state: Mapping[str, Any]) -> None:
        for key in self._state_keys():
            getattr(self, key)[...] = state[key]
        self.streams.load_state(state["streams"])
        self._clear_of_timeouts = 0

    def _state_keys(self) -> tuple[str, ...]:
        return (
            "cells",
            "present",
            "inventory",
            "t",
            "running",
            "episode_return",
            "episode_battery_return",
            "episode_harms",
            "left_at",
        )
