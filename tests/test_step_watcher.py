"""``agents.rewards.step_watcher``: the trainer gets what fills a step's batch from the reward
transforms themselves, and refuses what cannot be filled."""

from __future__ import annotations

import ast
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np
import pytest

from agents.rewards import step_watcher
from baselines.inaction_baseline import InactionBaseline
from baselines.reachability import RelativeReachability
from baselines.shaping import HarmPenalty
from empathy_zoo.vector import VectorEnv

ROOT = Path(__file__).resolve().parents[1]


class _Filler:
    def __init__(self, venv: VectorEnv, transforms: object) -> None:
        self.venv = venv

    def fill(self, batch):  # pragma: no cover - never stepped here
        return batch


@dataclass(frozen=True)
class _Watched:
    name: ClassVar[str] = "watched"
    step_watcher: ClassVar = _Filler

    def __call__(self, batch):  # pragma: no cover - never stepped here
        return batch.rewards


@dataclass(frozen=True)
class _BaselineWithoutWatcher:
    name: ClassVar[str] = "no_watcher"
    needs_inaction_baseline: ClassVar[bool] = True

    def __call__(self, batch):  # pragma: no cover - never stepped here
        return batch.rewards

    def state_codes(self, engine):  # pragma: no cover - never asked here
        return np.zeros(engine.num_envs, dtype=np.int64)


def test_no_transform_needs_a_watcher() -> None:
    assert step_watcher(VectorEnv("coexistence_v0", 1), [None, HarmPenalty()]) is None


def test_relative_reachability_gets_the_inaction_baseline() -> None:
    filler = step_watcher(VectorEnv("coexistence_v0", 2), [None, RelativeReachability()])
    assert isinstance(filler, InactionBaseline)


def test_a_plugin_watcher_is_built_once_for_the_ensemble() -> None:
    venv = VectorEnv("coexistence_v0", 1)
    filler = step_watcher(venv, [_Watched(), _Watched(), HarmPenalty()])
    assert isinstance(filler, _Filler) and filler.venv is venv


def test_two_different_watchers_are_refused() -> None:
    with pytest.raises(ValueError, match="different step watchers; train them in separate ensembles"):
        step_watcher(VectorEnv("coexistence_v0", 1), [_Watched(), RelativeReachability()])


def test_a_baseline_without_a_watcher_is_refused() -> None:
    with pytest.raises(ValueError, match="declares needs_inaction_baseline but names no step_watcher"):
        step_watcher(VectorEnv("coexistence_v0", 1), [_BaselineWithoutWatcher()])


def test_the_trainer_names_no_baseline() -> None:
    tree = ast.parse((ROOT / "empathy_zoo" / "training" / "ensemble.py").read_text(encoding="utf-8"))
    modules = {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)}
    assert not any(m is not None and m.startswith("baselines") for m in modules)
