"""Checkpoints a killed run resumes from: ``torch.save`` of plain data, loaded with
``weights_only=True``; written atomically; a corrupted one raises and is never overwritten."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import torch

from empathy_zoo.atomic import write_with_atomic
from empathy_zoo.safe_data import from_safe, to_safe

__all__ = ["save_checkpoint", "load_checkpoint", "check_checkpoint_keys", "corrupted", "to_safe", "from_safe", "CheckpointError"]

FORMAT = 1


class CheckpointError(ValueError):
    """A checkpoint exists but cannot be used."""


def save_checkpoint(path: Path, payload: dict[str, Any]) -> None:
    """Write ``payload`` to ``path`` atomically, streamed into the temporary file (no copy of the
    checkpoint is held in memory: an ensemble's replay memories are ≈ 1 GB in the paper profile).

    A write that fails (a full disk) raises ``OSError`` with its ``errno``, naming the checkpoint
    and saying whether an earlier one is kept (torch reports a failed write as a ``RuntimeError``
    of its zip writer, the ``OSError`` in its context)."""
    try:
        write_with_atomic(path, lambda handle: torch.save({"format": FORMAT, **payload}, handle))
    except (OSError, RuntimeError) as error:
        cause = error if isinstance(error, OSError) else error.__context__
        if not isinstance(cause, OSError):  # (a torch error that is no failed write)
            raise
        kept = (
            f"the previous checkpoint {path} is kept: free space and run the same command again to resume from it"
            if path.exists()
            else "no earlier checkpoint was written: free space and run the same command again to start these runs again"
        )
        raise OSError(cause.errno, f"cannot write checkpoint {path} ({cause.strerror or cause}); {kept}") from error


def load_checkpoint(path: Path) -> dict[str, Any]:
    """Load a checkpoint; raises :class:`CheckpointError` naming the file when it is unusable."""
    try:
        payload = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as error:  # torch raises many kinds for a damaged file
        raise corrupted(path, error) from error
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise CheckpointError(f"checkpoint {path} has an unknown format; delete or move it to restart")
    return payload


def corrupted(path: Path, error: BaseException | str) -> CheckpointError:
    """The error of checkpoint ``path``, unusable because of ``error`` (what was wrong in it)."""
    why = error if isinstance(error, str) else f"{type(error).__name__}: {error}"
    return CheckpointError(
        f"checkpoint {path} is corrupted or unreadable ({why}); "
        "it was left untouched: delete or move it to restart those runs from scratch"
    )


def check_checkpoint_keys(path: Path, payload: dict[str, Any], keys: dict[str, type | tuple[type, ...]]) -> dict[str, Any]:
    """``payload`` (checkpoint ``path`` as loaded) if it holds every key of ``keys`` with a value of
    its type, else the :func:`corrupted` error naming what is missing or wrong."""
    missing = [key for key in keys if key not in payload]
    if missing:
        raise corrupted(path, f"it holds no {', '.join(map(repr, missing))}")
    wrong = [key for key, kind in keys.items() if isinstance(payload[key], bool) or not isinstance(payload[key], kind)]
    if wrong:
        raise corrupted(path, ", ".join(f"{key!r} is a {type(payload[key]).__name__}" for key in wrong))
    return payload
