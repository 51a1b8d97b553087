"""Coexistence rules (SPEC §2, §3b): a robot and one or more cats; whoever is above or to the
right harms.

Every cat meets the robot by the same rule, pair by pair (:func:`harm_outcome`); cats pass
through one another and never harm each other. A robot harmed by several cats in one step names
the first of them (in agent order) in ``harmed_by``.

Fidelity options (SPEC §2; each a constructor argument, all defaults the paper's text): ``rules``
``"paper"`` or ``"authors"`` sets every option below as the paper's text or the authors' public code
plays it; each option given explicitly replaces what ``rules`` sets (its default, ``"rules"``,
takes it from ``rules``):

* ``sideways``: ``"right_harms_left"`` (paper) or ``"left_harms_right"`` (authors: a cat directly
  left of the robot harms it, and the robot harms a cat directly to its right);
* ``same_cell``: ``"came_from_above"`` (paper: compare the cells before the move) or
  ``"robot_unless_down_or_right"`` (authors: the robot is harmed unless its own action was down or
  right; the cat is never harmed on a shared cell);
* ``seam_contact``: ``"wrapped"`` (paper: agents on opposite edges of the torus touch) or
  ``"not_wrapped"`` (authors: positions wrap, the adjacency test does not);
* ``start``: ``"random"`` (paper) or ``"centre_corner"`` (authors: the robot in the centre cell, the
  cat in the corner ``(0, 0)``; further cats on the next free cells, row by row);
* ``observation_encoding``: ``"signed"`` (paper: own cell ``1``, another agent ``-1``) or
  ``"authors"`` (every agent drawn as ``5 / 100``);
* ``harmed_step_reward``: ``"zero"`` (paper: an agent gets ``0`` on the step it is harmed) or
  ``"paid"`` (authors: it still gets that step's ``+1``).

The authors' episodes end after step ``max_cycles + 1`` (``steps > max_steps``) and their learner
treats that end as terminal: set ``max_cycles=501`` for the first, and the learner's setting
``time_limit = "terminal"`` for the second.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar

import numpy as np

from empathy_zoo.actions import NUM_ACTIONS, Action
from empathy_zoo.engine.arguments import check_choice
from empathy_zoo.engine.base import NO_AGENT, GridEngine, StepEvents
from empathy_zoo.engine.placement import distinct_picks
from empathy_zoo.grid import MOVES, displacement_origin, signed_offset, spread_ids

__all__ = [
    "CoexistenceEngine",
    "harm_outcome",
    "OWN_CELL",
    "OTHER_AGENT",
    "AUTHORS_AGENT",
    "FLOOR",
    "AS_RULES",
    "RULE_SETS",
    "FIDELITY_OPTIONS",
]

OWN_CELL = 1.0
OTHER_AGENT = -1.0
AUTHORS_AGENT = np.float32(5 / 100)
"""How the authors' code draws every agent (its own cell and the others): ``5 / 100``."""
FLOOR = 0.0
AS_RULES = "rules"
"""The default of every fidelity option: take its value from ``rules``."""
FIDELITY_OPTIONS: dict[str, tuple[str, ...]] = {
    "sideways": ("right_harms_left", "left_harms_right"),
    "same_cell": ("came_from_above", "robot_unless_down_or_right"),
    "seam_contact": ("wrapped", "not_wrapped"),
    "start": ("random", "centre_corner"),
    "observation_encoding": ("signed", "authors"),
    "harmed_step_reward": ("zero", "paid"),
}
"""Every fidelity option and its values: the paper's first, then the authors' code's."""
RULE_SETS: dict[str, dict[str, str]] = {
    "paper": {name: values[0] for name, values in FIDELITY_OPTIONS.items()},
    "authors": {name: values[1] for name, values in FIDELITY_OPTIONS.items()},
}
"""What ``rules`` sets every fidelity option to."""
ROBOT, CAT = 0, 1
"""The robot's index and the first cat's (cat ``k`` is ``CAT + k``)."""

NO_HARM, ROBOT_HARMS_CAT, CAT_HARMS_ROBOT = 0, 1, 2
"""The outcomes of a step for one (robot, cat) pair, as :func:`harm_outcome` returns them."""

# What each outcome of the one pair does to (robot, cat) when there is one cat, indexed by outcome
# (the general bookkeeping of several pairs gives the same, only slower):
HARMED_BY = np.array([[NO_AGENT, NO_AGENT], [NO_AGENT, ROBOT], [CAT, NO_AGENT]], dtype=np.int64)
"""Who harmed the robot and who harmed the cat."""
HARMS_DONE = np.array([[0, 0], [1, 0], [0, 1]], dtype=np.int64)
"""How many others the robot and the cat harmed."""
CUT_SHORT = np.array([[False, False], [False, False], [False, True]])
"""Whose episode is truncated: the cat's when the robot falls."""


