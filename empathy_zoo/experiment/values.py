"""Reading configuration files: TOML parsing, key checks and value checks driven by the type
annotations of the dataclasses a file's tables fill.

Every value a sweep file or a ``train --config`` file gives is checked against the annotation of
the field it sets (:func:`check_value`): ``int``, ``float`` (an int is accepted), ``bool``,
``str``, ``T | None``, ``list[T]`` / ``tuple[T, ...]`` (a TOML array), ``Mapping[str, T]`` (a
TOML table), unions and ``Literal`` choices; any other annotation is left to the class that
takes the value (a settings dataclass checks its own fields). Errors are
:class:`SweepConfigError` naming the file, the table and the key.
"""

from __future__ import annotations

import tomllib
import types
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any, Literal, Union, get_args, get_origin

from empathy_zoo.limits import MAX_CONFIG_BYTES, MAX_SEED, MAX_SEEDS, read_bounded
from empathy_zoo.setting_values import field_types  # (here too: a config file's settings are read by their annotations)

__all__ = [
    "SweepConfigError",
    "PolicyTable",
    "Seeds",
    "check_keys",
    "check_seeds",
    "check_value",
    "describe_type",
    "field_types",
    "read_toml",
    "type_name",
]


class SweepConfigError(ValueError):
    """A sweep (or run) configuration file is invalid; the message names file, table and key."""


class Seeds:
    """Annotation of ``seeds``: an int ``N`` (seeds ``0..N-1``) or a list of distinct seeds."""


PolicyTable: Any = Mapping[str, str | Mapping[str, Any]]
"""Annotation of ``fixed``: agent names to policy names or to tables ``{ policy = name, ... }``."""

_NAMES: dict[Any, str] = {
    Seeds: "int (number of seeds) or list of distinct non-negative ints",
    PolicyTable: "table of strings (policy names) or of tables { policy = name, <argument> = value, ... }",
    int: "int",
    float: "float",
    bool: "bool",
    str: "str",
}


def describe_type(kind: Any) -> str:
    """What a value of annotation ``kind`` looks like in a TOML file, for an error message."""
    if kind in _NAMES:
        return _NAMES[kind]
    origin, arguments = get_origin(kind), get_args(kind)
    if origin is Literal:
        return "one of " + ", ".join(map(repr, arguments))
    if origin in (Union, types.UnionType):
        shown = [describe_type(a) for a in arguments if a is not type(None)]
        return " or ".join(shown)
    if origin in (list, tuple, Sequence):
        return f"list of {_plural(describe_type(arguments[0]))}" if arguments else "list"
    if origin in (dict, Mapping):
        return f"table of {_plural(describe_type(arguments[1]))}" if len(arguments) == 2 else "table"
    return getattr(kind, "__name__", str(kind))


def _plural(name: str) -> str:
    return {"str": "strings", "int": "ints", "float": "floats", "bool": "bools"}.get(name, name)


def type_name(value: Any) -> str:
    """A parsed TOML value's kind as TOML calls it (``table``, ``array``, ``int``, …)."""
    names: dict[type, str] = {dict: "table", list: "array"}
    return names.get(type(value), type(value).__name__)


def check_value(value: Any, kind: Any, where: str) -> Any:
    """``value`` if it matches the annotation ``kind`` (see the module page), else raise
    :class:`SweepConfigError` naming ``where``; an int given for a float is returned as a float."""

    def fail() -> SweepConfigError:
        return SweepConfigError(f"{where}: expected {describe_type(kind)}, got {type_name(value)} {value!r}")

    origin, arguments = get_origin(kind), get_args(kind)
    if kind is Seeds:
        return check_seeds(value, where)
    if kind is bool or kind is str:
        if not isinstance(value, kind):
            raise fail()
    elif kind is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise fail()
    elif kind is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise fail()
        return float(value)
    elif origin is Literal:
        if value not in arguments or type(value) is not type(next(a for a in arguments if a == value)):
            raise fail()
    elif origin in (Union, types.UnionType):
        for option in (a for a in arguments if a is not type(None)):
            try:
                return check_value(value, option, where)
            except SweepConfigError:
                continue
        raise fail()
    elif origin in (list, tuple, Sequence):
        if not isinstance(value, list):
            raise fail()
        item = arguments[0] if arguments else Any
        for element in value:
            try:
                check_value(element, item, where)
            except SweepConfigError:
                raise fail() from None
    elif origin in (dict, Mapping):
        if not isinstance(value, dict):
            raise fail()
        item = arguments[1] if len(arguments) == 2 else Any
        for element in value.values():
            try:
                check_value(element, item, where)
            except SweepConfigError:
                raise fail() from None
    return value


def check_seeds(value: Any, where: str) -> list[int]:
    """The seeds ``value`` gives (an int ``N``: ``0..N-1``; a list of distinct non-negative ints)."""
    seeds = [value] if isinstance(value, int) and not isinstance(value, bool) else value
    if not isinstance(seeds, list) or not seeds or any(isinstance(s, bool) or not isinstance(s, int) or s < 0 for s in seeds):
        raise SweepConfigError(f"{where}: expected {describe_type(Seeds)}, got {type_name(value)} {value!r}")
    if isinstance(value, int):
        if value < 1:
            raise SweepConfigError(f"{where}: expected a positive number of seeds, got {value}")
        if value > MAX_SEEDS:
            raise SweepConfigError(f"{where}: an experiment has at most {MAX_SEEDS:,} seeds (docs/limits.md), got {value:,}")
        return list(range(value))
    if len(value) > MAX_SEEDS:
        raise SweepConfigError(f"{where}: an experiment has at most {MAX_SEEDS:,} seeds (docs/limits.md), got {len(value):,}")
    if max(value) > MAX_SEED:
        raise SweepConfigError(f"{where}: a seed is at most {MAX_SEED:,} (2**63 - 1; docs/limits.md), got {max(value)}")
    if len(set(value)) != len(value):
        raise SweepConfigError(f"{where}: seed(s) listed twice in {value}")
    return list(value)


def check_keys(table: Mapping[str, Any], allowed: Iterable[str], where: str) -> None:
    """Raise naming the first key of ``table`` not in ``allowed`` (and listing those allowed)."""
    allowed = list(allowed)
    for key in table:
        if key not in allowed:
            raise SweepConfigError(f"{where}: unknown key {key!r}; allowed keys: {', '.join(allowed)}")


def read_toml(path: str | Path) -> dict[str, Any]:
    """Parse a TOML file; a missing, malformed or too large one (over
    :data:`~empathy_zoo.limits.MAX_CONFIG_BYTES`) raises :class:`SweepConfigError` naming it."""
    path = Path(path)
    try:
        data = read_bounded(path, MAX_CONFIG_BYTES, "config file")
    except FileNotFoundError:
        raise SweepConfigError(f"config file {path} does not exist") from None
    except ValueError as error:  # (larger than MAX_CONFIG_BYTES)
        raise SweepConfigError(str(error)) from None
    try:
        return tomllib.loads(data.decode("utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError, RecursionError) as error:
        raise SweepConfigError(f"{path}: not valid TOML ({type(error).__name__}: {str(error)[:200]})") from None
