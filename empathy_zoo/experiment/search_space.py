"""A tuning search space: ``NAME=KIND:…`` parameter specs, checked against a method's settings and
its reward transform's fields, and the runs a point of the space gives.

``empathy-zoo tune --param`` takes one spec per parameter (:mod:`empathy_zoo.training.tuning`
samples them with Optuna):

=====================  ==================================================================
``NAME=log:LOW:HIGH``  log-uniform between ``LOW`` and ``HIGH`` (``0 < LOW < HIGH``); an int
                       field draws whole numbers, log-spaced (``LOW >= 1``)
``NAME=float:LOW:HIGH`` uniform between ``LOW`` and ``HIGH`` (a float field)
``NAME=int:LOW:HIGH``  a uniform whole number from ``LOW`` to ``HIGH`` inclusive (an int field)
``NAME=choice:A,B,C``  one of the values listed (at least two, each read as the field's type:
                       ``choice:closest,mean,min``, ``choice:0.25,0.5,0.75``)
=====================  ==================================================================

``NAME`` is a setting of the method (not one it fixes: DQN's β is 1) or a field of its reward
transform, ``reward.<field>`` for a field named like a setting (as in sweep files: ``dqn_aup``'s
``reward.learning_rate``). A bad spec raises ``ValueError`` naming the part that is wrong and what
it takes; a bound is never clipped or rounded to fit: the settings class's own checks run at both
ends of every range before a study starts (:func:`check_ends`). A range's ends lie within
±:data:`~empathy_zoo.limits.MAX_RANGE_END` (a ``log`` range's ``LOW`` at least its inverse), as
a study's checker (``analyse tuning-summary``) takes them.
"""

from __future__ import annotations

import contextlib
import math
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

from agents.base import Method
from empathy_zoo.experiment.model import MethodEntry, RunSpec
from empathy_zoo.experiment.values import SweepConfigError, check_value, describe_type, field_types
from empathy_zoo.limits import MAX_RANGE_END

__all__ = ["KINDS", "REWARD_PREFIX", "ParamSpec", "check_ends", "parse_param", "parse_params", "point_runs", "tunable_names"]

KINDS = ("log", "float", "int", "choice")
"""The kinds of a parameter spec (see the module documentation)."""
REWARD_PREFIX = "reward."
"""How a spec names a reward transform's field that shares its name with a setting."""
_CATEGORICAL = (bool, int, float, str)
"""The values a choice may take (those Optuna stores)."""
_RANGE_BOUND = (
    f"a range's ends lie within ±{MAX_RANGE_END:g}, a log range's LOW at least {1 / MAX_RANGE_END:g} "
    "(the bound of a study's ranges, docs/limits.md)"
)
"""What a refusal of a range's end past :data:`~empathy_zoo.limits.MAX_RANGE_END` says."""


@dataclass(frozen=True)
class ParamSpec:
    """One tuned parameter: where it goes (a setting or a reward field), and the values it may take."""

    name: str
    """The name as given (``learning_rate``, ``penalty``, ``reward.learning_rate``): the key in a study."""
    part: str
    """``settings`` or ``reward``."""
    field: str
    """The field it sets in that part."""
    kind: str
    """One of :data:`KINDS`."""
    integer: bool = False
    """Whether a range draws whole numbers (the field is an int)."""
    low: float = 0.0
    """Lower bound of a range (inclusive)."""
    high: float = 0.0
    """Upper bound of a range (inclusive)."""
    choices: tuple[Any, ...] = ()
    """The values of a ``choice``."""

    @property
    def text(self) -> str:
        """The spec as ``--param`` takes it."""
        if self.kind == "choice":
            return f"{self.name}=choice:{','.join(_choice_text(c) for c in self.choices)}"
        low, high = (int(self.low), int(self.high)) if self.integer else (self.low, self.high)
        return f"{self.name}={self.kind}:{low!r}:{high!r}"

    def suggest(self, trial: Any) -> Any:
        """The value an Optuna ``trial`` draws for this parameter."""
        if self.kind == "choice":
            return trial.suggest_categorical(self.name, list(self.choices))
        if self.integer:
            return trial.suggest_int(self.name, int(self.low), int(self.high), log=self.kind == "log")
        return trial.suggest_float(self.name, self.low, self.high, log=self.kind == "log")

    def ends(self) -> tuple[Any, ...]:
        """The values at the ends of the space (a choice's every value)."""
        if self.kind == "choice":
            return self.choices
        return (int(self.low), int(self.high)) if self.integer else (self.low, self.high)


