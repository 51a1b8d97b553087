"""# Reading a separation table's JSON file

A separation table (:mod:`baselines.separation`, written by ``empathy-zoo analyse separation``) may
come from anyone, so the readers (``analyse discrimination``, ``analyse separation-reading``)
take it through :func:`read_separation_table`: a regular file of at most
:data:`MAX_SEPARATION_BYTES`, JSON nested no deeper than the suite's bound, and every field the
readers use checked against its range (rows of unique names, outcomes and pairs that name those
rows, finite numbers in their ranges, and a pair's ``differ`` true exactly when its
``differing_states`` is above 0, those at most its ``reachable_states``, as the producer writes
them), and the table consistent with itself as the producer writes it:

* every row has one outcome at every ε of the outcomes: a reader that looks one up (the scenarios
  reading's predictions, at ε = 0) never finds none. The one exception is the producer's own: a row
  of a method the table lists in ``omitted`` (its optimum found no fixed point at some ε) may lack
  an outcome at an ε, and then has no pair there either;
* an outcome's ``harms`` at most what one episode of the table's environment, built with its
  ``arguments``, can count (:func:`empathy_zoo.result_file.episode_bounds`: one Charger cat is
  harmed at most once), and its ``survival`` at most the episode's steps (``max_cycles``, which,
  where the table records it, is the one its environment and arguments give);
* a pair's ``harms_difference`` (``survival_difference``, ``equality_difference`` where it holds
  them) is its first row's outcome at its ε minus its second's, as the producer computes it, up to
  a float's rounding (:data:`ROUNDING` of the larger operand).

Every refusal is one ``ValueError`` line naming the file and the field.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from empathy_zoo.bounded_read import check_json_depth, parse_json
from empathy_zoo.document_checks import DocumentChecker, shown
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
"""How far a probability summed over states may pass 1 by rounding; likewise, relative to the
larger of its figures, how far an expected count may pass its bound (the shipped helping table's
harms are 1.0000000000000002 where one partner is harmed at most once) and a pair's difference may
stand from its outcomes' (the producer's are exact)."""
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
    table = check_separation_table(document, where)
    if "env" in table:  # (readers key a table by its file's name: a table saved under another task's name is refused)
        rules = dict(table.get("arguments", [])).get("rules")
        named = table["env"] if rules in (None, "paper") else f"{table['env']}_{rules}"
        if where.stem != named:
            raise SeparationTableError(
                f"separation table {where} holds the table of {named} (its env and rules), not of {where.stem}: "
                f"name it {named}.json, as empathy-zoo analyse separation does"
            )
    return table


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


def _plain_rest(check: DocumentChecker, entry: dict[str, Any], read: frozenset[str], where: str) -> None:
    """Every field of ``entry`` that no check reads (``where`` is its prefix, ``"rows[0]."``) plain
    data (:meth:`DocumentChecker.plain`): a reader may show it, so nothing that is no finite
    number or printable text passes unseen (``zzz: NaN``, an escape in a note)."""
    for key, value in entry.items():
        if key in read:
            continue
        if key:
            check.text(key, f"{where or '(the document) '}(the key {key[:60]!r})")
        check.plain(value, f"{where}{key}")


_READ_TOP = frozenset(("env", "arguments", "max_cycles", "rows", "outcomes", "pairs", "omitted"))
_READ_ROW = frozenset(("name", "method", "selfishness", "identical_to", "reason"))
_READ_OUTCOME = frozenset(("row", "epsilon", "harms", "robot_harmed", "survival", "changed", "equality"))
_READ_PAIR = frozenset(
    (
        "first",
        "second",
        "epsilon",
        "differ",
        "differing_states",
        "reachable_states",
        "harms_difference",
        "survival_difference",
        "equality_difference",
        "by_construction",
    )
)
_READ_OMISSION = frozenset(("method", "reason"))
_DIFFERENCES = (("harms_difference", "harms"), ("survival_difference", "survival"), ("equality_difference", "equality"))
"""Each difference a pair may hold and the outcome figure it is the first row's minus the second's of."""


def _environment(check: DocumentChecker, value: Any) -> str:
    """The name of a registered environment (:data:`empathy_zoo.environments.ENGINES`)."""
    from empathy_zoo.environments import ENGINES

    name = check.text(value, "env")
    if name not in ENGINES:
        raise check.fail("env", f"a registered environment ({', '.join(sorted(ENGINES))})", value)
    return name


def _episode_bounds(check: DocumentChecker, table: Mapping[str, Any], arguments: list[list[Any]]) -> tuple[float, float]:
    """The most ``harms`` and ``survival`` one episode of the table can count: what its environment
    built with its arguments can (:func:`empathy_zoo.result_file.episode_bounds`; :data:`MAX_COUNT`
    for a table that names none), the survival at most its ``max_cycles`` where it records them."""
    from empathy_zoo.engine.arguments import argument_defaults
    from empathy_zoo.environments import ENGINES
    from empathy_zoo.limits import MAX_CYCLES
    from empathy_zoo.result_file import check_env_kwargs, episode_bounds

    harms: float = MAX_COUNT
    cycles: int | None = None
    if "env" in table:
        env = table["env"]
        names = [name for name, _ in arguments]
        for i, name in enumerate(names):
            if name in names[:i]:
                raise check.fail(f"arguments[{i}][0]", "an argument not given before", name)
        kwargs = check_env_kwargs(check, env, dict(arguments), "arguments")
        bounds = episode_bounds(env, kwargs)
        harms = float(bounds["harms"] or 0)
        cycles = int({**argument_defaults(ENGINES[env]), **kwargs}["max_cycles"])
    if "max_cycles" in table:
        recorded = check.integer(table["max_cycles"], "max_cycles", 1, MAX_CYCLES)
        if cycles is not None and recorded != cycles:
            expected = f"the steps of an episode of {table['env']} built with the table's arguments ({cycles:,})"
            raise check.fail("max_cycles", expected, recorded)
        cycles = recorded
    return harms, float(MAX_COUNT if cycles is None else cycles)


def _at_most(check: DocumentChecker, value: float, most: float, field: str, what: str) -> None:
    """``value`` (a checked count) at most ``most``, up to a float's rounding (:data:`ROUNDING`)."""
    if value > most + ROUNDING * max(1.0, most):
        raise check.fail(field, f"at most {most:g} ({what})", value)


