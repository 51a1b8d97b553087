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
  bit for bit what :meth:`agents.replay.StackedReplay.sample` returns.
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

numba is optional: :func:`numba_available` says whether the kernels import and compile here (it
compiles them once, on tiny inputs, and never raises); the learner falls back to its PyTorch path
when they do not.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import torch

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
    numba: they are then never called). Floating-point division follows IEEE (numpy's error
    model: no test for a zero divisor in every division, which would keep loops from being
    vectorised; no kernel divides by zero), so the loops run in the machine's vector lanes, each
    element by the same operations as alone."""
    if numba is None:
        return lambda function: function
    try:
        numba.njit(cache=True)(lambda: 0)
    except Exception:  # (no cache directory numba can write)
        return numba.njit(nogil=True, error_model="numpy")
    return numba.njit(cache=True, nogil=True, error_model="numpy")


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
def column_sums(rows, out):  # type: ignore[no-untyped-def]
    """``out[0, j] = Σ_i rows[i, j]``, summed over the rows in order ``0 … B−1`` (a bias gradient)."""
    out[0, :] = 0
    for i in range(rows.shape[0]):
        for j in range(rows.shape[1]):
            out[0, j] += rows[i, j]


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
def dense_out(x, w, b, out, blas):  # type: ignore[no-untyped-def]
    """``out = x @ w + b`` for a network's output layer (a handful of outputs): ``w`` copied
    transposed first, so the product is taken as rows of ``x`` against rows of ``wᵀ``, the form
    in which BLAS serves such a narrow product fastest; the bias added to the finished sum."""
    gemm(False, True, x, np.ascontiguousarray(w.T), out, blas)
    n, fout = out.shape
    for r in range(n):
        row = out[r]
        for j in range(fout):
            row[j] = row[j] + b[0, j]


@jit
def forward(w1, b1, w2, b2, w3, b3, x, h1, h2, out, blas):  # type: ignore[no-untyped-def]
    """One network's forward pass on ``x (n, fin)``: hidden activations into ``h1``, ``h2``."""
    dense(x, w1, b1, h1, True, blas)
    dense(h1, w2, b2, h2, True, blas)
    dense_out(h2, w3, b3, out, blas)


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
        # output layer: only the taken action's value has a gradient (kept transposed, one
        # contiguous row per action, while it is summed)
        w3t = np.ascontiguousarray(w3.T)
        gw3t = np.zeros((acts, hid2), np.float32)
        for a in range(acts):
            gb3[0, a] = 0
        for i in range(b):
            a = action[run, i]
            gi = g[i]
            gb3[0, a] += gi
            grad_row, weight_row, h_row, dz_row = gw3t[a], w3t[a], h2[i], dz2[i]
            for j in range(hid2):
                grad_row[j] += h_row[j] * gi
            for j in range(hid2):
                dz_row[j] = gi * weight_row[j] if h_row[j] > 0 else 0
        for j in range(hid2):
            for a in range(acts):
                gw3[j, a] = gw3t[a, j]
        # second hidden layer
        column_sums(dz2, gb2)
        gemm(True, False, h1, dz2, gw2, blas)
        gemm(False, True, dz2, w2, dz1, blas)
        for i in range(b):
            for u in range(hid):
                if not h1[i, u] > 0:
                    dz1[i, u] = 0
        # first hidden layer
        column_sums(dz1, gb1)
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


# ---------------------------------------------------------------------------- the replay batch
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)
"""SplitMix64's constants, as :func:`empathy_zoo.randomness.counter_bits` uses them."""


@jit
def draw_indices_kernel(keys, start, size, index):  # type: ignore[no-untyped-def]
    """``index[r, i] = ⌊u·size⌋``, ``u`` the uniform of ``(keys[r], start + i)`` as
    :func:`empathy_zoo.randomness.counter_integers` computes it (SplitMix64, then float64)."""
    k, b = index.shape
    scale = 1.0 / 9007199254740992.0  # 2⁻⁵³
    high = np.float64(size)
    for run in range(k):
        key = keys[run]
        for i in range(b):
            z = key + (np.uint64(start + i) + np.uint64(1)) * _GOLDEN
            z = (z ^ (z >> np.uint64(30))) * _MIX1
            z = (z ^ (z >> np.uint64(27))) * _MIX2
            z = z ^ (z >> np.uint64(31))
            index[run, i] = np.int64(math.floor(np.float64(z >> np.uint64(11)) * scale * high))


