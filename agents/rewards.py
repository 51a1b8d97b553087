"""Reward transforms: what a run trains on instead of the environment's reward.

A method composes one (:attr:`agents.base.Method.reward`); the trainer gives each run the
rewards of its own method's transform before the learner sees the step (:class:`TrainRewards`),
so a learner knows nothing of it, and the suite's metrics, computed from the environment's
events, never see it. The built-in transforms are in :mod:`baselines.shaping`.

A transform is a frozen dataclass whose fields are its parameters (recorded in each result file
under ``config.reward``; read, set and bounded by :mod:`agents.transform_fields`), with a ``name``,
and either

* **stateless**: ``__call__(batch) -> (K, M) rewards``, a pure function of the step; or
* **stateful**: ``initial_state(num_runs, envs_per_run) -> dict of (K, M) arrays`` (it may also
  take ``seeds``, the runs' seeds in order, to draw each run's own random numbers) and
  ``__call__(batch, state) -> (rewards, new state)``, a pure function of the step and of its
  state (e.g. inequity aversion's smoothed rewards). The trainer keeps the state, one per
  transform and ensemble, and saves it in checkpoints; the transform resets what it must at the
  end of an episode (``batch.terminated | batch.truncated``).

A transform sees only the rows of the runs that use it (:meth:`agents.step_batch.StepBatch.runs`),
and its state holds those runs only.

Optional capability, **the stepwise inaction baseline** (:class:`InactionBaselineTransform`): a
transform that declares ``needs_inaction_baseline = True`` and codes an engine's states with
``state_codes(engine) -> (N,) int64`` (raising ``ValueError`` for an environment it cannot code)
gets, in training, :attr:`StepBatch.state_after` and :attr:`StepBatch.baseline_after`: the code of
the state each step ended in, and of the state it would have ended in had the learner taken the
no-op, the other agents acting as they did (:mod:`baselines.inaction_baseline` computes them with
the engine's ``state()``/``load_state()``, watching the vector env's engine steps; relative
reachability, :mod:`baselines.reachability`, reads them). Without the declaration both fields are
``None``; transforms of one ensemble that declare it must code states alike (one ``state_codes``).

Optional capability, **a step watcher** (:class:`WatchedTransform`): a transform that needs more
of each step than the batch carries names the factory of what fills it, ``step_watcher(venv,
transforms) -> BatchFiller | None`` (a class attribute). The trainer asks it once per ensemble
(:func:`step_watcher`) and passes every training step's batch through the filler's ``fill``
before the transforms see it. A transform declaring ``needs_inaction_baseline`` names
:meth:`baselines.inaction_baseline.InactionBaseline.for_transforms`; the trainer itself names no
baseline.

Optional capability, **costs priced when sampled** (:class:`PricedTransform`): a stateful
transform whose reward charges a cost at a price that moves as the run trains (the Lagrangian
method's ``r − λ·harms``, :mod:`baselines.lagrangian`) declares ``priced_at_sample = True``; its
call returns ``((rewards, costs), state)``, the rewards without the charge and each step's cost,
and ``price(state)`` gives each of its runs' price of one unit of cost now. :class:`TrainRewards`
hands both to the learner (:attr:`StepBatch.costs`, :attr:`StepBatch.prices`), which stores the
cost beside the reward and trains on ``reward − price·cost`` with the price at the time of each
update, not the one at the time the step was stored (the learner must offer ``price_costs``,
:class:`agents.base.Learner`). Its runs' result files record the price after every training
episode (``train.lambda``).
"""

from __future__ import annotations

import dataclasses
import inspect
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, ClassVar, Protocol, TypeGuard, runtime_checkable

import numpy as np

from agents.step_batch import StepBatch
from agents.transform_state import CheckedState, StateBounds, check_like

if TYPE_CHECKING:
    from empathy_zoo.engine import GridEngine
    from empathy_zoo.vector import VectorEnv

__all__ = [
    "BatchFiller",
    "InactionBaselineTransform",
    "PricedTransform",
    "RewardTransform",
    "TrainRewards",
    "is_priced",
    "same_transform",
    "StatefulTransform",
    "transform_config",
    "step_watcher",
    "StepWatcherFactory",
    "WatchedTransform",
]