def _choice_text(value: Any) -> str:
    return ("true" if value else "false") if isinstance(value, bool) else str(value)


def tunable_names(method: Method) -> list[str]:
    """What a spec of ``method`` may name: its settings but those it fixes, then its reward
    transform's fields (``reward.<field>`` for one named like a setting)."""
    settings = [name for name in field_types(method.settings) if name not in method.preset]
    reward = [f"{REWARD_PREFIX}{name}" if name in field_types(method.settings) else name for name in method.reward_fields()]
    return settings + reward


def _target(name: str, method: Method, where: str) -> tuple[str, str, Any]:
    """``(part, field, annotation)`` of the parameter ``name`` of ``method``."""
    settings, reward = field_types(method.settings), method.reward_fields()
    known = ", ".join(tunable_names(method)) or "none"
    if name.startswith(REWARD_PREFIX):
        field = name.removeprefix(REWARD_PREFIX)
        if field not in reward:
            what = "has no reward transform" if method.reward is None else f"'s reward transform has no field {field!r}"
            raise ValueError(f"{where}: method {method.name!r}{' ' if method.reward is None else ''}{what}; tunable: {known}")
        return "reward", field, reward[field]
    if name in settings:
        if name in method.preset:
            raise ValueError(f"{where}: method {method.name!r} fixes {name} = {method.preset[name]!r}; tunable: {known}")
        return "settings", name, settings[name]
    if name in reward:
        return "reward", name, reward[name]
    raise ValueError(
        f"{where}: {name!r} is no setting of method {method.name!r} nor a field of its reward transform; tunable: {known}"
    )


def _number(text: str, integer: bool, where: str, what: str) -> float:
    """``text``, an end of a range, as a number (a whole one where ``integer``): finite and within
    ±:data:`~empathy_zoo.limits.MAX_RANGE_END`, else a ``ValueError`` naming ``what`` it is."""
    try:
        value = int(text) if integer else float(text)
    except ValueError:
        kind = "a whole number" if integer else "a number"
        raise ValueError(f"{where}: {what} {text!r} is not {kind}") from None
    if not integer and not math.isfinite(value):
        raise ValueError(f"{where}: {what} {text!r} is not finite")
    if abs(value) > MAX_RANGE_END:  # (an int compared exactly: no float of it is made)
        raise ValueError(f"{where}: {what} {text!r} is out of bounds: {_RANGE_BOUND}")
    return value


def parse_param(text: str, method: Method) -> ParamSpec:
    """The spec ``text`` (``NAME=KIND:…``, see the module documentation) of a parameter of
    ``method``; ``ValueError`` naming the part that is wrong."""
    where = f"--param {text!r}"
    name, sep, rest = text.partition("=")
    name = name.strip()
    if not sep or not name:
        raise ValueError(f"{where}: expected NAME=KIND:..., e.g. learning_rate=log:1e-4:1e-2 ({_kinds_text()})")
    kind, sep, body = rest.partition(":")
    if kind not in KINDS or not sep:
        shown = f"unknown kind {kind!r}" if kind not in KINDS else f"{kind} needs values after a colon"
        raise ValueError(f"{where}: {shown}; {_kinds_text()}")
    part, field, annotation = _target(name, method, where)
    if kind == "choice":
        return ParamSpec(name, part, field, kind, choices=_choices(body, annotation, where))
    if annotation not in (int, float):
        raise ValueError(
            f"{where}: {name} takes {describe_type(annotation)}, not a range of numbers: give choice:A,B,... of its values"
        )
    integer = annotation is int
    if integer and kind == "float":
        raise ValueError(f"{where}: {name} is an int: give int:LOW:HIGH or log:LOW:HIGH (whole numbers), not float:")
    if not integer and kind == "int":
        raise ValueError(f"{where}: {name} is a float: give float:LOW:HIGH or log:LOW:HIGH, not int:")
    bounds = body.split(":")
    if len(bounds) != 2:
        raise ValueError(f"{where}: {kind} takes two bounds, {kind}:LOW:HIGH, got {body!r}")
    low, high = (_number(b.strip(), integer, where, what) for what, b in zip(("LOW", "HIGH"), bounds, strict=True))
    if not low < high:
        raise ValueError(f"{where}: LOW must be below HIGH, got LOW={bounds[0]} and HIGH={bounds[1]}")
    if kind == "log" and low <= 0:
        raise ValueError(f"{where}: a log range needs LOW > 0, got LOW={bounds[0]} (use {'int' if integer else 'float'}:)")
    if kind == "log" and low < 1 / MAX_RANGE_END:
        raise ValueError(f"{where}: LOW {bounds[0].strip()!r} is out of bounds: {_RANGE_BOUND}")
    return ParamSpec(name, part, field, kind, integer, float(low), float(high))


