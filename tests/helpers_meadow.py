"""A throwaway third environment, Meadow: ``robot_0`` and ``sheep_0`` walk a torus and each earns
1 for every step it is there; nothing else happens. Its engine, its PettingZoo face and its entry
of the environment table (:data:`MEADOW_ENTRY`), for tests that register it with
:func:`register_meadow` and check that the suite handles an environment it was never told about."""

from __future__ import annotations

import numpy as np
import pytest

from empathy_zoo.engine.base import GridEngine, StepEvents
from empathy_zoo.engine.placement import distinct_picks
from empathy_zoo.environments import ENVIRONMENT_TABLE, Environment
from empathy_zoo.metrics import HELDOUT_MARGINS
from empathy_zoo.parallel import GridParallelEnv, env_constructors, grid_metadata

__all__ = ["MEADOW", "MEADOW_ENTRY", "MeadowEngine", "raw_env", "parallel_env", "env", "register_meadow"]

MEADOW = "meadow_v0"
"""The environment's name."""


class MeadowEngine(GridEngine):
    """``robot_0`` and ``sheep_0`` on a torus, each paid 1 per step."""

    name = MEADOW
    agents = ("robot_0", "sheep_0")
    symbols = ("R", "S")
    colors = ((40, 110, 220), (120, 200, 80))
    obs_low = -1.0
    obs_high = 1.0

    def __init__(self, num_envs: int = 1, size: int = 7, view: int = 5, max_cycles: int = 500) -> None:
        super().__init__(num_envs, size, view, max_cycles)

    def _random_start(self, env_ids: np.ndarray) -> None:
        self.cells[env_ids] = distinct_picks(self.streams, env_ids, self.num_cells, self.num_agents)

    def _start_conflict(self, agent: int, cell: np.ndarray, other_agent: int, other: np.ndarray) -> bool:
        return False

    def _resolve(self, previous: np.ndarray, moves: np.ndarray, events: StepEvents) -> None:
        events.rewards = self.present.astype(np.float32)

    def _appearance(self, inventory: np.ndarray, viewer: np.ndarray) -> float:
        return -1.0

    def _self_appearance(self, inventory: np.ndarray, viewer: np.ndarray) -> float:
        return 1.0


class raw_env(GridParallelEnv):  # PettingZoo naming
    """Meadow as a ``ParallelEnv``."""

    engine_class = MeadowEngine
    metadata = grid_metadata(MEADOW)

    def __init__(self, size: int = 7, view: int = 5, max_cycles: int = 500, render_mode: str | None = None) -> None:
        super().__init__(size, view, max_cycles, render_mode)


parallel_env, env = env_constructors(raw_env)

MEADOW_ENTRY = Environment(
    MeadowEngine,
    "helpers_meadow",
    "empathy_zoo/Meadow-v0",
    {"sheep_0": "random_walk"},
    {"size": 7, "view": 5, "max_cycles": 500},
    task="return",
    task_label="steps in the meadow per episode (task: higher is better)",
    side_effects=("other_return",),
    side_effect_label="the sheep's steps per episode (higher is better)",
    table_metrics=("return", "other_return"),
    compact_metrics=("other_return", "return"),
    heldout_metrics=("return", "other_return"),
    curves=(("return", "Steps per episode (robot)"), ("other_return", "Steps per episode (sheep)")),
    can_harm=False,
    batteries=False,
    negative_rewards=False,
)
"""Its entry of the environment table."""


SHEEP_MARGIN = 10.0
"""The held-out margin of its side effect, the sheep's steps (a metric's own fact, in :mod:`empathy_zoo.metrics`)."""


def register_meadow(monkeypatch: pytest.MonkeyPatch) -> None:
    """Add Meadow to :data:`~empathy_zoo.environments.ENVIRONMENT_TABLE` for one test, and its side
    effect's held-out margin to :data:`~empathy_zoo.metrics.HELDOUT_MARGINS`."""
    monkeypatch.setitem(ENVIRONMENT_TABLE, MEADOW, MEADOW_ENTRY)
    monkeypatch.setitem(HELDOUT_MARGINS, "other_return", SHEEP_MARGIN)
