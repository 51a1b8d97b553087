"""Plain data that ``torch.load(weights_only=True)`` accepts: numpy arrays (anywhere in dicts and
lists) as tensors and back. Checkpoints (the trainer's, and a learner's own state, e.g. SB3's) are
stored this way, so loading one never runs code."""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

__all__ = ["to_safe", "from_safe"]


def to_safe(value: Any) -> Any:
    """Turn numpy arrays (anywhere in dicts/lists) into tensors ``torch.load(weights_only=True)`` accepts."""
    if isinstance(value, np.ndarray):
        if value.dtype == np.uint64:
            return {"__ndarray__": torch.from_numpy(value.view(np.int64).copy()), "dtype": "uint64"}
        return {"__ndarray__": torch.from_numpy(np.ascontiguousarray(value).copy()), "dtype": str(value.dtype)}
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, dict):
        return {key: to_safe(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_safe(item) for item in value]
    return value


NUMERIC_KINDS = "biuf"
"""Kinds of numpy dtype an array read back may have: booleans, integers, floats (no objects, no strings)."""


def from_safe(value: Any) -> Any:
    """Inverse of :func:`to_safe`; an array that is no tensor, or of a dtype that is no number (an
    object, a string), raises ``ValueError``."""
    if isinstance(value, dict):
        if "__ndarray__" in value:
            tensor, dtype = value["__ndarray__"], value.get("dtype")
            if not isinstance(tensor, torch.Tensor) or not isinstance(dtype, str):
                raise ValueError(f"an array is stored as a {type(tensor).__name__} of dtype {dtype!r}, not a tensor")
            try:
                kind: str = np.dtype(dtype).kind
            except TypeError:
                kind = ""
            if not kind or kind not in NUMERIC_KINDS:
                raise ValueError(f"an array has dtype {dtype!r}, which is no number")
            array = tensor.numpy()
            return array.view(np.uint64) if value["dtype"] == "uint64" else array.astype(value["dtype"], copy=False)
        return {key: from_safe(item) for key, item in value.items()}
    if isinstance(value, list):
        return [from_safe(item) for item in value]
    return value
