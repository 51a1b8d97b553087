"""Checkpoints a killed run resumes from: ``torch.save`` of plain data, loaded with
``weights_only=True``; written atomically; a corrupted one raises and is never overwritten."""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import numpy as np
import torch

from empathy_zoo.atomic import write_bytes_atomic

__all__ = ["save_checkpoint", "load_checkpoint", "to_safe", "from_safe", "CheckpointError"]

FORMAT = 1


class CheckpointError(ValueError):
    """A checkpoint exists but cannot be used."""


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


def from_safe(value: Any) -> Any:
    """Inverse of :func:`to_safe`."""
    if isinstance(value, dict):
        if "__ndarray__" in value:
            array = value["__ndarray__"].numpy()
            return array.view(np.uint64) if value["dtype"] == "uint64" else array.astype(value["dtype"], copy=False)
        return {key: from_safe(item) for key, item in value.items()}
    if isinstance(value, list):
        return [from_safe(item) for item in value]
    return value


def save_checkpoint(path: Path, payload: dict[str, Any]) -> None:
    buffer = io.BytesIO()
    torch.save({"format": FORMAT, **payload}, buffer)
    write_bytes_atomic(path, buffer.getvalue())


def load_checkpoint(path: Path) -> dict[str, Any]:
    """Load a checkpoint; raises :class:`CheckpointError` naming the file when it is unusable."""
    try:
        payload = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as error:  # torch raises many kinds for a damaged file
        raise CheckpointError(
            f"checkpoint {path} is corrupted or unreadable ({type(error).__name__}: {error}); "
            "it was left untouched: delete or move it to restart those runs from scratch"
        ) from error
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise CheckpointError(f"checkpoint {path} has an unknown format; delete or move it to restart")
    return payload
