"""One process at a time on an output directory.

``train``/``reproduce`` and ``evaluate`` hold :func:`hold_output_dir` while they write to a
directory: a second process asked to write there meanwhile is refused at once, with who holds it
(process id, host, command and since when), instead of training the same runs a second time beside
the first (their files would be identical, the work doubled). The lock is an advisory ``flock`` on
``<dir>/.empathy-zoo.lock``: the operating system releases it when its process ends, however it
ends (a ``kill -9`` included), so a crash never leaves a directory locked; the file is removed on
a clean exit (one taken over and then refused is put back as it was). On a system without
``fcntl`` (Windows) the directory is not locked, and the call says so once through its ``on_note``.

The lock file's place may hold anything a user (or a hostile results directory) put there. The
suite creates the file itself (``O_EXCL``), or takes over one it left before (a regular file with
one link, empty or holding a holder's record); anything else there (a symbolic link, a hard link
to another file, a directory, a FIFO, a device, a file of other content) is refused in one line
naming it, without being opened for writing, changed or removed. A file taken over holds this
call's record while it holds the lock; a block that raises (a refused command, one that failed
or was stopped) puts it back byte for byte, with its times, so a refusal changes nothing; one
that finishes removes it, as a file this call created is removed on leaving, and only while it is
still the one in that place. The directory itself is created when missing (and removed again on
leaving while it is empty), so a caller takes the lock before it creates anything inside the
directory.
"""

from __future__ import annotations

import errno
import json
import os
import socket
import stat
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress
from pathlib import Path

from empathy_zoo.names import cannot_create

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]

__all__ = ["LOCK_NAME", "DirectoryInUse", "UnsafeLockFile", "command_line", "hold_output_dir"]

LOCK_NAME = ".empathy-zoo.lock"
"""The lock file's name inside the directory it locks."""
_HOLDER_BYTES = 4096
"""The most of a lock file that is read to say who holds it."""


_RECORD_START = b'{"pid": '
"""How every holder's record (what :func:`hold_output_dir` writes into the file) starts."""
_OPEN_EXISTING = os.O_RDWR | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
"""How a lock file already there is opened: never through a link, never waiting on a FIFO."""
_KINDS = (
    (stat.S_ISLNK, "a symbolic link"),
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISFIFO, "a FIFO (a named pipe)"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)
"""What may lie in the lock file's place but a regular file, as a refusal names it."""


class DirectoryInUse(ValueError):
    """The directory is held by another process (the message says which)."""


class UnsafeLockFile(ValueError, OSError):
    """Something in the lock file's place that is not the suite's lock file (the message names it
    and what it is); left as it was. A ``ValueError`` (a refusal the command line prints in one
    line) that is an ``OSError`` too, as the failed ``open`` it replaces was."""


def _refuse(path: Path, what: str) -> UnsafeLockFile:
    return UnsafeLockFile(
        f"{path} is {what}, not this suite's lock file: it is left as it is (never written through, "
        "changed or removed); move it away or choose another output directory (--out)"
    )


def _check_place(path: Path, status: os.stat_result) -> None:
    """Refuse (:class:`UnsafeLockFile`) what ``status`` (``lstat`` of ``path``) shows unless it is a
    regular file with one link."""
    if not stat.S_ISREG(status.st_mode):
        kind = next((name for test, name in _KINDS if test(status.st_mode)), "no regular file")
        if stat.S_ISLNK(status.st_mode):
            with suppress(OSError):
                kind += f" (to {os.readlink(path)})"
        raise _refuse(path, kind)
    if status.st_nlink != 1:
        raise _refuse(path, f"a file with {status.st_nlink} hard links (another name of a file kept elsewhere)")


def _open_lock(path: Path) -> tuple[int, bool]:
    """The lock file ``path`` open for reading and writing, and whether this call created it: created
    new (``O_EXCL``), else the regular, singly linked file there, opened without following a link or
    waiting on a FIFO and seen to be the file that was checked; anything else in its place is
    refused (:class:`UnsafeLockFile`) untouched. An ``OSError`` of ``ENOENT`` asks the caller to try
    again (the file went away meanwhile)."""
    flags = os.O_RDWR | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        return os.open(path, flags, 0o644), True
    except FileExistsError:
        pass
    status = os.lstat(path)  # (FileNotFoundError: gone meanwhile; the caller tries again)
    _check_place(path, status)
    try:
        fd = os.open(path, _OPEN_EXISTING | getattr(os, "O_CLOEXEC", 0))
    except OSError as error:
        if error.errno == errno.ENOENT:
            raise
        raise _refuse(path, f"a file this process cannot open for writing ({error.strerror or error})") from None
    opened = os.fstat(fd)
    if (opened.st_dev, opened.st_ino) != (status.st_dev, status.st_ino):  # (replaced between lstat and open)
        os.close(fd)
        raise OSError(errno.ENOENT, "lock file replaced")
    try:
        _check_place(path, opened)
    except BaseException:
        os.close(fd)
        raise
    return fd, False


def _check_contents(path: Path, fd: int) -> None:
    """Refuse a lock file left before (by a process that was killed) unless it holds what a holder
    writes: nothing (killed before it wrote), or a record (:data:`_RECORD_START`) of at most
    :data:`_HOLDER_BYTES`. Asked while holding the lock, before the file is changed."""
    size = os.fstat(fd).st_size
    head = os.pread(fd, len(_RECORD_START), 0)
    if size > _HOLDER_BYTES or (size and not _RECORD_START.startswith(head[: len(_RECORD_START)])):
        raise _refuse(path, f"a file of {size:,} bytes that holds no holder's record")


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
        raise OSError(errno.ESTALE, "lock file replaced")  # open again
    return True


