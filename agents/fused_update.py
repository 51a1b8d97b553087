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
  ReLU on the hidden layers.
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

Every network is taken in turn (forward, backward and Adam of one row before the next), with
scratch buffers of one network's size, so a run's parameters, gradients and moments stay in the
core's cache; a network's numbers depend on nothing but its own row and its run's batch, so a run
computes bit for bit the same alone or in any ensemble.

numba is optional: :func:`numba_available` says whether the kernels import and compile here (it
compiles them once, on tiny inputs, and never raises); the learner falls back to its PyTorch path
when they do not.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import torch

__all__ = [
    "BLAS",
    "NumbaUpdate",
    "gemm",
    "adam_step",
    "dqn_targets",
    "next_values",
    "numba_available",
    "numba_unavailable_reason",
    "vector_width",
]

_KERNELS: dict[str, Any] | None = None
_FAILURE: str | None = None


def vector_width() -> int:
    """Float32 lanes of torch's vectorised CPU kernels on this machine (16 with AVX-512, 8 with
    AVX2, else 8, ATen's 256-bit default): where the fused Adam kernel's scalar tail begins."""
    capability = torch.backends.cpu.get_cpu_capability()
    return 16 if capability.startswith("AVX512") else 8


try:  # (optional: without numba the learner keeps its PyTorch update)
    import numba
    from numba import types
    from numba.extending import intrinsic
except ImportError as error:  # pragma: no cover - exercised where numba is absent
    numba = None  # type: ignore[assignment]
    _IMPORT_ERROR: str | None = f"numba is not installed ({error})"
else:
    _IMPORT_ERROR = None


def _jit() -> Any:
    """``numba.njit`` with an on-disk cache where numba finds a writable place for it (else the
    kernels compile in every process), or a stand-in that leaves the functions uncompiled (without
    numba: they are then never called)."""
    if numba is None:
        return lambda function: function
    try:
        numba.njit(cache=True)(lambda: 0)
    except Exception:  # (no cache directory numba can write)
        return numba.njit(nogil=True)
    return numba.njit(cache=True, nogil=True)


jit = _jit()


def _intrinsic(function: Any) -> Any:
    return intrinsic(function) if numba is not None else function


@_intrinsic
def fma32(typingctx: Any, a: Any, b: Any, c: Any) -> Any:
    """``a·b + c`` with one rounding (float32), as ATen's vectorised ``fmadd``."""
    sig = types.float32(types.float32, types.float32, types.float32)

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        return builder.fma(*args)

    return sig, codegen


_SGEMM_SYMBOL = "empathy_zoo_fused_update_sgemm"
"""The name the kernels call BLAS's ``sgemm`` by (bound below to MKL's, when torch exports it)."""


def _bind_sgemm() -> bool:
    """Bind :data:`_SGEMM_SYMBOL` to the ``sgemm_`` (Fortran interface, 32-bit integers) of the
    MKL that torch's CPU library carries, if it exports one; else to a stand-in the kernels never
    call (they then multiply in their own loops). Returns whether BLAS is bound."""
    import ctypes
    import os

    import llvmlite.binding

    library = os.path.join(os.path.dirname(torch.__file__), "lib", "libtorch_cpu.so")
    try:
        address = ctypes.cast(ctypes.CDLL(library).sgemm_, ctypes.c_void_p).value
    except (OSError, AttributeError):
        address = None
    found = address is not None and "mkl" in (torch.__config__.show().lower())
    if not found:
        stand_in = ctypes.CFUNCTYPE(None)(lambda: None)
        _KEEP_ALIVE.append(stand_in)
        address = ctypes.cast(stand_in, ctypes.c_void_p).value
    llvmlite.binding.add_symbol(_SGEMM_SYMBOL, address)
    return found


_KEEP_ALIVE: list[Any] = []
BLAS = _bind_sgemm() if numba is not None else False
"""Whether the kernels' matrix products are MKL's ``sgemm`` (else loops, in index order)."""


