"""One bounded reader for every file the suite reads that it did not just write.

A result, evaluation, agent, checkpoint or journal file may come from anyone. Each is read through
:func:`read_data` (or, for a checkpoint streamed into ``torch.load``, :func:`open_data`): a file that
is no regular file (a FIFO, a device, a directory, a dangling symbolic link or a loop of links) is
refused without waiting on it, one larger than the cap of its kind (:data:`CAPS`, the bounds of
:mod:`empathy_zoo.limits`) is refused by its size before it is read, and JSON nested deeper than
:data:`~empathy_zoo.limits.MAX_JSON_DEPTH` is refused before it is parsed (:func:`check_json_depth`).
JSON is parsed by :func:`parse_json`, which refuses an object holding one key twice (Python's
reader would keep the last silently, and another reader the first). Every refusal is one ``ValueError`` line naming the file.
"""

from __future__ import annotations

import json
import os
from typing import Any, BinaryIO

import numpy as np

from empathy_zoo.limits import (
    BOUNDS,
    MAX_JSON_DEPTH,
    format_bytes,
    open_regular,
    read_bounded,
)

__all__ = [
    "CAPS",
    "DuplicateKeyError",
    "check_json_depth",
    "json_depth",
    "open_data",
    "parse_json",
    "read_data",
    "read_json_data",
]

FILE_KINDS = ("result file", "evaluation file", "agent file", "checkpoint", "list of runs", "tuning journal")
"""The kinds of file read through :func:`read_data`, as :data:`~empathy_zoo.limits.BOUNDS` names them."""
CAPS: dict[str, int] = {kind: BOUNDS[kind] for kind in FILE_KINDS}
"""The largest file of each kind read, by what a refusal calls it."""

_QUOTE, _BACKSLASH = ord('"'), ord("\\")
"""The bytes that open or close a JSON string (a quote) and escape the next one (a backslash)."""
_STEPS = np.array([1 if code in b"[{" else -1 if code in b"]}" else 0 for code in range(256)], np.int8)
"""What each byte adds to the depth outside strings: 1 for ``[`` and ``{``, -1 for ``]`` and ``}``."""
_CHUNK = 1 << 22
"""Bytes scanned at once (any file is scanned in bounded memory)."""


def read_data(path: str | os.PathLike[str], kind: str) -> bytes:
    """The bytes of the file ``path`` of ``kind`` (a key of :data:`CAPS`): a regular file of at
    most its cap, else a ``ValueError`` naming it."""
    return read_bounded(path, CAPS[kind], kind)


def open_data(path: str | os.PathLike[str], kind: str) -> BinaryIO:
    """``path`` open for reading, once it is a regular file of at most the cap of ``kind``
    (``ValueError`` naming it otherwise, a dangling symbolic link in its place too): for a file
    streamed into a reader, not read into memory."""
    name = os.fspath(path)
    try:
        handle = open_regular(path, kind)
    except FileNotFoundError:
        if os.path.islink(name):
            raise ValueError(
                f"{kind} {name} is a dangling symbolic link (to {os.readlink(name)}), not a regular file; move it away"
            ) from None
        raise
    size = os.fstat(handle.fileno()).st_size
    if size > CAPS[kind]:
        handle.close()
        raise ValueError(
            f"{kind} {os.fspath(path)} is larger than {format_bytes(CAPS[kind])}, the most it may be (docs/limits.md)"
        )
    return handle


def json_depth(data: bytes, limit: int = MAX_JSON_DEPTH) -> int:
    """How deep arrays and objects nest in the JSON text ``data`` (brackets in strings do not
    count), counted no further than past ``limit``. One pass over the text, a chunk at a time
    (time linear in its length, whatever it holds: ``"\\"\\"\\"…`` too): a quote after an even
    number of backslashes opens or closes a string, one after an odd number is in it."""
    deepest, depth = 0, 0
    in_string, backslashes = 0, 0  # (carried from chunk to chunk: inside a string; the backslashes ending the last chunk)
    for start in range(0, len(data), _CHUNK):
        codes = np.frombuffer(data, np.uint8, count=min(_CHUNK, len(data) - start), offset=start)
        quotes = codes == _QUOTE
        slashes = codes == _BACKSLASH
        if backslashes or slashes.any():
            index = np.arange(codes.size, dtype=np.int64)
            last_other = np.maximum.accumulate(np.where(slashes, -1 - backslashes, index))  # (the last byte no backslash)
            run = index - 1 - np.concatenate(([-1 - backslashes], last_other[:-1]))  # (the backslashes before each byte)
            quotes &= run % 2 == 0
            backslashes = int(codes.size - 1 - last_other[-1])
        else:
            backslashes = 0
        if not quotes.any() and in_string:
            continue
        steps = _STEPS[codes]
        if quotes.any():
            inside = np.bitwise_xor.accumulate(quotes.view(np.uint8)) ^ in_string
            in_string = int(inside[-1])
            steps[inside.view(bool)] = 0
        levels = depth + np.cumsum(steps, dtype=np.int64)
        deepest, depth = max(deepest, int(levels.max())), int(levels[-1])
        if deepest > limit:
            break
    return deepest


def check_json_depth(data: bytes, where: str, limit: int = MAX_JSON_DEPTH) -> None:
    """Refuse (``ValueError`` naming ``where``) JSON text nested deeper than ``limit``."""
    if json_depth(data, limit) > limit:
        raise ValueError(
            f"{where} nests arrays and objects more than {limit} deep, deeper than any file of the suite (docs/limits.md)"
        )


class DuplicateKeyError(ValueError):
    """A JSON object holds one key twice."""


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """The object of ``pairs``, else :class:`DuplicateKeyError` naming the first key given twice."""
    table: dict[str, Any] = {}
    for key, value in pairs:
        if key in table:
            raise DuplicateKeyError(f"an object holds the key {key[:60]!r} twice")
        table[key] = value
    return table


def parse_json(text: str | bytes) -> Any:
    """The JSON document ``text`` (``json.loads``), an object holding one key twice refused with
    :class:`DuplicateKeyError` (a ``ValueError``): which of the two a reader keeps is no rule."""
    return json.loads(text, object_pairs_hook=_unique_keys)


def read_json_data(path: str | os.PathLike[str], kind: str) -> Any:
    """The JSON document of the file ``path`` of ``kind`` (:func:`read_data`, then
    :func:`check_json_depth`); text that is no JSON raises ``ValueError`` naming the file."""
    data = read_data(path, kind)
    check_json_depth(data, f"{kind} {os.fspath(path)}")
    try:
        return parse_json(data.decode("utf-8"))
    except (ValueError, RecursionError) as error:  # (bad JSON or UTF-8, an int of over 4,300 digits, a key twice)
        why = f"{type(error).__name__}: {str(error)[:200]}"
        raise ValueError(f"{os.fspath(path)} is corrupted ({why}); move it away to redo that run") from None
