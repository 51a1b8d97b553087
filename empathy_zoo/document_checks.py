"""Field-by-field checks of a parsed JSON document the suite wrote (a result file, an evaluation
file), each raising one ``ValueError`` line that names the file and the field.

:class:`DocumentChecker` is what :mod:`empathy_zoo.result_file` and
:mod:`empathy_zoo.evaluation_file` check with; each gives its own error class and says what the
document is and what to do with a damaged one.
"""

from __future__ import annotations

import math
import unicodedata
from collections.abc import Mapping
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from empathy_zoo.metrics import INTEGER_METRICS, METRIC_RANGES
from empathy_zoo.names import LABEL_REFUSED_CATEGORIES, check_label, check_path_name
from empathy_zoo.policies import checked_entry

__all__ = ["DocumentChecker", "finite_float", "one_line", "shown"]

SHOWN = 60
"""Characters of a bad value quoted in a message."""
HUGE_DIGITS = 30
"""An integer of more digits than this is shown by its number of digits, not its digits."""
EARLIEST, LATEST = datetime(1971, 1, 1, tzinfo=UTC), datetime(9999, 1, 1, tzinfo=UTC)
"""The range of a time stamp read (UTC), as a tuning journal's
(:data:`empathy_zoo.training.tuning_journal.EARLIEST`): any zone's local time of one inside it is a ``datetime``."""
MAX_DATETIME = 64
"""Longest time stamp read (the suite writes ISO 8601 with a zone: 25 to 32 characters)."""


def shown(value: Any) -> str:
    """``repr(value)``, cut to :data:`SHOWN` characters; an integer of more than :data:`HUGE_DIGITS`
    digits by its number of digits (``repr`` of one of over 4,300 digits raises ``ValueError``)."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value).bit_length() > HUGE_DIGITS * 3.33:
        return f"an integer of about {int(abs(value).bit_length() * 0.30103) + 1:,} digits"
    text = repr(value)
    return text if len(text) <= SHOWN else text[: SHOWN - 3] + "..."


def one_line(text: str, limit: int = 300) -> str:
    """``text`` as one line of at most ``limit`` characters: its line breaks and runs of white space
    made single spaces (a library's message, torch's, spans several lines), cut with ``...``."""
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def finite_float(value: Any) -> float | None:
    """``value`` as a ``float`` when it is a number (an int or a float, not a boolean) that a float
    holds as a finite number, else ``None``: NaN, an infinity, and an int past the range of a float
    (``10**400``: ``math.isfinite`` raises ``OverflowError`` on it, and every reader that computes
    with it would) are no finite number."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    try:
        number = float(value)
    except OverflowError:
        return None
    return number if math.isfinite(number) else None