@_intrinsic
def _sgemm(typingctx: Any, ta: Any, tb: Any, m: Any, n: Any, k: Any, a: Any, lda: Any, b: Any, ldb: Any, c: Any, ldc: Any) -> Any:
    """Column-major ``C (m, n) = op(A) @ op(B)`` by BLAS (``alpha`` 1, ``beta`` 0); ``ta``/``tb``
    are the characters ``N``/``T`` as integers, ``a``, ``b``, ``c`` data addresses."""
    from llvmlite import ir
    from numba.core import cgutils

    sig = types.void(*([types.int64] * 11))

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        i8, i32 = ir.IntType(8), ir.IntType(32)
        fnty = ir.FunctionType(ir.VoidType(), [cgutils.voidptr_t] * 13)
        fn = cgutils.get_or_insert_function(builder.module, fnty, _SGEMM_SYMBOL)

        def by_reference(value: Any) -> Any:
            slot = cgutils.alloca_once(builder, value.type)
            builder.store(value, slot)
            return builder.bitcast(slot, cgutils.voidptr_t)

        ta_, tb_, m_, n_, k_, a_, lda_, b_, ldb_, c_, ldc_ = args
        one, zero = ir.Constant(ir.FloatType(), 1.0), ir.Constant(ir.FloatType(), 0.0)
        ptr = lambda x: builder.inttoptr(x, cgutils.voidptr_t)  # noqa: E731
        small = lambda x, ty: by_reference(builder.trunc(x, ty))  # noqa: E731
        builder.call(
            fn,
            [
                small(ta_, i8), small(tb_, i8), small(m_, i32), small(n_, i32), small(k_, i32), by_reference(one),
                ptr(a_), small(lda_, i32), ptr(b_), small(ldb_, i32), by_reference(zero), ptr(c_), small(ldc_, i32),
            ],
        )  # fmt: skip
        return context.get_dummy_value()

    return sig, codegen


@jit
def gemm(ta, tb, a, b, c, blas):  # type: ignore[no-untyped-def]
    """``c = op(a) @ op(b)`` for row-major 2-d float32 arrays with unit column stride (``op``:
    transposed where ``ta``/``tb``): by BLAS where ``blas``, else in loops summing over the inner
    index in order from 0 (exact zeros of ``op(a)`` skipped)."""
    m, n = c.shape
    k = a.shape[0] if ta else a.shape[1]
    if blas:  # (row-major c = op(a) op(b) is column-major cᵀ = op(b)ᵀ op(a)ᵀ)
        _sgemm(
            84 if tb else 78, 84 if ta else 78, n, m, k, b.ctypes.data, b.strides[0] // 4,
            a.ctypes.data, a.strides[0] // 4, c.ctypes.data, c.strides[0] // 4,
        )  # fmt: skip
        return
    for i in range(m):
        row = c[i]
        for j in range(n):
            row[j] = 0
        for inner in range(k):
            ai = a[inner, i] if ta else a[i, inner]
            if ai != 0:
                if tb:
                    for j in range(n):
                        row[j] += ai * b[j, inner]
                else:
                    bi = b[inner]
                    for j in range(n):
                        row[j] += ai * bi[j]


@jit
def dense(x, w, b, out, relu, blas):  # type: ignore[no-untyped-def]
    """``out = act(x @ w + b)`` for one network's layer: ``x (n, fin)``, ``w (fin, fout)``, ``b (1, fout)``;
    the bias is added to the finished sum."""
    gemm(False, False, x, w, out, blas)
    n, fout = out.shape
    for r in range(n):
        row = out[r]
        for j in range(fout):
            value = row[j] + b[0, j]
            row[j] = value if (value > 0 or not relu) else 0


@jit
def forward(w1, b1, w2, b2, w3, b3, x, h1, h2, out, blas):  # type: ignore[no-untyped-def]
    """One network's forward pass on ``x (n, fin)``: hidden activations into ``h1``, ``h2``."""
    dense(x, w1, b1, h1, True, blas)
    dense(h1, w2, b2, h2, True, blas)
    dense(h2, w3, b3, out, False, blas)


