"""Two one-sided tests (TOST) of equivalence within a stated margin, on two samples of per-seed
values: pure functions over arrays.

Schuirmann's TOST with Welch's t: with ``d = mean(x) − mean(y)``, its standard error
``se = √(s²ₓ/n + s²ᵧ/m)`` and the Welch–Satterthwaite degrees of freedom ``ν``, the two nulls
``d ≤ −margin`` and ``d ≥ margin`` are each tested one-sided; the samples are **equivalent** when
both are rejected at ``level``, which is the same as the ``1 − 2·level`` interval ``d ± t(1 −
level, ν)·se`` lying inside ``(−margin, margin)``. The p of the TOST is the larger of the two
one-sided p's. A side with fewer than 2 finite values gives no verdict (:data:`TOO_FEW`); two
constant samples (``se = 0``) are equivalent exactly when ``|d| < margin``.

Student's t distribution for real ``ν`` is computed here from the regularised incomplete beta
function (continued fraction, Numerical Recipes §6.4), without SciPy.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["EQUIVALENT", "NOT_SHOWN", "TOO_FEW", "TostResult", "t_upper_tail", "t_quantile", "welch", "tost"]

EQUIVALENT = "equivalent"
NOT_SHOWN = "not shown equivalent"
TOO_FEW = "too few seeds"


def _beta_fraction(a: float, b: float, x: float) -> float:
    """The continued fraction of the incomplete beta function (modified Lentz)."""
    tiny, eps = 1e-300, 1e-15
    c, d = 1.0, 1.0 - (a + b) * x / (a + 1.0)
    d = 1.0 / (d if abs(d) > tiny else tiny)
    h = d
    for m in range(1, 500):
        even = m * (b - m) * x / ((a + 2 * m - 1) * (a + 2 * m))
        odd = -(a + m) * (a + b + m) * x / ((a + 2 * m) * (a + 2 * m + 1))
        for numerator in (even, odd):
            d = 1.0 + numerator * d
            d = 1.0 / (d if abs(d) > tiny else tiny)
            c = 1.0 + numerator / c
            c = c if abs(c) > tiny else tiny
            h *= d * c
        if abs(d * c - 1.0) < eps:
            break
    return h


def _incomplete_beta(a: float, b: float, x: float) -> float:
    """The regularised incomplete beta function ``I_x(a, b)``."""
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    front = math.exp(math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b) + a * math.log(x) + b * math.log1p(-x))
    if x < (a + 1.0) / (a + b + 2.0):
        return front * _beta_fraction(a, b, x) / a
    return 1.0 - front * _beta_fraction(b, a, 1.0 - x) / b


def t_upper_tail(t: float, df: float) -> float:
    """``P(T ≥ t)`` for Student's t with ``df > 0`` (real) degrees of freedom."""
    if df <= 0:
        raise ValueError(f"degrees of freedom must be positive, got {df}")
    if math.isinf(t):
        return 0.0 if t > 0 else 1.0
    half = 0.5 * _incomplete_beta(0.5 * df, 0.5, df / (df + t * t))
    return half if t >= 0 else 1.0 - half


def t_quantile(probability: float, df: float) -> float:
    """The ``probability`` quantile of Student's t with real ``df`` (bisection on :func:`t_upper_tail`)."""
    if not 0.0 < probability < 1.0:
        raise ValueError(f"a quantile needs a probability strictly between 0 and 1, got {probability}")
    target = 1.0 - probability  # the upper tail at the quantile
    low, high = -1.0, 1.0
    while t_upper_tail(low, df) < target:
        low *= 2.0
    while t_upper_tail(high, df) > target:
        high *= 2.0
    for _ in range(200):
        middle = 0.5 * (low + high)
        if middle in (low, high):
            break
        if t_upper_tail(middle, df) > target:
            low = middle
        else:
            high = middle
    return 0.5 * (low + high)


def welch(x: Sequence[float] | np.ndarray, y: Sequence[float] | np.ndarray) -> tuple[float, float, float, int, int]:
    """``(d, se, ν, n, m)``: the difference of means of the finite values, its Welch standard error
    and Welch–Satterthwaite degrees of freedom (NaN where a side has fewer than 2 values; ``ν`` NaN
    also when ``se`` is 0)."""
    a = np.asarray(x, dtype=np.float64).ravel()
    b = np.asarray(y, dtype=np.float64).ravel()
    a, b = a[np.isfinite(a)], b[np.isfinite(b)]
    n, m = int(a.size), int(b.size)
    if n < 2 or m < 2:
        difference = float(a.mean() - b.mean()) if n and m else math.nan
        return difference, math.nan, math.nan, n, m
    va, vb = float(a.var(ddof=1)) / n, float(b.var(ddof=1)) / m
    se = math.sqrt(va + vb)
    df = (va + vb) ** 2 / (va**2 / (n - 1) + vb**2 / (m - 1)) if se > 0 else math.nan
    return float(a.mean() - b.mean()), se, df, n, m


@dataclass(frozen=True)
class TostResult:
    """The TOST of two samples within ``±margin``."""

    difference: float
    """``mean(x) − mean(y)``."""
    low: float
    """The ``1 − 2·level`` Welch interval of the difference (NaN with too few seeds)."""
    high: float
    p_value: float
    """The larger of the two one-sided p's (NaN with too few seeds)."""
    margin: float
    n: int
    m: int
    verdict: str
    """:data:`EQUIVALENT`, :data:`NOT_SHOWN` or :data:`TOO_FEW`."""


def tost(x: Sequence[float] | np.ndarray, y: Sequence[float] | np.ndarray, margin: float, level: float = 0.05) -> TostResult:
    """The two one-sided Welch t tests of ``|mean(x) − mean(y)| < margin`` at ``level`` each (module page)."""
    if margin <= 0 or not 0.0 < level < 0.5:
        raise ValueError(f"a TOST needs a positive margin and a level in (0, 0.5), got {margin}, {level}")
    difference, se, df, n, m = welch(x, y)
    if n < 2 or m < 2:
        return TostResult(difference, math.nan, math.nan, math.nan, margin, n, m, TOO_FEW)
    if se == 0.0:
        inside = abs(difference) < margin
        verdict = EQUIVALENT if inside else NOT_SHOWN
        return TostResult(difference, difference, difference, 0.0 if inside else 1.0, margin, n, m, verdict)
    p_lower = t_upper_tail((difference + margin) / se, df)  # H0: d ≤ −margin
    p_upper = t_upper_tail((margin - difference) / se, df)  # H0: d ≥ margin
    p = max(p_lower, p_upper)
    half = t_quantile(1.0 - level, df) * se
    verdict = EQUIVALENT if p <= level else NOT_SHOWN
    return TostResult(difference, difference - half, difference + half, p, margin, n, m, verdict)
