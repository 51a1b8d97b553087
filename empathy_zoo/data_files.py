"""The files of one kind in a directory, each a regular file or refused.

A result, evaluation or agent file may come from anyone, and so may whatever lies in its place: a
FIFO, a device, a directory, a dangling symbolic link or a loop of links named ``runs/<id>.json``
would otherwise be left out of a listing without a word, and the run with it. :func:`data_files`
lists the files a command reads (the names matching a pattern) and refuses, with one
``ValueError`` line naming it, any of them that is no regular file; :func:`check_input_dir`
refuses a directory argument that names a file, or nothing, in the words every tool uses.
"""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

__all__ = ["check_input_dir", "check_regular_file", "data_files"]

_KINDS = {
    stat.S_IFIFO: "a FIFO (named pipe)",
    stat.S_IFCHR: "a character device",
    stat.S_IFBLK: "a block device",
    stat.S_IFDIR: "a directory",
    stat.S_IFSOCK: "a socket",
}
"""What a file that is no regular file is, as a refusal says it."""


def check_regular_file(path: str | os.PathLike[str], what: str = "file") -> Path:
    """``path`` if it is a regular file or a symbolic link to one; else a ``ValueError`` naming it
    (``what`` it was read as) and what it is: a FIFO, a device, a directory, a socket, a dangling
    symbolic link or a loop of links. Nothing is opened, so a FIFO is not waited on."""
    name = os.fspath(path)
    try:
        mode = os.stat(name).st_mode
    except FileNotFoundError:
        if os.path.islink(name):
            raise ValueError(
                f"{what} {name} is a dangling symbolic link (to {os.readlink(name)}), not a regular file; move it away"
            ) from None
        raise
    except OSError as error:
        if os.path.islink(name):
            why = "a loop of symbolic links" if error.errno == errno.ELOOP else "a symbolic link that cannot be followed"
            raise ValueError(f"{what} {name} is {why} ({error.strerror or error}), not a regular file; move it away") from None
        raise ValueError(f"cannot read {what} {name} ({error.strerror or error})") from None
    if not stat.S_ISREG(mode):
        kind = _KINDS.get(stat.S_IFMT(mode), "not a regular file")
        link = f" (a symbolic link to {os.readlink(name)})" if os.path.islink(name) else ""
        raise ValueError(f"{what} {name}{link} is {kind}, not a regular file; move it away")
    return Path(name)


def check_input_dir(path: str | os.PathLike[str], what: str, hint: str) -> Path:
    """``path`` if it is a directory (or a symbolic link to one) a command reads; else a
    ``ValueError`` naming it as ``what`` (``"results directory"``): ``{what} PATH is a file, not a
    directory: {hint}`` where something else is there (a file, a FIFO), ``{what} PATH does not
    exist`` where nothing is, and a loop of symbolic links named as one
    (:func:`empathy_zoo.names.resolved`)."""
    from empathy_zoo.names import resolved

    root = Path(path)
    resolved(root)  # (a loop of symbolic links is named as one, not as missing)
    if root.is_dir():
        return root
    if root.exists():
        raise ValueError(f"{what} {root} is a file, not a directory: {hint}")
    raise ValueError(f"{what} {root} does not exist")


def data_files(directory: Path, pattern: str, what: str = "file") -> list[Path]:
    """The names of ``directory`` matching the glob ``pattern`` (``"*.json"``, ``"*/*.json"``), sorted,
    each checked to be a regular file (:func:`check_regular_file`: a symbolic link to a regular file
    counts as one; a FIFO, a device, a directory, a socket, a dangling link or a loop of links
    raises ``ValueError`` naming it). Names starting with ``.`` (a write in progress) are left out;
    ``[]`` when ``directory`` is no directory."""
    root = Path(directory)
    if not root.is_dir():
        return []
    paths = sorted(path for path in root.glob(pattern) if not path.name.startswith("."))
    for path in paths:
        check_regular_file(path, what)
    return paths
