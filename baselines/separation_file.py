"""# Reading a separation table's JSON file

A separation table (:mod:`baselines.separation`, written by ``empathy-zoo analyse separation``) may
come from anyone, so the readers (``analyse discrimination``, ``analyse separation-reading``)
take it through :func:`read_separation_table`: a regular file of at most
:data:`MAX_SEPARATION_BYTES`, JSON nested no deeper than the suite's bound, and every field the
readers use checked against its range (rows of unique names, outcomes and pairs that name those
rows, finite numbers in their ranges, and a pair's ``differ`` true exactly when its
``differing_states`` is above 0, those at most its ``reachable_states``, as the producer writes
them). Every refusal is one ``ValueError`` line naming the file and the field.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from empathy_zoo.bounded_read import check_json_depth, parse_json
from empathy_zoo.document_checks import DocumentChecker
from empathy_zoo.limits import read_bounded

__all__ = [
    "MAX_ENTRIES",
    "MAX_ROWS",
    "MAX_SEPARATION_BYTES",
    "SeparationTableError",
    "check_separation_table",
    "read_separation_table",
]

MAX_SEPARATION_BYTES = 64 * 2**20
"""The largest separation table read (the shipped ones are under 1 MB)."""
MAX_ROWS = 1_000
"""The most rows a table may hold (the shipped ones hold 20)."""
MAX_ARGUMENTS = 20
"""The most environment arguments a table may record."""
MAX_ENTRIES = 100_000
"""The most outcomes, pairs or omissions a table may hold (the shipped ones hold at most 570)."""
MAX_ROW_NAME = 200
"""The longest row name or method name (the shipped ones are under 40 characters)."""
ROUNDING = 1e-9
"""How far a probability summed over states may pass 1 by rounding."""
MAX_COUNT = 10**9
"""The largest harms, survival or count of states a table may hold (the bound of ``max_cycles``)."""


class SeparationTableError(ValueError):
    """A separation table that is damaged or not the suite's (the message names file and field)."""


def _checker(path: Path) -> DocumentChecker:
    return DocumentChecker(
        path,
        SeparationTableError,
        "a separation table",
        "a separation table of this suite",
        "make it again with empathy-zoo analyse separation",
    )


