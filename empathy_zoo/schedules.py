"""The ε schedule of SPEC §6, as pure functions: the learner explores by :func:`linear_epsilon`, and
a method's description (``config.description.exploration`` of a result file) records the same
schedule as data, :func:`linear_schedule`, so that the leaderboard computes the ε a run explored
with at any step (:func:`epsilon_function`) without importing any learner or settings class."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, Protocol

__all__ = [
    "EpsilonSchedule",
    "SCHEDULE_KINDS",
    "linear_epsilon",
    "linear_schedule",
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


def check_schedule(schedule: Any) -> Mapping[str, Any]:
    """``schedule`` if it is a schedule of :data:`SCHEDULE_KINDS` with numeric fields (``decay_steps``
    at least 1), else ``ValueError`` saying what is wrong."""
    if not isinstance(schedule, Mapping) or not isinstance(schedule.get("kind"), str) or schedule["kind"] not in SCHEDULE_KINDS:
        raise ValueError(f"an exploration schedule is a table with kind one of {sorted(SCHEDULE_KINDS)}, got {schedule!r}")
    fields = SCHEDULE_KINDS[schedule["kind"]]
    if set(schedule) != {"kind", *fields}:
        raise ValueError(f"a {schedule['kind']} schedule has the fields kind, {', '.join(fields)}; got {sorted(schedule)}")
    for name in fields:
        value = schedule[name]
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"the schedule's {name} must be a number, got {value!r}")
    if schedule["decay_steps"] < 1:
        raise ValueError(f"the schedule's decay_steps must be at least 1, got {schedule['decay_steps']!r}")
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