@jit
def gather_kernel(codes, flags, stored_reward, table, index, decoded, action, terminated, reward, present, live, unseen):  # type: ignore[no-untyped-def]
    """The transitions at ``index (K, B)`` of the replay's arrays (``codes (K, C, 2 + O, V)``,
    ``flags (K, C, 2 + O)``, ``stored_reward (K, C)``), decoded by ``table``: observations into
    ``decoded (K, B, 2 + O, V)``, the flags into ``action``, ``terminated``, ``reward`` ``(K, B)``
    and ``present``, ``live``, ``unseen`` ``(K, B, O)`` (the codes of
    :attr:`agents.replay.StackedReplay.flags`). Raises ``IndexError`` on an index outside ``[0, C)``."""
    k, b = index.shape
    capacity, width, v = codes.shape[1], codes.shape[2], codes.shape[3]
    for run in range(k):
        for i in range(b):
            row = index[run, i]
            if row < 0 or row >= capacity:
                raise IndexError("a replay index lies outside the memory")
            for w in range(width):
                source, target = codes[run, row, w], decoded[run, i, w]
                for j in range(v):
                    target[j] = table[source[j]]
            action[run, i] = flags[run, row, 0]
            terminated[run, i] = flags[run, row, 1] != 0
            reward[run, i] = stored_reward[run, row]
            for o in range(width - 2):
                code = flags[run, row, 2 + o]
                present[run, i, o] = code == 2
                live[run, i, o] = code >= 1
                unseen[run, i, o] = code == 3


# ---------------------------------------------------------------------------- the targets
CLOSEST, MEAN, MIN = 0, 1, 2
"""How :func:`run_targets_kernel` takes the other agents (``others`` of :func:`agents.empathic_dqn.other_term`)."""
RULES = {"closest": CLOSEST, "mean": MEAN, "min": MIN}


@jit
def _max(values):  # type: ignore[no-untyped-def]
    best = values[0]
    for a in range(1, values.shape[0]):
        if values[a] > best:
            best = values[a]
    return best


@jit
def run_targets_kernel(  # type: ignore[no-untyped-def]
    reward, terminated, q_next, target_next, target_swapped, present, live, unseen, gamma, beta, rule, empathic, y, y_emp
):  # fmt: skip
    """One run's ``y`` (and, where ``empathic``, ``y_emp``) into ``(B,)`` arrays, the operations of
    :func:`agents.empathic_dqn.empathic_targets` in its order, in float32: ``reward``,
    ``terminated`` ``(B,)``, ``q_next``, ``target_next`` ``(B, A)``, ``target_swapped (B, O, A)``,
    ``present``, ``live``, ``unseen`` ``(B, O)``; ``rule`` one of :data:`RULES` (with
    :data:`CLOSEST`, the other agent is entry 0)."""
    b, a = q_next.shape
    others = target_swapped.shape[1]
    one, zero = np.float32(1.0), np.float32(0.0)
    rest = one - beta
    for i in range(b):
        best = 0
        for action in range(1, a):  # the first of equal values, as torch's argmax
            if q_next[i, action] > q_next[i, best]:
                best = action
        keep = zero if terminated[i] else one
        yi = reward[i] + gamma * keep * target_next[i, best]
        y[i] = yi
        if not empathic:
            continue
        if rule == CLOSEST:
            term = gamma * (one if present[i, 0] else zero) * _max(target_swapped[i, 0])
            own = unseen[i, 0]
        else:
            total, count, least = zero, 0, np.float32(np.inf)
            anyone_live, anyone_counted = False, False
            for o in range(others):
                value = gamma * (one if present[i, o] else zero) * _max(target_swapped[i, o])
                counted = live[i, o] and not unseen[i, o]
                anyone_live = anyone_live or live[i, o]
                anyone_counted = anyone_counted or counted
                if rule == MEAN:
                    total += value * (one if counted else zero)
                    count += 1 if counted else 0
                elif counted and value < least:
                    least = value
            if rule == MEAN:
                term = total / np.float32(max(count, 1))
            else:
                term = least if anyone_counted else zero
            own = anyone_live and not anyone_counted
        y_emp[i] = yi if own else beta * yi + rest * term


@jit
def targets_kernel(  # type: ignore[no-untyped-def]
    reward, terminated, q_next, target_next, target_swapped, present, live, unseen, gamma, beta, rule, y, y_emp
):  # fmt: skip
    for run in range(reward.shape[0]):
        run_targets_kernel(
            reward[run], terminated[run], q_next[run], target_next[run], target_swapped[run], present[run], live[run],
            unseen[run], gamma, beta[run], rule, True, y[run], y_emp[run],
        )  # fmt: skip


