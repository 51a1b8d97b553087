"""The parts every typed record of a file is made of: read-only tables of plain values, read-only
numeric series, and the agent file a record names.

A file the suite reads (a result file, an evaluation file) is checked once, then held as a frozen
record (:class:`empathy_zoo.experiment.records.RunResult`,
:class:`empathy_zoo.evaluation_record.EvaluationResult`). Its tables of plain values (a method's
settings, a description, a scenario's arguments) are read-only mappings at every depth, arrays as
tuples (:func:`frozen_plain`, :func:`thawed` gives the JSON back); its per-episode numbers are
read-only numpy arrays (:func:`read_only_series`), ``int64`` where the file writes integers and
``float64`` otherwise (a JSON number with a fraction or an exponent is a double: read exactly), so
a record gives back, number for number, what the file holds.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

__all__ = ["PlainTable", "frozen_plain", "thawed", "read_only_series", "listed", "empty_table", "AgentRef"]

PlainTable = Mapping[str, Any]
"""A read-only table of plain values (:func:`frozen_plain`): a config's settings, reward, description."""


def frozen_plain(value: Any) -> Any:
    """``value`` (plain JSON data) made read-only at every depth: an object a read-only mapping,
    an array a tuple; anything else as it is."""
    if isinstance(value, Mapping):
        return MappingProxyType({key: frozen_plain(item) for key, item in value.items()})
    if isinstance(value, (list, tuple)):
        return tuple(frozen_plain(item) for item in value)
    return value


def thawed(value: Any) -> Any:
    """``value`` made by :func:`frozen_plain` as JSON holds it again: mappings as dicts, tuples as lists."""
    if isinstance(value, Mapping):
        return {key: thawed(item) for key, item in value.items()}
    if isinstance(value, tuple):
        return [thawed(item) for item in value]
    return value


def read_only_series(values: Sequence[Any]) -> np.ndarray:
    """A column of numbers as a read-only array: ``int64`` when every value is an integer an
    ``int64`` holds, else ``float64`` (an empty column: ``float64``)."""
    array = np.array(values) if len(values) else np.zeros(0, dtype=np.float64)
    if array.dtype.kind != "i" or array.dtype != np.int64:
        array = np.array(values, dtype=np.float64)  # (a float, or an integer past int64: read as a double)
    array.flags.writeable = False
    return array


def listed(series: np.ndarray) -> list[Any]:
    """A series as its JSON array: Python ints of an ``int64`` series, floats of a ``float64`` one."""
    return list(series.tolist())


def empty_table() -> PlainTable:
    """A read-only table of nothing (a record's default for the fields a file adds)."""
    return MappingProxyType({})


@dataclass(frozen=True)
class AgentRef:
    """The agent file a run kept beside its result file (a result or evaluation file's ``agent``)."""

    file: str
    """Its name, ``<run id>.agent.pt`` or ``<run id>.agent.zip``, in the folder of the result file."""
    sha256: str
    """The SHA-256 (64 lowercase hex digits) of its bytes, as the run wrote them."""
    extra: PlainTable = field(default_factory=empty_table)
    """Fields of ``agent`` beyond these two (none in a file this suite writes), kept as read."""

    @classmethod
    def from_checked(cls, entry: Mapping[str, Any]) -> AgentRef:
        """The record of a checked ``agent`` table."""
        rest = {key: value for key, value in entry.items() if key not in ("file", "sha256")}
        return cls(str(entry["file"]), str(entry["sha256"]), frozen_plain(rest))

    def to_document(self) -> dict[str, Any]:
        """The ``agent`` table as the file holds it."""
        return {"file": self.file, "sha256": self.sha256, **thawed(self.extra)}
