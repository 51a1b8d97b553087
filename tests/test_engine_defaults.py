"""The vector env, the single-agent adapter and the PettingZoo face build an environment with its
engine's own defaults where ``size``, ``view`` or ``max_cycles`` is not given, so an environment
whose default grid is not 7×7 is built alike on every face."""

from __future__ import annotations

from typing import Any, ClassVar

from empathy_zoo.engine.coexistence import CoexistenceEngine
from empathy_zoo.environments import ENVIRONMENT_TABLE, Environment
from empathy_zoo.gym_adapter import SingleAgentEnv
from empathy_zoo.parallel import GridParallelEnv
from empathy_zoo.vector import VectorEnv


class SmallCoexistence(CoexistenceEngine):
    """Coexistence whose default grid is 5×5, its view 3 and its episodes 40 steps."""

    def __init__(self, num_envs: int = 1, size: int = 5, view: int = 3, max_cycles: int = 40, **options) -> None:
        super().__init__(num_envs, size=size, view=view, max_cycles=max_cycles, **options)


class SmallFace(GridParallelEnv):
    engine_class = SmallCoexistence
    metadata: ClassVar[dict[str, Any]] = {"name": "small_coexistence_v0", "render_modes": ["ansi"], "is_parallel": True}


def test_the_vector_env_and_the_parallel_face_take_the_engines_defaults():
    vector = VectorEnv(SmallCoexistence, 2)
    face = SmallFace()
    for engine in (vector.engine, face.engine):
        assert (engine.size, engine.view, engine.max_cycles) == (5, 3, 40)
    assert VectorEnv(SmallCoexistence, 1, size=7).engine.size == 7


def test_the_single_agent_adapter_takes_the_environments_defaults(monkeypatch):
    import empathy_zoo

    entry = ENVIRONMENT_TABLE["coexistence_v0"]
    monkeypatch.setitem(
        ENVIRONMENT_TABLE,
        "small_coexistence_v0",
        Environment(
            SmallCoexistence,
            __name__,
            "empathy_zoo/SmallCoexistence-v0",
            dict(entry.fixed),
            {**entry.arguments, "size": 5, "view": 3, "max_cycles": 40},
            task=entry.task,
            task_label=entry.task_label,
            table_metrics=entry.table_metrics,
            compact_metrics=entry.compact_metrics,
            heldout_metrics=entry.heldout_metrics,
            curves=entry.curves,
            can_harm=entry.can_harm,
            batteries=entry.batteries,
            negative_rewards=entry.negative_rewards,
        ),
    )
    assert "small_coexistence_v0" in empathy_zoo.ENVIRONMENTS  # (read from the table at each look-up)
    env = SingleAgentEnv("small_coexistence_v0")
    assert env.unwrapped._env.unwrapped.engine.size == 5


parallel_env = SmallFace
"""This module is the face of ``small_coexistence_v0`` in the test above."""