def read_separation_table(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The checked separation table of the file ``path`` (see the module page)."""
    where = Path(path)
    try:
        data = read_bounded(where, MAX_SEPARATION_BYTES, "separation table")
    except FileNotFoundError:
        raise SeparationTableError(f"separation table {where} does not exist") from None
    except OSError as error:
        raise SeparationTableError(f"separation table {where}: {error.strerror or error}") from None
    check_json_depth(data, f"separation table {where}")
    try:
        document = parse_json(data.decode("utf-8"))
    except (ValueError, RecursionError) as error:
        raise SeparationTableError(f"separation table {where} is no JSON ({type(error).__name__}: {str(error)[:200]})") from None
    return check_separation_table(document, where)


def _entries(check: DocumentChecker, value: Any, field: str, most: int = MAX_ENTRIES) -> list[dict[str, Any]]:
    """A list of at most ``most`` objects."""
    if not isinstance(value, list) or len(value) > most:
        raise check.fail(field, f"an array of at most {most:,} objects", value)
    return [check.table(item, f"{field}[{i}]") for i, item in enumerate(value)]


def _optional_text(check: DocumentChecker, value: Any, field: str) -> str:
    """``""`` or one line of printable text (:meth:`DocumentChecker.text`)."""
    return value if value == "" else check.text(value, field)


def _fraction(check: DocumentChecker, value: Any, field: str) -> float:
    number = check.finite(value, field, 0.0)
    if number > 1.0:
        raise check.fail(field, "a number in [0, 1]", value)
    return number


def _probability(check: DocumentChecker, value: Any, field: str) -> float:
    """A probability summed over an episode's states: in ``[0, 1]`` up to a float's rounding
    (:data:`ROUNDING`; the shipped vase table holds 1.0000000000000044)."""
    number = check.finite(value, field, 0.0)
    if number > 1.0 + ROUNDING:
        raise check.fail(field, "a probability in [0, 1]", value)
    return number


def _bounded(check: DocumentChecker, value: Any, field: str, low: float | None = 0.0) -> float:
    """A finite number within ``[low, MAX_COUNT]`` (``[-MAX_COUNT, MAX_COUNT]`` without ``low``)."""
    number = check.finite(value, field, -MAX_COUNT if low is None else low)
    if number > MAX_COUNT:
        raise check.fail(field, f"a number of at most {MAX_COUNT:,}", value)
    return number


def _short(check: DocumentChecker, value: Any, field: str) -> str:
    """One line of printable text of at most :data:`MAX_ROW_NAME` characters."""
    text = check.text(value, field)
    if len(text) > MAX_ROW_NAME:
        raise check.fail(field, f"a name of at most {MAX_ROW_NAME} characters", value)
    return text


def _row_name(check: DocumentChecker, value: Any, field: str, names: set[str]) -> str:
    """The name of one of the table's rows."""
    if not isinstance(value, str) or value not in names:
        raise check.fail(field, "the name of a row", value)
    return value


def check_separation_table(document: Any, path: Path) -> dict[str, Any]:
    """``document`` when it is a separation table whose every field the readers use is in range,
    else :class:`SeparationTableError` naming ``path`` and the field."""
    check = _checker(path)
    table = check.table(document, "(the document)")
    check.has(table, ("rows", "outcomes", "pairs"), "")
    if "env" in table:
        check.text(table["env"], "env")
    arguments = table.get("arguments", [])
    if not isinstance(arguments, list) or len(arguments) > MAX_ARGUMENTS:
        raise check.fail("arguments", f"an array of at most {MAX_ARGUMENTS} [name, value] pairs", arguments)
    for i, pair in enumerate(arguments):
        if not isinstance(pair, list) or len(pair) != 2:
            raise check.fail(f"arguments[{i}]", "a [name, value] pair", pair)
        if not isinstance(pair[0], str) or not pair[0].isidentifier() or not pair[0].isascii() or len(pair[0]) > 64:
            raise check.fail(f"arguments[{i}][0]", "an environment argument's name (a Python identifier)", pair[0])
        if isinstance(pair[1], str):
            check.name(pair[1], f"arguments[{i}][1]")  # (an option's word: shown in page headings)
        else:
            check.integer(pair[1], f"arguments[{i}][1]", -(10**9), 10**9)
    names: set[str] = set()
    for i, row in enumerate(_entries(check, table["rows"], "rows", MAX_ROWS)):
        where = f"rows[{i}]"
        check.has(row, ("name", "method"), f"{where}.")
        name = _short(check, row["name"], f"{where}.name")
        if name in names:
            raise check.fail(f"{where}.name", "a name no other row has", name)
        names.add(name)
        _short(check, row["method"], f"{where}.method")
        if row.get("selfishness") is not None:
            _fraction(check, row["selfishness"], f"{where}.selfishness")
        for key in ("identical_to", "reason"):
            _optional_text(check, row.get(key, ""), f"{where}.{key}")
        if row.get("identical_to") and row["identical_to"] not in names:  # (text: checked above)
            raise check.fail(f"{where}.identical_to", "the name of a row before it", row["identical_to"])
    for i, outcome in enumerate(_entries(check, table["outcomes"], "outcomes")):
        where = f"outcomes[{i}]"
        check.has(outcome, ("row", "epsilon", "harms", "robot_harmed"), f"{where}.")
        _row_name(check, outcome["row"], f"{where}.row", names)
        _fraction(check, outcome["epsilon"], f"{where}.epsilon")
        _bounded(check, outcome["harms"], f"{where}.harms")
        _fraction(check, outcome["robot_harmed"], f"{where}.robot_harmed")
        if "survival" in outcome:
            _bounded(check, outcome["survival"], f"{where}.survival")
        if outcome.get("changed") is not None:
            _probability(check, outcome["changed"], f"{where}.changed")
    for i, pair in enumerate(_entries(check, table["pairs"], "pairs")):
        where = f"pairs[{i}]"
        required = ("first", "second", "epsilon", "differ", "differing_states", "harms_difference", "by_construction")
        check.has(pair, required, f"{where}.")
        for key in ("first", "second"):
            _row_name(check, pair[key], f"{where}.{key}", names)
        _fraction(check, pair["epsilon"], f"{where}.epsilon")
        if not isinstance(pair["differ"], bool):
            raise check.fail(f"{where}.differ", "true or false", pair["differ"])
        differing = check.integer(pair["differing_states"], f"{where}.differing_states", 0, MAX_COUNT)
        if pair["differ"] != (differing > 0):  # (the producer: differ exactly where a reachable state differs)
            expected = f"{str(differing > 0).lower()} (differing_states is {differing})"
            raise check.fail(f"{where}.differ", expected, pair["differ"])
        if "reachable_states" in pair:  # (tables made by hand, the tests', may leave it out)
            check.integer(pair["reachable_states"], f"{where}.reachable_states", 0, MAX_COUNT)
            if differing > pair["reachable_states"]:
                expected = f"at most reachable_states ({pair['reachable_states']:,}): states that differ are reachable"
                raise check.fail(f"{where}.differing_states", expected, differing)
        _bounded(check, pair["harms_difference"], f"{where}.harms_difference", None)
        if pair.get("equality_difference") is not None:
            _bounded(check, pair["equality_difference"], f"{where}.equality_difference", None)
        _optional_text(check, pair["by_construction"], f"{where}.by_construction")
    for i, omission in enumerate(_entries(check, table.get("omitted", []), "omitted")):
        check.has(omission, ("method", "reason"), f"omitted[{i}].")
        check.text(omission["method"], f"omitted[{i}].method")
        check.text(omission["reason"], f"omitted[{i}].reason")
    return table
