"""What the plan of a tuning study's file (``study.json``, :mod:`leaderboard.study_file`) may hold,
checked field by field: the worlds it may have run on (:func:`plan_worlds`) and the range of a
metric's value in them (:func:`metric_bounds`), an objective metric that moves there
(:func:`check_moves`), its tuning seeds (:func:`tuning_seeds`), each parameter's spec
(:func:`parameter_spec`) and the values a trial holds of them (:func:`check_params`). Each check
refuses through the file's :class:`~empathy_zoo.document_checks.DocumentChecker`, naming the file and
the field.
"""

from __future__ import annotations

import contextlib
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from empathy_zoo.document_checks import DocumentChecker, finite_float
from empathy_zoo.limits import MAX_CYCLES, MAX_RANGE_END, MAX_SEED, MAX_SEEDS
from empathy_zoo.metrics import METRIC_RANGES

__all__ = [
    "RANGE_KINDS",
    "ParameterSpec",
    "check_moves",
    "check_params",
    "metric_bounds",
    "parameter_spec",
    "plan_worlds",
    "tuning_seeds",
]

RANGE_KINDS = ("log", "float", "int")
"""The kinds of a parameter spec that give a range (``choice`` lists its values)."""


@dataclass(frozen=True)
class ParameterSpec:
    """A parameter's spec as read: its kind, a range's ends, a choice's values (each as its text
    and, where the text is a TOML literal, that value)."""

    kind: str
    low: float = 0.0
    high: float = 0.0
    choices: tuple[tuple[str, Any], ...] = ()


def metric_bounds(metric: str, worlds: Sequence[tuple[str, Mapping[str, Any]]]) -> tuple[float, float | None]:
    """The range of a value of ``metric`` a study records (a mean over episodes and seeds):
    :data:`~empathy_zoo.metrics.METRIC_RANGES`, at most what one episode of its world can hold
    (:func:`~empathy_zoo.result_file.episode_bounds`; the largest of ``worlds`` where the study
    names several, :func:`plan_worlds`)."""
    from empathy_zoo.result_file import episode_bounds

    low, high = METRIC_RANGES[metric]
    most = [episode_bounds(env, kwargs)[metric] for env, kwargs in worlds]
    if any(bound is None for bound in most):
        return low, high
    world = max(bound for bound in most if bound is not None)
    return low, world if high is None else min(high, world)


def _largest_world(env: str) -> dict[str, Any]:
    """The arguments of ``env`` whose episodes hold the most of every count: ``max_cycles`` and its
    count of other agents at :data:`~empathy_zoo.limits.MAX_CYCLES` (the most a run is built with,
    :func:`~empathy_zoo.result_file.check_env_kwargs`)."""
    from empathy_zoo.environments import ENGINES

    count = ENGINES[env].count_argument
    return {"max_cycles": MAX_CYCLES, **({count: MAX_CYCLES} if count else {})}


def plan_worlds(check: DocumentChecker, plan: Mapping[str, Any]) -> list[tuple[str, Mapping[str, Any]]]:
    """The environments (with their arguments) the study's plan may have run on, checked as ``tune``
    makes a plan: ``experiment`` its ``variant`` and ``method``'s id
    (:func:`~empathy_zoo.run_ids.experiment_id`, ``<variant>__<method>-<hash>``; the two written
    together, or neither); ``env`` (which ``tune`` writes with ``env_kwargs``) a registered
    environment, the ``variant``'s own where the variant is named as one (a sweep file holds no
    other), ``env_kwargs`` its arguments within their ranges
    (:func:`~empathy_zoo.result_file.check_env_kwargs`). A study written before ``env`` was
    recorded: the variant's environment at its largest arguments (:func:`_largest_world`), or every
    environment's where the variant has a name of its own."""
    from empathy_zoo.environments import ENGINES
    from empathy_zoo.result_file import check_env_kwargs
    from empathy_zoo.run_ids import experiment_id

    variant = plan["variant"]
    if "experiment" in plan or "method" in plan:  # (tune writes both; a table of studies reads neither)
        check.has(plan, ("experiment", "method"), "plan.")
        method = check.text(plan["method"], "plan.method")
        experiment = check.text(plan["experiment"], "plan.experiment")
        head, _, digest = experiment.rpartition("-")
        if not head.startswith(f"{variant}__") or len(digest) != 8 or any(c not in "0123456789abcdef" for c in digest):
            raise check.fail(
                "plan.experiment", f"the id of an experiment of its variant ({variant}__<method>-<8 hex digits>)", experiment
            )
        if head != experiment_id(variant, method, {}).rpartition("-")[0]:
            raise check.fail("plan.method", f"the method of its experiment ({experiment})", method)
    if "env" not in plan and "env_kwargs" not in plan:
        envs = [variant] if variant in ENGINES else sorted(ENGINES)
        return [(env, _largest_world(env)) for env in envs]
    check.has(plan, ("env", "env_kwargs"), "plan.")
    env = plan["env"]
    if env not in ENGINES:
        raise check.fail("plan.env", f"one of the environments ({', '.join(sorted(ENGINES))})", env)
    if variant in ENGINES and variant != env:
        raise check.fail("plan.env", f"{variant}, the environment its variant is named as", env)
    return [(env, check_env_kwargs(check, env, plan["env_kwargs"], "plan.env_kwargs"))]


