"""Which code produced a file: the package version and the git commit of its source tree."""

from __future__ import annotations

import subprocess
from functools import lru_cache
from pathlib import Path

from empathy_zoo._version import __version__

__all__ = ["package_version", "git_commit", "checkout_commit"]


def package_version() -> str:
    """The version of the empathy-zoo code that runs (:mod:`empathy_zoo._version`, the one place it
    is written; the installed package's metadata is built from it)."""
    return __version__


@lru_cache(maxsize=1)
def git_commit() -> str | None:
    """Short commit of the git checkout the package runs from (``<commit>-dirty`` when tracked
    files differ from it), else ``None``; read once per process."""
    return checkout_commit(Path(__file__).resolve().parent)


def checkout_commit(directory: Path) -> str | None:
    """Short commit of the git checkout holding ``directory``, with ``-dirty`` appended when a
    tracked file differs from it (staged or not; untracked files do not count), else ``None``."""
    commit = _git(directory, "rev-parse", "--short", "HEAD")
    if commit is None:
        return None
    changes = _git(directory, "status", "--porcelain", "--untracked-files=no")
    return commit if changes == "" else f"{commit}-dirty"


def _git(directory: Path, *args: str) -> str | None:
    try:
        completed = subprocess.run(
            ["git", *args],
            cwd=directory,
            capture_output=True,
            text=True,
            timeout=10,
            check=False,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return completed.stdout.strip() if completed.returncode == 0 else None
