"""Which code produced a file: the package version and the git commit of its source tree."""

from __future__ import annotations

import importlib.metadata
import subprocess
from functools import lru_cache
from pathlib import Path

__all__ = ["package_version", "git_commit"]

_FALLBACK_VERSION = "0.1.0"


@lru_cache(maxsize=1)
def package_version() -> str:
    """The installed empathy-zoo version, or ``"0.1.0"`` when it is not installed."""
    try:
        return importlib.metadata.version("empathy-zoo")
    except importlib.metadata.PackageNotFoundError:
        return _FALLBACK_VERSION


@lru_cache(maxsize=1)
def git_commit() -> str | None:
    """Short commit of the git checkout the package runs from, else ``None``."""
    try:
        completed = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], cwd=Path(__file__).resolve().parent,
            capture_output=True, text=True, timeout=10, check=False,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    commit = completed.stdout.strip()
    return commit if completed.returncode == 0 and commit else None
