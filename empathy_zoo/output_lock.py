"""One process at a time on an output directory.

``train``/``reproduce`` and ``evaluate`` hold :func:`hold_output_dir` while they write to a
directory: a second process asked to write there meanwhile is refused at once, with who holds it
(process id, host, command and since when), instead of training the same runs a second time beside
the first (their files would be identical, the work doubled). The lock is an advisory ``flock`` on
``<dir>/.empathy-zoo.lock``: the operating system releases it when its process ends, however it
ends (a ``kill -9`` included), so a crash never leaves a directory locked; the file is removed on
a clean exit. On a system without ``fcntl`` (Windows) the directory is not locked, and the call
says so once through its ``on_note``.
"""

from __future__ import annotations

import json
import os
import socket
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress
from pathlib import Path

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]

__all__ = ["LOCK_NAME", "DirectoryInUse", "command_line", "hold_output_dir"]

LOCK_NAME = ".empathy-zoo.lock"
"""The lock file's name inside the directory it locks."""
_HOLDER_BYTES = 4096
"""The most of a lock file that is read to say who holds it."""


class DirectoryInUse(ValueError):
    """The directory is held by another process (the message says which)."""


def _holder(fd: int) -> str:
    """Who holds the lock, from what its holder wrote into the file (or 'another process')."""
    try:
        info = json.loads(os.pread(fd, _HOLDER_BYTES, 0).decode("utf-8"))
        started = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime(float(info["since"])))
        return f"process {int(info['pid'])} on {info['host']} ({info['command']}, since {started})"
    except (OSError, ValueError, KeyError, TypeError):  # (written by its holder a moment from now)
        return "another process"


def _acquire(path: Path, fd: int) -> bool:
    """Whether ``fd`` (an open ``path``) now holds the lock of the file at ``path``: ``False``
    when another process holds it. A file removed by its last holder between our open and our lock
    is not the lock any more (``path`` names a new file, or none): then ``OSError`` ``ESTALE``
    asks the caller to open again."""
    assert fcntl is not None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    try:
        current = os.stat(path, follow_symlinks=False).st_ino
    except FileNotFoundError:
        current = None
    if current != os.fstat(fd).st_ino:
        fcntl.flock(fd, fcntl.LOCK_UN)
        raise OSError(116, "lock file replaced")  # ESTALE: open again
    return True


@contextmanager
def hold_output_dir(
    directory: str | os.PathLike[str], command: str, on_note: Callable[[str], None] | None = None
) -> Iterator[Path]:
    """Hold ``directory`` (which exists) for this process while the ``with`` block runs; yields the
    lock file. ``DirectoryInUse`` (a ``ValueError``) naming the holder when another process holds
    it. ``command`` says what this process is doing (shown to a process refused meanwhile)."""
    path = Path(directory) / LOCK_NAME
    if fcntl is None:  # pragma: no cover - Windows
        if on_note is not None:
            on_note(f"{directory} is not locked on this system (no fcntl): do not run two processes on it")
        yield path
        return
    for _attempt in range(100):
        fd = os.open(path, os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0), 0o644)
        try:
            if not _acquire(path, fd):
                holder = _holder(fd)
                raise DirectoryInUse(
                    f"{directory} is in use by {holder}: two processes on one directory would do the same "
                    "work twice; wait for it to finish (what it finished is then reused) or choose another "
                    "output directory (--out)"
                )
        except OSError as error:
            os.close(fd)
            if error.errno == 116:
                continue
            raise
        except BaseException:
            os.close(fd)
            raise
        break
    else:  # pragma: no cover - a hundred replaced files in a row
        raise DirectoryInUse(f"{directory}: its lock file {path} keeps being replaced; is another process looping on it?")
    try:
        info = {"pid": os.getpid(), "host": socket.gethostname(), "command": command[:200], "since": time.time()}
        os.ftruncate(fd, 0)
        os.pwrite(fd, json.dumps(info).encode("utf-8"), 0)
        yield path
    finally:
        with suppress(OSError):
            path.unlink()  # (still holding the lock: a process that opened it meanwhile sees it replaced)
        os.close(fd)


def command_line() -> str:
    """This process's command line, for the lock file."""
    return " ".join([Path(sys.argv[0]).name, *sys.argv[1:]]) if sys.argv and sys.argv[0] else "python"
