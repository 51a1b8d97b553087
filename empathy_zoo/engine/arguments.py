"""The arguments every environment takes (``size``, ``view``, ``max_cycles`` and its own), their
checks, and the limits on grid size and memory (docs/limits.md)."""

from __future__ import annotations

import inspect
from collections.abc import Mapping, Sequence
from typing import Any, Protocol

import numpy as np

from empathy_zoo.limits import MAX_CYCLES, MAX_SIZE, MAX_TABLE_BYTES

__all__ = [
    "GRID_ARGUMENTS",
    "MAX_CYCLES",
    "MAX_SIZE",
    "MAX_TABLE_BYTES",
    "table_bytes",
    "check_grid_arguments",
    "check_choice",
    "check_agent_count",
    "check_env_arguments",
    "UnknownArgumentError",
    "TakesArguments",
    "GRID_ARGUMENT_HELP",
    "argument_defaults",
    "argument_help",
    "argument_types",
    "own_arguments",
]

GRID_ARGUMENTS = ("size", "view", "max_cycles")
"""Constructor arguments every environment takes (besides its :attr:`GridEngine.extra_arguments`)."""
GRID_ARGUMENT_HELP = {
    "size": "side of the torus",
    "view": "side of the observation window (odd, smaller than size)",
    "max_cycles": "steps before an episode is truncated",
}
"""One line for each of :data:`GRID_ARGUMENTS`: the command line's help."""


class TakesArguments(Protocol):
    """What :func:`check_env_arguments` reads of an engine class."""

    name: str
    """The environment's name."""
    extra_arguments: Mapping[str, tuple[str, ...]]
    """Its own constructor arguments and their allowed values."""
    count_argument: str | None
    """Its constructor argument saying how many other agents it holds (``num_cats``), if any."""


def own_arguments(engine: TakesArguments) -> tuple[str, ...]:
    """The arguments ``engine``'s environment takes besides :data:`GRID_ARGUMENTS`, as it declares
    them (its :attr:`~TakesArguments.extra_arguments`, then its :attr:`~TakesArguments.count_argument`)."""
    return (*engine.extra_arguments, *((engine.count_argument,) if engine.count_argument else ()))


def argument_types(engine: TakesArguments) -> dict[str, Any]:
    """``{argument: type}`` of every argument ``engine``'s environment takes (a choice among
    strings is a ``str``, its values checked by :func:`check_choice`): what a configuration file
    and the command line accept for it."""
    return {
        **dict.fromkeys(GRID_ARGUMENTS, int),
        **dict.fromkeys(engine.extra_arguments, str),
        **({engine.count_argument: int} if engine.count_argument else {}),
    }


def argument_defaults(engine: Any) -> dict[str, Any]:
    """``{argument: default}`` of every argument ``engine``'s environment takes, read from its
    constructor (the one place they are written)."""
    parameters = inspect.signature(engine).parameters
    return {name: parameters[name].default for name in argument_types(engine)}


def argument_help(engine: TakesArguments) -> dict[str, str]:
    """One line of help for each argument ``engine``'s environment takes."""
    own: Mapping[str, str] = getattr(engine, "argument_help", {})
    return {name: GRID_ARGUMENT_HELP.get(name) or own.get(name, "") for name in argument_types(engine)}


def table_bytes(size: int, view: int) -> int:
    """An upper bound, in bytes, of the memory an engine builds its lookup tables with:
    ``600 + 24·view + 8·view²`` per cell (the window of every cell, the moves, the displacements,
    and the rows and columns the window of every cell is built from)."""
    return size * size * (600 + 24 * view + 8 * view * view)


def _megabytes(count: int) -> str:
    return f"{count / 2**20:,.0f} MB"


def check_grid_arguments(size: int, view: int, max_cycles: int, min_size: int) -> None:
    """Raise ``ValueError`` for grid arguments the rules cannot honour, or whose lookup tables
    would need more memory than the limits allow (the message says how much)."""
    for name, value in (("size", size), ("view", view), ("max_cycles", max_cycles)):
        if not isinstance(value, (int, np.integer)) or isinstance(value, bool):
            raise ValueError(f"{name} must be an int, got {value!r}")
    if size < min_size:
        raise ValueError(f"size must be at least {min_size}, got {size}")
    if size > MAX_SIZE:
        raise ValueError(
            f"size must be at most {MAX_SIZE}, got {size}: its lookup tables alone would need about "
            f"{_megabytes(table_bytes(size, min(view, size - 1)))} (docs/limits.md)"
        )
    if view < 1 or view % 2 == 0 or view >= size:
        raise ValueError(f"view must be odd, positive and smaller than size={size}, got {view}")
    if table_bytes(size, view) > MAX_TABLE_BYTES:
        raise ValueError(
            f"view={view} on size={size} would need about {_megabytes(table_bytes(size, view))} of lookup tables, "
            f"more than the limit of {_megabytes(MAX_TABLE_BYTES)}: use a smaller view or size (docs/limits.md)"
        )
    if max_cycles < 1:
        raise ValueError(f"max_cycles must be positive, got {max_cycles}")
    if max_cycles > MAX_CYCLES:
        raise ValueError(f"max_cycles must be at most {MAX_CYCLES:,} (no run is longer), got {max_cycles:,} (docs/limits.md)")


def check_choice(name: str, value: Any, allowed: Sequence[str]) -> str:
    """``value`` if it is one of the strings ``allowed``, else raise ``ValueError`` naming the
    argument ``name`` and the allowed values (never a silent default)."""
    if not isinstance(value, str) or value not in allowed:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, allowed))}; got {value!r}")
    return value


def check_agent_count(name: str, value: Any, most: int, room: str) -> int:
    """``value`` as an ``int`` if it is a whole number of agents from 1 to ``most``, else raise
    ``ValueError`` naming the argument ``name`` (``room`` says what bounds ``most``)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be an int, got {value!r}")
    if value < 1:
        raise ValueError(f"{name} must be at least 1, got {value}")
    if value > most:
        raise ValueError(f"{name}={value} is too many: {room}, so {name} is at most {most}")
    return int(value)


class UnknownArgumentError(ValueError, TypeError):
    """An environment argument no environment of that kind takes: a ``ValueError``, as every
    refusal of the suite is (docs/limits.md), and a ``TypeError``, as Python's own for an
    unexpected keyword is."""


def check_env_arguments(engine: TakesArguments, kwargs: Mapping[str, Any], error: type[Exception] = UnknownArgumentError) -> None:
    """Raise ``error`` (default :class:`UnknownArgumentError`) naming every key of ``kwargs`` that
    ``engine``'s environment does not take, and the arguments it does take."""
    known = (*GRID_ARGUMENTS, *own_arguments(engine))
    unknown = [key for key in kwargs if key not in known]
    if unknown:
        raise error(f"{engine.name} takes no argument(s) {unknown}; its environment arguments: {', '.join(known)}")
