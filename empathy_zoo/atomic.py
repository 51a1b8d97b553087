"""Atomic file writes: a reader (or a crash) never sees a half-written results file.

:func:`check_output_dir` is asked before any long work starts: it refuses an output directory
that is a file, cannot be created or cannot be written (as much as a result file and its agent file
take: a full disk too), so no training is lost at the first write.
"""

from __future__ import annotations

import json
import os
import re
import secrets
import stat
from collections.abc import Callable
from pathlib import Path
from typing import Any, BinaryIO

from empathy_zoo.names import check_no_links

__all__ = [
    "write_bytes_atomic",
    "write_text_atomic",
    "write_json_atomic",
    "write_with_atomic",
    "read_json",
    "check_output_dir",
    "remove_stale_temp_files",
]

TEMP_SUFFIX = ".tmp"
"""Name suffix of the temporary file of an atomic write in progress (its name starts with ``.``)."""
PROBE_PREFIX = ".write-probe-"
"""Name prefix of the file :func:`check_output_dir` writes (atomically) and removes."""
PROBE_BYTES = 256 * 1024
"""Bytes :func:`check_output_dir` writes to each directory: as much as a run's result file and its
agent file take (≈ 200 KB at the paper's settings), so a full disk is found before training, not
after it."""
_OURS = re.compile(rf"(?:\.(?P<pid>\d+)\.[0-9a-f]{{8}}{re.escape(TEMP_SUFFIX)}|^{re.escape(PROBE_PREFIX)}(?P<prober>\d+))$")
"""The end of a temporary file name this module writes, with the writer's process id."""


def write_with_atomic(path: str | os.PathLike[str], write: Callable[[BinaryIO], object]) -> Path:
    """Call ``write(file)`` on a temporary file beside ``path``, fsync it, then rename it over ``path``.

    The file gets the permissions an ordinary write would give it: a new file ``0666 & ~umask``
    (the kernel applies the umask), a rewritten one the mode it had."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = _create_temp(path)
    try:
        with os.fdopen(fd, "wb") as handle:
            if path.exists() and hasattr(os, "fchmod"):  # a new file keeps the mode it was created with
                os.fchmod(handle.fileno(), stat.S_IMODE(path.stat().st_mode))
            write(handle)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    return path


def _create_temp(path: Path) -> tuple[int, Path]:
    """A new, empty temporary file beside ``path`` (mode ``0666 & ~umask``), named
    ``.<name>.<pid>.<random>.tmp`` so a later run can tell whose it is, and its descriptor."""
    while True:
        tmp = path.parent / f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}{TEMP_SUFFIX}"
        try:
            return os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666), tmp
        except FileExistsError:
            continue


def write_bytes_atomic(path: str | os.PathLike[str], data: bytes) -> Path:
    return write_with_atomic(path, lambda handle: handle.write(data))


def write_text_atomic(path: str | os.PathLike[str], text: str) -> Path:
    return write_bytes_atomic(path, text.encode("utf-8"))


def write_json_atomic(path: str | os.PathLike[str], payload: Any) -> Path:
    return write_text_atomic(path, json.dumps(payload, indent=1, sort_keys=False) + "\n")


def read_json(path: str | os.PathLike[str]) -> Any:
    """Read a JSON file; a corrupted one raises ``ValueError`` naming the file (it is never rewritten)."""
    path = Path(path)
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, RecursionError) as error:  # (bad JSON or UTF-8, an int of over 4,300 digits, nesting past the stack)
        why = f"{type(error).__name__}: {str(error)[:200]}"
        raise ValueError(f"{path} is corrupted ({why}); move it away to redo that run") from error


def check_output_dir(path: str | os.PathLike[str], subdirs: tuple[str, ...] = ()) -> Path:
    """``path`` (and ``path / sub`` for every name in ``subdirs``), created if missing, once a file of
    :data:`PROBE_BYTES` was written there atomically and removed again; a ``ValueError`` naming the directory
    and the reason when it is a file, cannot be created or cannot be written, or naming the link
    when a ``sub`` is (or passes through) a symbolic link (:func:`empathy_zoo.names.check_no_links`)."""
    root = Path(path)
    for directory in (root, *(root / sub for sub in subdirs)):
        check_no_links(root, directory)  # (the output directory itself may be a link; nothing below it)
        if directory.exists() and not directory.is_dir():
            raise ValueError(
                f"output directory {directory} is a file, not a directory; "
                "choose another output directory (--out) or move the file away"
            )
        try:
            directory.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            raise ValueError(
                f"cannot create output directory {directory} ({error.strerror or error}); choose another output directory (--out)"
            ) from None
        probe = directory / f"{PROBE_PREFIX}{os.getpid()}"
        try:
            write_bytes_atomic(probe, bytes(PROBE_BYTES))
            probe.unlink()
        except OSError as error:
            raise ValueError(
                f"output directory {directory} is not writable ({error.strerror or error}); "
                "choose another output directory (--out) or fix its permissions"
            ) from None
    return root


def remove_stale_temp_files(directory: str | os.PathLike[str]) -> list[Path]:
    """Remove the temporary files that writes killed mid-way left in ``directory`` (those of a live
    process on this machine are kept: it may still be writing); returns what was removed."""
    removed = []
    for path in Path(directory).glob(".*"):
        if not path.is_file() or not (path.name.endswith(TEMP_SUFFIX) or path.name.startswith(PROBE_PREFIX)):
            continue
        match = _OURS.search(path.name)
        pid = int(match["pid"] or match["prober"]) if match else None  # no pid: written before names carried one
        if pid is not None and _alive(pid):
            continue
        path.unlink(missing_ok=True)
        removed.append(path)
    return removed


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True  # it exists (another user's), or this system cannot tell: keep the file
    return True
