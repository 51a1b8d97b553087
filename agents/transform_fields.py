"""How a reward transform's fields are read and set: every way a run's transform is configured
(a sweep file's entry, ``train --config`` and its options, a tuning study's points and the ends of
its ranges, a result file's ``config.reward``) goes through :func:`configure_transform`, which
checks each value (:func:`check_field_value`) against the field's type and the bounds
:data:`MAX_TRANSFORM_WEIGHT` (a float field) and :data:`MAX_TRANSFORM_COUNT` (an int field),
refusing one with a :class:`TransformFieldError`. The transforms themselves, and the protocol
they follow, are in :mod:`agents.rewards`."""

from __future__ import annotations

import dataclasses
import math
import sys
import types
import typing
from collections.abc import Mapping
from typing import Any

from agents.rewards import RewardTransform
from empathy_zoo.limits import MAX_STEPS

__all__ = [
    "MAX_TRANSFORM_COUNT",
    "MAX_TRANSFORM_WEIGHT",
    "TransformFieldError",
    "check_field_value",
    "configure_transform",
    "transform_fields",
]


MAX_TRANSFORM_WEIGHT = 1e4
"""The largest magnitude of a float field of a reward transform (a penalty, a weight, a rate):
checked when the transform is configured (:func:`configure_transform`: a sweep file, ``train
--config`` and its options, a tuning range's ends, a result file's ``config.reward``), so that a
run's shaped rewards stay within the replay memory's bound, :data:`agents.replay.MAX_ABS_REWARD`
= 1e6, which it checks only when a step is stored, minutes into training.

The arithmetic, with ``R`` the largest reward an agent gets in a step (the engine's
``step_reward_bound``: 1 in Coexistence, Helping and Charger, 2 in Vase, 1.0 in Sharing at its
default size 7 and ``0.1·⌊size/2⌋² − 1.1`` on larger grids, whose late batteries are worth less
than nothing), ``H`` the agents harmed in one step (at most ``num_cats``) and ``W`` this bound:

* ``harm_penalty``: ``|r + p·H| ≤ R + W·H`` = 10,001 with one cat; within 1e6 while ``H ≤ 99``;
* ``negative_reward_empathy``: ``|r + c·min(r_j, 0)| ≤ R·(1 + W)``: within 1e6 while ``R ≤ 99``;
* ``inequity_aversion``: the smoothed rewards differ by at most ``R/(1 − γλ)``, and the transform
  itself holds ``max(|α|, |β|)/(1 − γλ) ≤ W`` (:class:`baselines.shaping.InequityAversion`), so
  ``|r'| ≤ R·(1 + W)`` as above;
* ``social_value_orientation``: ``|θ − θ*| ≤ 2π``, so ``|r'| ≤ R + 2π·W`` ≈ 62,833;
* ``relative_reachability``: a deviation lies in ``[0, 1]``, so ``|r'| ≤ R + W`` = 10,001;
* ``lagrangian``: the stored reward is the environment's and the cost the harms; ``λ`` prices them
  when sampled, never stored; ``equality_scaling``: ``|r'| ≤ R`` (equality lies in ``[0, 1]``);
* ``attainable_utility`` and ``considerate``: ``λ`` (``α``) times a quantity of the learned side
  network (a relative shift of auxiliary values; the other's value ``V_j`` summed over the others),
  which no field bounds: the replay memory's check is their bound (docs/limits.md).

So in every environment of the suite at its defaults (``R ≤ 2``, one other agent) no shaped reward
of a field-bounded transform leaves ±1e6, with a factor of 15 to spare; with more than 99 cats
harmed in one step, or a Sharing grid of side 64 or more, one at this bound can, and the replay
memory refuses that step (docs/limits.md). The shipped profiles and results use at most 100
(the harm penalty, relative reachability's λ): two orders of magnitude below."""
MAX_TRANSFORM_COUNT = MAX_STEPS
"""The largest magnitude of an int field of a reward transform (a side learner's replay capacity,
warm-up, update interval, width): each counts steps, updates or units of a run, and no run is
longer than :data:`~empathy_zoo.limits.MAX_STEPS` steps."""


class TransformFieldError(ValueError):
    """A value a reward transform's field does not take: ``"<field> must be <wanted>, got ..."``;
    :attr:`field`, :attr:`wanted` and :attr:`value` let a caller that names the field itself (a
    file and its key) say only :attr:`problem`."""

    def __init__(self, field: str, wanted: str, value: Any, owner: str = "") -> None:
        self.field, self.wanted, self.value, self.owner = field, wanted, value, owner
        whose = f" (a reward field of method {owner!r})" if owner else ""
        super().__init__(f"{field} {self.problem}{whose}")

    @property
    def problem(self) -> str:
        """What is wrong, without the field's name: ``"must be <wanted>, got <type> <value>"``."""
        return f"must be {self.wanted}, got {type(self.value).__name__} {_shown_value(self.value)}"


def _shown_value(value: Any) -> str:
    """``value`` as an error shows it: a float as ``%g`` (``2e+06``), anything else as ``repr``."""
    return f"{value:g}" if isinstance(value, float) else repr(value)