@dataclass(frozen=True)
class DocumentChecker:
    """Checks of one document, each raising :attr:`error` naming :attr:`path` and the field."""

    path: Path
    """The file the document was read from."""
    error: type[ValueError]
    """The error raised (e.g. :class:`~empathy_zoo.result_file.ResultFileError`)."""
    what: str
    """What the document is, as a message says it: ``"a result file"``."""
    suite: str
    """What a good one is: ``"a result of this suite"``."""
    remedy: str
    """What to do with a damaged one: ``"move it away (...)"``."""

    def fail(self, field: str, expected: str, value: Any) -> ValueError:
        """The error for ``field`` holding ``value`` where ``expected`` was."""
        return self.error(
            f"{self.path}: field {field}: expected {expected}, got {shown(value)}; the file is damaged or not "
            f"{self.suite}: {self.remedy}"
        )

    def table(self, value: Any, field: str) -> dict[str, Any]:
        """An object (a JSON table whose keys are strings)."""
        if not isinstance(value, dict) or not all(isinstance(key, str) for key in value):
            raise self.fail(field, "an object", value)
        return value

    def has(self, table: Mapping[str, Any], keys: tuple[str, ...], field: str) -> None:
        """Every one of ``keys`` is in ``table`` (``field`` is its prefix, ``"config."``)."""
        missing = [key for key in keys if key not in table]
        if missing:
            raise self.error(
                f"{self.path}: field {field}{missing[0]}: missing ({self.what} has {', '.join(keys)}); "
                f"the file is damaged or not {self.suite}: move it away"
            )

    def integer(self, value: Any, field: str, low: int, high: int | None = None) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or value < low or (high is not None and value > high):
            raise self.fail(field, f"an int >= {low}" + ("" if high is None else f" and <= {high:,}"), value)
        return value

    def positive(self, value: Any, field: str) -> int:
        return self.integer(value, field, 1)

    def number(self, value: Any, field: str) -> float:
        """A number (an int or a float, not a boolean)."""
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.fail(field, "a number", value)
        return value

    def finite(self, value: Any, field: str, low: float | None = None) -> float:
        """A finite number (at least ``low`` where given): an int or a float a float holds finitely
        (:func:`finite_float`: an int of any size is checked, never converted blindly)."""
        if finite_float(value) is None:
            raise self.fail(field, "a finite number", value)
        if low is not None and value < low:
            raise self.fail(field, f"a number >= {low}", value)
        return value

    def metric(self, value: Any, field: str, metric: str, high: float | None = None, length: int | None = None) -> list[Any]:
        """An array of values of ``metric`` (of ``length`` items where given), each within what an
        episode can give: a finite number within :data:`~empathy_zoo.metrics.METRIC_RANGES` (a
        count, :data:`~empathy_zoo.metrics.INTEGER_METRICS`, at least 0; equality at most 1) and at
        most ``high`` where given (the caller's bound for the episode's environment: a survival of at
        most ``max_cycles`` steps, harms of at most the other agents): what the leaderboard can draw."""
        low, fixed_high = METRIC_RANGES[metric]
        if fixed_high is not None:
            high = fixed_high if high is None else min(high, fixed_high)
        kind = "a count (a whole number)" if metric in INTEGER_METRICS else "a finite number"
        expected = f"{kind} >= {low:g}" + ("" if high is None else f" and <= {high:g}")
        values = self.numbers(value, field, length=length)
        for i, item in enumerate(values):
            finite = finite_float(item) is not None
            whole = metric not in INTEGER_METRICS or (finite and item == int(item))
            if not finite or item < low or (high is not None and item > high) or not whole:
                raise self.fail(f"{field}[{i}]", f"{metric}, {expected}", item)
        return values

    def increasing(self, values: list[int], field: str, low: int, high: int) -> None:
        """``values`` (integers) strictly increasing, each in ``[low, high]``."""
        for i, item in enumerate(values):
            if not low <= item <= high or (i and item <= values[i - 1]):
                raise self.fail(
                    f"{field}[{i}]", f"an increasing step in [{low:,}, {high:,}] (after {values[i - 1] if i else low - 1})", item
                )

    def text(self, value: Any, field: str) -> str:
        """A non-empty string of printable text: no control or format character and no line break
        (Unicode categories :data:`~empathy_zoo.names.LABEL_REFUSED_CATEGORIES`, as labels)."""
        if not isinstance(value, str) or not value:
            raise self.fail(field, "a non-empty one-line string", value)
        for position, character in enumerate(value):
            category = unicodedata.category(character)
            if category in LABEL_REFUSED_CATEGORIES:
                name = unicodedata.name(character, f"U+{ord(character):04X}")
                raise self.fail(field, f"one line of printable text (it holds {name}, {category}, at position {position})", value)
        return value

    def date_time(self, value: Any, field: str) -> datetime:
        """An ISO 8601 date and time with its offset from UTC (``2026-11-29T22:32:30+00:00``, as the
        suite writes ``created``), from :data:`EARLIEST` to :data:`LATEST` (years 1971 to 9998, UTC:
        the tuning journal's rule)."""
        expected = f"an ISO 8601 date and time with its offset from UTC, from {EARLIEST.year} to {LATEST.year - 1}"
        if not isinstance(value, str) or not 0 < len(value) <= MAX_DATETIME:
            raise self.fail(field, expected, value)
        try:
            stamp = datetime.fromisoformat(value)
            utc = stamp.astimezone(UTC) if stamp.tzinfo is not None else None
        except (ValueError, OverflowError):
            utc = None
        if utc is None or not EARLIEST <= utc < LATEST:
            raise self.fail(field, expected, value)
        return stamp

    def plain(self, value: Any, field: str) -> Any:
        """Plain data a method records (a reward transform's fields, a description): objects, arrays,
        ``null``, booleans, finite numbers (:func:`finite_float`) and strings of printable text (as
        :meth:`text`, empty allowed; an object's keys too), at any depth; the first value that is
        not is named."""
        if isinstance(value, dict):
            for key, item in self.table(value, field).items():
                if key:
                    self.text(key, f"{field} (the key {key[:60]!r})")
                self.plain(item, f"{field}.{key}")
        elif isinstance(value, list):
            for i, item in enumerate(value):
                self.plain(item, f"{field}[{i}]")
        elif isinstance(value, str):
            if value:
                self.text(value, field)
        elif value is not None and not isinstance(value, bool) and finite_float(value) is None:
            raise self.fail(field, "plain data (an object, array, string, boolean, null or finite number)", value)
        return value

    def label(self, value: Any, field: str) -> str:
        """A label by the rule runs are built with (:func:`empathy_zoo.names.check_label`)."""
        expected = "a non-empty one-line string, a label as a run is built with"
        if not isinstance(value, str) or not value:
            raise self.fail(field, expected, value)
        try:
            return check_label(value, "the label")
        except ValueError as error:
            raise self.fail(field, f"{expected} ({error})", value) from None

    def policy_label(self, value: Any, field: str) -> str:
        """A fixed policy's label as a run records it (``patrol``, ``patrol(period=3)``), checked by
        :func:`empathy_zoo.policies.checked_entry`, the rule a policy is built by: a registered
        policy with arguments it takes, of their type and range, every partner it names registered;
        or a ``package.module:Name``, kept as text (never imported: replaying it needs
        ``--allow-import``). Nothing is imported or built."""
        self.text(value, field)
        try:
            checked_entry(value)
        except ValueError as error:
            raise self.fail(field, f"a fixed policy's label ({error})", value) from None
        return value

    def name(self, value: Any, field: str) -> str:
        """A name that becomes part of file names (:func:`empathy_zoo.names.check_path_name`)."""
        try:
            return check_path_name(value, "a file-name-safe name")
        except ValueError:
            raise self.fail(field, "a name of letters, digits, '_', '-' and '.' (it becomes part of file names)", value) from None

    def numbers(self, value: Any, field: str, integral: bool = False, length: int | None = None) -> list[Any]:
        """An array of numbers (integers where ``integral``; of ``length`` items where given)."""
        if not isinstance(value, list) or (length is not None and len(value) != length):
            raise self.fail(field, "an array of numbers" + ("" if length is None else f" of {length:,} items"), value)
        for i, item in enumerate(value):
            self.number(item, f"{field}[{i}]")
            if integral and not isinstance(item, int) and not (math.isfinite(item) and item == int(item)):
                raise self.fail(f"{field}[{i}]", "an integer", item)
        return value