class RewardTransform(Protocol):
    """Turns the environment's rewards into the rewards a run trains on (see the module page)."""

    name: ClassVar[str]
    """What the result file calls the transform."""

    def __call__(self, batch: StepBatch, *state: Any) -> Any:
        """``(K, M)`` training rewards for every run of ``batch`` (``batch.rewards`` holds the
        environment's); a stateful transform also takes its state and returns ``(rewards, state)``."""


@runtime_checkable
class StatefulTransform(RewardTransform, Protocol):
    """A reward transform that keeps state between steps (inequity aversion's smoothed rewards):
    :class:`TrainRewards` keeps it, checkpoints it and passes it to each call."""

    def initial_state(self, num_runs: int, envs_per_run: int, *args: Any, **kwargs: Any) -> dict[str, np.ndarray]:
        """The state of ``num_runs`` runs of ``envs_per_run`` environments each, as arrays with a
        leading run axis; a transform whose ``initial_state`` also takes ``seeds`` gets the runs'
        seeds (for random numbers of its own)."""
        ...


class InactionBaselineTransform(RewardTransform, Protocol):
    """A reward transform that compares each step with the stepwise inaction baseline (see the
    module page; :class:`baselines.reachability.RelativeReachability` is one)."""

    needs_inaction_baseline: ClassVar[bool]
    """``True``: in training, :attr:`StepBatch.state_after` and :attr:`StepBatch.baseline_after`
    hold the codes of each step's outcome and of its baseline (a transform without this
    declaration, or with ``False``, gets ``None`` in both)."""

    def state_codes(self, engine: GridEngine) -> np.ndarray:
        """``(N,)`` int64 codes of the states of ``engine``'s ``N`` environments (equal states,
        equal codes); ``ValueError`` for an environment it cannot code (asked once before
        training)."""


class BatchFiller(Protocol):
    """Fills in what a training step's batch lacks (the stepwise inaction baseline's codes)."""

    def fill(self, batch: StepBatch) -> StepBatch:
        """``batch`` (the last step of every environment) with the fields this filler owns."""
        ...


StepWatcherFactory = Callable[["VectorEnv", Sequence["RewardTransform | None"]], "BatchFiller | None"]
"""``(venv, transforms) -> filler``: the filler an ensemble's transforms need, or ``None``."""


class WatchedTransform(RewardTransform, Protocol):
    """A reward transform whose training steps pass through a :class:`BatchFiller` it names
    (see the module page)."""

    step_watcher: ClassVar[StepWatcherFactory]
    """Builds the filler for a vector env and the ensemble's distinct transforms; it starts
    watching the vector env when built."""


def step_watcher(venv: VectorEnv, transforms: Sequence[RewardTransform | None]) -> BatchFiller | None:
    """The one filler the transforms ``transforms`` of an ensemble on ``venv`` need: ``None`` when
    none names a :attr:`WatchedTransform.step_watcher`. Transforms that name different factories
    are refused (train them in separate ensembles), and so is a transform that declares
    ``needs_inaction_baseline`` but names no factory."""
    factories: list[StepWatcherFactory] = []
    for transform in transforms:
        if transform is None:
            continue
        factory = getattr(type(transform), "step_watcher", None)
        if factory is None:
            if getattr(transform, "needs_inaction_baseline", False):
                raise ValueError(
                    f"reward transform {transform.name!r} declares needs_inaction_baseline but names no step_watcher "
                    "(set step_watcher = InactionBaseline.for_transforms, from baselines.inaction_baseline)"
                )
            continue
        if not callable(factory):
            raise ValueError(f"reward transform {transform.name!r}: step_watcher is not callable ({factory!r})")
        if factory not in factories:
            factories.append(factory)
    if not factories:
        return None
    if len(factories) > 1:
        names = sorted({t.name for t in transforms if t is not None and getattr(type(t), "step_watcher", None) is not None})
        raise ValueError(f"reward transforms {names} need different step watchers; train them in separate ensembles")
    return factories[0](venv, transforms)


