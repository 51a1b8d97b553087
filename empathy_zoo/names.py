"""Names that become parts of file paths (environment variants, run ids), and paths kept inside
the directory they belong to: a name read from a file or a sweep can never point elsewhere."""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

__all__ = ["PATH_NAME", "check_path_name", "confined"]

PATH_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]*")
"""What a name used in a file name may look like: letters, digits, ``_``, ``-`` and ``.``,
starting with a letter or a digit (so never ``..``, a hidden name, a separator or an absolute path)."""
MAX_NAME = 200
"""Longest such name, in characters (file names are at most 255 bytes on common file systems)."""


def check_path_name(value: Any, what: str) -> str:
    """``value`` if it may be part of a file name (:data:`PATH_NAME`), else a ``ValueError``
    naming ``what`` it is and what it may hold."""
    if not isinstance(value, str) or not PATH_NAME.fullmatch(value) or len(value) > MAX_NAME:
        raise ValueError(
            f"{what} {value!r} cannot be part of a file name: use letters, digits, '_', '-' and '.' only, "
            f"starting with a letter or a digit, at most {MAX_NAME} characters"
        )
    return value


def confined(root: str | os.PathLike[str], *parts: str) -> Path:
    """``root / parts…``, or a ``ValueError`` when that path would lie outside ``root``."""
    base = Path(root)
    path = base.joinpath(*parts)
    if not path.resolve().is_relative_to(base.resolve()):
        raise ValueError(f"{path} lies outside {base}; refusing to write there")
    return path
