"""Atomic file writes: a reader (or a crash) never sees a half-written results file.

:func:`check_output_dir` is asked before any long work starts: it refuses an output directory
that is a file, cannot be created or cannot be written (as much as a result file and its agent file
take, or the largest file the caller will write there, a checkpoint: a full disk too), so no
training is lost at the first write. :func:`check_output_places` asks what of that needs no write
(a dry run's check).

Temporary files carry the suite's own marker (``.<name>.ezoo-<pid>-<8 hex>.tmp``, a probe
``.ezoo-write-probe-<pid>-<8 hex>``): :func:`remove_stale_temp_files` deletes only names of exactly
that form, whose writer is gone, never a file of the user's.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import secrets
import shutil
import stat
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, BinaryIO

from empathy_zoo.bounded_read import read_json_data
from empathy_zoo.limits import format_bytes
from empathy_zoo.names import cannot_create, check_no_links, check_replaceable

__all__ = [
    "write_bytes_atomic",
    "write_text_atomic",
    "write_json_atomic",
    "write_with_atomic",
    "write_all_atomic",
    "read_json",
    "check_output_dir",
    "check_output_folders",
    "check_output_places",
    "remove_stale_temp_files",
    "process_alive",
    "MAX_PID",
]

TEMP_SUFFIX = ".tmp"
"""Name suffix of the temporary file of an atomic write in progress (its name starts with ``.``)."""
TEMP_MARKER = "ezoo"
"""The suite's mark in the name of every temporary file it writes: ``.<name>.ezoo-<pid>-<8 hex>.tmp``."""
PROBE_PREFIX = ".ezoo-write-probe-"
"""Name prefix of the file :func:`check_output_dir` writes (atomically) and removes:
``.ezoo-write-probe-<pid>-<8 hex>``."""
PROBE_BYTES = 256 * 1024
"""Bytes :func:`check_output_dir` writes to each directory: as much as a run's result file and its
agent file take (≈ 200 KB at the paper's settings), so a full disk is found before training, not
after it. A caller that writes larger files (checkpoints) gives their size: that much free space
is then asked for too."""
MAX_PID = 2**31 - 1
"""The largest process id there can be (``pid_t`` is a signed 32-bit number on every system the
suite runs on): a name that carries a larger one, or one written otherwise than ``str(os.getpid())``
writes it (a leading zero), is no name the suite made."""
_PID = r"[1-9][0-9]{0,9}"
"""A process id as the suite writes it into a name (at most ten digits, no leading zero)."""
_OURS = re.compile(
    rf"\.(?:.+\.{TEMP_MARKER}-(?P<pid>{_PID})-[0-9a-f]{{8}}{re.escape(TEMP_SUFFIX)}"
    rf"|{re.escape(PROBE_PREFIX[1:])}(?P<prober>{_PID})-[0-9a-f]{{8}})"
)
"""The whole name of a temporary file this module writes, with the writer's process id."""


def write_with_atomic(path: str | os.PathLike[str], write: Callable[[BinaryIO], object]) -> Path:
    """Call ``write(file)`` on a temporary file beside ``path``, fsync it, then rename it over ``path``.

    Only nothing or a regular file is replaced: a link, a directory, a FIFO or a device in
    ``path``'s place is a ``ValueError`` naming it (:func:`empathy_zoo.names.check_replaceable`,
    asked before the directory is created and again just before the rename), and nothing is
    left behind. The file gets the permissions an ordinary write would give it: a new file
    ``0666 & ~umask`` (the kernel applies the umask), a rewritten one the mode it had."""
    path = check_replaceable(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = _write_temp(path, write)
    try:
        os.replace(tmp, check_replaceable(path))
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise
    return path


def write_all_atomic(files: Sequence[tuple[str | os.PathLike[str], bytes]]) -> list[Path]:
    """Write every ``(path, data)`` of ``files`` or none: each to a temporary file of the suite's
    own, run-specific name beside it (as :func:`write_with_atomic` names one), fsynced, and only
    once all are written rename each over its path, in order; returns the paths. Every path is
    checked (:func:`empathy_zoo.names.check_replaceable`) before anything is written. A write or
    rename that fails (a full disk) removes every temporary file this call made and raises
    ``OSError`` with the failed call's ``errno`` and ``strerror`` and, as its ``filename``, the path
    it was writing: what was in place before stays (a rename, which needs no room for the data,
    failing after an earlier one succeeded leaves that earlier file renamed)."""
    paths = [check_replaceable(path) for path, _ in files]
    staged: list[Path] = []
    current = paths[0] if paths else None
    try:
        for path, (_, data) in zip(paths, files, strict=True):
            current = path
            path.parent.mkdir(parents=True, exist_ok=True)
            staged.append(_write_temp(path, _writer(data)))
        for path, tmp in zip(paths, staged, strict=True):
            current = path
            os.replace(tmp, check_replaceable(path))
    except BaseException as error:
        for tmp in staged:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp)
        if isinstance(error, OSError):
            raise OSError(error.errno, error.strerror or str(error), str(current)) from error
        raise
    return paths