class PricedTransform(StatefulTransform, Protocol):
    """A stateful reward transform whose costs are priced when a step is sampled (see the module
    page; :class:`baselines.lagrangian.Lagrangian` is one)."""

    priced_at_sample: ClassVar[bool]
    """``True``: its call returns ``((rewards, costs), state)``, each ``(K, M)``: the rewards
    without the cost's charge, and the cost of each step, which the learner charges at
    :meth:`price` when it samples the step."""

    def price(self, state: dict[str, np.ndarray]) -> np.ndarray:
        """``(K,)`` each run's price of one unit of cost in ``state`` (finite, at least 0)."""
        ...


def is_priced(transform: RewardTransform | None) -> TypeGuard[PricedTransform]:
    """Whether ``transform`` prices its costs when a step is sampled (:class:`PricedTransform`)."""
    return transform is not None and getattr(transform, "priced_at_sample", False) is True


def transform_config(transform: RewardTransform | None) -> dict[str, Any] | None:
    """What a result file records of a reward transform: ``{"name": ..., **its fields}``."""
    if transform is None:
        return None
    fields: dict[str, Any] = dataclasses.asdict(transform) if dataclasses.is_dataclass(transform) else {}
    return {"name": transform.name, **fields}


def same_transform(a: RewardTransform | None, b: RewardTransform | None) -> bool:
    """``a`` and ``b`` are the same transform: one object, or of one class with equal fields
    (two runs whose transforms are equal share its state and each call, as one object would)."""
    if a is b:
        return True
    if a is None or b is None or type(a) is not type(b) or not dataclasses.is_dataclass(a):
        return False
    return repr(transform_config(a)) == repr(transform_config(b))