def harm_outcome(
    before: np.ndarray,
    after: np.ndarray,
    size: int,
    robot_action: np.ndarray | int | None = None,
    *,
    sideways: str = "right_harms_left",
    same_cell: str = "came_from_above",
) -> np.ndarray:
    """Who harms whom (SPEC §2) given where the cat stands relative to the robot before and after
    the simultaneous move (``(K, 2)`` displacements on a ``size`` torus); returns ``(K,)`` outcomes.

    Vertically adjacent, the upper one harms the lower; horizontally adjacent, the right one harms
    the left (``sideways="left_harms_right"``: the left one harms the right); on the same cell, the
    one that was above before the move harms, and on equal rows the one that was to the right
    (shortest torus displacement) — or, with ``same_cell="robot_unless_down_or_right"``, the cat
    harms the robot unless the robot's action (``robot_action``) was down or right. Diagonal is
    not contact.
    """
    dr, dc = after[:, 0] % size, after[:, 1] % size
    before = signed_offset(before, size)
    same = (dr == 0) & (dc == 0)
    cat_right, cat_left = (dr == 0) & (dc == 1), (dr == 0) & (dc == size - 1)
    robot_beside = cat_right if sideways == "left_harms_right" else cat_left
    cat_beside = cat_left if sideways == "left_harms_right" else cat_right
    if same_cell == "robot_unless_down_or_right":
        if robot_action is None:
            raise ValueError("the authors' same-cell rule needs the robot's action")
        robot_on_same = np.zeros_like(same)
        cat_on_same = same & ~np.isin(robot_action, (int(Action.DOWN), int(Action.RIGHT)))
    else:
        robot_was_above = before[:, 0] > 0
        cat_was_above = before[:, 0] < 0
        level = before[:, 0] == 0
        robot_on_same = same & (robot_was_above | (level & (before[:, 1] < 0)))
        cat_on_same = same & (cat_was_above | (level & (before[:, 1] > 0)))
    robot_harms = ((dr == 1) & (dc == 0)) | robot_beside | robot_on_same  # (robot directly above the cat)
    cat_harms = ((dr == size - 1) & (dc == 0)) | cat_beside | cat_on_same
    return np.select([robot_harms, cat_harms], [ROBOT_HARMS_CAT, CAT_HARMS_ROBOT], NO_HARM)


