"""Empathic DQN's gradient step as compiled per-run loops (numba), on the learner's own tensors.

What is computed is what :meth:`agents.empathic_dqn.EmpathicDQN.update` computes with PyTorch, in
float32 throughout (weights, activations, gradients, Adam's moments, targets; no float64
accumulation); only the order in which sums are taken differs:

* **the matrix products** of every layer, forward and backward (:func:`gemm`), are one call each
  of the ``sgemm`` of the MKL that torch's CPU library carries (:data:`BLAS`; its own blocking and
  summation order, fixed for given shapes, which are a network's, never an ensemble's); where torch
  exports none, loops summing over the inner index in order from 0 (exact zeros skipped).
* **the forward passes** of ``Q(s')``, ``Q̂(s')`` and ``Q̂(s_emp')`` (:func:`next_values`) and of
  the trained networks on ``s``: each layer's product, then its bias added to the finished sum;
  ReLU on the hidden layers; the output layer's product taken against its weights transposed
  (the form BLAS serves fastest for a handful of outputs).
* **the loss** of each network (row of the stacked parameters): the mean over the batch of
  ``(Q(s, a) − y)²``, summed in batch order; its gradient with respect to ``Q(s, a)`` is
  ``2·(Q(s, a) − y)·(1/B)``; the output layer's gradients (one taken action per row) and every
  bias gradient are sums over the batch in row order ``0 … B−1``.
* **Adam** (:func:`adam_step`): element by element as ``torch._fused_adam_`` computes it on the
  CPU (tested to float32 rounding; bit for bit where torch's build contracts the same operations
  into multiply-adds as the one it was written against): step size and bias correction in float64
  from the float32 step count,
  then cast to float32; the elements of a run's tensor in its vectorised body (all but the last
  ``size % width``, :func:`vector_width`) and those of its scalar tail each with the multiply-adds
  torch's build contracted them into. Step counts, moments and parameters are the learner's
  :class:`agents.stacked_adam.StackedAdam` tensors, written in place, so a checkpoint holds them
  as the PyTorch path keeps them.
* **the loops** are compiled with IEEE division (numba's numpy error model: no zero test in
  each division), so the element-wise ones (Adam, biases, ReLU masks) run in the vector lanes,
  each element by the operations written.
* **the batch** (:func:`draw_indices`, :func:`gather`): the replay indices drawn from each run's
  sampling stream as :meth:`agents.empathic_dqn.EmpathicDQN.sample_indices` draws them (SplitMix64,
  the same integers), and the transitions gathered and decoded from the replay's one-byte codes,
  bit for bit what :meth:`agents.replay.StackedReplay.sample` returns; from a memory that keeps
  costs, each reward charged its cost at its run's price, ``r − price·c`` in float32, as
  :meth:`agents.empathic_dqn.EmpathicDQN.sample_batch` charges it.
* **the targets** (:func:`empathic_targets`): the operations of
  :func:`agents.empathic_dqn.empathic_targets` in its order, in float32: bit for bit for the
  closest other agent and for two to four aggregated (tested); a mean is summed over the others
  in order, which torch does not for five (float32 rounding then).

:meth:`NumbaUpdate.step` is the whole update in one call: indices, gather, and run by run the
next-state values and targets, then the train step; a learner whose :meth:`targets` is overridden
(a plug-in's rule) gets the compiled batch and passes with its own torch targets in between.

Every network is taken in turn (forward, backward and Adam of one row before the next), with
scratch buffers of one network's size, so a run's parameters, gradients and moments stay in the
core's cache; a network's numbers depend on nothing but its own row and its run's batch, so a run
computes bit for bit the same alone or in any ensemble.

The kernels themselves are in :mod:`agents.fused_kernels`; this module drives them. numba is
optional: :func:`numba_available` says whether the kernels import and compile here (it
compiles them once, on tiny inputs, and never raises); the learner falls back to its PyTorch path
when they do not.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from agents.fused_kernels import (
    BLAS,
    IMPORT_ERROR,
    RULES,
    adam_kernel,
    dqn_targets_kernel,
    draw_indices_kernel,
    gather_kernel,
    gemm,
    next_values_kernel,
    targets_kernel,
    train_kernel,
    update_kernel,
    vector_width,
)
from empathy_zoo.observation_codes import DECODE_TABLE

__all__ = [
    "BLAS",
    "NumbaUpdate",
    "gemm",
    "adam_step",
    "draw_indices",
    "dqn_targets",
    "empathic_targets",
    "gather",
    "next_values",
    "numba_available",
    "numba_unavailable_reason",
    "vector_width",
]

_KERNELS: dict[str, Any] | None = None
_FAILURE: str | None = None


def _tiny_inputs() -> tuple[Any, ...]:
    """Arguments of every kernel for a 2-3-3-2 network, one run, two rows (to compile them once)."""
    rng = np.random.default_rng(0)
    sizes = [(2, 3), (1, 3), (3, 3), (1, 3), (3, 2), (1, 2)]
    params = tuple(rng.standard_normal((1, *s)).astype(np.float32) for s in sizes)
    return params, tuple(np.zeros_like(p) for p in params)


def _kernels() -> dict[str, Any]:
    """The compiled kernels (compiled and tried once per process); raises ``RuntimeError`` saying
    why when numba is missing or they do not build here."""
    global _KERNELS, _FAILURE
    if _KERNELS is not None:
        return _KERNELS
    if _FAILURE is not None:
        raise RuntimeError(_FAILURE)
    try:
        if IMPORT_ERROR is not None:
            raise ImportError(IMPORT_ERROR)
        kernels = {
            "next_values": next_values_kernel,
            "dqn_targets": dqn_targets_kernel,
            "adam": adam_kernel,
            "train": train_kernel,
            "draw_indices": draw_indices_kernel,
            "gather": gather_kernel,
            "targets": targets_kernel,
            "update": update_kernel,
        }
        params, zeros = _tiny_inputs()
        update = NumbaUpdate.__new__(NumbaUpdate)
        update._setup(kernels, params, params, zeros, tuple(np.zeros_like(p) for p in params), np.zeros((6, 1), np.float32))
        update._setup_rows(np.zeros(1, dtype=np.int64), 2, 1e-3, (0.9, 0.999), 1e-8)
        obs = np.ones((1, 2, 2), np.float32)
        q_next, target_next, swapped = update._values(obs, obs[:, :, None])
        targets = np.zeros((1, 2), np.float32)
        kernels["dqn_targets"](targets, np.zeros((1, 2), np.bool_), q_next, target_next, np.float32(0.9), targets)
        update._train(obs, np.zeros((1, 2), np.int64), targets)
        replay = _TinyReplay()
        update.setup_step(np.zeros(1, np.uint64), np.zeros(1, np.int64), np.ones(1, np.float32), 0.9, "mean", 1)
        update.sample_batch(replay, torch.zeros((1, 2), dtype=torch.int64), aggregated=True)
        update.step(replay, 0)
        flags = np.zeros((1, 2, 1), np.bool_)
        empathic_targets(
            targets, flags[:, :, 0], q_next, target_next, swapped, flags, 0.9, np.ones(1), "min", flags, flags, kernels=kernels
        )
    except Exception as error:  # (numba missing, or it cannot compile here: the caller falls back)
        _FAILURE = f"{type(error).__name__}: {str(error).splitlines()[0] if str(error) else ''}"
        raise RuntimeError(_FAILURE) from error
    _KERNELS = kernels
    return kernels


class _TinyReplay:
    """A replay memory's arrays for two transitions of the 2-input network (to compile the step)."""

    def __init__(self) -> None:
        self.observations = torch.full((1, 2, 3, 2), 20, dtype=torch.uint8)
        self.flags = torch.full((1, 2, 3), 2, dtype=torch.uint8)
        self.reward = torch.zeros((1, 2))
        self.decode_table = torch.from_numpy(DECODE_TABLE.copy())
        self.size = 2