class TrainRewards:
    """The rewards each run of an ensemble trains on: run ``k`` gets ``transforms[k]``'s (``None``:
    the environment's), with the state of every stateful transform kept here."""

    def __init__(
        self, transforms: Sequence[RewardTransform | None], envs_per_run: int = 1, seeds: Sequence[int] | None = None
    ) -> None:
        self.transforms = list(transforms)
        self.distinct: list[RewardTransform] = []
        """Each transform once (equal ones count as one: :func:`same_transform`), in the order of its first run."""
        for t in self.transforms:
            if t is not None and not any(same_transform(t, seen) for seen in self.distinct):
                self.distinct.append(t)
        self.rows = [
            np.array([k for k, t in enumerate(self.transforms) if same_transform(t, transform)]) for transform in self.distinct
        ]
        """The runs of each distinct transform: it sees only their rows of a step (``StepBatch`` sliced)."""
        if seeds is not None and len(seeds) != len(self.transforms):
            raise ValueError(f"got {len(seeds)} seeds for {len(self.transforms)} runs")
        self.states: list[dict[str, np.ndarray] | None] = [
            self._initial_state(t, rows, envs_per_run, seeds) if isinstance(t, StatefulTransform) else None
            for t, rows in zip(self.distinct, self.rows, strict=True)
        ]
        for transform, state in zip(self.distinct, self.states, strict=True):
            if is_priced(transform) and (state is None or not callable(getattr(transform, "price", None))):
                raise ValueError(
                    f"reward transform {transform.name!r} prices its costs when sampled: it needs a state "
                    "(initial_state) and price(state)"
                )
        self.priced_runs = np.array([is_priced(t) for t in self.transforms], dtype=bool)
        """``(K,)`` whether each run's transform prices its costs when sampled (:class:`PricedTransform`)."""

    @staticmethod
    def _initial_state(
        transform: StatefulTransform, rows: np.ndarray, envs_per_run: int, seeds: Sequence[int] | None
    ) -> dict[str, np.ndarray]:
        if "seeds" not in inspect.signature(transform.initial_state).parameters:
            return transform.initial_state(len(rows), envs_per_run)
        if seeds is None:
            raise ValueError(
                f"reward transform {transform.name!r} draws random numbers per run: give TrainRewards the runs' seeds"
            )
        return transform.initial_state(len(rows), envs_per_run, seeds=[seeds[k] for k in rows])

    def __call__(self, batch: StepBatch) -> StepBatch:
        """``batch`` with each run's training rewards (the batch itself is not changed)."""
        if not self.distinct:
            return batch
        if len(self.transforms) != batch.rewards.shape[0]:
            raise ValueError(f"got {len(self.transforms)} reward transforms for {batch.rewards.shape[0]} runs")
        rewards = batch.rewards.copy()
        costs = np.zeros(batch.rewards.shape, dtype=np.float32) if self.priced_runs.any() else None
        for i, (transform, rows) in enumerate(zip(self.distinct, self.rows, strict=True)):
            part = batch if len(rows) == len(self.transforms) else batch.runs(rows)
            if self.states[i] is None:
                shaped = transform(part)
            else:
                shaped, self.states[i] = transform(part, self.states[i])
            if costs is not None and is_priced(transform):
                shaped, cost = shaped
                costs[rows] = self._checked(transform, "costs", cost, part.rewards.shape)
            rewards[rows] = self._checked(transform, "rewards", shaped, part.rewards.shape)
        if costs is None:
            return dataclasses.replace(batch, rewards=rewards)
        prices = self.prices()
        assert prices is not None
        return dataclasses.replace(batch, rewards=rewards, costs=costs, prices=prices.astype(np.float32))

    @staticmethod
    def _checked(transform: RewardTransform, what: str, values: Any, shape: tuple[int, ...]) -> np.ndarray:
        """A transform's ``(K, M)`` rewards or costs, or ``ValueError`` naming it."""
        values = np.asarray(values)
        if values.shape != shape:
            raise ValueError(f"reward transform {transform.name!r} returned {what} of shape {values.shape}, expected {shape}")
        return values

    def prices(self) -> np.ndarray | None:
        """``(K,)`` float64: each run's price of one unit of cost now (:meth:`PricedTransform.price`;
        0 for a run whose transform prices none), or ``None`` where no run's transform does."""
        if not self.priced_runs.any():
            return None
        prices = np.zeros(len(self.transforms))
        for transform, rows, state in zip(self.distinct, self.rows, self.states, strict=True):
            if is_priced(transform) and state is not None:
                price = np.asarray(transform.price(state), dtype=np.float64)
                if price.shape != (len(rows),) or not np.isfinite(price).all() or (price < 0).any():
                    raise ValueError(
                        f"reward transform {transform.name!r} priced its costs at {price!r}: expected {len(rows)} "
                        "finite numbers >= 0, one per run"
                    )
                prices[rows] = price
        return prices

    def state(self) -> list[dict[str, np.ndarray] | None]:
        """The stateful transforms' states (for checkpoints)."""
        return [None if state is None else {key: value.copy() for key, value in state.items()} for state in self.states]

    def load_state(self, states: Sequence[Any], bounds: Callable[[int], StateBounds] | None = None) -> None:
        """Continue from :meth:`state`, every saved state checked first (:mod:`agents.transform_state`):
        against the state each transform holds now, and by the transform's own ``check_state``
        given ``bounds(runs)`` (what the checkpoint's runs allow); ``ValueError`` naming the field."""
        if len(states) != len(self.states) or any((a is None) != (b is None) for a, b in zip(states, self.states, strict=True)):
            raise ValueError("this checkpoint holds the state of other reward transforms; move it away to restart")
        loaded: list[dict[str, np.ndarray] | None] = []
        for i, (transform, saved, initial, rows) in enumerate(zip(self.distinct, states, self.states, self.rows, strict=True)):
            if saved is None or initial is None:
                loaded.append(None)
                continue
            try:
                if not isinstance(saved, dict) or not all(isinstance(key, str) for key in saved):
                    raise ValueError("is no table of named arrays")
                saved = {key: np.array(value) for key, value in saved.items()}
                loaded.append(saved)
                if bounds is not None and isinstance(transform, CheckedState):
                    transform.check_state(saved, initial, bounds(len(rows)))
                else:
                    check_like(saved, initial)
            except ValueError as error:
                raise ValueError(f"rewards[{i}] ({transform.name}): {error}") from None
        self.states = loaded
