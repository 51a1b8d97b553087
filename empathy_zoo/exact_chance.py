"""The chance of a step in the exact model (:mod:`empathy_zoo.exact_solver`), drawn every way.

An engine whose step draws from its random streams (Sharing: a battery the robot and the human
reach in one step goes to either, by the env's generator) names how many equally likely outcomes
that draw has: ``tabular_draws`` (``D``, default 1: the step draws nothing). The tabulation then
steps every joint state and joint action once per draw ``d``, with the engine's streams replaced by
:class:`FixedDraws`, whose every number is ``(d + ½)/D``: an engine that picks one of ``k ≤ D``
contenders as ``contenders[int(u·k)]`` meets each of them in ``D/k`` of the draws (with ``D = 2``
and two contenders, one each). Each draw is one of the model's equally likely *other moves*.

:func:`check_draws` holds the engine to what it declares: an engine of one draw may draw nothing,
no environment may draw more than once in a step, every draw of the tabulation draws in the same
environments, and an environment that draws nothing steps the same way in every draw.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from empathy_zoo.randomness import EnvStreams

__all__ = ["FixedDraws", "check_draws"]


class FixedDraws(EnvStreams):
    """A stand-in for an engine's streams inside the tabulation: every number drawn is
    ``(draw + ½)/draws``, and :attr:`drawn` counts the numbers each environment drew since
    :meth:`forget`. Seeding is a no-op: it holds no generator."""

    def __init__(self, num_envs: int, draw: int = 0, draws: int = 1) -> None:
        super().__init__(0)
        if not 0 <= draw < draws:
            raise ValueError(f"draw must lie in [0, {draws}), got {draw}")
        self.value = (draw + 0.5) / draws
        """The number every draw returns."""
        self.drawn = np.zeros(num_envs, dtype=np.int64)
        """``(N,)``: numbers each environment drew since :meth:`forget`."""

    def seed(self, env_id: int, seed: int | None) -> None:
        """Nothing: the stand-in draws no number from a generator."""

    def ensure_seeded(self, env_ids: Sequence[int] | np.ndarray) -> None:
        """Nothing: the stand-in draws no number from a generator."""

    def uniform(self, env_ids: np.ndarray) -> np.ndarray:
        env_ids = np.asarray(env_ids, dtype=np.int64)
        np.add.at(self.drawn, env_ids, 1)
        return np.full(env_ids.shape, self.value)

    def forget(self) -> None:
        """Count from 0 again (after a reset, whose draws are no part of a step)."""
        self.drawn[:] = 0


def check_draws(env: str, draws: int, drawn: Sequence[np.ndarray], steps: Sequence[Mapping[str, np.ndarray]]) -> None:
    """Raise where the tabulation of ``env`` did not enumerate its step's chance exactly: ``drawn``
    (per draw, the numbers each environment drew in the step) and ``steps`` (per draw, the arrays
    read off the engine, one entry per environment) of the ``draws`` draws (see the module page)."""
    counts = drawn[0]
    if draws == 1 and counts.any():
        raise ValueError(
            f"{env}'s engine drew a random number in a step, and declares no chance (tabular_draws = 1): "
            "the exact model would take one draw for its step's every outcome"
        )
    if (counts > 1).any():
        raise ValueError(
            f"{env}'s engine drew {int(counts.max())} numbers in one step of one environment: "
            f"its {draws} draws enumerate one chance per step"
        )
    for d in range(1, draws):
        if not np.array_equal(drawn[d], counts):
            raise RuntimeError(f"{env}'s engine drew in other environments in draw {d} than in draw 0")
        calm = counts == 0
        for key, first in steps[0].items():
            if not np.array_equal(steps[d][key][calm], first[calm]):
                raise RuntimeError(f"{env}'s engine stepped an environment that drew nothing otherwise in draw {d} ({key})")
