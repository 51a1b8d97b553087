"""A method's settings as ``train`` options: one ``--<field>`` per field of its settings dataclass.

``train`` builds them for the method it trains (``--method``, else ``method`` in the ``--config``
file, else the default), so a plug-in method's own settings are options like the built-in ones.
A field's type says how its option reads values:

==============================  ==================================================
``bool``                        ``--field`` / ``--no-field``
``int``, ``float``, ``str``     one value of that type
``tuple[T, ...]``, ``list[T]``  one or more values of type ``T`` (``int``, ``float``, ``str``)
``T | None``                    as ``T``
``dict[str, T]``, ``Mapping``    one or more ``KEY=VALUE``, each value a TOML value
                                (``--algorithm-kwargs learning_starts=300 policy='"MlpPolicy"'``),
                                merged over the ``--config`` file's table
anything else                   no option: set it in ``[settings]`` of ``--config``
==============================  ==================================================

A field whose option would be a run option's (a setting named ``seed``, say) is set in
``[settings]`` too. A field the method fixes (``Method.preset``) keeps its option, listed apart:
another value is refused naming the method, as the same key in a ``--config`` file is.

The fields of the method's reward transform (``Method.reward``) are options too, read the same
way, in a group of their own: ``--<field>``, or ``--reward-<field>`` where ``--<field>`` is a
setting's or a run option's (``dqn_aup``'s ``--reward-learning-rate``), or names a setting of
another registered method (``sb3_ppo_aup``'s ``--reward-hidden-size``, as on ``dqn_aup``: an
option never reads as a learner's setting on one method and a transform's field on another); in
a ``--config`` file they are keys of ``[reward]``.
"""

from __future__ import annotations

import argparse
import ast
import inspect
import itertools
import textwrap
import tomllib
import types
from collections.abc import Mapping
from dataclasses import MISSING, Field, fields, is_dataclass
from typing import TYPE_CHECKING, Any, Union, get_args, get_origin

from empathy_zoo.cli.common import help_text

if TYPE_CHECKING:
    from agents.base import Method

__all__ = [
    "REWARD_DEST",
    "SETTINGS_DEST",
    "add_reward_options",
    "add_settings_options",
    "field_docs",
    "given_reward",
    "given_settings",
    "merged_settings",
    "option_reading",
]

SETTINGS_DEST = "settings."
"""Prefix of a setting's attribute on the parsed namespace (apart from the run options')."""
REWARD_DEST = "reward."
"""Prefix of a reward transform field's attribute on the parsed namespace."""
_SCALARS = (int, float, str)


def field_docs(cls: type) -> dict[str, str]:
    """The docstring under every field of a dataclass (``{}`` when the source is unavailable)."""
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(cls)))
    except (OSError, TypeError, SyntaxError):
        return {}
    body = tree.body[0].body if tree.body and isinstance(tree.body[0], ast.ClassDef) else []
    docs = {}
    for node, after in itertools.pairwise(body):
        if (
            isinstance(node, ast.AnnAssign)
            and isinstance(node.target, ast.Name)
            and isinstance(after, ast.Expr)
            and isinstance(after.value, ast.Constant)
            and isinstance(after.value.value, str)
        ):
            docs[node.target.id] = " ".join(after.value.value.split())
    return docs


