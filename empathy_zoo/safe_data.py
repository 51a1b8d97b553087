"""Plain data that ``torch.load(weights_only=True)`` accepts: numpy arrays (anywhere in dicts and
lists) as tensors and back. Checkpoints (the trainer's, and a learner's own state, e.g. SB3's) are
stored this way, so loading one never runs code.

The zip archive ``torch.save`` writes is checked before ``torch.load`` (or a library's ``load``)
reads a byte of it: :func:`zip_members` reads a zip's central directory only, once its end record
and the bytes of that directory say it holds no more members than its caller allows (nothing is
decompressed), and :func:`torch_zip_problem` says what makes those members no archive of
``torch.save``: a member that is no record it writes, a compressed one (``torch.save`` stores every
member as it is, so a member is as large in the file as once read: a deflated one could expand to
gigabytes), or members declaring more bytes than the file holds."""

from __future__ import annotations

import re
import struct
import zipfile
from typing import Any, BinaryIO

import numpy as np
import torch

__all__ = ["to_safe", "from_safe", "zip_members", "torch_zip_problem", "ZIP_ENTRY_BYTES", "TORCH_RECORD"]

ZIP_ENTRY_BYTES = 1024
"""Most bytes of a zip's central directory per member it may hold: a member's entry is 46 bytes,
its name (``torch.save``'s are ``<archive>/data/<n>``, the archive named after the file, at most 255
bytes) and its extra fields."""
TORCH_RECORD = re.compile(
    r"(?:data\.pkl|byteorder|version|\.format_version|\.storage_alignment|\.data/version|\.data/serialization_id|data/[0-9]+)\Z"
)
"""The records ``torch.save`` writes in its archive's one folder: the pickle, its storages
(``data/<n>``) and what says how to read them (older versions write fewer)."""
_END = struct.Struct("<4s4H2LH")
"""A zip's end of central directory record (22 bytes; then a comment of up to 64 KiB)."""
_END64_LOCATOR = struct.Struct("<4sLQL")
"""The ZIP64 end of central directory locator, just before the end record (20 bytes)."""
_END64 = struct.Struct("<4sQ2H2L4Q")
"""The ZIP64 end of central directory record, just before its locator (56 bytes)."""
_CENTRAL_ENTRY = b"PK\x01\x02"
"""What each member's entry in a zip's central directory begins with."""


