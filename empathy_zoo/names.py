"""Names that become parts of file paths (environment variants, run ids), labels that become table
rows, and paths kept inside the directory they belong to: a name read from a file or a sweep can
never point elsewhere, and a label the result-file reader accepts is exactly one a run may be built
with (:func:`check_label`, the one rule both apply)."""

from __future__ import annotations

import errno
import inspect
import os
import re
import stat
import sys
import unicodedata
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from empathy_zoo.limits import MAX_LABEL, MAX_NAME

__all__ = [
    "LABEL_REFUSED_CATEGORIES",
    "MAX_LABEL",
    "MAX_NAME",
    "PATH_NAME",
    "check_label",
    "check_output_file",
    "check_no_links",
    "check_path_name",
    "check_replaceable",
    "check_own_file",
    "cannot_create",
    "PNG_OPENING",
    "GIF_OPENING",
    "FIGURE_MARK_KEY",
    "TUNING_SUMMARY_MARK",
    "TRIALS_MARK",
    "IMPORTANCE_MARK",
    "WATCH_GIF_MARK",
    "check_marked_figure",
    "figure_marker",
    "confined",
    "positional_tool",
    "terminal_line",
]

PATH_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]*")
"""What a name used in a file name may look like: letters, digits, ``_``, ``-`` and ``.``,
starting with a letter or a digit (so never ``..``, a hidden name, a separator or an absolute path)."""
LABEL_REFUSED_CATEGORIES = frozenset({"Cc", "Cf", "Cs", "Zl", "Zp"})
"""Unicode categories a label may not hold: control characters (a newline, a tab, an escape), format
characters (a right-to-left override, a zero-width joiner), lone surrogates, and line and paragraph
separators: each would break a table row, a line of the report or the file's one-line fields."""


def check_path_name(value: Any, what: str) -> str:
    """``value`` if it may be part of a file name (:data:`PATH_NAME`), else a ``ValueError``
    naming ``what`` it is and what it may hold."""
    if not isinstance(value, str) or not PATH_NAME.fullmatch(value) or len(value) > MAX_NAME:
        raise ValueError(
            f"{what} {value!r} cannot be part of a file name: use letters, digits, '_', '-' and '.' only, "
            f"starting with a letter or a digit, at most {MAX_NAME} characters"
        )
    return value


def check_label(value: Any, what: str) -> str:
    """``value`` if it may be a label (a table row's name): a non-empty string of at most
    :data:`~empathy_zoo.limits.MAX_LABEL` characters, none of them of :data:`LABEL_REFUSED_CATEGORIES`;
    else a ``ValueError`` naming ``what`` it is and the first character refused. The writer (a run's
    label, when it is built) and the reader (a result file's) apply this same rule."""
    if not isinstance(value, str) or not value:
        raise ValueError(f"{what} must be a non-empty string, got {value!r}")
    if len(value) > MAX_LABEL:
        raise ValueError(f"{what} must be at most {MAX_LABEL} characters, got {len(value):,} ({value[:40]!r}...)")
    for position, character in enumerate(value):
        category = unicodedata.category(character)
        if category in LABEL_REFUSED_CATEGORIES:
            name = unicodedata.name(character, f"U+{ord(character):04X}")
            raise ValueError(
                f"{what} {value[:60]!r} holds {name} ({category}) at position {position}: a label is one line of "
                "printable text (no control or format characters, no line breaks)"
            )
    return value


def resolved(path: str | os.PathLike[str]) -> Path:
    """``path`` made absolute with every symbolic link followed (:meth:`Path.resolve`), or a
    one-line ``ValueError`` naming it where it cannot be: a loop of symbolic links raises
    ``RuntimeError`` up to Python 3.12 and ``OSError`` after. Every path a user gives is resolved here."""
    try:
        return Path(path).resolve()
    except (RuntimeError, OSError) as error:
        raise ValueError(f"{path} cannot be resolved ({_first_line(error)}): a loop of symbolic links; move it away") from None


def _refuse_a_loop(path: Path, error: OSError) -> None:
    """A one-line ``ValueError`` naming ``path`` where looking at it met a loop of symbolic links
    (``ELOOP``: a folder on its way links to itself); other errors are left to the write to report."""
    if error.errno == errno.ELOOP:
        raise ValueError(f"{path} cannot be resolved ({_first_line(error)}): a loop of symbolic links; move it away") from None