class CoexistenceEngine(GridEngine):
    """``robot_0`` and ``cat_0 … cat_{num_cats-1}`` on a torus; contact of the robot and a cat
    means one harms the other."""

    name = "coexistence_v0"
    agents = ("robot_0", "cat_0")
    symbols = ("R", "C")
    colors = ((40, 110, 220), (230, 140, 30))
    min_size: ClassVar[int] = 5
    harm_infos: ClassVar[bool] = True
    obs_low = -1.0
    obs_high = 1.0
    count_argument = "num_cats"
    extra_arguments: ClassVar[Mapping[str, tuple[str, ...]]] = {
        "rules": tuple(RULE_SETS),
        **{name: (AS_RULES, *values) for name, values in FIDELITY_OPTIONS.items()},
    }
    argument_help: ClassVar[Mapping[str, str]] = {
        "rules": "paper (the paper's text) or authors (the authors' code): sets every option below (default: paper)",
        "sideways": "who harms sideways: right_harms_left (paper) or left_harms_right (authors) (default: as rules)",
        "same_cell": "on a shared cell: came_from_above (paper) or robot_unless_down_or_right (authors) (default: as rules)",
        "seam_contact": "contact across the torus edge: wrapped (paper) or not_wrapped (authors) (default: as rules)",
        "start": "start cells: random (paper) or centre_corner (authors) (default: as rules)",
        "observation_encoding": "agents drawn as signed +1/-1 (paper) or authors (5/100) (default: as rules)",
        "harmed_step_reward": "reward on the step an agent is harmed: zero (paper) or paid (authors) (default: as rules)",
        "num_cats": "cats, each walking by its own policy (default: 1)",
    }
    one_pair_tables: bool = True
    """With one cat, look the step's effects up in the one-pair tables (:data:`HARMED_BY`, …)
    rather than through the bookkeeping of several pairs: the same effects, fewer operations."""

    def __init__(
        self,
        num_envs: int = 1,
        size: int = 7,
        view: int = 5,
        max_cycles: int = 500,
        *,
        rules: str = "paper",
        sideways: str = AS_RULES,
        same_cell: str = AS_RULES,
        seam_contact: str = AS_RULES,
        start: str = AS_RULES,
        observation_encoding: str = AS_RULES,
        harmed_step_reward: str = AS_RULES,
        num_cats: int = 1,
    ) -> None:
        self.rules = check_choice("rules", rules, tuple(RULE_SETS))
        given = {
            "sideways": sideways,
            "same_cell": same_cell,
            "seam_contact": seam_contact,
            "start": start,
            "observation_encoding": observation_encoding,
            "harmed_step_reward": harmed_step_reward,
        }
        self.options: dict[str, str] = {
            name: RULE_SETS[rules][name] if check_choice(name, value, self.extra_arguments[name]) == AS_RULES else value
            for name, value in given.items()
        }
        """Every fidelity option as this engine plays it (``rules``' values, replaced by those given)."""
        super().__init__(num_envs, size, view, max_cycles, num_others=num_cats)
        self._wrapped = self.options["seam_contact"] == "wrapped"
        self._paid_when_harmed = self.options["harmed_step_reward"] == "paid"
        self._agent_drawn = AUTHORS_AGENT if self.options["observation_encoding"] == "authors" else None
        if self.options["start"] == "centre_corner":
            centre = (self.size // 2) * self.size + self.size // 2
            self.start_order = np.array([centre, *(cell for cell in range(self.num_cells) if cell != centre)])
        dr, dc = (d.ravel() for d in np.indices((self.size, self.size)))
        contact = np.abs(signed_offset(dr, self.size)) + np.abs(signed_offset(dc, self.size)) <= 1
        self._start_offsets = np.stack([dr[~contact], dc[~contact]], axis=1)
        """Where a cat may start relative to the robot (not in contact), row-major."""
        # The outcome depends on the cat's displacement before the move and the two actions:
        # tabulate harm_outcome over those (one entry per displacement between two cells, see
        # grid.spread_ids, times 5 × 5 actions), so that a step looks it up once.
        origin = displacement_origin(self.size)
        dr, dc = np.divmod(np.arange(2 * origin + 1) - origin + (self.size - 1), 2 * self.size)
        before = np.stack([dr, dc - (self.size - 1)], axis=1)  # every (dr, dc) with |dr|, |dc| < size, and unused ones
        robot_action, cat_action = (a.ravel() for a in np.indices((NUM_ACTIONS, NUM_ACTIONS)))
        self._outcomes = np.stack(
            [
                harm_outcome(
                    before,
                    before + MOVES[c] - MOVES[r],
                    self.size,
                    int(r),
                    sideways=self.options["sideways"],
                    same_cell=self.options["same_cell"],
                ).astype(np.int8)
                for r, c in zip(robot_action, cat_action, strict=True)
            ],
            axis=1,
        ).ravel()
        """``[displacement · 25 + robot action · 5 + cat action]``: the step's outcome."""
        moves = np.arange(self.num_cells * NUM_ACTIONS)
        cell, action = np.divmod(moves, NUM_ACTIONS)
        spread = spread_ids(self.size)[cell]
        self._cat_move = (spread + origin) * NUM_ACTIONS**2 + action
        self._robot_move = spread * NUM_ACTIONS**2 - NUM_ACTIONS * action
        """``[cell · 5 + action]``: the cat's and the robot's parts of the index into :attr:`_outcomes`
        (their difference is ``displacement · 25 + robot action · 5 + cat action``)."""
        self._cat_ids = np.arange(CAT, self.num_agents)
        """The cats' agent indices."""

    def _room_for_others(self) -> tuple[int, str]:
        room = self.size * self.size - 5  # (the robot's cell and its four neighbours are taken)
        return room, f"cats start on distinct cells not in contact with the robot: {room} on a {self.size}x{self.size} grid"

    def _in_contact(self, delta: np.ndarray) -> bool:
        return int(np.abs(signed_offset(delta, self.size)).sum()) <= 1

    def _start_conflict(self, agent: int, cell: np.ndarray, other_agent: int, other: np.ndarray) -> bool:
        return ROBOT in (agent, other_agent) and self._in_contact(other - cell)  # cats may start side by side

    def _random_start(self, env_ids: np.ndarray) -> None:
        robot = np.floor(self.streams.uniform(env_ids) * self.num_cells).astype(np.int64)
        picks = distinct_picks(self.streams, env_ids, len(self._start_offsets), self.num_others)
        cat_rc = (self._cell_rc[robot][:, None, :] + self._start_offsets[picks]) % self.size
        self.cells[env_ids, ROBOT] = robot
        self.cells[env_ids, CAT:] = cat_rc[..., 0] * self.size + cat_rc[..., 1]

    def start_distribution(self) -> np.ndarray:
        """``(cells, cells)``: the probability that an episode starts with the robot on flat cell
        ``i`` and the one cat on flat cell ``j``, by this engine's start rule (a uniform cell for
        the robot and a uniform cell among those not in contact with it, or the fixed cells of
        ``start="centre_corner"``): what :mod:`empathy_zoo.exact_solver` starts from."""
        if self.num_others != 1:
            raise ValueError(f"the start distribution is tabulated for one cat, not {self.num_others}")
        p = np.zeros((self.num_cells, self.num_cells))
        if self.start_order is not None:
            placed = self._start_rules(0).in_order(self.start_order, {}, range(self.num_agents))
            p[self.flat_cell(*placed[ROBOT]), self.flat_cell(*placed[CAT])] = 1.0
            return p
        cat_rc = (self._cell_rc[:, None, :] + self._start_offsets[None, :, :]) % self.size
        cats = cat_rc[..., 0] * self.size + cat_rc[..., 1]
        np.add.at(p, (np.repeat(np.arange(self.num_cells), len(self._start_offsets)), cats.ravel()), 1.0 / cats.size)
        return p

    def _resolve(self, previous: np.ndarray, moves: np.ndarray, events: StepEvents) -> None:
        present = self.present
        # (N, cats): each cat's outcome with the robot, looked up pair by pair
        outcome = self._outcomes.take(self._cat_move.take(moves[:, CAT:]) - self._robot_move.take(moves[:, :CAT]))
        outcome[~(present[:, :CAT] & present[:, CAT:])] = NO_HARM
        if not self._wrapped and np.count_nonzero(outcome):
            outcome[self._across_the_seam()] = NO_HARM
        if np.count_nonzero(outcome):
            if self.num_others == 1 and self.one_pair_tables:
                self._one_pair_effects(outcome[:, 0], events)
            else:
                self._pair_effects(outcome, events)
            self._leave(events.terminated)
        operative = events.present_before if self._paid_when_harmed else self.present & events.present_before
        events.rewards = operative.astype(np.float32)

    def _across_the_seam(self) -> np.ndarray:
        """``(N, cats)``: where a cat and the robot stand on opposite edges of the torus after the
        move (row or column indices ``size − 1`` apart), so that they touch only through the seam."""
        rc = self._cell_rc[self.cells]
        apart = np.abs(rc[:, CAT:, :] - rc[:, :CAT, :])
        return (apart == self.size - 1).any(axis=2)

    def _one_pair_effects(self, outcome: np.ndarray, events: StepEvents) -> None:
        """Fill ``events`` and count the harms from the ``(N,)`` outcomes of the one cat."""
        events.harmed_by = HARMED_BY[outcome]
        events.terminated = events.harmed_by >= 0
        events.truncated = CUT_SHORT[outcome]
        events.episode_over = outcome == CAT_HARMS_ROBOT
        self.episode_harms += HARMS_DONE[outcome]

    def _pair_effects(self, outcome: np.ndarray, events: StepEvents) -> None:
        """Fill ``events`` and count the harms from the ``(N, cats)`` outcomes of every pair."""
        cats_harmed = outcome == ROBOT_HARMS_CAT
        harmers = outcome == CAT_HARMS_ROBOT
        robot_harmed = harmers.any(axis=1)
        harmed_by = events.harmed_by
        harmed_by[:, CAT:][cats_harmed] = ROBOT
        harmed_by[robot_harmed, ROBOT] = CAT + harmers[robot_harmed].argmax(axis=1)  # the first harmer
        events.terminated = harmed_by >= 0
        # the robot fell: every cat still standing is cut short
        events.truncated = robot_harmed[:, None] & self.present & ~events.terminated
        events.episode_over = robot_harmed
        self.episode_harms[:, ROBOT] += cats_harmed.sum(axis=1)
        self.episode_harms[:, CAT:] += harmed_by[:, ROBOT, None] == self._cat_ids

    def _appearance(self, inventory: np.ndarray, viewer: np.ndarray) -> float:
        return OTHER_AGENT if self._agent_drawn is None else float(self._agent_drawn)

    def _self_appearance(self, inventory: np.ndarray, viewer: np.ndarray) -> float:
        return OWN_CELL if self._agent_drawn is None else float(self._agent_drawn)