def to_safe(value: Any) -> Any:
    """Turn numpy arrays (anywhere in dicts/lists) into tensors ``torch.load(weights_only=True)`` accepts."""
    if isinstance(value, np.ndarray):
        if value.dtype == np.uint64:
            return {"__ndarray__": torch.from_numpy(value.view(np.int64).copy()), "dtype": "uint64"}
        return {"__ndarray__": torch.from_numpy(np.ascontiguousarray(value).copy()), "dtype": str(value.dtype)}
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, dict):
        return {key: to_safe(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_safe(item) for item in value]
    return value


NUMERIC_KINDS = "biuf"
"""Kinds of numpy dtype an array read back may have: booleans, integers, floats (no objects, no strings)."""


def from_safe(value: Any) -> Any:
    """Inverse of :func:`to_safe`; an array that is no tensor, or of a dtype that is no number (an
    object, a string), raises ``ValueError``."""
    if isinstance(value, dict):
        if "__ndarray__" in value:
            tensor, dtype = value["__ndarray__"], value.get("dtype")
            if not isinstance(tensor, torch.Tensor) or not isinstance(dtype, str):
                raise ValueError(f"an array is stored as a {type(tensor).__name__} of dtype {dtype!r}, not a tensor")
            try:
                kind: str = np.dtype(dtype).kind
            except TypeError:
                kind = ""
            if not kind or kind not in NUMERIC_KINDS:
                raise ValueError(f"an array has dtype {dtype!r}, which is no number")
            array = tensor.numpy()
            return array.view(np.uint64) if value["dtype"] == "uint64" else array.astype(value["dtype"], copy=False)
        return {key: from_safe(item) for key, item in value.items()}
    if isinstance(value, list):
        return [from_safe(item) for item in value]
    return value


def _central_directory(file: BinaryIO, size: int) -> tuple[int, int, int] | None:
    """``(members, start, length)`` of the central directory of the zip ``file`` (``size`` bytes), as
    :mod:`zipfile` finds it (its ``_EndRecData``: the end record at the file's end, else the last
    one in its last 64 KiB, and the ZIP64 record before it where there is one); ``None`` when there
    is no end record (no zip)."""
    tail_start = max(size - (1 << 16) - _END.size, 0)
    file.seek(tail_start)
    tail = file.read(size - tail_start)
    if len(tail) >= _END.size and tail[-_END.size :][:4] == b"PK\x05\x06" and tail[-2:] == b"\0\0":
        at = len(tail) - _END.size
    else:
        at = tail.rfind(b"PK\x05\x06")
        if at < 0 or at + _END.size > len(tail):
            return None
    end = _END.unpack_from(tail, at)
    members, length, location, extra = end[4], end[5], tail_start + at, 0
    if location >= _END64_LOCATOR.size + _END64.size:
        file.seek(location - _END64_LOCATOR.size)
        locator = _END64_LOCATOR.unpack(file.read(_END64_LOCATOR.size))
        if locator[0] == b"PK\x06\x07":
            file.seek(location - _END64_LOCATOR.size - _END64.size)
            record = _END64.unpack(file.read(_END64.size))
            if record[0] == b"PK\x06\x06":
                members, length, extra = record[7], record[8], _END64_LOCATOR.size + _END64.size
    return members, location - length - extra, length


def zip_members(file: BinaryIO, size: int, most: int) -> list[zipfile.ZipInfo]:
    """The members of the zip archive ``file`` (``size`` bytes, read from its central directory:
    nothing is decompressed), once its end record declares at most ``most`` of them in a central
    directory of at most ``most ×`` :data:`ZIP_ENTRY_BYTES` bytes, and that directory holds no more
    entries (each an object in memory once read); ``file`` is left at its start. Else ``ValueError``
    saying what is wrong (the caller names the file)."""
    found = _central_directory(file, size)
    if found is None:
        raise ValueError("it is no zip archive (torch.save writes one)")
    members, start, length = found
    if members > most or length > most * ZIP_ENTRY_BYTES:
        raise ValueError(
            f"its zip directory declares {members:,} members in {length:,} bytes; it may hold at most {most:,} members"
        )
    file.seek(max(start, 0))
    if file.read(length).count(_CENTRAL_ENTRY) > most:
        raise ValueError(f"its zip directory holds more than {most:,} members")
    file.seek(0)
    try:
        with zipfile.ZipFile(file) as archive:
            infos = archive.infolist()
    except (zipfile.BadZipFile, zipfile.LargeZipFile, NotImplementedError, ValueError, EOFError, OSError) as error:
        raise ValueError(f"it is a damaged zip ({type(error).__name__}: {str(error)[:200]})") from None
    finally:
        file.seek(0)
    names = [info.filename for info in infos]
    if len(set(names)) != len(names):
        twice = sorted({name for name in names if names.count(name) > 1})
        raise ValueError(f"its zip holds two members named {twice[0][:100]!r}")
    return infos


def torch_zip_problem(members: list[zipfile.ZipInfo], size: int) -> str:
    """What makes ``members`` (:func:`zip_members` of a file of ``size`` bytes) no archive that
    ``torch.save`` writes (``""``: nothing): a member outside its one folder or that is no record it
    writes (:data:`TORCH_RECORD`), no ``data.pkl``, a member compressed or encrypted (``torch.save``
    stores each as it is), or members declaring more bytes than the file holds."""
    if not members:
        return "its zip holds no member"
    folder = members[0].filename.split("/", 1)[0]
    for info in members:
        name = info.filename
        if not name.startswith(folder + "/") or not TORCH_RECORD.match(name, len(folder) + 1):
            return f"its zip holds a member {name[:100]!r}, which is no record torch.save writes"
        if info.compress_type != zipfile.ZIP_STORED or info.flag_bits & 0x1 or info.file_size != info.compress_size:
            encrypted = ", encrypted" if info.flag_bits & 0x1 else ""
            return (
                f"its member {name[:100]!r} is not stored as it is (compression method {info.compress_type}{encrypted}, "
                f"{info.compress_size:,} bytes in the file for {info.file_size:,} once read); torch.save stores every "
                "member as it is: refusing to expand it"
            )
    if not any(info.filename == folder + "/data.pkl" for info in members):
        return "its zip holds no data.pkl (torch.save's pickle)"
    total = sum(info.file_size for info in members)
    if total > size:
        return f"its members declare {total:,} bytes, more than the {size:,} bytes of the file"
    return ""
