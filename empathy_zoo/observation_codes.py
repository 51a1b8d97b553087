"""Observation values as one-byte codes: the arithmetic the engines and the replay memory share.

Every observation value of the suite is a multiple of ``1/20`` (floor ``0``, battery and cat
``-1``, an agent ``1 + batteries`` or, with Sharing's ``inventory_encoding="authors"``,
``5·(n+1)/100 = (n+1)/20``). Value ``k/20`` is computed in exactly one way, :func:`step_value`
(``np.float32(k / 20)``: a float64 division rounded once to float32), so the engine that draws an
observation and the replay memory that decodes a stored one produce the same float32, bit for bit.

A stored value is the byte ``code = k + CODE_OFFSET`` (``k = round(value·20)``), decoded by the
256-entry table :data:`DECODE_TABLE` (``DECODE_TABLE[c] = step_value(c - CODE_OFFSET)``): codes
0 … 255 hold the values −1, −0.95, …, 11.75. Integers decode to themselves exactly.
"""

from __future__ import annotations

import numpy as np

__all__ = ["STEPS_PER_UNIT", "CODE_OFFSET", "MIN_VALUE", "MAX_VALUE", "DECODE_TABLE", "step_value", "encode"]

STEPS_PER_UNIT = 20
"""Observation values are multiples of ``1 / STEPS_PER_UNIT``."""
CODE_OFFSET = 20
"""The code of value 0 (so that value −1 has code 0)."""
DECODE_TABLE: np.ndarray
"""(256,) float32, read-only: the value of every code."""


def step_value(k: np.ndarray | int) -> np.ndarray:
    """The float32 value ``k / 20`` of integer(s) ``k`` (``np.float32(k / 20)``, elementwise)."""
    return (np.asarray(k, dtype=np.int64) / STEPS_PER_UNIT).astype(np.float32)


DECODE_TABLE = step_value(np.arange(256) - CODE_OFFSET)
DECODE_TABLE.flags.writeable = False
MIN_VALUE = float(DECODE_TABLE[0])
"""The smallest value a code holds (−1)."""
MAX_VALUE = float(DECODE_TABLE[-1])
"""The largest value a code holds (11.75)."""


def encode(values: np.ndarray) -> np.ndarray:
    """uint8 codes of float ``values``; raise ``ValueError`` unless every value decodes back
    exactly (a multiple of 1/20, as :func:`step_value` computes it, in [−1, 11.75]): nothing is
    ever rounded silently."""
    values = np.asarray(values)
    if values.size == 0:
        return np.zeros(values.shape, dtype=np.uint8)
    # (in float64, so that integer inputs cannot overflow; NaN fails every test below)
    wide = np.multiply(values, STEPS_PER_UNIT, dtype=np.float64)
    np.rint(wide, out=wide)
    wide += CODE_OFFSET
    if wide.min() >= 0 and wide.max() <= 255:
        codes = wide.astype(np.uint8)
        if np.array_equal(DECODE_TABLE.take(codes), values):
            return codes
    inside = (wide >= 0) & (wide <= 255)
    exact = inside & (DECODE_TABLE.take(np.where(inside, wide, 0).astype(np.uint8)) == values)
    raise ValueError(
        f"observation value(s) {np.unique(values[~exact])[:5].tolist()} cannot be stored exactly as one-byte "
        f"codes, which hold the float32 multiples of 1/{STEPS_PER_UNIT} in [{MIN_VALUE:g}, {MAX_VALUE:g}] "
        f"(np.float32(k / {STEPS_PER_UNIT}); a float64 0.05 is not the float32 0.05); nothing is rounded"
    )
