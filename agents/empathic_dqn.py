"""Empathic DQN (Bussmann et al. 2019, Algorithm 1), K runs at once; DQN is its β = 1 case.

Three networks per run, each an MLP obs → 128 → 128 → 5 with ReLU: ``Q`` (the robot's own
value), its target copy ``Q̂``, and ``Q_emp`` (the empathic value the robot acts on). Per
gradient step, on a batch ``(s, a, r, s', done, s_emp', other_present)``:

    y     = r + γ·(1 − done)·Q̂(s', argmax_a Q(s', a))                      (double DQN)
    y_emp = β·y + (1 − β)·γ·other_present·max_a Q̂(s_emp', a)
    Q     ← Adam step on mean (Q(s, a) − y)²
    Q_emp ← Adam step on mean (Q_emp(s, a) − y_emp)²

A run whose reward transform prices a cost when it is sampled (the Lagrangian method's harms,
:class:`agents.rewards.PricedTransform`) trains on ``r = reward − price·cost`` in these targets:
the replay keeps each transition's cost beside its reward, and the price is the run's at the time
of the update (:meth:`EmpathicDQN.price_costs`), not the one it had when the step was stored.

``s_emp'`` is the robot's swapped observation at t+1 with the closest other agent when the step
began (SPEC §3b); the other-term is 0 when that agent is terminal at t+1. With in-view-only swaps
an other out of view at t+1 is *unseen*, not harmed: it is taken to fare as the robot does, and
the robot's own continuation ``c = y − r`` stands in its place, ``y_emp = β·y + (1 − β)·c =
y − (1 − β)·r`` (SPEC §4). Acting is ε-greedy on ``Q_emp``.

β = 1 is standard DQN (the paper: "1.0 recovers standard DQN"), and it is run as such: one
network ``Q`` (and its target), acting on ``Q``, no ``Q_emp`` (whose target would equal ``y``).
That is what the DQN-type runs (β = 1 and the reward-shaped baselines) train, at a bit more than
half the cost of a run that needs ``Q_emp``. Runs of both kinds share an ensemble: the stacked
parameters hold ``Q`` of every run, then ``Q_emp`` of the runs that have one, so each run computes
exactly what it would alone. A subclass that overrides :meth:`targets` gives every run both
networks. The K runs' networks
are stacked tensors (``agents.stacked_mlp``) so one batched matmul serves every run; runs share
nothing else: each has its own seed, replay memory, ε stream and target copies.
"""

from __future__ import annotations

import importlib
import itertools
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import torch

from agents.base import UPDATE_KERNELS, StepBatch
from agents.replay import StackedReplay, check_keys
from agents.settings import EmpathicDQNSettings
from agents.stacked_adam import StackedAdam
from agents.stacked_mlp import StackedMLP, init_stacked_mlp
from empathy_zoo.limits import check_memory, format_bytes
from empathy_zoo.randomness import STREAMS, counter_integers, counter_uniform, derive_key
from empathy_zoo.schedules import linear_epsilon

__all__ = [
    "EmpathicDQN",
    "MemoryEstimate",
    "double_dqn_target",
    "continuation_value",
    "empathic_targets",
    "other_term",
    "own_continuation_where_unseen",
    "unseen_rows",
    "linear_epsilon",
]

if TYPE_CHECKING:
    from agents.fused_update import NumbaUpdate

STREAM_INIT, STREAM_EXPLORE, STREAM_SAMPLE = STREAMS["network_init"], STREAMS["exploration"], STREAMS["replay_sample"]
LEARNER_STATE_KEYS = frozenset(
    {"online", "target", "optimizer", "replay", "env_steps", "grad_steps", "seeds", "update_kernel", "prices"}
)
"""The keys of :meth:`EmpathicDQN.state_dict` (``prices``: a learner that prices costs only)."""


def double_dqn_target(
    reward: torch.Tensor,
    terminated: torch.Tensor,
    q_next_online: torch.Tensor,
    q_next_target: torch.Tensor,
    gamma: float,
) -> torch.Tensor:
    """``y = r + γ·(1 − done)·Q̂(s', argmax_a Q(s', a))``, ``(K, B)``, from ``(K, B, A)`` values."""
    return reward + continuation_value(terminated, q_next_online, q_next_target, gamma)


def continuation_value(
    terminated: torch.Tensor,
    q_next_online: torch.Tensor,
    q_next_target: torch.Tensor,
    gamma: float,
) -> torch.Tensor:
    """``c = γ·(1 − done)·Q̂(s', argmax_a Q(s', a))``, ``(K, B)``: the robot's target without its
    immediate reward (``y = r + c``)."""
    best = q_next_online.argmax(dim=2, keepdim=True)
    bootstrap = q_next_target.gather(2, best).squeeze(2)
    return gamma * (~terminated).float() * bootstrap