@contextmanager
def hold_output_dir(
    directory: str | os.PathLike[str], command: str, on_note: Callable[[str], None] | None = None
) -> Iterator[Path]:
    """Hold ``directory`` for this process while the ``with`` block runs; yields the lock file.
    ``DirectoryInUse`` (a ``ValueError``) naming the holder when another process holds it;
    :class:`UnsafeLockFile` (a ``ValueError``) naming what lies in the lock file's place when it is
    not the suite's lock file; a ``ValueError`` naming ``directory`` when it is a file or cannot be
    created or written. ``directory`` is created when missing, and removed again on leaving while
    empty (with the parents this call created), so nothing need be created before the lock is
    taken. ``command`` says what this process is doing (shown to a process refused meanwhile)."""
    root = Path(directory)
    path = root / LOCK_NAME
    created = _make_directory(root)
    try:
        if fcntl is None:  # pragma: no cover - Windows
            if on_note is not None:
                on_note(f"{directory} is not locked on this system (no fcntl): do not run two processes on it")
            yield path
            return
        with _locked(root, path, command):
            yield path
    finally:
        for folder in reversed(created):  # (only what this call made, deepest first, and only while empty)
            with suppress(OSError):
                folder.rmdir()


def _make_directory(root: Path) -> list[Path]:
    """Create ``root`` (and its missing parents) when missing; returns the directories created. A
    ``ValueError`` naming it when it is a file or cannot be created."""
    if root.exists() and not root.is_dir():
        raise ValueError(
            f"output directory {root} is a file, not a directory; choose another output directory (--out) or move the file away"
        )
    created = [folder for folder in (*reversed(root.parents), root) if not folder.exists()]
    try:
        root.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        for folder in reversed(created):
            with suppress(OSError):
                folder.rmdir()
        raise cannot_create(root, error) from None
    return created


@contextmanager
def _locked(root: Path, path: Path, command: str) -> Iterator[None]:
    """Hold the lock file ``path`` of ``root`` while the block runs (see :func:`hold_output_dir`)."""
    assert fcntl is not None
    for _attempt in range(100):
        try:
            fd, created = _open_lock(path)
            found = os.fstat(fd)  # (its times before a byte of it is read)
        except UnsafeLockFile:
            raise
        except OSError as error:
            if error.errno == errno.ENOENT and root.is_dir():
                continue  # (the file went away between looking and opening)
            raise ValueError(
                f"output directory {root} is not writable ({error.strerror or error}); "
                "choose another output directory (--out) or fix its permissions"
            ) from None
        try:
            if not _acquire(path, fd):
                holder = _holder(fd)
                raise DirectoryInUse(
                    f"{root} is in use by {holder}: two processes on one directory would do the same "
                    "work twice; wait for it to finish (what it finished is then reused) or choose another "
                    "output directory (--out)"
                )
            _check_contents(path, fd)
        except OSError as error:
            os.close(fd)
            if error.errno == errno.ESTALE and not isinstance(error, UnsafeLockFile):
                continue
            raise
        except BaseException:
            os.close(fd)
            raise
        break
    else:  # pragma: no cover - a hundred replaced files in a row
        raise DirectoryInUse(f"{root}: its lock file {path} keeps being replaced; is another process looping on it?")
    before = None if created else _contents(fd, found)  # (a file taken over: put back as it was if the block fails)
    try:
        info = {"pid": os.getpid(), "host": socket.gethostname(), "command": command[:200], "since": time.time()}
        os.ftruncate(fd, 0)
        os.pwrite(fd, json.dumps(info).encode("utf-8"), 0)
        yield
    except BaseException:
        if before is None:
            _remove_own(path, fd)
        else:
            _put_back(fd, before)  # (a refused or failed command leaves the file it found as it was)
        raise
    else:
        _remove_own(path, fd)  # (still holding the lock: a process that opened it meanwhile sees it replaced)
    finally:
        os.close(fd)


def _contents(fd: int, found: os.stat_result) -> tuple[bytes, int, int]:
    """What the lock file open as ``fd`` holds (at most :data:`_HOLDER_BYTES`, as
    :func:`_check_contents` saw) and its access and modification times as ``found`` (its ``fstat``
    before it was read) has them, in nanoseconds."""
    return os.pread(fd, _HOLDER_BYTES, 0), found.st_atime_ns, found.st_mtime_ns


def _put_back(fd: int, before: tuple[bytes, int, int]) -> None:
    """Give the lock file open as ``fd`` back the bytes and times it had (:func:`_contents`) before
    this call took it over: a file the suite did not create is left as it was."""
    data, accessed, modified = before
    with suppress(OSError):
        os.ftruncate(fd, 0)
        os.pwrite(fd, data, 0)
        if os.utime in os.supports_fd:
            os.utime(fd, ns=(accessed, modified))


def _remove_own(path: Path, fd: int) -> None:
    """Remove ``path`` if it is still the file open as ``fd`` (what this call held), and nothing else."""
    with suppress(OSError):
        held, there = os.fstat(fd), os.lstat(path)
        if stat.S_ISREG(there.st_mode) and (there.st_dev, there.st_ino) == (held.st_dev, held.st_ino):
            path.unlink()


def command_line() -> str:
    """This process's command line, for the lock file."""
    return " ".join([Path(sys.argv[0]).name, *sys.argv[1:]]) if sys.argv and sys.argv[0] else "python"
