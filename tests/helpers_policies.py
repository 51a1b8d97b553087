"""Tiny fixed policies that tests load by ``"helpers_policies:ClassName"`` (a user's own module)."""

from __future__ import annotations

import copy
from collections.abc import Mapping
from typing import Any

import numpy as np

from empathy_zoo.actions import Action


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


class _Wandering:
    """A cat with a memory: it repeats its last move with probability ``repeat``, else moves at
    random, drawing from its own ``np.random.Generator`` (seeded in ``reset``)."""

    def __init__(self, repeat: float = 0.5) -> None:
        self.repeat = float(repeat)
        self.rng = np.random.default_rng()
        self.memory: list[int] = []

    def reset(self, seed: int | None = None) -> None:
        if seed is not None:
            self.rng = np.random.default_rng(seed)
        self.memory = []

    def act(self, observation: np.ndarray, info: Mapping[str, Any]) -> int:
        action = self.memory[-1] if self.memory and self.rng.random() < self.repeat else int(self.rng.integers(len(Action)))
        self.memory.append(action)
        return action


class Wanderer(_Wandering):
    """:class:`_Wandering` that saves its generator and memory in checkpoints."""

    def state(self) -> dict[str, Any]:
        return {"rng": self.rng.bit_generator.state, "memory": list(self.memory)}

    def load_state(self, state: Mapping[str, Any]) -> None:
        self.rng = np.random.default_rng()
        self.rng.bit_generator.state = state["rng"]
        self.memory = [int(action) for action in state["memory"]]


class WandererWithoutState(_Wandering):
    """:class:`_Wandering` without ``state``/``load_state``: a checkpoint would lose its generator."""


class Recorder(Wanderer):
    """Wanders, and keeps a copy of every context it is given in :attr:`seen`."""

    def __init__(self, repeat: float = 0.5) -> None:
        super().__init__(repeat)
        self.seen: list[dict[str, Any]] = []

    def act(self, observation: np.ndarray, info: Mapping[str, Any]) -> int:
        self.seen.append(copy.deepcopy(dict(info)))
        return super().act(observation, info)


class RecorderWithState(Recorder):
    """:class:`Recorder` that also asks for the true state (``positions``)."""

    needs_state = True


class Chaser:
    """Steps towards the robot along the shorter way round the torus (rows first) on every
    ``every``-th step of the episode (stays otherwise, or when the robot is gone), from the true
    positions it asks for."""

    needs_state = True
    stateless = True

    def __init__(self, target: str = "robot_0", every: int = 1) -> None:
        if every < 1:
            raise ValueError(f"every must be positive, got {every}")
        self.target, self.every = target, int(every)

    def reset(self, seed: int | None = None) -> None:
        pass

    def act(self, observation: np.ndarray, info: Mapping[str, Any]) -> int:
        positions, size = info["positions"], info["size"]
        if info["step"] % self.every or self.target not in positions:
            return int(Action.STAY)
        (row, col), (to_row, to_col) = positions[info["agent"]], positions[self.target]
        down, right = (to_row - row) % size, (to_col - col) % size
        if down:
            return int(Action.DOWN) if down <= size - down else int(Action.UP)
        if right:
            return int(Action.RIGHT) if right <= size - right else int(Action.LEFT)
        return int(Action.STAY)


class SavesItsGenerator(_Wandering):
    """Its ``state()`` holds the generator object itself, which is not plain data."""

    def state(self) -> dict[str, Any]:
        return {"rng": self.rng}

    def load_state(self, state: Mapping[str, Any]) -> None:
        self.rng = state["rng"]
