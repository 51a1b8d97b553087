"""The arguments each registered fixed policy takes, declared once, and the one rule every fixed
policy is checked by before anything is imported or built.

A registered policy class declares ``parameters``: its keyword arguments in signature order, each
a :class:`Parameter` that knows its type and range, and, for a partner's own partners
(``partner``, ``members``), which policies it names. :func:`check_policy` is the rule: a
registered name with arguments it declares, of their type and range, each policy a value names
checked by the same rule (a ``package.module:Name`` there is never allowed); or a
``package.module:Name`` where the caller allows one, kept as text (its arguments are checked by
:func:`check_arguments` once the caller has imported it). Building (:func:`empathy_zoo.policies.make_policy`,
and every constructor, through :func:`check_arguments`) and reading a recorded label
(:func:`empathy_zoo.policies.checked_entry`) both go through it, so they cannot disagree.
"""

from __future__ import annotations

import inspect
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from empathy_zoo.import_names import is_registered
from empathy_zoo.limits import MAX_CYCLES

__all__ = [
    "REGISTRY",
    "MAX_POLICY_INT",
    "UnlistedPlugin",
    "Parameter",
    "Whole",
    "Share",
    "AgentName",
    "Partner",
    "Members",
    "Weights",
    "check_policy",
    "check_arguments",
    "declared_parameters",
]

REGISTRY: dict[str, type] = {}
"""The registered fixed policies by name: :data:`empathy_zoo.policies.POLICIES` (the same dict,
which that module fills)."""

MAX_POLICY_INT = MAX_CYCLES
"""The largest magnitude of an int argument of any fixed policy (a period, a step count): no
episode is longer (:data:`~empathy_zoo.limits.MAX_CYCLES`)."""


class UnlistedPlugin(ValueError):
    """A ``package.module:Name`` the caller does not allow (nothing was imported)."""

    def __init__(self, name: str) -> None:
        super().__init__(f"fixed policy {name!r} is not registered (a package.module:Name here is never imported)")
        self.name = name


class Parameter:
    """One keyword argument of a fixed policy: its type and range."""

    def expected(self) -> str:
        """What the argument holds, as a message says it."""
        return "a value"

    def problem(self, key: str, value: Any, arguments: Mapping[str, Any]) -> str | None:
        """What is wrong with ``value`` as argument ``key`` (``arguments``: every argument, defaults
        included), or ``None``; the policies it names are checked apart (:meth:`partners`)."""
        raise NotImplementedError

    def outside(self, arguments: Mapping[str, Any]) -> Any:
        """A value of the right shape just outside the declared range (what tests refuse)."""
        raise NotImplementedError

    def partners(self, key: str, value: Any) -> list[tuple[str, str]]:
        """``(field, name)`` of every policy ``value`` names (none for most arguments)."""
        return []

    def partner_problem(self, key: str, name: str) -> str | None:
        """What keeps registered policy ``name``, named in ``value``, from being one, or ``None``."""
        return None


@dataclass(frozen=True)
class Whole(Parameter):
    """An int (not a boolean) in ``[low, high]``."""

    low: int
    high: int
    what: str = "an int"

    def problem(self, key: str, value: Any, arguments: Mapping[str, Any]) -> str | None:
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not self.low <= value <= self.high:
            return f"{key} must be {self.what} in [{self.low:,}, {self.high:,}], got {value!r:.80}"
        return None

    def outside(self, arguments: Mapping[str, Any]) -> Any:
        return self.low - 1


@dataclass(frozen=True)
class Share(Parameter):
    """A number (an int or a float, not a boolean) in ``(0, high]``: a probability."""

    high: float = 1.0

    def problem(self, key: str, value: Any, arguments: Mapping[str, Any]) -> str | None:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 < value <= self.high:
            return f"{key} must be a number in (0, {self.high:g}], got {value!r:.80}"
        return None

    def outside(self, arguments: Mapping[str, Any]) -> Any:
        return self.high * 2