def empathic_targets(
    reward: torch.Tensor,
    terminated: torch.Tensor,
    q_next_online: torch.Tensor,
    q_next_target: torch.Tensor,
    q_swapped_target: torch.Tensor,
    other_present: torch.Tensor,
    gamma: float,
    selfishness: torch.Tensor,
    others: str = "closest",
    live: torch.Tensor | None = None,
    unseen: torch.Tensor | None = None,
) -> tuple[torch.Tensor, torch.Tensor]:
    """The two TD targets ``(y, y_emp)``, each ``(K, B)``; Q-value inputs are ``(K, B, A)``,
    ``selfishness`` is β per run, ``(K, 1)``; with several others aggregated (``others`` "mean" or
    "min"), ``q_swapped_target`` is ``(K, B, N, A)``, ``other_present``, ``live`` and ``unseen``
    ``(K, B, N)`` (see :func:`other_term`). Where the other agent is ``unseen`` (in-view-only
    swaps, out of view; with several others: every one counted is), the robot's continuation
    ``c`` is the other-term, ``y_emp = β·y + (1 − β)·c = y − (1 − β)·r`` (SPEC §4)."""
    continuation = continuation_value(terminated, q_next_online, q_next_target, gamma)
    y = reward + continuation
    term = other_term(q_swapped_target, other_present, gamma, others, live, unseen)
    term = own_continuation_where_unseen(term, continuation, unseen, others, live)
    return y, selfishness * y + (1.0 - selfishness) * term


def unseen_rows(unseen: torch.Tensor | None, others: str = "closest", live: torch.Tensor | None = None) -> torch.Tensor | None:
    """``(K, B)`` bool: the transitions with no other agent seen to care about (SPEC §4): the
    closest other is unseen; with several others aggregated, every other that was live when the
    step began is unseen (and at least one was). ``None`` where ``unseen`` is."""
    if unseen is None or others == "closest":
        return unseen
    live = torch.ones_like(unseen) if live is None else live
    return live.any(dim=2) & ~(live & ~unseen).any(dim=2)


def own_continuation_where_unseen(
    term: torch.Tensor,
    continuation: torch.Tensor,
    unseen: torch.Tensor | None,
    others: str = "closest",
    live: torch.Tensor | None = None,
) -> torch.Tensor:
    """The other-term ``term`` with the robot's own continuation ``c`` (``y = r + c``) in its
    place where no other agent is seen (:func:`unseen_rows`): an unseen other is taken to fare as
    the robot does (SPEC §4)."""
    rows = unseen_rows(unseen, others, live)
    return term if rows is None else torch.where(rows, continuation, term)


def other_term(
    q_swapped_target: torch.Tensor,
    other_present: torch.Tensor,
    gamma: float,
    others: str = "closest",
    live: torch.Tensor | None = None,
    unseen: torch.Tensor | None = None,
) -> torch.Tensor:
    """``γ·other_present·max_a Q̂(s_emp', a)``, ``(K, B)``: the robot's value in the other's place
    at t+1 (0 where that agent is terminal). With ``others`` "mean" or "min", the inputs carry one
    entry per other agent (``(K, B, N, A)``, ``(K, B, N)``) and the terms of the others that were
    ``live`` when the step began (``(K, B, N)``; default all) and are not ``unseen`` (default
    none) are averaged, or the least taken: one harmed in this step counts 0, one that had left
    before, or is out of view, does not count (0 when none counts)."""
    terms = gamma * other_present.float() * q_swapped_target.max(dim=-1).values
    if others == "closest":
        return terms
    if terms.dim() != 3:
        raise ValueError(
            f"others={others!r} needs one swapped value per other agent, (K, B, N, A); got {tuple(q_swapped_target.shape)}"
        )
    live = torch.ones_like(terms, dtype=torch.bool) if live is None else live
    if unseen is not None:
        live = live & ~unseen
    anyone = live.any(dim=2)
    if others == "mean":
        return (terms * live).sum(dim=2) / live.sum(dim=2).clamp(min=1)
    least = torch.where(live, terms, torch.full_like(terms, torch.inf)).min(dim=2).values
    return torch.where(anyone, least, torch.zeros_like(least))


@dataclass(frozen=True)
class MemoryEstimate:
    """The memory an ensemble of Empathic DQN will hold, computed from its settings before anything
    is allocated (:meth:`EmpathicDQN.memory_needed`)."""

    per_run: int
    """Bytes each run holds, as the built learner reports them (:meth:`EmpathicDQN.memory_bytes_per_run`)."""
    replay_per_run: int
    """The part of :attr:`per_run` that is its replay memory (:meth:`EmpathicDQN.replay_bytes_per_run`)."""
    total: int
    """Bytes the whole ensemble needs at its peak: every run's memory, its gradients, and one
    gradient step's batch (decoded observations and activations)."""