@jit
def next_values_kernel(online, target, next_obs, swapped, q_next, target_next, target_swapped, h1, h2, blas):  # type: ignore[no-untyped-def]
    k = next_obs.shape[0]
    others = swapped.shape[2]
    for run in range(k):
        forward(
            online[0][run], online[1][run], online[2][run], online[3][run], online[4][run], online[5][run],
            next_obs[run], h1, h2, q_next[run], blas,
        )  # fmt: skip
        t = (target[0][run], target[1][run], target[2][run], target[3][run], target[4][run], target[5][run])
        forward(t[0], t[1], t[2], t[3], t[4], t[5], next_obs[run], h1, h2, target_next[run], blas)
        for o in range(others):
            forward(t[0], t[1], t[2], t[3], t[4], t[5], swapped[run, :, o], h1, h2, target_swapped[run, :, o], blas)


@jit
def dqn_targets_kernel(reward, terminated, q_next, target_next, gamma, out):  # type: ignore[no-untyped-def]
    k, b, a = q_next.shape
    for run in range(k):
        for i in range(b):
            best = 0
            for action in range(1, a):  # the first of equal values, as torch's argmax
                if q_next[run, i, action] > q_next[run, i, best]:
                    best = action
            keep = np.float32(0.0) if terminated[run, i] else np.float32(1.0)
            out[run, i] = reward[run, i] + gamma * keep * target_next[run, i, best]


@jit
def adam_kernel(p, g, m, v, vector_end, step, lr, beta1, beta2, eps):  # type: ignore[no-untyped-def]
    bias_correction1 = 1.0 - beta1**step
    bias_correction2 = 1.0 - beta2**step
    step_size = np.float32(lr / bias_correction1)
    c1 = np.float32(1.0 - beta1)
    c2 = np.float32(1.0 - beta2)
    b2 = np.float32(beta2)
    sqrt_bc2 = np.float32(math.sqrt(bias_correction2))
    e = np.float32(eps)
    minus_step = -step_size
    small = abs(c1) < np.float32(0.5)  # (how torch's lerp picks its form)
    c1_big = c1 - np.float32(1.0)
    c1_rest = np.float32(1.0) - c1
    n = p.shape[0]
    for d in range(vector_end):  # torch's vectorised body
        grad = g[d]
        avg = fma32(c1, grad - m[d], m[d]) if small else fma32(c1_big, grad - m[d], grad)
        avg_sq = fma32(c2 * grad, grad, v[d] * b2)  # (contracted by the build's compiler, as the tail below)
        m[d] = avg
        v[d] = avg_sq
        p[d] = p[d] + minus_step * avg / (np.sqrt(avg_sq) / sqrt_bc2 + e)
    for d in range(vector_end, n):  # its scalar tail
        grad = g[d]
        # (the build's compiler contracted these into multiply-adds)
        avg = fma32(c1, grad - m[d], m[d]) if small else fma32(-(grad - m[d]), c1_rest, grad)
        avg_sq = fma32(v[d], b2, c2 * grad * grad)
        m[d] = avg
        v[d] = avg_sq
        p[d] = p[d] - step_size * avg / (np.sqrt(avg_sq) / sqrt_bc2 + e)