def _kinds_text() -> str:
    return "kinds: log:LOW:HIGH, float:LOW:HIGH, int:LOW:HIGH, choice:A,B,C"


def _choices(body: str, annotation: Any, where: str) -> tuple[Any, ...]:
    items = [item.strip() for item in body.split(",")]
    if any(not item for item in items):
        raise ValueError(f"{where}: an empty value in choice:{body} (give values separated by commas)")
    if len(items) < 2:
        raise ValueError(f"{where}: choice:{body} lists one value: give at least two (one value is a setting, not a search)")
    values = [_choice_value(item, annotation, where) for item in items]
    if len({(type(v), v) for v in values}) != len(values):
        raise ValueError(f"{where}: a value is listed twice in choice:{body}")
    return tuple(values)


def _choice_value(item: str, annotation: Any, where: str) -> Any:
    """``item`` read as a value of ``annotation``: a TOML literal (``0.5``, ``true``) when that fits,
    else the text itself."""
    candidates: list[Any] = []
    with contextlib.suppress(tomllib.TOMLDecodeError):
        candidates.append(tomllib.loads(f"v = {item}")["v"])
    candidates.append(item)
    for candidate in candidates:
        try:
            value = check_value(candidate, annotation, where)
        except SweepConfigError:
            continue
        if isinstance(value, _CATEGORICAL) and not (isinstance(value, float) and not math.isfinite(value)):
            return value
    raise ValueError(f"{where}: {item!r} is not a value it takes ({describe_type(annotation)})")


def parse_params(texts: Sequence[str], method: Method) -> tuple[ParamSpec, ...]:
    """The specs ``texts`` of ``method`` (at least one; a field named twice is refused)."""
    if not texts:
        raise ValueError(
            f"give at least one --param NAME=KIND:... (tunable for {method.name}: {', '.join(tunable_names(method))})"
        )
    specs = tuple(parse_param(text, method) for text in texts)
    seen: dict[tuple[str, str], str] = {}
    for spec in specs:
        if (spec.part, spec.field) in seen:
            raise ValueError(f"--param {spec.name} is given twice ({seen[spec.part, spec.field]} and {spec.text})")
        seen[spec.part, spec.field] = spec.text
    return specs


def point_runs(base: RunSpec, params: Sequence[ParamSpec], values: Mapping[str, Any], seeds: Sequence[int]) -> list[RunSpec]:
    """The runs of ``base`` with the parameters ``values`` (by spec name) set, one per seed of
    ``seeds``: ``base``'s other settings and reward fields, environment variant and budget, and the
    method's own label (``ValueError`` where the settings class refuses the point)."""
    settings = base.entry.changed_settings()
    reward = base.entry.changed_reward()
    for spec in params:
        (settings if spec.part == "settings" else reward)[spec.field] = values[spec.name]
    entry = MethodEntry.resolve(base.entry.name, settings, reward)
    return [replace(base, entry=entry, seed=seed) for seed in seeds]


def check_ends(base: RunSpec, params: Sequence[ParamSpec]) -> None:
    """Build ``base``'s runs at both ends of every range and at every choice (the others at their
    low end), so that a bound the method refuses is said before a study starts, naming the spec."""
    for spec in params:
        for value in spec.ends():
            values = {other.name: other.ends()[0] for other in params} | {spec.name: value}
            try:
                point_runs(base, params, values, [base.seed])
            except ValueError as error:
                raise ValueError(
                    f"--param {spec.text}: method {base.method!r} refuses {spec.name} = {value!r} ({error})"
                ) from None