class EmpathicDQN:
    """``K`` runs of Empathic DQN in lockstep (the runs may differ in seed and β; each trains on
    ``StepBatch.rewards``, whatever reward transform its method composes)."""

    settings_class = EmpathicDQNSettings

    update_kernel = "auto"
    """How :meth:`update` computes a gradient step unless the constructor is told (one of
    :data:`UPDATE_KERNELS`): ``"numba"`` (compiled per-run loops, :mod:`agents.fused_update`: the
    same algorithm in float32, sums in another order), ``"torch"`` (batched PyTorch operations), or
    ``"auto"``: numba on a CPU device where it compiles, else torch (on a CPU with a warning, since
    the last bits of every run then differ). On an instance: the kernel it uses, ``"torch"`` or
    ``"numba"``, which each result file records (``update_kernel``)."""

    @classmethod
    def resolved_update_kernel(cls, update_kernel: str | None = None, device: str | torch.device = "cpu") -> str:
        """The kernel an instance built with ``update_kernel`` on ``device`` uses (what the
        constructor resolves, without building anything; ``None``: the class's own
        :attr:`update_kernel`): ``"torch"`` or ``"numba"``. ``ValueError`` for an unknown name, and
        for ``"numba"`` on a device that is not a CPU."""
        kernel = cls.update_kernel if update_kernel is None else update_kernel
        if kernel not in UPDATE_KERNELS:
            raise ValueError(f"update_kernel must be one of {', '.join(map(repr, UPDATE_KERNELS))}, got {kernel!r}")
        on_cpu = torch.device(device).type == "cpu"
        if kernel == "numba" and not on_cpu:
            raise ValueError(f"the numba update kernel runs on the CPU only; on {device} use update_kernel='torch' or 'auto'")
        if kernel == "torch" or not on_cpu:
            return "torch"
        return "numba" if importlib.import_module("agents.fused_update").numba_available() else "torch"

    @classmethod
    def memory_needed(
        cls,
        settings: Sequence[EmpathicDQNSettings],
        obs_size: int,
        num_actions: int = 5,
        *,
        num_others: int = 1,
        priced_costs: bool = False,
    ) -> MemoryEstimate:
        """The memory ``K = len(settings)`` runs of this learner will need (see :class:`MemoryEstimate`),
        from the settings alone: the replay memories (one-byte codes, :mod:`agents.replay`; with
        ``priced_costs``, each transition's cost too: :meth:`price_costs`), the networks ``Q``,
        ``Q̂`` and, for the runs that have one, ``Q_emp`` (float32), and Adam's two moments. The
        constructor refuses, before allocating anything, an ensemble that would not fit."""
        config, k = settings[0], len(settings)
        overridden = cls.targets is not EmpathicDQN.targets
        empathic = sum(overridden or s.selfishness < 1.0 for s in settings)
        others = num_others if config.others != "closest" and num_others > 1 else 1
        replay = config.replay_capacity * ((2 + others) * obs_size + (2 + others) + 4 + (4 if priced_costs else 0))
        sizes = [obs_size, config.hidden_size, config.hidden_size, num_actions]
        network = 4 * sum(fan_in * fan_out + fan_out for fan_in, fan_out in itertools.pairwise(sizes))
        per_run = replay + 3 * (network * (2 if empathic else 1) + network)
        online = k + empathic
        batch = online * config.batch_size * 4 * ((3 + others) * obs_size + 4 * config.hidden_size + 2 * num_actions) * 2
        return MemoryEstimate(per_run, replay, k * per_run + 2 * online * network + batch)

    @classmethod
    def check_memory(
        cls, settings: Sequence[EmpathicDQNSettings], obs_size: int, num_actions: int, device: str, *, num_others: int = 1
    ) -> None:
        """Refuse (``ValueError``, with the figures) ``len(settings)`` runs that would need more
        memory than ``device`` has available (:meth:`memory_needed`,
        :func:`empathy_zoo.limits.check_memory`); the constructor asks first, the trainer asks for
        every ensemble of a sweep before the first one trains."""
        needed = cls.memory_needed(settings, obs_size, num_actions, num_others=num_others)
        first = settings[0]
        check_memory(
            needed.total,
            str(torch.device(device)),
            f"{len(settings)} run(s) of {cls.__name__} with replay_capacity={first.replay_capacity:,}, "
            f"hidden_size={first.hidden_size:,} and batch_size={first.batch_size:,} ({format_bytes(needed.per_run)} per run)",
            "lower replay_capacity or hidden_size, or train fewer runs at once (--max-parallel-runs)",
        )

    def __init__(
        self,
        settings: Sequence[EmpathicDQNSettings],
        seeds: Sequence[int],
        obs_size: int,
        num_actions: int = 5,
        device: str = "cpu",
        *,
        num_others: int = 1,
        update_kernel: str | None = None,
    ) -> None:
        requested = type(self).update_kernel if update_kernel is None else update_kernel
        kernel = type(self).resolved_update_kernel(requested, device)  # (checks the name first)
        if len(settings) != len(seeds) or not settings:
            raise ValueError("give one settings object per seed, and at least one run")
        shared = {s.shared() for s in settings}
        if len(shared) != 1:
            raise ValueError("runs of one ensemble may differ only in seed and selfishness")
        type(self).check_memory(settings, obs_size, num_actions, device, num_others=num_others)  # before allocating
        self.settings = list(settings)
        self.config = settings[0]
        self.seeds = [int(s) for s in seeds]
        self.num_runs = k = len(seeds)
        self.num_actions = num_actions
        self.device = torch.device(device)
        generators = [torch.Generator().manual_seed(derive_key(s, STREAM_INIT) >> 1) for s in self.seeds]
        sizes = [obs_size, self.config.hidden_size, self.config.hidden_size, num_actions]
        q = init_stacked_mlp(sizes, generators, self.device)
        overridden = type(self).targets is not EmpathicDQN.targets
        self.empathic_runs = np.array([overridden or s.selfishness < 1.0 for s in settings])
        """Which runs train ``Q_emp`` and act on it (the others are standard DQN: ``Q`` only)."""
        self._emp = np.flatnonzero(self.empathic_runs)
        if self._emp.size:
            q_emp = init_stacked_mlp(sizes, [generators[i] for i in self._emp], self.device)
            q = [torch.cat([a, b]) for a, b in zip(q, q_emp, strict=True)]
        # online parameters: rows 0..K-1 are every run's Q, the rows after them the Q_emp of the
        # runs that have one (in run order): one batched pass serves both
        self.online = [p.requires_grad_() for p in q]
        self._emp_rows = torch.as_tensor(self._emp, device=self.device)
        acting = np.arange(k)
        acting[self._emp] = k + np.arange(self._emp.size)
        self._acting = None if self._emp.size in (0, k) else torch.as_tensor(acting, device=self.device)
        """Row of each run's acting network in :attr:`online` (``None``: a slice will do)."""
        self.target = [p[:k].detach().clone() for p in self.online]
        self.optimizer = StackedAdam(self.online, lr=self.config.learning_rate)
        self.aggregated = self.config.others != "closest" and num_others > 1
        """The other-term aggregates one swapped value per other agent (``num_others`` of them);
        else it is the closest other agent's, the one kept in the replay memory."""
        self.replay = StackedReplay(
            k, self.config.replay_capacity, obs_size, self.device, others=num_others if self.aggregated else 1
        )
        self.selfishness = torch.tensor([[s.selfishness] for s in settings], device=self.device)
        self._explore_keys = np.array([derive_key(s, STREAM_EXPLORE) for s in self.seeds], dtype=np.uint64)[:, None]
        self._sample_keys = np.array([derive_key(s, STREAM_SAMPLE) for s in self.seeds], dtype=np.uint64)[:, None]
        self.prices: torch.Tensor | None = None
        """``(K,)`` float32: each run's price of one unit of a sampled transition's cost, the latest
        step's (``StepBatch.prices``); ``None`` unless the learner prices costs (:meth:`price_costs`)."""
        self._priced_runs = np.zeros(k, dtype=bool)
        self.env_steps = 0  # per run
        self.grad_steps = 0
        self.last_loss = float("nan")
        self._numba: NumbaUpdate | None = None
        if kernel == "numba":
            fused_update = importlib.import_module("agents.fused_update")
            self._numba = fused_update.NumbaUpdate(
                self.online, self.target, self.optimizer, np.concatenate([np.arange(k), self._emp]), self.config.batch_size
            )
            emp_row = np.full(k, -1, dtype=np.int64)
            emp_row[self._emp] = k + np.arange(self._emp.size)
            self._numba.setup_step(
                self._sample_keys[:, 0], emp_row, self.selfishness[:, 0].numpy(), self.config.gamma,
                self._others_rule(), self.replay.others,
            )  # fmt: skip
        elif requested != "torch" and self.device.type == "cpu":  # (asked for numba, or auto, where it cannot build)
            reason = importlib.import_module("agents.fused_update").numba_unavailable_reason()
            warnings.warn(
                f"the numba update kernel is not available ({reason}); using the PyTorch update, whose sums run in "
                "another order: results differ in their last bits from the numba kernel's (install numba to use it)",
                RuntimeWarning,
                stacklevel=2,
            )
        self.update_kernel = "numba" if self._numba is not None else "torch"

    # ------------------------------------------------------------------ acting
    def q_values(self, observations: torch.Tensor, which: str = "emp") -> torch.Tensor:
        """``(K, R, A)`` values of ``Q_emp`` (``which="emp"``), ``Q`` or ``Q̂`` (``"target"``)."""
        k = self.num_runs
        if which == "target":
            params = self.target
        elif which == "emp" and self._acting is not None:
            params = [p.index_select(0, self._acting) for p in self.online]
        else:
            part = slice(k, 2 * k) if which == "emp" and self._emp.size == k else slice(0, k)
            params = [p[part] for p in self.online]
        with torch.no_grad():  # (exact: the same values alone or in any ensemble)
            return StackedMLP.forward_exact(params, observations)

    def epsilon(self) -> float:
        return linear_epsilon(self.config, self.env_steps)

    def act(self, observations: np.ndarray, greedy: bool = False) -> np.ndarray:
        obs = torch.as_tensor(observations, dtype=torch.float32, device=self.device)
        actions = self.q_values(obs).argmax(dim=2).cpu().numpy()
        if greedy:
            return actions
        m = observations.shape[1]
        counter = (self.env_steps * m + np.arange(m))[None, :] * 2
        explore = counter_uniform(self._explore_keys, counter) < self.epsilon()
        if not explore.any():  # (the random actions are drawn from counters of their own: none is needed)
            return actions
        random_actions = counter_integers(self._explore_keys, counter + 1, self.num_actions)
        return np.where(explore, random_actions, actions)

    # ------------------------------------------------------------------ learning
    def price_costs(self, runs: Sequence[bool] | np.ndarray | None = None) -> None:
        """From the first step on, keep each transition's cost (``StepBatch.costs``) beside its
        reward and train on ``reward − price·cost`` with each run's price at the time of the update
        (:attr:`prices`, the latest ``StepBatch.prices``); ``runs`` says which runs' transforms
        price costs (default all; the others store cost 0 at price 0, which changes none of their
        numbers, and their memory is counted without the column). Called before the first step
        (and before a checkpoint is loaded): the replay memory is built again, with the column."""
        if self.replay.size:
            raise ValueError("price_costs() must come before the first transition is stored")
        priced = np.ones(self.num_runs, dtype=bool) if runs is None else np.asarray(runs, dtype=bool).reshape(-1)
        if priced.shape != (self.num_runs,):
            raise ValueError(f"expected one flag per run ({self.num_runs}), got {priced.shape}")
        old = self.replay
        self.replay = StackedReplay(old.num_runs, old.capacity, old.obs_size, self.device, others=old.others, costs=True)
        self.prices = torch.zeros(self.num_runs, dtype=torch.float32, device=self.device)
        self._priced_runs = priced

    def observe(self, batch: StepBatch) -> None:
        swapped, present, live, unseen = (
            x if self.aggregated or x.shape[2] == 1 else batch.of_closest(x)[:, :, None]  # (else the closest one's only)
            for x in (batch.others_swapped, batch.others_present, batch.others_live, batch.others_unseen)
        )
        cost = None
        if self.prices is not None:
            if batch.costs is None or batch.prices is None:
                raise ValueError("this learner prices costs when sampled: each step needs StepBatch.costs and prices")
            cost = batch.costs
            self.prices.copy_(torch.as_tensor(np.asarray(batch.prices, dtype=np.float32), device=self.device))
        elif batch.costs is not None:
            raise ValueError("this step carries costs to price when sampled: call price_costs() before training")
        self.replay.add(
            batch.obs, batch.next_obs, swapped, batch.actions, batch.rewards, self._ends(batch), present, live, unseen, cost
        )
        m = batch.actions.shape[1]
        for _ in range(m):
            self.env_steps += 1
            if self.env_steps >= self.config.learning_starts:
                self.update()

    def _ends(self, batch: StepBatch) -> np.ndarray:
        """``(K, M)`` where each learner's target stops bootstrapping: its episode's end for good,
        and with ``time_limit = "terminal"`` its time-limit truncation too."""
        if self.config.time_limit == "bootstrap":
            return batch.terminated
        if batch.truncated is None:
            raise ValueError('time_limit = "terminal" needs each step\'s truncations (StepBatch.truncated)')
        return batch.terminated | batch.truncated

    def sample_indices(self) -> torch.Tensor:
        """``(K, B)`` replay indices for the next gradient step, from each run's own stream."""
        b = self.config.batch_size
        counter = self.grad_steps * b + np.arange(b)[None, :]
        index = counter_integers(self._sample_keys, counter, self.replay.size)
        return torch.as_tensor(index, device=self.device)

    def sample_batch(self, index: torch.Tensor | None = None) -> dict[str, torch.Tensor]:
        """The transitions at ``index`` ``(K, B)`` of every run's replay memory (default
        :meth:`sample_indices`: the next gradient step's), as :meth:`targets` gets them: ``obs``,
        ``next_obs`` ``(K, B, V)``, ``action``, ``terminated``, ``reward`` ``(K, B)``; aggregating,
        ``others_swapped`` ``(K, B, O, V)``, ``others_present``, ``others_live`` and
        ``others_unseen`` ``(K, B, O)``; else the closest other agent's ``other_swapped``
        ``(K, B, V)``, ``other_present`` and ``other_unseen`` ``(K, B)`` (the names of
        :class:`agents.step_batch.StepBatch`). Where the learner prices costs (:meth:`price_costs`),
        ``reward`` is the stored reward charged its cost at the run's price now."""
        batch = self._charged(self.replay.sample(self.sample_indices() if index is None else index))
        if not self.aggregated:  # (the one other agent kept: the closest)
            for name in ("swapped", "present", "unseen"):
                batch[f"other_{name}"] = batch.pop(f"others_{name}")[:, :, 0]
            del batch["others_live"]
        return batch

    def _charged(self, batch: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        """``batch`` with each sampled reward charged its cost at its run's price now, ``reward −
        price·cost`` in float32 (the product rounded first), where the replay keeps costs."""
        cost = batch.pop("cost", None)
        if cost is not None and self.prices is not None:
            batch["reward"] = batch["reward"] - self.prices[:, None] * cost
        return batch

    def update(self) -> float:
        """One gradient step of every run's ``Q`` (and ``Q_emp``); returns the mean loss."""
        k, cfg, emp = self.num_runs, self.config, self._emp.size
        loss = self._torch_step(self.sample_batch()) if self._numba is None else self._numba_step(self._numba)
        self.grad_steps += 1
        if self.grad_steps % cfg.target_update_interval == 0:
            self.sync_target()
        self.last_loss = loss / (k + emp)
        return self.last_loss

    def _torch_step(self, batch: dict[str, torch.Tensor]) -> float:
        """The gradient step of :meth:`update` in batched PyTorch operations; returns the summed loss."""
        k, cfg, emp = self.num_runs, self.config, self._emp.size
        with torch.no_grad():
            q_next = StackedMLP.forward([p[:k] for p in self.online], batch["next_obs"])
            if emp:
                swapped, b = batch["others_swapped" if self.aggregated else "other_swapped"], cfg.batch_size
                if self.aggregated:  # (K, B, O, V) -> rows other by other, and back to (K, B, O, A)
                    swapped = swapped.transpose(1, 2).reshape(k, -1, swapped.shape[-1])
                target_both = StackedMLP.forward(self.target, torch.cat([batch["next_obs"], swapped], dim=1))
                target_swapped = target_both[:, b:]
                if self.aggregated:
                    target_swapped = target_swapped.reshape(k, self.replay.others, b, -1).transpose(1, 2)
                y, y_emp = self.targets(batch, q_next, target_both[:, :b], target_swapped)
                targets = torch.cat([y, y_emp if emp == k else y_emp.index_select(0, self._emp_rows)])
            else:
                target_next = StackedMLP.forward(self.target, batch["next_obs"])
                targets = double_dqn_target(batch["reward"], batch["terminated"], q_next, target_next, cfg.gamma)
        obs, action = batch["obs"], batch["action"]
        if emp == k:
            obs, action = obs.repeat(2, 1, 1), action.repeat(2, 1)
        elif emp:
            obs = torch.cat([obs, obs.index_select(0, self._emp_rows)])
            action = torch.cat([action, action.index_select(0, self._emp_rows)])
        values = StackedMLP.forward(self.online, obs)
        taken = values.gather(2, action.unsqueeze(2)).squeeze(2)
        loss = ((taken - targets) ** 2).mean(dim=1).sum()
        self.optimizer.zero_grad()
        loss.backward()
        self.optimizer.step()
        return float(loss.detach())

    def _numba_step(self, fused: NumbaUpdate) -> float:
        """The gradient step of :meth:`update` in compiled per-run loops (:mod:`agents.fused_update`):
        one call from the batch's indices to Adam, or, where :meth:`targets` (or the batch) is
        overridden, the compiled gather and forward passes, :meth:`targets` in torch, then the
        compiled train step; returns the summed loss."""
        k, emp = self.num_runs, self._emp.size
        if not any(map(self._overridden, ("targets", "other_inputs", "sample_batch"))):  # (the default targets and batch)
            index = self.sample_indices().numpy() if self._overridden("sample_indices") else None  # (None: drawn there)
            prices = None if self.prices is None else self.prices.numpy()
            return fused.step(self.replay, self.grad_steps * self.config.batch_size, index, prices)
        if not self._overridden("sample_batch"):
            batch = self._charged(fused.sample_batch(self.replay, self.sample_indices(), self.aggregated))
        else:
            batch = self.sample_batch()
        if emp:
            swapped = batch["others_swapped" if self.aggregated else "other_swapped"]
            q_next, target_next, target_swapped = fused.next_values(batch["next_obs"], swapped)
            assert target_swapped is not None
            with torch.no_grad():
                y, y_emp = self.targets(batch, q_next, target_next, target_swapped)
                targets = torch.cat([y, y_emp if emp == k else y_emp.index_select(0, self._emp_rows)])
        else:
            q_next, target_next, _ = fused.next_values(batch["next_obs"], None)
            targets = fused.dqn_targets(batch["reward"], batch["terminated"], q_next, target_next, self.config.gamma)
        return fused.train(batch["obs"], batch["action"], targets)

    def _overridden(self, name: str) -> bool:
        """Whether method ``name`` is not :class:`EmpathicDQN`'s own here (a subclass's, or one set
        on the instance): the compiled update then calls it instead of its compiled twin."""
        return name in vars(self) or getattr(type(self), name) is not getattr(EmpathicDQN, name)

    def targets(
        self, batch: dict[str, torch.Tensor], q_next: torch.Tensor, target_next: torch.Tensor, target_swapped: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """The TD targets ``(y, y_emp)`` of ``Q`` and ``Q_emp`` for a sampled batch, ``(K, B)`` each.

        ``q_next = Q(s')``, ``target_next = Q̂(s')``, ``target_swapped = Q̂(s_emp')``, all
        ``(K, B, actions)``; ``batch`` holds the closest other agent's ``other_present`` and
        ``other_unseen``, ``(K, B)``. Aggregating several others, ``target_swapped`` is
        ``(K, B, others, actions)`` and ``batch`` holds ``others_present``, ``others_live`` and
        ``others_unseen``, ``(K, B, others)`` (:meth:`other_inputs` gives either; see
        :func:`other_term`). Override this to try another way of caring about the other agent.
        """
        present, live, unseen = self.other_inputs(batch)
        return empathic_targets(
            batch["reward"],
            batch["terminated"],
            q_next,
            target_next,
            target_swapped,
            present,
            self.config.gamma,
            self.selfishness,
            self._others_rule(),
            live,
            unseen,
        )

    def other_inputs(self, batch: dict[str, torch.Tensor]) -> tuple[torch.Tensor, torch.Tensor | None, torch.Tensor | None]:
        """``(present, live, unseen)`` of a sampled batch as :func:`other_term` takes them: each
        other agent's ``(K, B, O)`` when aggregating, else the closest one's ``(K, B)`` (``live``
        ``None``); ``unseen`` is ``None`` where the batch holds none (a hand-made one)."""
        if self.aggregated:
            return batch["others_present"], batch.get("others_live"), batch.get("others_unseen")
        return batch["other_present"], None, batch.get("other_unseen")

    def _others_rule(self) -> str:
        """How :func:`other_term` treats the other agents (``closest`` unless aggregating)."""
        return self.config.others if self.aggregated else "closest"

    def sync_target(self) -> None:
        """Copy every run's ``Q`` into its ``Q̂``."""
        with torch.no_grad():
            for target, online in zip(self.target, self.online, strict=True):
                target.copy_(online[: self.num_runs])

    # ------------------------------------------------------------------ bookkeeping
    def live_stats(self) -> dict[str, float]:
        return {"eps": self.epsilon(), "loss": self.last_loss}

    def tracked_scalars(self) -> list[dict[str, float]]:
        """Per run, the mean squared TD error and mean ``Q(s, a)`` of each head on the batch of the
        last gradient step (``losses/td_loss``, ``losses/q_values``; ``Q_emp``'s as ``…_emp``),
        recomputed now with the current networks, without gradients (empty before the first step).
        Computed only when asked (:meth:`agents.base.Learner.tracked_scalars`: a logged run, every
        few hundred steps); it draws nothing and changes nothing."""
        k, b = self.num_runs, self.config.batch_size
        if self.grad_steps == 0:
            return [{} for _ in range(k)]
        index = counter_integers(self._sample_keys, (self.grad_steps - 1) * b + np.arange(b)[None, :], self.replay.size)
        batch = self.sample_batch(torch.as_tensor(index, device=self.device))
        obs, action, emp = batch["obs"], batch["action"].unsqueeze(2), self._emp_rows
        with torch.no_grad():
            q_next = StackedMLP.forward([p[:k] for p in self.online], batch["next_obs"])
            target_next = StackedMLP.forward(self.target, batch["next_obs"])
            y = double_dqn_target(batch["reward"], batch["terminated"], q_next, target_next, self.config.gamma)
            heads = {"": (StackedMLP.forward([p[:k] for p in self.online], obs).gather(2, action).squeeze(2), y)}
            if emp.numel():
                swapped = batch["others_swapped" if self.aggregated else "other_swapped"]
                target_swapped = StackedMLP.forward(self.target, swapped.reshape(k, -1, swapped.shape[-1]))
                y, y_emp = self.targets(batch, q_next, target_next, target_swapped.reshape(*swapped.shape[:-1], -1))
                taken = StackedMLP.forward([p[k:] for p in self.online], obs.index_select(0, emp))
                heads = {"": (heads[""][0], y), "_emp": (taken.gather(2, action.index_select(0, emp)).squeeze(2), y_emp[emp])}
        scalars: list[dict[str, float]] = [{} for _ in range(k)]
        for suffix, (values, targets) in heads.items():
            runs = range(k) if suffix == "" else self._emp.tolist()
            loss, mean = ((values - targets) ** 2).mean(dim=1).tolist(), values.mean(dim=1).tolist()
            for row, run in enumerate(runs):
                scalars[run] |= {f"losses/td_loss{suffix}": loss[row], f"losses/q_values{suffix}": mean[row]}
        return scalars

    def memory_bytes_per_run(self) -> int:
        """The largest run's bytes (a run with ``Q_emp`` when the ensemble has one)."""
        return max(self.memory_bytes_of(run) for run in range(self.num_runs))

    def memory_bytes_of(self, run: int) -> int:
        """Run ``run``'s own bytes: its replay memory, ``Q`` (and ``Q_emp`` if it has one), ``Q̂``
        and Adam's two moments of what it trains; the same in any ensemble (what its result file
        records)."""
        heads = 2 if self.empathic_runs[run] else 1
        params = sum(p[0].numel() * p.element_size() for p in self.online) * heads
        params += sum(p[0].numel() * p.element_size() for p in self.target)
        return self.replay_bytes_of(run) + 3 * params  # parameters + two Adam moments

    def replay_bytes_per_run(self) -> int:
        """Bytes of each run's replay memory (part of :meth:`memory_bytes_per_run`); where runs
        differ, the largest run's."""
        return max(self.replay_bytes_of(run) for run in range(self.num_runs))

    def replay_bytes_of(self, run: int) -> int:
        """Run ``run``'s replay memory's bytes, the cost column counted for a run that prices costs
        only (:meth:`price_costs`): the same in any ensemble."""
        column = 0 if self.replay.cost is None or self._priced_runs[run] else self.replay.cost[0].numel() * 4
        return self.replay.nbytes_per_run() - column

    def check_observation_range(self, low: float, high: float) -> None:
        """Refuse, before any training, observations in ``[low, high]`` that the replay memory's
        one-byte codes cannot hold (``ValueError``)."""
        self.replay.check_range(low, high)

    def state_dict(self) -> dict[str, Any]:
        return {
            "online": [p.detach().clone() for p in self.online],
            "target": [p.clone() for p in self.target],
            "optimizer": self.optimizer.state_dict(),
            "replay": self.replay.state_dict(),
            "env_steps": self.env_steps,
            "grad_steps": self.grad_steps,
            "seeds": list(self.seeds),
            "update_kernel": self.update_kernel,
            **({} if self.prices is None else {"prices": self.prices.clone()}),
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        check_keys(state, LEARNER_STATE_KEYS, "learner checkpoint", "Empathic DQN")
        if list(state["seeds"]) != self.seeds:
            raise ValueError(f"checkpoint is for seeds {state['seeds']}, not {self.seeds}")
        shapes = [tuple(p.shape) for p in state["online"]]
        if shapes != [tuple(p.shape) for p in self.online]:
            raise ValueError(
                f"checkpoint holds networks of shapes {shapes}, not {[tuple(p.shape) for p in self.online]}: it was "
                "made by another version or other settings (β = 1 runs train one network since 0.2); move it away to restart"
            )
        with torch.no_grad():
            for p, saved in zip(self.online, state["online"], strict=True):
                p.copy_(saved)
            for p, saved in zip(self.target, state["target"], strict=True):
                p.copy_(saved)
        self.optimizer.load_state_dict(state["optimizer"])
        self.replay.load_state_dict(state["replay"])
        if self.prices is not None:
            prices = torch.as_tensor(state["prices"], dtype=torch.float32)
            if tuple(prices.shape) != (self.num_runs,):
                raise ValueError(f"checkpoint holds {tuple(prices.shape)} prices, not one per run ({self.num_runs})")
            self.prices.copy_(prices)
        self.env_steps, self.grad_steps = int(state["env_steps"]), int(state["grad_steps"])

    # ------------------------------------------------------------------ keeping a trained agent
    def agent_state(self, run: int) -> dict[str, Any]:
        """Run ``run``'s acting networks for its agent file (:meth:`agents.base.Learner.agent_state`):
        ``{"heads": {"q": Q, "q_emp": Q_emp}, "acting": "q_emp"}``, each head the list
        ``[W₁, b₁, W₂, b₂, W₃, b₃]`` of its rows of :attr:`online` (``W: (in, out)``, ``b: (1, out)``;
        live views, which the writer copies). ``Q`` of run ``r`` is row ``r``, its ``Q_emp`` the row after
        the ``K`` rows of ``Q`` at its place among the runs that have one; a run without ``Q_emp``
        (β = 1, DQN) has the head ``q`` alone and acts on it, as :meth:`act` does."""
        if not 0 <= run < self.num_runs:
            raise ValueError(f"run must be in [0, {self.num_runs}), got {run!r}")
        heads = {"q": [p[run].detach() for p in self.online]}
        if self.empathic_runs[run]:
            row = self.num_runs + int(np.flatnonzero(self._emp == run)[0])
            heads["q_emp"] = [p[row].detach() for p in self.online]
        return {"heads": heads, "acting": "q_emp" if self.empathic_runs[run] else "q"}