def check_moves(check: DocumentChecker, worlds: Sequence[tuple[str, Mapping[str, Any]]], metric: str) -> None:
    """Refuse an objective's ``metric`` that every episode of the study's world gives one value
    (:func:`~empathy_zoo.result_file.constant_metrics`, as ``tune`` refuses it: every trial would tie)."""
    from empathy_zoo.result_file import constant_metrics

    if all(metric in constant_metrics(env, kwargs) for env, kwargs in worlds):
        envs = ", ".join(sorted({env for env, _ in worlds}))
        raise check.fail(
            "plan.objective.metric", f"a metric that moves in {envs} (tune refuses one every episode gives one value)", metric
        )


def tuning_seeds(check: DocumentChecker, value: Any) -> list[int]:
    """``plan.tuning_seeds``: 1 … :data:`~empathy_zoo.limits.MAX_SEEDS` distinct seeds."""
    if not isinstance(value, list) or not 1 <= len(value) <= MAX_SEEDS:
        raise check.fail("plan.tuning_seeds", f"an array of 1 to {MAX_SEEDS:,} seeds", value)
    seeds = [check.integer(seed, f"plan.tuning_seeds[{i}]", 0, MAX_SEED) for i, seed in enumerate(value)]
    if len(set(seeds)) != len(seeds):
        raise check.fail("plan.tuning_seeds", "distinct seeds", value)
    return seeds


def parameter_spec(check: DocumentChecker, name: str, spec: Any) -> ParameterSpec:
    """A parameter's name and spec (``log:1e-4:1e-2``, ``choice:a,b``) as labels; a choice's values
    at least two, none empty; a range's ends finite, ``LOW < HIGH`` (as ``tune`` takes them) and
    within :data:`MAX_RANGE_END` (a ``log`` range's ``LOW`` at least its inverse)."""
    check.label(name, f"plan.params (the parameter {name[:60]!r})")
    where = f"plan.params.{name}"
    check.label(spec, where)
    kind, _, rest = spec.partition(":")
    items = [item.strip() for item in rest.split(",")]
    if kind == "choice" and len(items) >= 2 and all(items):
        return ParameterSpec(kind, choices=tuple((item, _literal(item)) for item in items))
    ends = [_finite(end) for end in rest.split(":")] if kind in RANGE_KINDS else []
    if (
        len(ends) != 2
        or ends[0] is None
        or ends[1] is None
        or not -MAX_RANGE_END <= ends[0] < ends[1] <= MAX_RANGE_END
        or (kind == "log" and ends[0] < 1 / MAX_RANGE_END)
        or (kind == "int" and any(end != int(end) for end in ends if end is not None))
    ):
        raise check.fail(
            where,
            f"a parameter's spec (log:LOW:HIGH with 0 < LOW, float:LOW:HIGH, int:LOW:HIGH of whole ends: LOW < HIGH, each within "
            f"±{MAX_RANGE_END:g}, a log range's LOW at least {1 / MAX_RANGE_END:g}; or choice:A,B,... of two values or more)",
            spec,
        )
    return ParameterSpec(kind, ends[0], ends[1])


_NO_LITERAL = object()
"""A choice's text that is no TOML literal (a text value)."""


def _literal(text: str) -> Any:
    """``text`` read as a TOML literal (``0.5``, ``true``), as ``tune`` reads a choice's value
    (:func:`empathy_zoo.experiment.search_space.parse_param`), or :data:`_NO_LITERAL`."""
    with contextlib.suppress(tomllib.TOMLDecodeError):
        return tomllib.loads(f"v = {text}")["v"]
    return _NO_LITERAL


def _is_choice(value: Any, choices: tuple[tuple[str, Any], ...]) -> bool:
    """Whether ``value`` is one of ``choices``: a text one of their texts, a boolean or a number one
    of their literals of its kind (a boolean is no number here, ``true`` no ``1``)."""
    if isinstance(value, str):
        return any(value == text for text, _ in choices)
    return any(
        isinstance(literal, (bool, int, float)) and isinstance(literal, bool) == isinstance(value, bool) and literal == value
        for _, literal in choices
    )


def _finite(text: str) -> float | None:
    """``text`` as a finite float, or ``None``."""
    try:
        return finite_float(float(text))
    except ValueError:
        return None


def check_params(check: DocumentChecker, value: Any, specs: Mapping[str, ParameterSpec], where: str, whole: bool = True) -> None:
    """A trial's parameter values: each of a parameter of the plan and, where ``whole`` (every trial
    but an interrupted one, which may have stopped before its parameters were drawn), every one of
    them; a range's a number within it (a whole one for an ``int``), a choice's one of its values."""
    table = check.table(value, where)
    for name, item in table.items():
        field = f"{where}.{name}" if name in specs else f"{where} (the parameter {name[:60]!r})"
        if name not in specs:
            raise check.fail(field, f"one of the plan's parameters ({', '.join(specs)})", name)
        spec = specs[name]
        kind, low, high = spec.kind, spec.low, spec.high
        if kind == "choice":
            if isinstance(item, str):
                check.label(item, field)
            elif not isinstance(item, bool):
                check.finite(item, field)
            if not _is_choice(item, spec.choices):
                texts = ", ".join(text for text, _ in spec.choices)
                raise check.fail(field, f"one of its choices ({texts}; a number as a number, text as text)", item)
            continue
        number = finite_float(item)
        if number is None or isinstance(item, bool) or not low <= number <= high or (kind == "int" and number != int(number)):
            raise check.fail(field, f"{'a whole number' if kind == 'int' else 'a number'} in [{low:g}, {high:g}]", item)
    missing = [name for name in specs if name not in table] if whole else []
    if missing:
        raise check.fail(f"{where}.{missing[0]}", f"a value of each of the plan's parameters ({', '.join(specs)})", None)