def confined(root: str | os.PathLike[str], *parts: str) -> Path:
    """``root / parts…``, or a ``ValueError`` when that path would lie outside ``root``, pass
    through a symbolic link below it (:func:`check_no_links`) or cannot be resolved (a loop of
    symbolic links)."""
    base = Path(root)
    path = base.joinpath(*parts)
    inside = resolved(path).is_relative_to(resolved(base))
    if not inside:
        raise ValueError(f"{path} lies outside {base}; refusing to write there")
    return check_no_links(base, path)


def _first_line(error: BaseException) -> str:
    """The first line of ``error``'s message (a message is one line of a refusal)."""
    return (str(error).splitlines() or [type(error).__name__])[0]


def check_no_links(root: str | os.PathLike[str], path: str | os.PathLike[str]) -> Path:
    """``path`` if none of its components below ``root`` is a symbolic link (``root`` itself may be
    one: whoever named it chose it), else a ``ValueError`` naming the link and its target: nothing
    is written through a link inside an output directory. ``path`` must lie below ``root``."""
    base, target = Path(root), Path(path)
    try:
        parts = target.relative_to(base).parts
    except ValueError:
        raise ValueError(f"{target} lies outside {base}; refusing to write there") from None
    current = base
    for part in parts:
        if part == "..":
            raise ValueError(f"{target} leaves {base} ('..'); refusing to write there")
        current = current / part
        if current.is_symlink():
            raise ValueError(
                f"{current} is a symbolic link (to {os.readlink(current)}) inside the output directory {base}: "
                "refusing to write through it; remove the link (a real directory is created in its place) "
                "or choose another output directory"
            )
    return target


_KINDS = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISFIFO, "a FIFO (a named pipe)"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)
"""What may lie in a file's place but a regular file or a link, as a refusal names it."""


PNG_OPENING = b"\x89PNG\r\n\x1a\n"
"""The first bytes of every PNG file."""
GIF_OPENING = b"GIF8"
"""The first bytes of every GIF file (``GIF87a``, ``GIF89a``)."""

FIGURE_MARK_KEY = "Software"
"""The key of the PNG ``tEXt`` chunk that marks a figure the suite wrote (its value: one of the marks below)."""
TUNING_SUMMARY_MARK = "empathy-zoo tuning-summary"
"""The mark of the figure ``analyse tuning-summary --figure`` writes."""
TRIALS_MARK = "empathy-zoo trials"
"""The mark of the ``trials.png`` figure ``tune`` writes."""
IMPORTANCE_MARK = "empathy-zoo importance"
"""The mark of the ``importance.png`` figure ``tune`` writes."""
WATCH_GIF_MARK = "empathy-zoo watch"
"""The comment of the GIF ``watch --gif`` writes."""
MARK_HEAD_BYTES = 64 * 1024
"""Bytes of a file read, at most, to find its mark (the suite writes it before the image data)."""


def figure_marker(opening: bytes, mark: str) -> bytes:
    """The bytes ``mark`` takes in a file that begins with ``opening``: a PNG's ``tEXt`` chunk
    keyed :data:`FIGURE_MARK_KEY` (as Matplotlib's ``savefig(metadata=...)`` writes it), a GIF's
    comment extension (as Pillow's ``save(comment=...)`` writes it)."""
    text = mark.encode("latin-1")
    if opening == PNG_OPENING:
        data = FIGURE_MARK_KEY.encode("latin-1") + b"\0" + text
        return len(data).to_bytes(4, "big") + b"tEXt" + data
    return b"\x21\xfe" + bytes([len(text)]) + text + b"\0"


def _head(target: Path, count: int) -> bytes | None:
    """The first ``count`` bytes of the regular, non-empty file ``target``; ``None`` where nothing
    is there, anything but a regular file, or an empty file (a loop of links refused by name)."""
    try:
        status = os.lstat(target)
        if not stat.S_ISREG(status.st_mode) or status.st_size == 0:
            return None
        with open(target, "rb") as handle:
            return handle.read(count)
    except OSError as error:
        _refuse_a_loop(target, error)
        return None