def numba_available() -> bool:
    """Whether the numba kernels import and compile in this process (tried once; never raises)."""
    try:
        _kernels()
    except RuntimeError:
        return False
    return True


def numba_unavailable_reason() -> str | None:
    """Why :func:`numba_available` is false (``None`` while it is true or not yet asked)."""
    return _FAILURE


def next_values(
    online: tuple[np.ndarray, ...],
    target: tuple[np.ndarray, ...],
    next_obs: np.ndarray,
    swapped: np.ndarray,
    scratch: tuple[np.ndarray, np.ndarray],
    *,
    kernels: dict[str, Any] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Q(s'), Q̂(s'), Q̂(s_emp'))`` of every run: ``(K, B, A)``, ``(K, B, A)``, ``(K, B, O, A)``,
    from ``next_obs (K, B, V)`` and ``swapped (K, B, O, V)`` (``O`` may be 0). ``online`` and
    ``target`` are the six stacked float32 parameter arrays ``W₁, b₁, W₂, b₂, W₃, b₃`` (``Q`` of
    run ``r`` is row ``r`` of ``online``); ``scratch`` two ``(B, hidden)`` float32 buffers;
    ``kernels`` the compiled kernels (default: compiled now, or taken from the cache)."""
    kernels = _kernels() if kernels is None else kernels
    k, b, _ = next_obs.shape
    actions = online[4].shape[2]
    q_next = np.empty((k, b, actions), np.float32)
    target_next = np.empty((k, b, actions), np.float32)
    target_swapped = np.empty((k, b, swapped.shape[2], actions), np.float32)
    kernels["next_values"](online, target, next_obs, swapped, q_next, target_next, target_swapped, *scratch, BLAS)
    return q_next, target_next, target_swapped


def dqn_targets(
    reward: np.ndarray, terminated: np.ndarray, q_next: np.ndarray, target_next: np.ndarray, gamma: float
) -> np.ndarray:
    """``y = r + γ·(1 − done)·Q̂(s', argmax_a Q(s', a))``, ``(K, B)`` float32, as
    :func:`agents.empathic_dqn.double_dqn_target` computes it (the same operations, in float32)."""
    out = np.empty(reward.shape, np.float32)
    _kernels()["dqn_targets"](reward, terminated, q_next, target_next, np.float32(gamma), out)
    return out


def draw_indices(keys: np.ndarray, start: int, size: int, batch_size: int) -> np.ndarray:
    """``(K, B)`` int64 replay indices: row ``r`` is ``counter_integers(keys[r], start + arange(B),
    size)`` (:func:`empathy_zoo.randomness.counter_integers`, the same numbers), ``keys (K,)`` uint64."""
    keys = np.ascontiguousarray(keys, dtype=np.uint64).reshape(-1)
    index = np.empty((keys.shape[0], batch_size), np.int64)
    _kernels()["draw_indices"](keys, int(start), int(size), index)
    return index


def gather(replay: Any, index: torch.Tensor | np.ndarray) -> dict[str, torch.Tensor]:
    """The transitions at ``index (K, B)`` of ``replay`` (an :class:`agents.replay.StackedReplay`
    on the CPU), as :meth:`agents.replay.StackedReplay.sample` returns them, bit for bit: the same
    keys, dtypes, shapes and values, in fresh CPU tensors."""
    return _gather(_kernels(), replay, np.asarray(index, dtype=np.int64))


def _replay_arrays(replay: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """numpy views of a CPU replay memory's codes, flags, rewards and decode table."""
    return (replay.observations.numpy(), replay.flags.numpy(), replay.reward.numpy(), replay.decode_table.numpy())


def _batch_buffers(k: int, b: int, others: int, obs_size: int) -> tuple[np.ndarray, ...]:
    """``(decoded, action, terminated, reward, present, live, unseen)`` for a batch of ``(K, B)``."""
    return (
        np.empty((k, b, 2 + others, obs_size), np.float32),
        np.empty((k, b), np.int64),
        np.empty((k, b), np.bool_),
        np.empty((k, b), np.float32),
        *(np.empty((k, b, others), np.bool_) for _ in range(3)),
    )


def _gather(kernels: dict[str, Any], replay: Any, index: np.ndarray) -> dict[str, torch.Tensor]:
    """:func:`gather` with the given kernels (``cost`` too where the memory keeps costs)."""
    if replay.observations.device.type != "cpu":
        raise ValueError("the compiled gather reads replay memories on the CPU only")
    codes = replay.observations
    k, b = index.shape
    if k != codes.shape[0]:
        raise ValueError(f"expected one row of indices per run, ({codes.shape[0]}, B); got {index.shape}")
    buffers = _batch_buffers(k, b, codes.shape[2] - 2, codes.shape[3])
    kernels["gather"](*_replay_arrays(replay), np.ascontiguousarray(index), *buffers)
    decoded, action, terminated, reward, present, live, unseen = (torch.from_numpy(x) for x in buffers)
    batch = {
        "obs": decoded[:, :, 0],
        "next_obs": decoded[:, :, 1],
        "others_swapped": decoded[:, :, 2:],
        "action": action,
        "terminated": terminated,
        "reward": reward,
        "others_present": present,
        "others_live": live,
        "others_unseen": unseen,
    }
    cost = getattr(replay, "cost", None)
    if cost is not None:  # (a copy of the stored values, at indices the gather found inside the memory)
        batch["cost"] = torch.from_numpy(np.take_along_axis(cost.numpy(), index, axis=1))
    return batch


def empathic_targets(
    reward: np.ndarray,
    terminated: np.ndarray,
    q_next: np.ndarray,
    target_next: np.ndarray,
    target_swapped: np.ndarray,
    present: np.ndarray,
    gamma: float,
    selfishness: np.ndarray,
    others: str = "closest",
    live: np.ndarray | None = None,
    unseen: np.ndarray | None = None,
    *,
    kernels: dict[str, Any] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`agents.empathic_dqn.empathic_targets` compiled: ``(y, y_emp)``, ``(K, B)`` float32
    each, from numpy arrays of the same shapes (``selfishness`` ``(K,)`` or ``(K, 1)``; with
    ``others="closest"``, ``q_swapped`` is ``(K, B, A)`` and ``present``, ``unseen`` ``(K, B)``),
    by the same float32 operations in the same order (sums over several others in their order).
    ``kernels``: the compiled kernels (default: compiled now, or taken from the cache)."""
    kernels = _kernels() if kernels is None else kernels
    if others not in RULES:
        raise ValueError(f"others must be one of {sorted(RULES)}, got {others!r}")
    swapped = np.asarray(target_swapped, np.float32)
    present = np.asarray(present, np.bool_)
    if others == "closest":
        swapped, present = swapped[:, :, None], present[:, :, None]
        unseen = None if unseen is None else np.asarray(unseen)[:, :, None]
        live = np.ones_like(present)
    elif swapped.ndim != 4:
        raise ValueError(f"others={others!r} needs one swapped value per other agent, (K, B, N, A); got {swapped.shape}")
    live = np.ones_like(present) if live is None else np.asarray(live, np.bool_)
    unseen = np.zeros_like(present) if unseen is None else np.asarray(unseen, np.bool_)
    y = np.empty(np.shape(reward), np.float32)
    y_emp = np.empty_like(y)
    kernels["targets"](
        np.asarray(reward, np.float32), np.asarray(terminated, np.bool_), np.asarray(q_next, np.float32),
        np.asarray(target_next, np.float32), swapped, present, live, unseen, np.float32(gamma),
        np.asarray(selfishness, np.float32).reshape(-1), RULES[others], y, y_emp,
    )  # fmt: skip
    return y, y_emp


def adam_step(
    param: np.ndarray,
    grad: np.ndarray,
    exp_avg: np.ndarray,
    exp_avg_sq: np.ndarray,
    step: float,
    lr: float,
    betas: tuple[float, float] = (0.9, 0.999),
    eps: float = 1e-8,
) -> None:
    """One Adam step of one run's tensor, in place (contiguous float32 arrays of one shape), at step
    count ``step`` (already advanced), as ``torch._fused_adam_`` computes it on this CPU."""
    n = param.size
    _kernels()["adam"](
        param.reshape(-1),
        grad.reshape(-1),
        exp_avg.reshape(-1),
        exp_avg_sq.reshape(-1),
        n - n % vector_width(),
        float(step),
        float(lr),
        float(betas[0]),
        float(betas[1]),
        float(eps),
    )


class NumbaUpdate:
    """The compiled update of one learner's stacked networks, working in place on its tensors: the
    online parameters (``R`` rows: every run's ``Q``, then the ``Q_emp`` of the runs that have one),
    the target copies (``K`` rows), and the moments and step counts of its
    :class:`agents.stacked_adam.StackedAdam` (shared memory: CPU tensors only). Raises
    ``RuntimeError`` when numba is not available (:func:`numba_available`)."""

    def __init__(
        self,
        online: list[torch.Tensor],
        target: list[torch.Tensor],
        optimizer: Any,
        run_of_row: np.ndarray,
        batch_size: int,
    ) -> None:
        kernels = _kernels()
        tensors = [*online, *target, *optimizer.exp_avg, *optimizer.exp_avg_sq, optimizer._step_table]
        if len(online) != 6 or any(t.device.type != "cpu" or t.dtype != torch.float32 for t in tensors):
            raise ValueError("the numba update takes three-layer networks of float32 CPU tensors")
        if not all(t.is_contiguous() for t in tensors):
            raise ValueError("the numba update needs contiguous parameter tensors")

        def arrays(ts: list[torch.Tensor]) -> tuple[np.ndarray, ...]:
            return tuple(t.detach().numpy() for t in ts)

        self._setup(
            kernels,
            arrays(online),
            arrays(target),
            arrays(optimizer.exp_avg),
            arrays(optimizer.exp_avg_sq),
            optimizer._step_table.numpy(),
        )
        self._setup_rows(np.asarray(run_of_row, dtype=np.int64), batch_size, optimizer.lr, optimizer.betas, optimizer.eps)

    def _setup(
        self,
        kernels: dict[str, Any],
        online: tuple[np.ndarray, ...],
        target: tuple[np.ndarray, ...],
        exp_avg: tuple[np.ndarray, ...],
        exp_avg_sq: tuple[np.ndarray, ...],
        steps: np.ndarray,
    ) -> None:
        self._k = kernels
        self.online, self.target, self.exp_avg, self.exp_avg_sq, self.steps = online, target, exp_avg, exp_avg_sq, steps
        """numpy views of the learner's tensors (the same memory)."""

    def _setup_rows(self, run_of_row: np.ndarray, batch_size: int, lr: float, betas: tuple[float, float], eps: float) -> None:
        self.run_of_row = run_of_row
        """``(R,)``: the run whose batch each online row trains on."""
        self.lr, self.beta1, self.beta2, self.eps = float(lr), float(betas[0]), float(betas[1]), float(eps)
        b, hidden = batch_size, self.online[0].shape[2]
        obs_size, actions = self.online[0].shape[1], self.online[4].shape[2]
        h1, h2, dz1, dz2 = (np.zeros((b, hidden), np.float32) for _ in range(4))
        out, g = np.zeros((b, actions), np.float32), np.zeros(b, np.float32)
        self._scratch = (h1, h2, out, dz1, dz2, g)
        self._grads = tuple(np.zeros(p.shape[1:], np.float32) for p in self.online)
        """One network's gradients ``(W₁, b₁, …)``, reused network after network."""
        assert self._grads[0].shape == (obs_size, hidden)
        self._width = vector_width()

    def setup_step(
        self, keys: np.ndarray, empathic_row: np.ndarray, selfishness: np.ndarray, gamma: float, others: str, num_others: int
    ) -> None:
        """Prepare :meth:`step`, the whole update in one compiled call: ``keys (K,)`` uint64, each
        run's replay-sampling key (:meth:`agents.empathic_dqn.EmpathicDQN.sample_indices`);
        ``empathic_row (K,)`` the online row of each run's ``Q_emp`` (−1: none); ``selfishness
        (K,)`` β; ``others`` the rule of :func:`agents.empathic_dqn.other_term` over
        ``num_others`` swapped observations per transition (``"closest"``: one). Allocates every
        buffer the step uses, once."""
        if others not in RULES:
            raise ValueError(f"others must be one of {sorted(RULES)}, got {others!r}")
        k, b = self.target[0].shape[0], self._scratch[0].shape[0]
        obs_size, actions = self.online[0].shape[1], self.online[4].shape[2]
        self._keys = np.ascontiguousarray(keys, dtype=np.uint64).reshape(k)
        self._emp_row = np.ascontiguousarray(empathic_row, dtype=np.int64).reshape(k)
        self._beta = np.ascontiguousarray(selfishness, dtype=np.float32).reshape(k)
        self._gamma, self._rule = np.float32(gamma), RULES[others]
        self._index = np.zeros((k, b), np.int64)
        self._batch = _batch_buffers(k, b, num_others, obs_size)
        self._step_values = (
            np.zeros((b, actions), np.float32),
            np.zeros((b, actions), np.float32),
            np.zeros((b, num_others, actions), np.float32),
        )
        self._targets = np.zeros((self.run_of_row.shape[0], b), np.float32)
        self._no_cost, self._no_price = np.zeros((k, 0), np.float32), np.zeros(k, np.float32)
        """What :meth:`step` passes for a memory that keeps no costs."""
        self._replay: tuple[tuple[torch.Tensor, ...], tuple[np.ndarray, ...]] | None = None
        """The replay tensors :meth:`step` last read, and their numpy views."""

    def step(self, replay: Any, start: int, index: np.ndarray | None = None, prices: np.ndarray | None = None) -> float:
        """One whole gradient step of every online row in one compiled call (:func:`update_kernel`):
        the batch at ``index (K, B)``, or where ``None`` at the indices drawn from the keys at
        counter ``start`` (as :meth:`agents.empathic_dqn.EmpathicDQN.sample_indices` draws them),
        gathered from ``replay`` (a CPU :class:`agents.replay.StackedReplay`; one that keeps costs
        has each reward charged its cost at ``prices (K,)`` float32, its runs' prices now), the targets of
        :func:`agents.empathic_dqn.empathic_targets` (of ``Q`` only for a run without ``Q_emp``),
        forward, backward and Adam network after network (:meth:`setup_step` first). Returns the
        summed loss, as :meth:`train`."""
        tensors, cached = (replay.observations, replay.flags, replay.reward, replay.decode_table), self._replay
        if cached is None or any(a is not b for a, b in zip(cached[0], tensors, strict=True)):
            if any(t.device.type != "cpu" for t in tensors):
                raise ValueError("the compiled step reads replay memories on the CPU only")
            cached = self._replay = (tensors, _replay_arrays(replay))
        if index is not None:
            self._index[...] = index
        cost = getattr(replay, "cost", None)
        if cost is not None and prices is None:
            raise ValueError("this replay memory keeps costs: give the runs' prices")
        stored_cost = self._no_cost if cost is None else cost.numpy()
        price = self._no_price if cost is None else np.ascontiguousarray(prices, dtype=np.float32).reshape(-1)
        total = self._k["update"](
            cached[1], self._keys, int(start), int(replay.size), index is None, self._index, self._batch,
            self.online, self.target, self.exp_avg, self.exp_avg_sq, self.steps, self.run_of_row, self._emp_row,
            self._beta, self._gamma, self._rule, self.lr, self.beta1, self.beta2, self.eps, self._width,
            self._scratch, self._step_values, self._targets, self._grads, BLAS, stored_cost, price, cost is not None,
        )  # fmt: skip
        return float(total)

    def sample_batch(self, replay: Any, index: torch.Tensor, aggregated: bool) -> dict[str, torch.Tensor]:
        """The transitions :meth:`agents.empathic_dqn.EmpathicDQN.sample_batch` takes at ``index``,
        by the compiled gather (:func:`gather`; fresh tensors): with ``aggregated`` false, the
        closest other agent's ``other_swapped``, ``other_present`` and ``other_unseen`` in place of
        the ``others_…``; ``cost`` where the memory keeps costs, not yet charged (the learner
        charges it)."""
        batch = _gather(self._k, replay, np.asarray(index.numpy(), dtype=np.int64))
        if not aggregated:
            for name in ("swapped", "present", "unseen"):
                batch[f"other_{name}"] = batch.pop(f"others_{name}")[:, :, 0]
            del batch["others_live"]
        return batch

    def _values(self, next_obs: np.ndarray, swapped: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return next_values(self.online, self.target, next_obs, swapped, (self._scratch[0], self._scratch[1]), kernels=self._k)

    def _train(self, obs: np.ndarray, action: np.ndarray, targets: np.ndarray) -> float:
        total = self._k["train"](
            self.online,
            self.exp_avg,
            self.exp_avg_sq,
            self.steps,
            obs,
            action,
            targets,
            self.run_of_row,
            self.lr,
            self.beta1,
            self.beta2,
            self.eps,
            self._width,
            self._scratch,
            self._grads,
            BLAS,
        )
        return float(total)

    def next_values(
        self, next_obs: torch.Tensor, swapped: torch.Tensor | None
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor | None]:
        """``(Q(s'), Q̂(s'), Q̂(s_emp'))`` of every run as CPU tensors: ``next_obs (K, B, V)``;
        ``swapped`` the closest other's ``(K, B, V)`` (values ``(K, B, A)``), one per other agent
        ``(K, B, O, V)`` (values ``(K, B, O, A)``), or ``None`` (no swapped values)."""
        nxt = _as_float32(next_obs)
        if swapped is None:
            others = np.zeros((nxt.shape[0], nxt.shape[1], 0, nxt.shape[2]), np.float32)
        else:
            others = _as_float32(swapped)
            if swapped.dim() == 3:
                others = others[:, :, None]
        q_next, target_next, target_swapped = self._values(nxt, others)
        values: torch.Tensor | None = None
        if swapped is not None:
            values = torch.from_numpy(target_swapped[:, :, 0] if swapped.dim() == 3 else target_swapped)
        return torch.from_numpy(q_next), torch.from_numpy(target_next), values

    def dqn_targets(
        self,
        reward: torch.Tensor,
        terminated: torch.Tensor,
        q_next: torch.Tensor,
        target_next: torch.Tensor,
        gamma: float,
    ) -> torch.Tensor:
        """:func:`dqn_targets` on tensors (``(K, B)`` float32)."""
        out = np.empty(tuple(reward.shape), np.float32)
        self._k["dqn_targets"](
            _as_float32(reward), terminated.numpy(), q_next.numpy(), target_next.numpy(), np.float32(gamma), out
        )
        return torch.from_numpy(out)

    def train(self, obs: torch.Tensor, action: torch.Tensor, targets: torch.Tensor) -> float:
        """One gradient step of every online row on its run's ``obs (K, B, V)``, taken ``action
        (K, B)`` and its row of ``targets (R, B)`` (float32): forward, loss, backward and Adam,
        network after network, in place. Returns the summed loss (over rows, each the mean over
        the batch), as the PyTorch update's ``loss``."""
        y = np.ascontiguousarray(targets.detach().numpy(), dtype=np.float32)
        return self._train(_as_float32(obs), np.asarray(action.numpy(), dtype=np.int64), y)


def _as_float32(x: torch.Tensor) -> np.ndarray:
    """A float32 numpy view of a CPU tensor (a copy only when it is of another dtype)."""
    array = x.detach().numpy()
    return array if array.dtype == np.float32 else array.astype(np.float32)