# ---------------------------------------------------------------------------- the whole update
@jit
def update_kernel(  # type: ignore[no-untyped-def]
    replay, keys, start, size, draw, index, batch, online, target, exp_avg, exp_avg_sq, steps, run_of_row, emp_row,
    beta, gamma, rule, lr, beta1, beta2, eps, width, scratch, values, targets, grads, blas,
):  # fmt: skip
    """One gradient step of every online row from the replay's arrays: the batch's indices (drawn
    here where ``draw``, else ``index`` as given), its gather and decode, then run by run
    ``Q(s')``, ``Q̂(s')`` (and ``Q̂(s_emp')`` where the run has ``Q_emp``, row ``emp_row[run] ≥ 0``)
    and its targets into ``targets (R, B)``, then :func:`train_kernel`. Returns the summed loss."""
    codes, flags, stored_reward, table = replay
    decoded, action, terminated, reward, present, live, unseen = batch
    if draw:
        draw_indices_kernel(keys, start, size, index)
    gather_kernel(codes, flags, stored_reward, table, index, decoded, action, terminated, reward, present, live, unseen)
    h1, h2 = scratch[0], scratch[1]
    q_next, target_next, target_swapped = values
    others = target_swapped.shape[1]
    for run in range(index.shape[0]):
        nxt = decoded[run, :, 1]
        forward(
            online[0][run], online[1][run], online[2][run], online[3][run], online[4][run], online[5][run],
            nxt, h1, h2, q_next, blas,
        )  # fmt: skip
        t = (target[0][run], target[1][run], target[2][run], target[3][run], target[4][run], target[5][run])
        forward(t[0], t[1], t[2], t[3], t[4], t[5], nxt, h1, h2, target_next, blas)
        row = emp_row[run]
        empathic = row >= 0
        if empathic:
            for o in range(others):
                forward(t[0], t[1], t[2], t[3], t[4], t[5], decoded[run, :, 2 + o], h1, h2, target_swapped[:, o], blas)
        run_targets_kernel(
            reward[run], terminated[run], q_next, target_next, target_swapped, present[run], live[run], unseen[run],
            gamma, beta[run], rule, empathic, targets[run], targets[row if empathic else run],
        )  # fmt: skip
    return train_kernel(
        online, exp_avg, exp_avg_sq, steps, decoded[:, :, 0], action, targets, run_of_row,
        lr, beta1, beta2, eps, width, scratch, grads, blas,
    )  # fmt: skip


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
    if replay.observations.device.type != "cpu":
        raise ValueError("the compiled gather reads replay memories on the CPU only")
    codes = replay.observations
    k, b = index.shape
    if k != codes.shape[0]:
        raise ValueError(f"expected one row of indices per run, ({codes.shape[0]}, B); got {index.shape}")
    buffers = _batch_buffers(k, b, codes.shape[2] - 2, codes.shape[3])
    kernels["gather"](*_replay_arrays(replay), np.ascontiguousarray(index), *buffers)
    decoded, action, terminated, reward, present, live, unseen = (torch.from_numpy(x) for x in buffers)
    return {
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
        self._replay: tuple[tuple[torch.Tensor, ...], tuple[np.ndarray, ...]] | None = None
        """The replay tensors :meth:`step` last read, and their numpy views."""

    def step(self, replay: Any, start: int, index: np.ndarray | None = None) -> float:
        """One whole gradient step of every online row in one compiled call (:func:`update_kernel`):
        the batch at ``index (K, B)``, or where ``None`` at the indices drawn from the keys at
        counter ``start`` (as :meth:`agents.empathic_dqn.EmpathicDQN.sample_indices` draws them),
        gathered from ``replay`` (a CPU :class:`agents.replay.StackedReplay`), the targets of
        :func:`agents.empathic_dqn.empathic_targets` (of ``Q`` only for a run without ``Q_emp``),
        forward, backward and Adam network after network (:meth:`setup_step` first). Returns the
        summed loss, as :meth:`train`."""
        tensors, cached = (replay.observations, replay.flags, replay.reward, replay.decode_table), self._replay
        if cached is None or any(a is not b for a, b in zip(cached[0], tensors)):
            if any(t.device.type != "cpu" for t in tensors):
                raise ValueError("the compiled step reads replay memories on the CPU only")
            cached = self._replay = (tensors, _replay_arrays(replay))
        if index is not None:
            self._index[...] = index
        total = self._k["update"](
            cached[1], self._keys, int(start), int(replay.size), index is None, self._index, self._batch,
            self.online, self.target, self.exp_avg, self.exp_avg_sq, self.steps, self.run_of_row, self._emp_row,
            self._beta, self._gamma, self._rule, self.lr, self.beta1, self.beta2, self.eps, self._width,
            self._scratch, self._step_values, self._targets, self._grads, BLAS,
        )  # fmt: skip
        return float(total)

    def sample_batch(self, replay: Any, index: torch.Tensor, aggregated: bool) -> dict[str, torch.Tensor]:
        """:meth:`agents.empathic_dqn.EmpathicDQN.sample_batch` at ``index`` by the compiled gather
        (:func:`gather`; fresh tensors): with ``aggregated`` false, the closest other agent's
        ``other_swapped``, ``other_present`` and ``other_unseen`` in place of the ``others_…``."""
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