def _writer(data: bytes) -> Callable[[BinaryIO], object]:
    """What writes ``data`` to a file."""
    return lambda handle: handle.write(data)


def _write_temp(path: Path, write: Callable[[BinaryIO], object]) -> Path:
    """A temporary file beside ``path`` (:func:`_create_temp`) holding what ``write(file)`` wrote,
    fsynced, with the mode ``path`` has (a new file: the mode it was created with); removed again
    when writing it fails."""
    fd, tmp = _create_temp(path)
    try:
        with os.fdopen(fd, "wb") as handle:
            if path.exists() and hasattr(os, "fchmod"):  # a new file keeps the mode it was created with
                os.fchmod(handle.fileno(), stat.S_IMODE(path.stat().st_mode))
            write(handle)
            handle.flush()
            os.fsync(handle.fileno())
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise
    return tmp


def _create_temp(path: Path) -> tuple[int, Path]:
    """A new, empty temporary file beside ``path`` (mode ``0666 & ~umask``), named
    ``.<name>.ezoo-<pid>-<random>.tmp`` so a later run can tell it is the suite's and whose, and its
    descriptor."""
    while True:
        tmp = path.parent / f".{path.name}.{TEMP_MARKER}-{os.getpid()}-{secrets.token_hex(4)}{TEMP_SUFFIX}"
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


def read_json(path: str | os.PathLike[str], kind: str = "result file") -> Any:
    """Read a JSON file of ``kind`` (a kind of :data:`empathy_zoo.bounded_read.CAPS`) through the
    bounded reader: no regular file, one past its cap or nested too deep, or a corrupted one raises
    ``ValueError`` naming the file (it is never rewritten)."""
    return read_json_data(path, kind)


def check_output_dir(path: str | os.PathLike[str], subdirs: tuple[str, ...] = (), largest_file: int = PROBE_BYTES) -> Path:
    """``path`` (and ``path / sub`` for every name in ``subdirs``), created if missing, once a file of
    :data:`PROBE_BYTES` was written there atomically and removed again, and (when ``largest_file``,
    the largest file the caller will write, a checkpoint's estimated size, is more) once the file
    system has that much free space; a ``ValueError`` naming the directory and the reason when it
    is a file, cannot be created or cannot be written, or has too little room, or naming the link
    when a ``sub`` is (or passes through) a symbolic link (:func:`empathy_zoo.names.check_no_links`).
    Every directory is checked before the first is created, and a refusal removes again the
    directories this call created (while empty): a refused call leaves the file system as it was."""
    root = Path(path)
    directories = check_output_folders(root, subdirs)  # (all of them before any is created)
    missing = [folder for directory in directories for folder in (*reversed(directory.parents), directory) if not folder.exists()]
    created = list(dict.fromkeys(missing))
    try:
        for directory in directories:
            _check_directory(directory, largest_file)
    except BaseException:
        for folder in reversed(created):  # (only what this call made, deepest first, and only while empty)
            with contextlib.suppress(OSError):
                folder.rmdir()
        raise
    return root