@dataclass(frozen=True)
class AgentName(Parameter):
    """An agent's name (a non-empty string)."""

    def problem(self, key: str, value: Any, arguments: Mapping[str, Any]) -> str | None:
        if not isinstance(value, str) or not value:
            return f"{key} must be an agent's name (e.g. 'robot_0'), got {value!r:.80}"
        return None

    def outside(self, arguments: Mapping[str, Any]) -> Any:
        return ""


@dataclass(frozen=True)
class Partner(Parameter):
    """The name of one registered policy other than ``exclude``, built with its defaults; one that
    keeps nothing between steps (``stateless = True``) where ``stateless``."""

    exclude: str
    stateless: bool = False

    def expected(self) -> str:
        return f"a registered policy other than {self.exclude!r}"

    def problem(self, key: str, value: Any, arguments: Mapping[str, Any]) -> str | None:
        if not isinstance(value, str) or not value:
            return f"{key} must name {self.expected()}, got {value!r:.80}"
        return None

    def outside(self, arguments: Mapping[str, Any]) -> Any:
        return self.exclude

    def partners(self, key: str, value: Any) -> list[tuple[str, str]]:
        return [(key, value)]

    def partner_problem(self, key: str, name: str) -> str | None:
        if name == self.exclude:
            return f"{key} must name {self.expected()}, got {name!r}"
        if self.stateless and getattr(REGISTRY[name], "stateless", False) is not True:
            return f"{key} must keep nothing between steps (stateless = True); {name!r} does not"
        return None


@dataclass(frozen=True)
class Members(Parameter):
    """A list of 1 to ``most`` different names of registered policies other than ``exclude``, each
    built with its defaults."""

    exclude: str
    most: int

    def expected(self) -> str:
        return f"registered policies other than {self.exclude!r}"

    def problem(self, key: str, value: Any, arguments: Mapping[str, Any]) -> str | None:
        if isinstance(value, str) or not isinstance(value, Sequence) or not 1 <= len(value) <= self.most:
            return f"{key} must be a list of 1 to {self.most} registered policy names, got {value!r:.200}"
        if not all(isinstance(name, str) and name for name in value):
            return f"{key} must name {self.expected()}, got {list(value)!r:.200}"
        if len(set(value)) != len(value):
            return f"{key} must differ (give a member more weight instead), got {list(value)!r:.200}"
        return None

    def outside(self, arguments: Mapping[str, Any]) -> Any:
        return []

    def partners(self, key: str, value: Any) -> list[tuple[str, str]]:
        return [(f"{key}[{i}]", name) for i, name in enumerate(value)]

    def partner_problem(self, key: str, name: str) -> str | None:
        return f"{key} must name {self.expected()}, got {name!r}" if name == self.exclude else None


@dataclass(frozen=True)
class Weights(Parameter):
    """``None`` (equal shares), or one number in ``(0, high]`` for each entry of argument ``of``."""

    of: str
    high: float

    def problem(self, key: str, value: Any, arguments: Mapping[str, Any]) -> str | None:
        if value is None:
            return None
        count = len(arguments[self.of])
        if isinstance(value, str) or not isinstance(value, Sequence) or len(value) != count:
            return f"{key} must be a list of {count} numbers (one per member), got {value!r:.200}"
        if any(isinstance(w, bool) or not isinstance(w, (int, float)) or not 0 < w <= self.high for w in value):
            return f"{key} must be positive finite numbers of at most {self.high:g}, got {list(value)!r:.200}"
        return None

    def outside(self, arguments: Mapping[str, Any]) -> Any:
        return [self.high * 2] * len(arguments[self.of])


def declared_parameters(policy: type) -> dict[str, Parameter] | None:
    """The parameters ``policy`` declares (its own class attribute ``parameters``, not one it
    inherits: a subclass may take other arguments), or ``None``."""
    declared = vars(policy).get("parameters") if isinstance(policy, type) else None
    return dict(declared) if isinstance(declared, Mapping) else None