def _check_differences(
    check: DocumentChecker, pair: Mapping[str, Any], where: str, first: Mapping[str, Any], second: Mapping[str, Any]
) -> None:
    """Each difference ``pair`` holds (:data:`_DIFFERENCES`) the first row's outcome ``first`` minus
    the second's, ``second``, as the producer computes it, up to a float's rounding of the larger
    figure (a difference the outcomes do not give, their figure absent or ``null``, is left as read)."""
    for key, figure in _DIFFERENCES:
        stored, a, b = pair.get(key), first.get(figure), second.get(figure)
        if stored is None or a is None or b is None:
            continue
        expected = float(a) - float(b)
        if abs(float(stored) - expected) > ROUNDING * max(1.0, abs(float(a)), abs(float(b))):
            rows = f"the first row's {figure} ({shown(pair['first'])}: {a!r}) minus the second's ({shown(pair['second'])}: {b!r})"
            raise check.fail(f"{where}.{key}", f"{expected!r}, {rows} at ε = {pair['epsilon']!r}", stored)


def check_separation_table(document: Any, path: Path) -> dict[str, Any]:
    """``document`` when it is a separation table whose every field the readers use is in range,
    else :class:`SeparationTableError` naming ``path`` and the field."""
    check = _checker(path)
    table = check.table(document, "(the document)")
    check.has(table, ("rows", "outcomes", "pairs"), "")
    if "env" in table:
        _environment(check, table["env"])
    _plain_rest(check, table, _READ_TOP, "")
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
    most_harms, most_survival = _episode_bounds(check, table, arguments)
    names: set[str] = set()
    methods: dict[str, str] = {}  # (each row's method)
    same_as: dict[str, str] = {}  # (each row's first row by identical_to: rows marked identical, directly or not, share it)
    for i, row in enumerate(_entries(check, table["rows"], "rows", MAX_ROWS)):
        where = f"rows[{i}]"
        _plain_rest(check, row, _READ_ROW, f"{where}.")
        check.has(row, ("name", "method"), f"{where}.")
        name = _short(check, row["name"], f"{where}.name")
        if name in names:
            raise check.fail(f"{where}.name", "a name no other row has", name)
        methods[name] = _short(check, row["method"], f"{where}.method")
        if row.get("selfishness") is not None:
            _fraction(check, row["selfishness"], f"{where}.selfishness")
        for key in ("identical_to", "reason"):
            _optional_text(check, row.get(key, ""), f"{where}.{key}")
        if row.get("identical_to") and row["identical_to"] not in names:  # (text: checked above)
            raise check.fail(f"{where}.identical_to", "the name of a row before it", row["identical_to"])
        same_as[name] = same_as[row["identical_to"]] if row.get("identical_to") else name
        names.add(name)  # (after identical_to is checked: a row is never identical to itself)
    outcomes: dict[tuple[str, float], dict[str, Any]] = {}
    for i, outcome in enumerate(_entries(check, table["outcomes"], "outcomes")):
        where = f"outcomes[{i}]"
        check.has(outcome, ("row", "epsilon", "harms", "robot_harmed"), f"{where}.")
        _plain_rest(check, outcome, _READ_OUTCOME, f"{where}.")
        row_name = _row_name(check, outcome["row"], f"{where}.row", names)
        epsilon = _fraction(check, outcome["epsilon"], f"{where}.epsilon")
        if (row_name, epsilon) in outcomes:
            raise check.fail(f"{where}.epsilon", f"an ε at which row {shown(row_name)} has no other outcome", epsilon)
        outcomes[row_name, epsilon] = outcome
        harms = _bounded(check, outcome["harms"], f"{where}.harms")
        _at_most(check, harms, most_harms, f"{where}.harms", "the most harms an episode of the table's environment counts")
        _fraction(check, outcome["robot_harmed"], f"{where}.robot_harmed")
        if "survival" in outcome:
            survival = _bounded(check, outcome["survival"], f"{where}.survival")
            _at_most(check, survival, most_survival, f"{where}.survival", "the steps of an episode: max_cycles")
        if outcome.get("changed") is not None:
            _probability(check, outcome["changed"], f"{where}.changed")
        if outcome.get("equality") is not None:
            _probability(check, outcome["equality"], f"{where}.equality")
    omitted: set[str] = set()
    for i, omission in enumerate(_entries(check, table.get("omitted", []), "omitted")):
        check.has(omission, ("method", "reason"), f"omitted[{i}].")
        _plain_rest(check, omission, _READ_OMISSION, f"omitted[{i}].")
        omitted.add(check.text(omission["method"], f"omitted[{i}].method"))
        check.text(omission["reason"], f"omitted[{i}].reason")
    epsilons = sorted({epsilon for _, epsilon in outcomes})
    for name in methods:  # (in the rows' order: the first missing one named is the table's first)
        if methods[name] in omitted:
            continue  # (the producer's: an optimum with no fixed point at some ε, its method omitted there)
        for epsilon in epsilons:
            if (name, epsilon) not in outcomes:
                shown_epsilons = ", ".join(f"{e!r}" for e in epsilons[:10])
                raise check.error(
                    f"{check.path}: field outcomes: missing the outcome of row {shown(name)} at ε = {epsilon!r} (every "
                    f"row has one at each ε of the outcomes, {shown_epsilons}, unless omitted lists its method "
                    f"{shown(methods[name])}); the file is damaged or not {check.suite}: {check.remedy}"
                )
    pairs: set[tuple[frozenset[str], float]] = set()
    for i, pair in enumerate(_entries(check, table["pairs"], "pairs")):
        where = f"pairs[{i}]"
        required = ("first", "second", "epsilon", "differ", "differing_states", "harms_difference", "by_construction")
        check.has(pair, required, f"{where}.")
        _plain_rest(check, pair, _READ_PAIR, f"{where}.")
        first, second = (_row_name(check, pair[key], f"{where}.{key}", names) for key in ("first", "second"))
        if second == first:
            raise check.fail(f"{where}.second", f"a row other than the first ({shown(first)})", second)
        epsilon = _fraction(check, pair["epsilon"], f"{where}.epsilon")
        if epsilon not in epsilons:
            shown_epsilons = ", ".join(f"{e!r}" for e in sorted(epsilons)[:10])
            raise check.fail(f"{where}.epsilon", f"an ε of the outcomes ({shown_epsilons or 'none'})", epsilon)
        if (frozenset((first, second)), epsilon) in pairs:
            raise check.fail(f"{where}.second", f"a row not paired with {shown(first)} at ε = {epsilon!r} before", second)
        pairs.add((frozenset((first, second)), epsilon))
        for key, name in (("first", first), ("second", second)):
            if (name, epsilon) not in outcomes:  # (a row of an omitted method, with no outcome here)
                raise check.fail(f"{where}.{key}", f"a row with an outcome at ε = {epsilon!r}", name)
        if not isinstance(pair["differ"], bool):
            raise check.fail(f"{where}.differ", "true or false", pair["differ"])
        if pair["differ"] and same_as[first] == same_as[second]:
            expected = f"false ({shown(first)} and {shown(second)} are marked identical: identical_to)"
            raise check.fail(f"{where}.differ", expected, pair["differ"])
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
        for key in ("survival_difference", "equality_difference"):
            if pair.get(key) is not None:
                _bounded(check, pair[key], f"{where}.{key}", None)
        _optional_text(check, pair["by_construction"], f"{where}.by_construction")
        _check_differences(check, pair, where, outcomes[first, epsilon], outcomes[second, epsilon])
    return table