@jit
def train_kernel(  # type: ignore[no-untyped-def]
    online, exp_avg, exp_avg_sq, steps, obs, action, targets, run_of_row,
    lr, beta1, beta2, eps, width, scratch, grads, blas,
):  # fmt: skip
    rows = targets.shape[0]
    b = targets.shape[1]
    h1, h2, out, dz1, dz2, g = scratch
    gw1, gb1, gw2, gb2, gw3, gb3 = grads
    hid = gw1.shape[1]
    hid2 = gw2.shape[1]
    acts = gw3.shape[1]
    inv_b = np.float32(1.0) / np.float32(b)
    total = np.float32(0.0)
    for r in range(rows):
        run = run_of_row[r]
        w1, b1, w2, b2, w3, b3 = online[0][r], online[1][r], online[2][r], online[3][r], online[4][r], online[5][r]
        x = obs[run]
        forward(w1, b1, w2, b2, w3, b3, x, h1, h2, out, blas)
        loss = np.float32(0.0)
        for i in range(b):
            diff = out[i, action[run, i]] - targets[r, i]
            loss += diff * diff
            g[i] = np.float32(2.0) * diff * inv_b
        total += loss / np.float32(b)
        # output layer: only the taken action's value has a gradient
        for j in range(hid2):
            for a in range(acts):
                gw3[j, a] = 0
        for a in range(acts):
            gb3[0, a] = 0
        for i in range(b):
            a = action[run, i]
            gi = g[i]
            gb3[0, a] += gi
            for j in range(hid2):
                gw3[j, a] += h2[i, j] * gi
            for j in range(hid2):
                dz2[i, j] = gi * w3[j, a] if h2[i, j] > 0 else 0
        # second hidden layer
        for j in range(hid2):
            gb2[0, j] = 0
        for i in range(b):
            for j in range(hid2):
                gb2[0, j] += dz2[i, j]
        gemm(True, False, h1, dz2, gw2, blas)
        gemm(False, True, dz2, w2, dz1, blas)
        for i in range(b):
            for u in range(hid):
                if not h1[i, u] > 0:
                    dz1[i, u] = 0
        # first hidden layer
        for u in range(hid):
            gb1[0, u] = 0
        for i in range(b):
            for u in range(hid):
                gb1[0, u] += dz1[i, u]
        gemm(True, False, x, dz1, gw1, blas)
        # Adam, tensor by tensor of this network
        for t in range(6):
            steps[t, r] += np.float32(1.0)
            p = online[t][r].reshape(-1)
            n = p.shape[0]
            adam_kernel(
                p, grads[t].reshape(-1), exp_avg[t][r].reshape(-1), exp_avg_sq[t][r].reshape(-1), n - n % width,
                np.float64(steps[t, r]), lr, beta1, beta2, eps,
            )  # fmt: skip
    return total


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
        if numba is None:
            raise ImportError(_IMPORT_ERROR)
        kernels = {
            "next_values": next_values_kernel,
            "dqn_targets": dqn_targets_kernel,
            "adam": adam_kernel,
            "train": train_kernel,
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
    except Exception as error:  # (numba missing, or it cannot compile here: the caller falls back)
        _FAILURE = f"{type(error).__name__}: {str(error).splitlines()[0] if str(error) else ''}"
        raise RuntimeError(_FAILURE) from error
    _KERNELS = kernels
    return kernels


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
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Q(s'), Q̂(s'), Q̂(s_emp'))`` of every run: ``(K, B, A)``, ``(K, B, A)``, ``(K, B, O, A)``,
    from ``next_obs (K, B, V)`` and ``swapped (K, B, O, V)`` (``O`` may be 0). ``online`` and
    ``target`` are the six stacked float32 parameter arrays ``W₁, b₁, W₂, b₂, W₃, b₃`` (``Q`` of
    run ``r`` is row ``r`` of ``online``); ``scratch`` two ``(B, hidden)`` float32 buffers."""
    return _next_values(_kernels(), online, target, next_obs, swapped, scratch)


def _next_values(
    kernels: dict[str, Any],
    online: tuple[np.ndarray, ...],
    target: tuple[np.ndarray, ...],
    next_obs: np.ndarray,
    swapped: np.ndarray,
    scratch: tuple[np.ndarray, np.ndarray],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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

    def _values(self, next_obs: np.ndarray, swapped: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return _next_values(self._k, self.online, self.target, next_obs, swapped, (self._scratch[0], self._scratch[1]))

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
