"""The stepwise inaction baseline (Krakovna et al. 2019): the state each environment would have
reached in its last step had the learner taken the no-op, and everything else (the fixed agents'
moves) been the same. One step only: no inaction rollouts (the baseline ``step_noroll`` of their
code; :mod:`baselines.reachability` says why).

A reward transform that declares ``needs_inaction_baseline = True`` and codes states with
``state_codes(engine) -> (N,) int64`` (:class:`agents.rewards.InactionBaselineTransform`) gets,
in every training step, :attr:`StepBatch.state_after` (the code of the state the step ended in)
and :attr:`StepBatch.baseline_after` (the code of the baseline state). The trainer builds an
:class:`InactionBaseline` for its vector env (:meth:`InactionBaseline.for_transforms`), which
watches the vector env's engine steps (:meth:`empathy_zoo.vector.VectorEnv.watch_engine`): just
before each engine step it keeps the engine's state (``state()``); after it, it codes the state
reached (before any autoreset), loads the kept state into a copy of the engine and steps that
copy with the same joint action except the learner's, replaced by the no-op. The outcome of both
steps is the engine's; nothing of the rules is repeated here. The fixed agents act once (in the
real step), so the baseline sees exactly their actions.
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Callable, Sequence
from typing import Any, cast

import numpy as np

from agents.rewards import InactionBaselineTransform, RewardTransform
from agents.step_batch import StepBatch
from empathy_zoo.actions import Action
from empathy_zoo.engine import GridEngine, StepEvents
from empathy_zoo.vector import VectorEnv

__all__ = ["InactionBaseline"]

StateCodes = Callable[[GridEngine], np.ndarray]
"""``(N,)`` int64 codes of the states of an engine's ``N`` environments."""


class InactionBaseline:
    """The stepwise inaction baseline of every environment of ``venv`` (see the module page),
    coded by ``codes``; it watches ``venv``'s engine steps from its construction on
    (:meth:`empathy_zoo.vector.VectorEnv.watch_engine`)."""

    def __init__(self, venv: VectorEnv, codes: StateCodes) -> None:
        codes(venv.engine)  # an environment the coding refuses is refused before any step
        self._codes = codes
        self._learners = list(venv.learner_index)
        self._copy: GridEngine = copy.deepcopy(venv.engine)
        """Where the baseline step runs: loaded with the state the real step started from."""
        self._before: dict[str, Any] | None = None
        """The engine's state just before the step being taken (between the two calls of the watch)."""
        self._last: tuple[np.ndarray, np.ndarray] | None = None
        """Codes of the last step's outcome and baseline, until :meth:`fill` takes them."""
        venv.watch_engine(self)

    @classmethod
    def for_transforms(cls, venv: VectorEnv, transforms: Sequence[RewardTransform | None]) -> InactionBaseline | None:
        """The baseline the reward transforms ``transforms`` need (``None`` when none declares
        ``needs_inaction_baseline``, :class:`agents.rewards.InactionBaselineTransform`); transforms
        of one ensemble that need it must code states alike."""
        needing = [
            cast(InactionBaselineTransform, t)
            for t in transforms
            if t is not None and getattr(t, "needs_inaction_baseline", False)
        ]
        if not needing:
            return None
        codings = {getattr(type(t), "state_codes", None) for t in needing}
        if None in codings:
            raise ValueError(f"reward transform {needing[0].name!r} needs the inaction baseline but has no state_codes(engine)")
        if len(codings) > 1:
            raise ValueError(
                f"reward transforms {sorted({t.name for t in needing})} code states differently; train them in separate ensembles"
            )
        return cls(venv, needing[0].state_codes)

    def before_engine_step(self, engine: GridEngine, actions: np.ndarray) -> None:
        """Keep the state the engine steps from (:class:`empathy_zoo.vector.EngineWatcher`)."""
        self._before = engine.state()

    def after_engine_step(self, engine: GridEngine, actions: np.ndarray, events: StepEvents) -> None:
        """Code the state the step ended in, and the state the copy of the engine ends in from the
        kept one with the learner's action replaced by the no-op."""
        if self._before is None:
            raise RuntimeError("the inaction baseline saw the end of an engine step but not its start")
        after = self._codes(engine)
        inaction = np.array(actions, dtype=np.int64, copy=True)
        inaction[:, self._learners] = int(Action.STAY)
        self._copy.load_state(self._before)
        self._before = None
        self._copy.step(inaction)
        self._last = (after, self._codes(self._copy))

    def fill(self, batch: StepBatch) -> StepBatch:
        """``batch`` (the last step of every environment) with :attr:`StepBatch.state_after` and
        :attr:`StepBatch.baseline_after`."""
        if self._last is None:
            raise RuntimeError("no step of the vector env since the last batch: the inaction baseline has nothing to give")
        after, baseline = self._last
        self._last = None
        shape = batch.actions.shape
        return dataclasses.replace(batch, state_after=after.reshape(shape), baseline_after=baseline.reshape(shape))
