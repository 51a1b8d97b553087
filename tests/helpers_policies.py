"""Tiny fixed policies that tests load by ``"helpers_policies:ClassName"`` (a user's own module)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from empathy_zoo.grid import Action


class AlwaysLeft:
    """Moves left every step."""

    def reset(self, seed: int | None = None) -> None:
        pass

    def act(self, observation: np.ndarray, info: Mapping[str, Any]) -> int:
        return int(Action.LEFT)


class UpWhenCrowded:
    """Moves up while anything other than floor and itself is in view, otherwise stays (it reads
    its observation, so it exercises the generic per-environment path of the vector env)."""

    def reset(self, seed: int | None = None) -> None:
        pass

    def act(self, observation: np.ndarray, info: Mapping[str, Any]) -> int:
        others = np.delete(observation, len(observation) // 2)
        return int(Action.UP) if np.any(others != 0) else int(Action.STAY)


class NotAPolicy:
    """Has no ``act``: the registry must refuse it."""

    def reset(self, seed: int | None = None) -> None:
        pass


class ReturnsAFloat:
    """Chooses 2.7, which is no action: every path must refuse it (never truncate it to 2)."""

    def reset(self, seed: int | None = None) -> None:
        pass

    def act(self, observation: np.ndarray, info: Mapping[str, Any]) -> float:
        return 2.7
