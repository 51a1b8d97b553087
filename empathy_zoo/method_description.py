"""What a result file says its run's method was: ``config.description`` (result schema 3).

A method describes each of its runs as plain JSON data (:meth:`agents.base.Method.describe`), and
the leaderboard reads that, never the method's name or its settings class, so a plug-in method is
scored, grouped and compared by what it declares. The fields (:data:`DESCRIPTION_FIELDS`):

``family``
    The algorithm the run is a case of (``"empathic_dqn"``, ``"dqn"``, ``"sb3"``, a plug-in's own;
    by default the method's name).
``dqn_reference``
    Whether the run is plain DQN on the environment's reward: the reference the leaderboard
    compares every other method with.
``selfishness``
    β, the weight of the robot's own target (``None``: the method has none).
``target``
    The empathic target the run learns, as :mod:`empathy_zoo.reference` names its rules
    (``"golden"``: Empathic DQN's ``β·own + (1 − β)·other``, plain DQN at β = 1; ``"silver"``: the
    silver rule's); ``None``: none (a plug-in may name its own, which has no reference).
``in_view_only``
    It swaps with another agent only while that agent is in its window.
``gamma``
    Its discount factor γ (``None``: not declared).
``exploration``
    Its ε schedule as data (:mod:`empathy_zoo.schedules`: ``{"kind": "linear", "start", "end",
    "warmup", "decay_steps"}``), from which the ε at any step follows; ``None``: not declared.
``reward``
    What it trains on instead of the environment's reward (``config.reward``: the reward
    transform's name and fields); ``None``: that reward.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from empathy_zoo.schedules import ScheduleError, check_schedule

__all__ = ["DESCRIPTION_FIELDS", "DescriptionError", "default_description", "check_description"]

DESCRIPTION_FIELDS: dict[str, str] = {
    "family": "a non-empty string",
    "dqn_reference": "true or false",
    "selfishness": "a number in [0, 1] or null",
    "target": "a non-empty string or null",
    "in_view_only": "true or false",
    "gamma": "a number in [0, 1] or null",
    "exploration": "an exploration schedule (kind linear: start, end, warmup, decay_steps) or null",
    "reward": "a reward transform's config (an object with a name) or null",
}
"""Every field of a description, with what its value must be."""


class DescriptionError(ValueError):
    """A description field that is not what :data:`DESCRIPTION_FIELDS` says."""

    def __init__(self, field: str, expected: str, value: Any) -> None:
        super().__init__(f"description field {field}: expected {expected}, got {value!r}")
        self.field, self.expected, self.value = field, expected, value


def default_description(family: str) -> dict[str, Any]:
    """The description of a run of a method that declares nothing: its family (the method's name),
    no DQN reference, no β, no target, an omniscient swap, nothing else known."""
    return {
        "family": family,
        "dqn_reference": False,
        "selfishness": None,
        "target": None,
        "in_view_only": False,
        "gamma": None,
        "exploration": None,
        "reward": None,
    }


def _is_number(value: Any, low: float, high: float) -> bool:
    return not isinstance(value, bool) and isinstance(value, (int, float)) and low <= value <= high


def check_description(description: Any) -> dict[str, Any]:
    """``description`` if it has exactly the fields of :data:`DESCRIPTION_FIELDS`, each of its kind
    (the exploration schedule's fields within their ranges: :func:`~empathy_zoo.schedules.check_schedule`),
    and ``dqn_reference`` only on the environment's reward at β = 1 (or none); else
    :class:`DescriptionError` naming the first field that is not."""
    if not isinstance(description, Mapping):
        raise DescriptionError("(the whole description)", "an object", description)
    for field in description:
        if field not in DESCRIPTION_FIELDS:
            raise DescriptionError(str(field), f"one of the fields {', '.join(DESCRIPTION_FIELDS)}", description[field])
    for field, expected in DESCRIPTION_FIELDS.items():
        if field not in description:
            raise DescriptionError(field, expected + " (the field is missing)", None)
        value = description[field]
        if field == "family":
            ok = isinstance(value, str) and bool(value) and "\n" not in value
        elif field in ("dqn_reference", "in_view_only"):
            ok = isinstance(value, bool)
        elif field in ("selfishness", "gamma"):
            ok = value is None or _is_number(value, 0.0, 1.0)
        elif field == "target":
            ok = value is None or (isinstance(value, str) and bool(value))
        elif field == "exploration":
            try:
                ok = value is None or bool(check_schedule(value))
            except ScheduleError as error:
                if error.field:  # (a field of the schedule: named)
                    raise DescriptionError(f"exploration.{error.field}", error.expected, error.value) from None
                ok = False
        else:  # reward
            ok = value is None or (isinstance(value, Mapping) and isinstance(value.get("name"), str) and bool(value["name"]))
        if not ok:
            raise DescriptionError(field, expected, value)
    if description["dqn_reference"] and (description["reward"] is not None or description["selfishness"] not in (None, 1.0)):
        raise DescriptionError(
            "dqn_reference",
            "false for a run that is no plain DQN: the reference trains on the environment's reward (reward null) "
            f"at β = 1 (selfishness 1 or null; this run's: reward {description['reward']!r}, selfishness "
            f"{description['selfishness']!r})",
            True,
        )
    return dict(description)
