"""Where runs may log their scalars, as a sweep file or ``--log`` names it: :data:`BACKENDS` and
:func:`parse_log` (the loggers themselves: :mod:`empathy_zoo.training.tracking`)."""

from __future__ import annotations

from collections.abc import Sequence

__all__ = ["BACKENDS", "NO_LOG", "parse_log"]

BACKENDS = ("tensorboard", "csv", "wandb")
"""Where runs may log their scalars (:attr:`~empathy_zoo.training.options.RunnerOptions.log`)."""
NO_LOG = "none"
"""The value of ``--log`` that logs nothing (over a sweep file's ``log``)."""


def parse_log(value: str | Sequence[str] | None, where: str = "log") -> tuple[str, ...]:
    """The backends ``value`` names: a comma-separated string (``"tensorboard,csv"``) or a sequence
    of names, in the order given; ``"none"``, an empty sequence and ``None`` log nothing. An unknown
    name, an empty one or one given twice raises ``ValueError`` naming ``where`` and the choices."""
    if value is None:
        return ()
    names = [part.strip() for part in value.split(",")] if isinstance(value, str) else list(value)
    if names == [NO_LOG]:
        return ()
    choices = f"choose from {', '.join(BACKENDS)}, comma-separated (or {NO_LOG})"
    for name in names:
        if not isinstance(name, str) or name not in BACKENDS:
            shown = "an empty name" if name == "" else f"unknown backend {name!r}"
            raise ValueError(f"{where}: {shown}; {choices}")
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        raise ValueError(f"{where}: {', '.join(repeated)} given twice; {choices}")
    return tuple(names)
