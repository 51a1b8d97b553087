"""The compiled kernels of Empathic DQN's gradient step (numba), which :mod:`agents.fused_update`
drives: the matrix products (MKL's ``sgemm`` where torch's CPU library carries it, else loops), the
forward and backward passes, Adam, the batch's indices and gather, the targets, and the whole
update in one call. What each computes, and in which order it sums, is said in
:mod:`agents.fused_update`, whose functions are the way to call them.

numba is optional: without it the functions below are left uncompiled (never called then), and
:func:`agents.fused_update.numba_available` is false.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import torch

__all__ = [
    "BLAS",
    "IMPORT_ERROR",
    "RULES",
    "adam_kernel",
    "dqn_targets_kernel",
    "draw_indices_kernel",
    "gather_kernel",
    "gemm",
    "next_values_kernel",
    "price_kernel",
    "targets_kernel",
    "train_kernel",
    "update_kernel",
    "vector_width",
]


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
    IMPORT_ERROR: str | None = f"numba is not installed ({error})"
else:
    IMPORT_ERROR = None
"""Why numba could not be imported (``None`` when it was)."""


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


@jit
def price_kernel(stored_cost, price, index, reward):  # type: ignore[no-untyped-def]
    """``reward[r, i] = reward[r, i] − price[r]·stored_cost[r, index[r, i]]``: each sampled
    transition's cost charged at its run's price now, in float32 (the product rounded, then the
    difference), as :meth:`agents.empathic_dqn.EmpathicDQN.sample_batch` computes it."""
    k, b = index.shape
    for run in range(k):
        for i in range(b):
            reward[run, i] = reward[run, i] - price[run] * stored_cost[run, index[run, i]]


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
    :data:`CLOSEST`, the other agent is entry 0). Where no other is seen, the robot's continuation
    is the other-term (SPEC §4)."""
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
        continuation = gamma * keep * target_next[i, best]
        yi = reward[i] + continuation
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
            if rule == MEAN:  # noqa: SIM108 - a numba kernel: the branches stay as numba types them today
                term = total / np.float32(max(count, 1))
            else:
                term = least if anyone_counted else zero
            own = anyone_live and not anyone_counted
        if own:
            term = continuation
        y_emp[i] = beta * yi + rest * term


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
    beta, gamma, rule, lr, beta1, beta2, eps, width, scratch, values, targets, grads, blas, stored_cost, price, priced,
):  # fmt: skip
    """One gradient step of every online row from the replay's arrays: the batch's indices (drawn
    here where ``draw``, else ``index`` as given), its gather and decode (where ``priced``, each
    reward charged its stored cost at its run's ``price``: :func:`price_kernel`), then run by run
    ``Q(s')``, ``Q̂(s')`` (and ``Q̂(s_emp')`` where the run has ``Q_emp``, row ``emp_row[run] ≥ 0``)
    and its targets into ``targets (R, B)``, then :func:`train_kernel`. Returns the summed loss."""
    codes, flags, stored_reward, table = replay
    decoded, action, terminated, reward, present, live, unseen = batch
    if draw:
        draw_indices_kernel(keys, start, size, index)
    gather_kernel(codes, flags, stored_reward, table, index, decoded, action, terminated, reward, present, live, unseen)
    if priced:
        price_kernel(stored_cost, price, index, reward)
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