def check_policy(name: Any, arguments: Mapping[str, Any], plugins: Collection[str] | None) -> type | None:
    """The rule a fixed policy ``name`` built with ``arguments`` is checked by, importing and
    building nothing. A registered name gives its class, its arguments checked (each a number a
    policy may take, :func:`_number_problem`, then :func:`check_arguments`). A
    ``package.module:Name`` gives ``None`` when ``plugins`` is ``None`` (any, kept as text) or
    holds it, and raises :class:`UnlistedPlugin` otherwise. Any other name raises ``ValueError``
    (:func:`~empathy_zoo.import_names.is_registered`)."""
    if is_registered(name, REGISTRY, "fixed policy"):
        for key, value in arguments.items():
            problem = _number_problem(key, value)
            if problem:
                raise ValueError(f"cannot build fixed policy {name!r}: {problem}")
        check_arguments(name, REGISTRY[name], arguments)
        return REGISTRY[name]
    if plugins is not None and name not in plugins:
        raise UnlistedPlugin(name)
    return None


def check_arguments(name: str, policy: type, arguments: Mapping[str, Any]) -> None:
    """Raise ``ValueError`` (``cannot build fixed policy NAME: ...``) unless ``policy`` takes every
    one of ``arguments``: where it declares its parameters, each of its type and range, every
    policy it names checked by :func:`check_policy` (no ``package.module:Name``); otherwise each
    named in its signature and a number a policy may take (:func:`_number_problem`)."""
    declared = declared_parameters(policy)
    named = list(declared) if declared is not None else _signature_names(policy)
    for key in arguments:
        if named is not None and key not in named:
            raise ValueError(
                f"cannot build fixed policy {name!r}: it takes no argument {key!r} (its arguments: {', '.join(named) or 'none'})"
            )
        problem = None if declared is not None else _number_problem(key, arguments[key])
        if problem:
            raise ValueError(f"cannot build fixed policy {name!r}: {problem}")
    if declared is None:
        return
    given = {**_defaults(policy), **arguments}
    for key, parameter in declared.items():
        if key in arguments:
            problem = parameter.problem(key, arguments[key], given) or _partners_problem(key, parameter, arguments[key])
            if problem:
                raise ValueError(f"cannot build fixed policy {name!r}: {problem}")


def _partners_problem(key: str, parameter: Parameter, value: Any) -> str | None:
    """What keeps a policy that argument ``key`` names from being one it may name: each checked by
    :func:`check_policy` (no ``package.module:Name`` allowed), then by ``parameter``; else ``None``."""
    for field, partner in parameter.partners(key, value):
        try:
            check_policy(partner, {}, plugins=())
        except ValueError as error:
            return f"{field}: {error}; {key} must name {parameter.expected()}"
        problem = parameter.partner_problem(key, partner)
        if problem:
            return problem
    return None


def _number_problem(key: str, value: Any) -> str | None:
    """What makes ``value`` (or a number inside a list) one no policy takes: an int beyond
    :data:`MAX_POLICY_INT`, or a float that is not finite; else ``None``."""
    for item in value if isinstance(value, (list, tuple)) else [value]:
        if isinstance(item, (list, tuple)):
            problem = _number_problem(key, item)
            if problem:
                return problem
        elif isinstance(item, (int, np.integer)) and not isinstance(item, bool) and abs(int(item)) > MAX_POLICY_INT:
            return f"{key} = {item!r:.40} is beyond ±{MAX_POLICY_INT:,}"
        elif isinstance(item, (float, np.floating)) and not np.isfinite(item):
            return f"{key} = {item!r} is not a finite number"
    return None


def _signature(policy: type) -> list[inspect.Parameter] | None:
    """The parameters of ``policy``'s constructor, or ``None`` when it has no signature to read."""
    try:
        return list(inspect.signature(policy).parameters.values())
    except (TypeError, ValueError):
        return None


def _signature_names(policy: type) -> list[str] | None:
    """The keyword arguments ``policy``'s signature names, or ``None`` when it takes any (``**kwargs``)
    or has no signature to read (the call itself will say)."""
    parameters = _signature(policy)
    if parameters is None or any(p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters):
        return None
    return [p.name for p in parameters if p.kind in (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)]


def _defaults(policy: type) -> dict[str, Any]:
    """The default of every argument of ``policy``'s signature that has one."""
    return {p.name: p.default for p in _signature(policy) or [] if p.default is not inspect.Parameter.empty}
