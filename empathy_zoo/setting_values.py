"""The rule a method's settings follow, as a result file records them (``config.settings``): one
rule for the result reader (:func:`empathy_zoo.experiment.result_reader.check_result`) and for
every writer (:meth:`agents.base.Method.make_settings`, through which the command line, a
``--config`` file, a sweep or profile file and a tuning study build a run's settings), so that no
run is trained whose result file the reader would refuse.

Each recorded setting is of the type its settings class declares (:func:`setting_problem`): an
``int`` an int (not a boolean) in ``[0, MAX_SETTING]``; a ``float`` a finite number of magnitude
at most :data:`MAX_SETTING`; a ``bool`` true or false; a ``str`` one non-empty line of printable
text; ``X | None`` null or an ``X``; a tuple or list an array of its items; anything else plain
data (:func:`plain_problem`)."""

from __future__ import annotations

import types
import unicodedata
from collections.abc import Mapping
from dataclasses import asdict, fields
from typing import Any, Union, get_args, get_origin, get_type_hints

from empathy_zoo.document_checks import finite_float
from empathy_zoo.limits import MAX_STEPS
from empathy_zoo.names import LABEL_REFUSED_CATEGORIES

__all__ = [
    "MAX_SETTING",
    "Problem",
    "check_recorded_settings",
    "field_types",
    "plain_problem",
    "recorded_problem",
    "setting_problem",
    "settings_record",
]

MAX_SETTING = MAX_STEPS
"""The largest magnitude of a number in a registered method's settings (as a result file records
them): every count a setting gives (steps, transitions, widths) is at most the steps of the
longest run, and no rate or weight is larger."""

Problem = tuple[str, str, Any]
"""Where in a setting a value is wrong, what it should be, and the value."""


def field_types(cls: type) -> dict[str, Any]:
    """``{field: annotation}`` of a dataclass (annotations resolved; ``Any`` where one cannot be)."""
    try:
        hints = get_type_hints(cls)
    except (NameError, TypeError):
        hints = {}
    return {f.name: hints.get(f.name, Any) for f in fields(cls)}


def settings_record(settings: Any) -> dict[str, Any]:
    """``settings`` as a result file records them: ``settings.record()`` where the settings class
    has one (it leaves out fields at their default that were added later), else every field."""
    return settings.record() if hasattr(settings, "record") else asdict(settings)


def recorded_problem(settings_class: type, record: Mapping[str, Any]) -> Problem | None:
    """What is wrong with ``record`` (settings of ``settings_class`` as a result file records them,
    or the values a run is about to be built with), or ``None``: a name the class has no field of,
    or the first value :func:`setting_problem` refuses for its field's type. A tuple counts as the
    array a result file holds of it."""
    kinds = field_types(settings_class)
    for name, value in record.items():
        if name not in kinds:
            return name, f"no such setting; its settings: {', '.join(kinds)}", name
        problem = setting_problem(_as_written(value), kinds[name], name)
        if problem is not None:
            return problem
    return None


def check_recorded_settings(settings_class: type, record: Mapping[str, Any]) -> None:
    """Raise ``ValueError`` (one line, naming the setting and its bound: ``learning_rate must be a
    finite number in [-1,000,000,000, 1,000,000,000] (what a result file records), got 5e+09``)
    where :func:`recorded_problem` finds something wrong in ``record``."""
    problem = recorded_problem(settings_class, record)
    if problem is not None:
        where, what, value = problem
        if what.startswith("no such setting"):
            raise ValueError(f"{where}: {what}")
        raise ValueError(f"{where} must be {what} (what a result file records), got {_shown(value)}")


def setting_problem(value: Any, kind: Any, where: str) -> Problem | None:
    """What is wrong with ``value`` for the type ``kind`` declares, or ``None`` (see the module page)."""
    origin, arguments = get_origin(kind), get_args(kind)
    if origin in (Union, types.UnionType) and type(None) in arguments:
        if value is None:
            return None
        rest = [argument for argument in arguments if argument is not type(None)]
        kind, origin, arguments = (rest[0], get_origin(rest[0]), get_args(rest[0])) if len(rest) == 1 else (Any, None, ())
    if kind is bool:
        return None if isinstance(value, bool) else (where, "true or false", value)
    if kind is int:
        whole = not isinstance(value, bool) and isinstance(value, int) and 0 <= value <= MAX_SETTING
        return None if whole else (where, f"an int in [0, {MAX_SETTING:,}]", value)
    if kind is float:
        number = finite_float(value) is not None and abs(value) <= MAX_SETTING
        return None if number else (where, f"a finite number in [-{MAX_SETTING:,}, {MAX_SETTING:,}]", value)
    if kind is str:
        text = isinstance(value, str) and bool(value) and unprintable(value) is None
        return None if text else (where, "a non-empty line of printable text", value)
    if origin in (tuple, list):
        if not isinstance(value, list):
            return where, "an array", value
        item_kind = arguments[0] if arguments and (len(arguments) == 1 or arguments[1] is Ellipsis) else Any
        return next(
            (problem for i, item in enumerate(value) if (problem := setting_problem(item, item_kind, f"{where}[{i}]"))), None
        )
    return plain_problem(value, where)


def plain_problem(value: Any, where: str) -> Problem | None:
    """What is not plain data in ``value`` (as :meth:`~empathy_zoo.document_checks.DocumentChecker.plain`
    reads it: objects with string keys, arrays, ``null``, booleans, finite numbers, printable
    text), or ``None``."""
    if isinstance(value, dict):
        for key, item in value.items():
            if not isinstance(key, str):
                return where, "an object (string keys)", key
            if (problem := plain_problem(item, f"{where}.{key}")) is not None:
                return problem
    elif isinstance(value, list):
        return next((problem for i, item in enumerate(value) if (problem := plain_problem(item, f"{where}[{i}]"))), None)
    elif isinstance(value, str):
        if unprintable(value) is not None:
            return where, "one line of printable text", value
    elif value is not None and not isinstance(value, bool) and finite_float(value) is None:
        return where, "plain data (an object, array, string, boolean, null or finite number)", value
    return None


def unprintable(text: str) -> str | None:
    """The first character of ``text`` one line of text may not hold (a control or format character,
    a line break: :data:`~empathy_zoo.names.LABEL_REFUSED_CATEGORIES`), or ``None``."""
    return next((c for c in text if unicodedata.category(c) in LABEL_REFUSED_CATEGORIES), None)


def _as_written(value: Any) -> Any:
    """``value`` as a result file holds it: its tuples arrays (lists), at any depth; the rest as it is."""
    if isinstance(value, (list, tuple)):
        return [_as_written(item) for item in value]
    if isinstance(value, Mapping):
        return {key: _as_written(item) for key, item in value.items()}
    return value


def _shown(value: Any) -> str:
    """``value`` in a refusal: its ``repr``, cut at 100 characters (one line)."""
    text = " ".join(repr(value).split())
    return text if len(text) <= 100 else text[:97] + "..."