def check_marked_figure(path: str | os.PathLike[str], kind: str, opening: bytes, mark: str) -> Path:
    """``path`` if nothing is there, or anything but a regular file (:func:`check_replaceable`
    says what of those), or an empty file, or a file that begins with ``opening`` and holds the
    mark ``mark`` (:func:`figure_marker`) in its first :data:`MARK_HEAD_BYTES` bytes: a ``kind``
    figure the suite wrote there; else a ``ValueError`` naming it. Another image (a user's, or
    one the suite wrote for another purpose) is never replaced."""
    target = Path(path)
    head = _head(target, MARK_HEAD_BYTES)
    if head is None:
        return target
    if not head.startswith(opening) or figure_marker(opening, mark) not in head:
        raise ValueError(f"{target} exists and is no {kind} figure this suite wrote: move it away or choose another path")
    return target


def check_own_file(path: str | os.PathLike[str], kind: str, opening: bytes) -> Path:
    """``path`` if nothing is there, or anything but a regular file (:func:`check_replaceable`
    says what of those), or an empty file (it holds nothing to lose), or a regular file that begins
    with ``opening`` (the first bytes of every ``kind`` file the writer makes: a page's title, a
    figure's signature); else a ``ValueError`` naming it: the suite replaces a file only with one of
    the same kind, never a user's other file of that name. Only ``len(opening)`` bytes are read."""
    target = Path(path)
    head = _head(target, len(opening))
    if head is None:
        return target
    if head != opening:
        shown = terminal_line(opening.rstrip(b"\n").decode("utf-8", errors="backslashreplace"))
        raise ValueError(
            f"{target} exists and is no {kind} this suite writes (those begin “{shown}”): the suite replaces only "
            "its own; move the file away or name another"
        )
    return target


def check_output_file(out: str | os.PathLike[str], kind: str, suffix: str, example: str, opening: bytes | None = None) -> Path:
    """``out`` as a path if a ``kind`` file (``"PNG"``, ``"JSON"``) can be written there; else a
    ``ValueError`` naming it: an existing directory, a name not ending in ``suffix``, anything but
    a regular file in its place (:func:`check_replaceable`), a regular file that does not begin
    with ``opening`` where one is given (:func:`check_own_file`), or a parent that is a file.
    ``example`` is a file name a message suggests."""
    path = Path(out)
    if path.is_dir() and not path.is_symlink():
        raise ValueError(f"{out} is a directory: name the {kind} file to write (e.g. {path / example})")
    if path.suffix.lower() != suffix:
        raise ValueError(f"{out} is no {kind} file name: name the file to write, ending in {suffix} (e.g. {example})")
    check_replaceable(path)  # (only nothing or a regular file is replaced: never a link, a FIFO or a device)
    if opening is not None:
        check_own_file(path, f"{kind} file", opening)
    parent = next((folder for folder in path.absolute().parents if folder.exists()), None)
    if parent is not None and not parent.is_dir():
        raise ValueError(f"{out} cannot be written: {parent} is a file, not a directory")
    return path


def check_output_folder(out: str | os.PathLike[str], option: str = "--out") -> Path:
    """``out`` as a path if a folder is there or can be made there (nothing is made): a ``ValueError``
    naming it where ``out`` itself, or the nearest of its parents that exists, is no directory (a
    file in the way), or a loop of symbolic links lies on its way. Asked before a long computation
    whose results go into ``out``, so a folder that cannot be is refused before the work, not after."""
    path = Path(out)
    resolved(path)  # (a loop on the way: named as one)
    existing = next((folder for folder in (path, *path.parents) if folder.exists()), None)
    if existing is not None and not existing.is_dir():
        where = "is a file" if existing == path else f"lies under {existing}, which is a file"
        raise ValueError(f"{option} {out} {where}, not a folder: give a folder for the files")
    return path