def check_output_places(path: str | os.PathLike[str], subdirs: tuple[str, ...] = (), largest_file: int = PROBE_BYTES) -> Path:
    """What :func:`check_output_dir` asks of ``path`` and ``path / sub`` that needs no write: the
    same ``ValueError`` when one is a file or passes through a link below ``path``, when the nearest
    folder that exists of one cannot be written to by this user (its permissions, ``os.access``),
    or when its file system has less than ``largest_file`` free (asked when more than
    :data:`PROBE_BYTES`). Nothing is created or written (a dry run's check): a disk that refuses
    the write itself (full to its last blocks, read-only mounted) is found only by
    :func:`check_output_dir`."""
    root = Path(path)
    for directory in check_output_folders(root, subdirs):
        existing = next(folder for folder in (directory, *directory.parents) if folder.exists() or folder == folder.parent)
        if not os.access(existing, os.W_OK | os.X_OK):
            raise ValueError(
                f"output directory {directory} is not writable ({existing} does not let this user write); "
                "choose another output directory (--out) or fix its permissions"
            )
        if largest_file > PROBE_BYTES:
            _check_room(directory, shutil.disk_usage(existing).free, largest_file)
    return root


def check_output_folders(root: Path, subdirs: tuple[str, ...]) -> tuple[Path, ...]:
    """``root`` and ``root / sub`` for each of ``subdirs``, once each is no file and has no
    symbolic link below ``root`` (the output directory itself may be a link); else ``ValueError``."""
    directories = (root, *(root / sub for sub in subdirs))
    for directory in directories:
        check_no_links(root, directory)
        if directory.exists() and not directory.is_dir():
            raise ValueError(
                f"output directory {directory} is a file, not a directory; "
                "choose another output directory (--out) or move the file away"
            )
    return directories


def _check_room(directory: Path, free: int, largest_file: int) -> None:
    """Refuse ``directory`` when ``free`` bytes are less than ``largest_file``."""
    if free < largest_file:
        raise ValueError(
            f"output directory {directory} has {format_bytes(free)} free, less than the {format_bytes(largest_file)} "
            "of the largest file this run writes there (a checkpoint); free space or choose another output directory (--out)"
        )


def _check_directory(directory: Path, largest_file: int) -> None:
    """Create ``directory`` if missing, write a probe of :data:`PROBE_BYTES` there and remove it, and
    see that the file system has ``largest_file`` free; a ``ValueError`` saying what failed."""
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise cannot_create(directory, error) from None
    probe = directory / f"{PROBE_PREFIX}{os.getpid()}-{secrets.token_hex(4)}"
    try:
        write_bytes_atomic(probe, bytes(PROBE_BYTES))
        probe.unlink()
        free = shutil.disk_usage(directory).free if largest_file > PROBE_BYTES else None
    except OSError as error:
        raise ValueError(
            f"output directory {directory} is not writable ({error.strerror or error}); "
            "choose another output directory (--out) or fix its permissions"
        ) from None
    if free is not None:
        _check_room(directory, free, largest_file)


def remove_stale_temp_files(directory: str | os.PathLike[str]) -> list[Path]:
    """Remove the temporary files that the suite's writes killed mid-way left in ``directory``;
    returns what was removed. The suite deletes only names it made: a file whose whole name is of
    the form it gives its temporary files and probes (``.<name>.ezoo-<pid>-<8 hex>.tmp``,
    ``.ezoo-write-probe-<pid>-<8 hex>``, the pid at most :data:`MAX_PID`), of a writer that is no
    live process on this machine (a live one may still be writing). Any other name (``.notes.tmp``,
    a name of another program or of an earlier version, one with a pid no process can have) is left
    alone."""
    removed = []
    for path in Path(directory).glob(".*"):
        match = _OURS.fullmatch(path.name)
        if match is None or not path.is_file() or path.is_symlink():
            continue
        pid = int(match["pid"] or match["prober"])
        if pid > MAX_PID or process_alive(pid):  # (a larger pid: no writer of the suite's)
            continue
        path.unlink(missing_ok=True)
        removed.append(path)
    return removed


def process_alive(pid: int) -> bool:
    """Whether process ``pid`` may still be running on this machine (this process counts; a process
    of another user, or one this system cannot tell of, counts as running, and so does a number that
    is no process id, 0 or below or above :data:`MAX_PID`, which is never given to ``os.kill``)."""
    if pid == os.getpid() or not 0 < pid <= MAX_PID:
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True  # it exists (another user's), or this system cannot tell: keep the file
    return True