class _StoreAs(argparse.Action):
    """Store an ``nargs="+"`` option's values as the field's container (a tuple field gets a tuple)."""

    def __init__(self, *args: Any, sequence: type, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.sequence = sequence  # (argparse gives every action a ``container``: its parser or group)

    def __call__(
        self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: Any, option_string: str | None = None
    ) -> None:
        setattr(namespace, self.dest, self.sequence(values))


class _StoreMapping(argparse.Action):
    """Store ``KEY=VALUE`` values as a dict, each value read as a TOML value (``300``, ``0.5``,
    ``true``, ``"text"``, ``[64, 64]``); anything else is refused naming the option."""

    def __call__(
        self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: Any, option_string: str | None = None
    ) -> None:
        table: dict[str, Any] = {}
        for item in values:
            key, equals, text = item.partition("=")
            if not equals or not key.strip():
                raise argparse.ArgumentError(self, f"{item!r} is no KEY=VALUE")
            if key.strip() in table:
                raise argparse.ArgumentError(self, f"{key.strip()} given twice")
            try:
                table[key.strip()] = tomllib.loads(f"value = {text}")["value"]
            except tomllib.TOMLDecodeError:
                raise argparse.ArgumentError(
                    self, f"{key.strip()}={text}: the value is no TOML value (a string needs quotes: {key.strip()}='\"{text}\"')"
                ) from None
        setattr(namespace, self.dest, table)


def option_reading(kind: Any) -> dict[str, Any] | None:
    """``add_argument`` keywords that read a value of type ``kind``; ``None`` if no option can."""
    arguments = get_args(kind)
    if get_origin(kind) in (Union, types.UnionType) and type(None) in arguments and len(arguments) == 2:
        kind = next(a for a in arguments if a is not type(None))  # T | None reads as T
        arguments = get_args(kind)
    if kind is bool:
        return {"action": argparse.BooleanOptionalAction}
    if kind in _SCALARS:
        return {"type": kind, "metavar": kind.__name__.upper()}
    container = get_origin(kind)
    if container in (dict, Mapping) and arguments and arguments[0] is str:
        return {"nargs": "+", "metavar": "KEY=VALUE", "action": _StoreMapping}
    sequence = (container is tuple and len(arguments) == 2 and arguments[1] is Ellipsis) or (container is list and arguments)
    if sequence and arguments[0] in _SCALARS:
        return {
            "type": arguments[0],
            "nargs": "+",
            "metavar": arguments[0].__name__.upper(),
            "action": _StoreAs,
            "sequence": container,
        }
    return None


def _default(field: Field) -> Any:
    if field.default is MISSING and field.default_factory is not MISSING:
        return field.default_factory()
    return field.default


def add_settings_options(parser: argparse.ArgumentParser, method: Method) -> None:
    """One option per field of ``method``'s settings dataclass, its help the field's docstring."""
    from empathy_zoo.experiment.values import field_types

    settings = method.settings
    if not (isinstance(settings, type) and is_dataclass(settings)):
        raise ValueError(f"method {method.name!r}: its settings {settings!r} is not a dataclass")
    docs, kinds = field_docs(settings), field_types(settings)
    description = f"the fields of {settings.__name__} (also keys of [settings] in --config)"
    free = parser.add_argument_group(f"settings of {method.name}", description)
    fixed = None
    in_config_only = []
    for field in fields(settings):
        reading = option_reading(kinds[field.name])
        if reading is None:
            in_config_only.append(field.name)
            continue
        if field.name in method.preset:
            fixed = fixed or parser.add_argument_group(f"settings {method.name} fixes", "another value is an error")
            group, text = fixed, f"{docs.get(field.name, '')} (fixed at {method.preset[field.name]!r})"
        else:
            group, text = free, f"{docs.get(field.name, '')} (default: {_default(field)!r})"
        try:
            group.add_argument(
                "--" + field.name.replace("_", "-"), dest=SETTINGS_DEST + field.name, help=help_text(text.strip()), **reading
            )
        except argparse.ArgumentError:  # its option is a run option's (a setting named ``seed``, say)
            in_config_only.append(field.name)
    if in_config_only:
        free.description = f"{description}; in [settings] only: {', '.join(in_config_only)}"


def add_reward_options(parser: argparse.ArgumentParser, method: Method) -> None:
    """One option per field of ``method``'s reward transform, its help the field's docstring:
    ``--<field>``, or ``--reward-<field>`` where that option is taken (a setting's, a run option's)."""
    transform = method.reward
    kinds = method.reward_fields()
    if transform is None or not kinds or not is_dataclass(transform):  # (a transform with fields is a dataclass)
        return
    from baselines.registry import METHODS  # (lazily: the registry imports the learners)

    settings_anywhere = {f.name for registered in METHODS.values() for f in fields(registered.settings)}
    docs = field_docs(type(transform))
    defaults = {f.name: _default(f) for f in fields(transform)}
    description = f"the fields of {type(transform).__name__} ({transform.name!r}; also keys of [reward] in --config)"
    group = parser.add_argument_group(f"reward transform of {method.name}", description)
    in_config_only = []
    for name, kind in kinds.items():
        reading = option_reading(kind)
        if reading is None:
            in_config_only.append(name)
            continue
        text = help_text(f"{docs.get(name, '')} (default: {defaults[name]!r})".strip())
        forms = ("--" + name.replace("_", "-"), "--reward-" + name.replace("_", "-"))
        for option in forms[1:] if name in settings_anywhere else forms:
            try:
                group.add_argument(option, dest=REWARD_DEST + name, help=text, **reading)
                break
            except argparse.ArgumentError:  # taken by a setting or a run option: the next form
                continue
        else:
            in_config_only.append(name)
    if in_config_only:
        group.description = f"{description}; in [reward] only: {', '.join(in_config_only)}"


def given_reward(args: argparse.Namespace) -> dict[str, Any]:
    """The reward transform's fields given as options (the namespace holds only those given)."""
    given = vars(args)
    return {key.removeprefix(REWARD_DEST): value for key, value in given.items() if key.startswith(REWARD_DEST)}


def given_settings(args: argparse.Namespace) -> dict[str, Any]:
    """The settings given as options (the namespace holds only those given); a table's keys are
    merged over the ``--config`` file's by :func:`merged_settings`."""
    given = vars(args)
    return {key.removeprefix(SETTINGS_DEST): value for key, value in given.items() if key.startswith(SETTINGS_DEST)}


def merged_settings(settings: Mapping[str, Any], given: Mapping[str, Any]) -> dict[str, Any]:
    """``settings`` (a ``--config`` file's) with the options ``given`` over them: a table option
    (``--algorithm-kwargs``) replaces the keys it names and keeps the file's others."""
    merged = dict(settings)
    for name, value in given.items():
        before = merged.get(name)
        merged[name] = {**before, **value} if isinstance(value, dict) and isinstance(before, Mapping) else value
    return merged