def check_replaceable(path: str | os.PathLike[str]) -> Path:
    """``path`` if the suite may write a file there: nothing is there, or a regular file that is
    no symbolic link (which the write replaces, or appends to); else a ``ValueError`` naming
    ``path`` and what is there (a link with its target, a directory, a FIFO, a device, a socket).
    Every writer asks it of every file before it writes the first (:mod:`empathy_zoo.atomic`
    asks it again of each file it writes): the suite never replaces, and never writes through,
    anything but a regular file. A path whose directory is missing (or cannot be looked into)
    has nothing there: creating or writing it says what is wrong."""
    target = Path(path)
    try:
        mode = os.lstat(target).st_mode
    except OSError as error:
        _refuse_a_loop(target, error)
        return target
    if stat.S_ISREG(mode):
        return target
    if stat.S_ISLNK(mode):
        try:
            kind = f"a symbolic link (to {os.readlink(target)})"
        except OSError:
            kind = "a symbolic link"
    else:
        kind = next((name for test, name in _KINDS if test(mode)), "no regular file")
    raise ValueError(
        f"{target} is {kind}, not a regular file: the suite replaces only a regular file it may write, "
        "and never writes through a link; move it away or choose another path"
    )


def terminal_line(text: object) -> str:
    """``text`` as one line that shows as itself on a terminal: each control or format character,
    line break or lone surrogate (:data:`LABEL_REFUSED_CATEGORIES`) written as its code
    (``\\x1b``), so a name read from a file or a file name cannot move the cursor, retitle the
    window or break the line."""
    return "".join(
        c.encode("unicode_escape").decode("ascii") if unicodedata.category(c) in LABEL_REFUSED_CATEGORIES else c
        for c in str(text)
    )


def positional_tool(prog: str, usage: str, args: Sequence[str], count: int, body: Callable[[list[str]], int]) -> int:
    """Run a tool that takes ``count`` paths and nothing else: ``body(paths)``'s status, or 2 with
    ``usage`` (``usage: python -m ...``) and a line ``prog: error: ...`` saying what is wrong (as
    argparse says it) when the arguments are not ``count`` paths (an unknown option included), or
    2 with one line ``prog: error: ...`` when a file it reads is refused (a ``ValueError`` or
    ``OSError``: never a traceback)."""
    paths = list(args)
    options = [path for path in paths if path.startswith("-")]
    if options or len(paths) != count:
        wanted = f"{count} path{'s' if count != 1 else ''}"
        given = ", ".join(terminal_line(path) for path in paths[:5]) + (", ..." if len(paths) > 5 else "")
        problem = (
            f"unrecognized arguments: {' '.join(terminal_line(option) for option in options[:5])}"
            if options
            else f"takes {wanted}, got {len(paths)}{f': {given}' if paths else ''}"
        )
        print(f"{usage}\n{prog}: error: {problem}", file=sys.stderr)
        return 2
    try:
        return body(paths)
    except (ValueError, OSError) as error:
        print(f"{prog}: error: {terminal_line(error)}", file=sys.stderr)
        return 2


_ROLE = re.compile(r":[a-z]+:`~?([^`<]+?)(?:\s*<[^>]+>)?`")


def tool_help(usage: str, doc: str | None) -> str:
    """The ``--help`` text of a tool that :func:`positional_tool` runs: ``usage``, then its module's
    docstring ``doc`` (what it reads, matches and refuses), its cross-references as plain names."""
    text = _ROLE.sub(lambda found: found.group(1).strip(), inspect.cleandoc(doc or ""))
    return f"{usage}\n\n{text}" if text else usage


def cannot_create(directory: Path, error: OSError) -> ValueError:
    """The refusal of an output ``directory`` that ``mkdir`` could not create (``error``): what
    is in the way where a plain "File exists" would not say (a symbolic link, on its path, to
    nothing), and what to do."""
    reason = error.strerror or str(error)
    for place in (directory, *directory.parents):
        if place.is_symlink() and not place.exists():
            try:
                place.resolve(strict=True)
            except (RuntimeError, OSError) as looking:  # (a loop raises RuntimeError up to Python 3.12, ELOOP after)
                if isinstance(looking, RuntimeError) or looking.errno == errno.ELOOP:
                    reason = f"{place} is a loop of symbolic links (a link to {os.readlink(place)})"
                    break
            reason = f"{place} is a symbolic link to {os.readlink(place)}, which does not exist"
            break
    return ValueError(f"cannot create output directory {directory} ({reason}); choose another output directory (--out)")
