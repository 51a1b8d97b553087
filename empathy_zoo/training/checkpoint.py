"""Checkpoints a killed run resumes from: ``torch.save`` of plain data, loaded with
``weights_only=True``; written atomically; a corrupted one raises and is never overwritten."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import torch

from empathy_zoo.atomic import write_with_atomic
from empathy_zoo.safe_data import from_safe, to_safe

__all__ = ["save_checkpoint", "load_checkpoint", "to_safe", "from_safe", "CheckpointError"]

FORMAT = 1


class CheckpointError(ValueError):
    """A checkpoint exists but cannot be used."""


def save_checkpoint(path: Path, payload: dict[str, Any]) -> None:
    """Write ``payload`` to ``path`` atomically, streamed into the temporary file (no copy of the
    checkpoint is held in memory: an ensemble's replay memories are ≈ 1 GB in the paper profile)."""
    write_with_atomic(path, lambda handle: torch.save({"format": FORMAT, **payload}, handle))


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