def transform_fields(transform: RewardTransform | None) -> dict[str, Any]:
    """``{field: type}`` of a reward transform's parameters (its dataclass fields, annotations
    resolved; ``Any`` where one cannot be), in declaration order; ``{}`` for ``None`` or a transform
    that is no dataclass (it has no parameters one could set). Where the class's annotations cannot
    all be resolved (a class variable naming a type imported for type checking only), each field's
    own is resolved alone, so a ``float`` field is a ``float`` (and bounded) all the same."""
    if transform is None or not dataclasses.is_dataclass(transform):
        return {}
    try:
        hints = typing.get_type_hints(type(transform))
    except (NameError, TypeError):
        hints = {f.name: _field_hint(type(transform), f) for f in dataclasses.fields(transform)}
    return {f.name: hints.get(f.name, Any) for f in dataclasses.fields(transform) if f.init}


def _field_hint(cls: type, field: dataclasses.Field[Any]) -> Any:
    """The annotation of one dataclass field of ``cls``, resolved in its module; ``Any`` where it
    cannot be."""
    if not isinstance(field.type, str):
        return field.type
    module = sys.modules.get(cls.__module__)
    holder = types.SimpleNamespace(__annotations__={field.name: field.type})
    try:
        return typing.get_type_hints(holder, globalns=vars(module) if module is not None else {}).get(field.name, Any)
    except (NameError, TypeError, SyntaxError):
        return Any


def configure_transform(transform: RewardTransform | None, overrides: Mapping[str, Any], owner: str = "") -> Any:
    """``transform`` with the fields ``overrides`` set (``dataclasses.replace``, so the transform's
    own checks run), or ``transform`` itself when there are none. An unknown field raises
    ``ValueError``, and a value :func:`check_field_value` refuses (the wrong type: an int is taken
    for a float, a bool is not a number; a float that is not finite or beyond
    ±:data:`MAX_TRANSFORM_WEIGHT`; an int beyond ±:data:`MAX_TRANSFORM_COUNT`) a
    :class:`TransformFieldError`, each naming the field and ``owner`` (a method's name) when given.
    Every way a run's transform is set goes through here: a sweep file's entry, ``train`` (its
    ``--config`` file's ``[reward]`` and its options), a tuning study's points and the ends of its
    ranges, a result file's ``config.reward``."""
    overrides = dict(overrides)
    if not overrides:
        return transform
    whose = f" of method {owner!r}" if owner else ""
    kinds = transform_fields(transform)
    if transform is None or not kinds:
        what = "no reward transform" if transform is None else f"a reward transform without fields ({transform.name!r})"
        raise ValueError(
            f"{f'method {owner!r}' if owner else 'this method'} has {what}: {', '.join(sorted(overrides))} cannot be set"
        )
    unknown = [name for name in overrides if name not in kinds]
    if unknown:
        raise ValueError(
            f"unknown field(s) {unknown} of the reward transform {transform.name!r}{whose}; its fields: {', '.join(kinds)}"
        )
    checked = {name: check_field_value(transform, name, value, owner) for name, value in overrides.items()}
    editable: Any = transform  # (a dataclass: transform_fields found its fields)
    return dataclasses.replace(editable, **checked)


def check_field_value(transform: RewardTransform | None, name: str, value: Any, owner: str = "") -> Any:
    """``value`` as the field ``name`` of ``transform`` takes it (an int given for a float becomes a
    float), else :class:`TransformFieldError` naming the field (and ``owner``, a method's name):
    a float must be a finite number within ±:data:`MAX_TRANSFORM_WEIGHT`, an int a whole number
    within ±:data:`MAX_TRANSFORM_COUNT`, a bool or str of its type; other types, and the ranges a
    transform keeps itself (a smoothing in ``[0, 1)``), are the transform's to check when it is
    built. A field the transform does not have is ``ValueError`` (:func:`configure_transform` names
    them all)."""
    kinds = transform_fields(transform)
    if name not in kinds:
        what = "no reward transform" if transform is None else f"the reward transform {transform.name!r}"
        raise ValueError(f"{name!r} is no field of {what}; its fields: {', '.join(kinds) or 'none'}")
    return _checked_value(name, value, kinds[name], owner)


def _checked_value(name: str, value: Any, kind: Any, owner: str = "") -> Any:
    """``value`` for a field of type ``kind`` (``float``, ``int``, ``bool``, ``str``; other types are
    the transform's to check), or a :class:`TransformFieldError` naming the field."""

    def fail(wanted: str) -> TransformFieldError:
        return TransformFieldError(name, wanted, value, owner)

    if kind is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise fail("a number")
        if isinstance(value, float) and not math.isfinite(value):
            raise fail("a finite number")
        if abs(value) > MAX_TRANSFORM_WEIGHT:  # (an int compared exactly: no float of it is made)
            raise fail(_bounded("a number", MAX_TRANSFORM_WEIGHT, "MAX_TRANSFORM_WEIGHT"))
        return float(value)
    if kind is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise fail("an int")
        if abs(value) > MAX_TRANSFORM_COUNT:
            raise fail(_bounded("an int", MAX_TRANSFORM_COUNT, "MAX_TRANSFORM_COUNT"))
    if kind in (bool, str) and not isinstance(value, kind):
        raise fail(f"a {kind.__name__}")
    return value


def _bounded(what: str, bound: float, constant: str) -> str:
    """What a field beyond its bound must be, with the bound and where it is set."""
    return (
        f"{what} within ±{bound:,g} (agents.transform_fields.{constant}: larger ones would shape rewards past what "
        "the replay memory holds, docs/limits.md)"
        if constant == "MAX_TRANSFORM_WEIGHT"
        else f"{what} within ±{bound:,g} (agents.transform_fields.{constant}: no run is longer, docs/limits.md)"
    )
