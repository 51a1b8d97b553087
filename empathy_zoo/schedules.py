"""The ε schedule of SPEC §6, as pure functions: the learner explores by :func:`linear_epsilon`, and
a method's description (``config.description.exploration`` of a result file) records the same
schedule as data, :func:`linear_schedule`, so that the leaderboard computes the ε a run explored
with at any step (:func:`epsilon_function`) without importing any learner or settings class."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any, Protocol

from empathy_zoo.limits import MAX_STEPS

__all__ = [
    "EpsilonSchedule",
    "ScheduleError",
    "SCHEDULE_KINDS",
    "linear_epsilon",
    "linear_schedule",
    "SCHEDULE_FIELDS",
    "check_schedule",
    "epsilon_function",
    "epsilon_at",
]

SCHEDULE_KINDS: dict[str, tuple[str, ...]] = {"linear": ("start", "end", "warmup", "decay_steps")}
"""Every kind of exploration schedule a description may record, with its fields: ``linear`` is ε = 1
for the first ``warmup`` env steps, then linear from ``start`` to ``end`` over ``decay_steps``."""


class EpsilonSchedule(Protocol):
    """The settings the schedule reads (``EmpathicDQNSettings`` has them)."""

    @property
    def learning_starts(self) -> int: ...
    @property
    def epsilon_start(self) -> float: ...
    @property
    def epsilon_end(self) -> float: ...
    @property
    def epsilon_decay_steps(self) -> int: ...


def _linear(start: float, end: float, warmup: int, decay_steps: int, env_step: int) -> float:
    """ε after ``env_step`` steps: 1 during the ``warmup`` steps, then linear from ``start`` to ``end``."""
    if env_step < warmup:
        return 1.0
    fraction = min(1.0, (env_step - warmup) / decay_steps)
    return start + fraction * (end - start)


def linear_epsilon(settings: EpsilonSchedule, env_step: int) -> float:
    """ε after ``env_step`` steps of a run: 1 during warm-up, then linear to ``epsilon_end``."""
    return _linear(settings.epsilon_start, settings.epsilon_end, settings.learning_starts, settings.epsilon_decay_steps, env_step)


def linear_schedule(settings: EpsilonSchedule) -> dict[str, Any]:
    """The schedule :func:`linear_epsilon` follows with ``settings``, as a description records it:
    ``{"kind": "linear", "start": …, "end": …, "warmup": …, "decay_steps": …}``."""
    return {
        "kind": "linear",
        "start": settings.epsilon_start,
        "end": settings.epsilon_end,
        "warmup": settings.learning_starts,
        "decay_steps": settings.epsilon_decay_steps,
    }


SCHEDULE_FIELDS: dict[str, tuple[str, bool, int | float, int | float]] = {
    "start": ("ε at the end of warm-up", False, 0.0, 1.0),
    "end": ("ε after the decay", False, 0.0, 1.0),
    "warmup": ("env steps at ε = 1", True, 0, MAX_STEPS),
    "decay_steps": ("env steps of the decay", True, 1, MAX_STEPS),
}
"""Every numeric field a schedule may hold: ``(what it is, whole (an int), low, high)``. ε is a
probability; the steps are whole env steps, at most :data:`~empathy_zoo.limits.MAX_STEPS` (the
longest run)."""


class ScheduleError(ValueError):
    """A schedule that is not what :data:`SCHEDULE_KINDS` says: ``field`` (``""`` for the whole
    schedule), what it should be, and the value found."""

    def __init__(self, message: str, field: str = "", expected: str = "", value: Any = None) -> None:
        super().__init__(message)
        self.field, self.expected, self.value = field, expected, value


def _is_within(value: Any, whole: bool, low: float, high: float) -> bool:
    """``value`` is an int (or, unless ``whole``, a float) in ``[low, high]``, never a boolean, NaN or
    an infinity; an int of any size is compared as an int, never made a float."""
    if isinstance(value, bool) or not isinstance(value, int if whole else (int, float)):
        return False
    if isinstance(value, float) and not math.isfinite(value):
        return False
    return low <= value <= high


def check_schedule(schedule: Any) -> Mapping[str, Any]:
    """``schedule`` if it is a schedule of :data:`SCHEDULE_KINDS` whose fields are within
    :data:`SCHEDULE_FIELDS` (ε in ``[0, 1]``; ``warmup`` and ``decay_steps`` whole steps, ``decay_steps``
    at least 1), else :class:`ScheduleError` saying what is wrong and naming the field."""
    if not isinstance(schedule, Mapping) or not isinstance(schedule.get("kind"), str) or schedule["kind"] not in SCHEDULE_KINDS:
        raise ScheduleError(f"an exploration schedule is a table with kind one of {sorted(SCHEDULE_KINDS)}, got {schedule!r}")
    fields = SCHEDULE_KINDS[schedule["kind"]]
    if set(schedule) != {"kind", *fields}:
        raise ScheduleError(f"a {schedule['kind']} schedule has the fields kind, {', '.join(fields)}; got {sorted(schedule)}")
    for name in fields:
        value = schedule[name]
        what, whole, low, high = SCHEDULE_FIELDS[name]
        expected = f"{'an int' if whole else 'a number'} in [{low:,}, {high:,}] ({what})"
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ScheduleError(f"the schedule's {name} must be a number, got {value!r}", name, expected, value)
        if name == "decay_steps" and not _is_within(value, False, low, math.inf):
            raise ScheduleError(f"the schedule's decay_steps must be at least 1, got {value!r}", name, expected, value)
        if not _is_within(value, whole, low, high):
            raise ScheduleError(f"the schedule's {name} must be {expected}, got {value!r}", name, expected, value)
    return schedule


def epsilon_function(schedule: Mapping[str, Any]) -> Callable[[int], float]:
    """ε as a function of the env step for a run explored by ``schedule`` (a description's
    ``exploration``, checked once here): the same numbers the learner computed."""
    check_schedule(schedule)
    start, end, warmup, decay_steps = (schedule[name] for name in SCHEDULE_KINDS["linear"])
    return lambda env_step: _linear(start, end, warmup, decay_steps, env_step)


def epsilon_at(schedule: Mapping[str, Any], env_step: int) -> float:
    """ε after ``env_step`` steps of a run explored by ``schedule`` (:func:`epsilon_function`)."""
    return epsilon_function(schedule)(env_step)
