"""Sweeps as TOML files: which methods to train, on which environments, with which seeds.

``load_sweep(path)`` reads and validates a sweep file (Python's ``tomllib``) and returns the
list of :class:`~empathy_zoo.training.RunSpec` it declares; ``empathy-zoo reproduce`` trains
them and writes the leaderboard. Everything is checked before any training starts: an unknown
table or key, a value of the wrong type, an unknown method, environment or fixed policy, an
empty grid or two entries that would give the same runs raise :class:`SweepConfigError` (a
``ValueError``) naming the file, the table and the key.

Schema (every table but ``[[methods]]`` and ``[envs.<variant>]`` is optional)::

    [sweep]
    name = "quick"              # default: the file's stem
    seeds = 3                   # an int N = seeds 0..N-1, or a list of distinct seeds (default 5)
    steps = 50_000              # env steps per run (default 1,000,000)
    eval_interval = 10_000      # env steps between greedy evaluations (default 50,000)
    eval_episodes = 10          # episodes per greedy evaluation (default 10)
    log = ["tensorboard"]       # optional: log every run's scalars live (tensorboard, csv, wandb; or
                                #   "tensorboard,csv"): how the runs are watched, not what they
                                #   compute (run ids unchanged; reproduce --log overrides it)

    [settings]                  # defaults for every method: any field every method declared takes,
    learning_starts = 2_000     # single values (settings a method fixes are left to it; a field
                                #   some method lacks is an error: put it in the entries that take it)

    [envs.<variant>]            # one table per environment variant; <variant> names it in
    env = "coexistence_v0"      #   run ids and tables (default env: the variant name)
    size = 9                    # environment arguments: size, view, max_cycles, and the
                                #   environment's own: sharing_v0 takes start = "random" | "centre"
                                #   and inventory_encoding = "count_plus_one" | "authors";
    num_cats = 2                #   how many other agents: coexistence_v0 num_cats, sharing_v0 num_humans
    fixed = { cat_0 = "random_walk" }  # fixed agents: a registered policy or "package.module:ClassName",
                                #   or a table to build it with keyword arguments:
                                #   fixed = { cat_0 = { policy = "pkg.mod:Chaser", speed = 2 } }
    methods = ["empathic_dqn"]  # optional: only these [[methods]] (by their `method`) run here

    [[methods]]                 # one table per method entry
    method = "empathic_dqn"     # registry name (empathy-zoo methods) or "package.module:NAME"
    envs = ["coexistence_v0"]   # optional: the variants it runs on (default: all)
    label = "..."               # optional table name; may use {field} placeholders of the
                                #   settings and of the reward transform's fields ({reward.<field>}
                                #   too), with a short format spec or none, e.g.
                                #   "Mine (β={selfishness:g})"; default: the method's
    selfishness = [1.0, 0.5]    # any settings field; a list is a grid: one experiment per value
                                #   (several lists: every combination)
    disadvantageous = [0.1, 1.0]  # any field of the method's reward transform (here
                                #   dqn_inequity_aversion's α), a grid as a setting is;
    reward.smoothing = 0.9      #   also as reward.<field> (TOML's dotted key), which a field
                                #   named like a setting needs (dqn_aup's reward.learning_rate:
                                #   learning_rate alone is the learner's)

Every experiment (variant × method entry × grid point) runs once per seed. Precedence of
settings: the method's defaults < ``[settings]`` < the ``[[methods]]`` entry. The reward
transform's fields are set in ``[[methods]]`` entries only (each method has its own transform);
the default label of a run shows those it sets to other values than the method's, and a field
the entry gives a grid of at every value, the default's too: ``"DQN + inequity aversion
(disadvantageous=0.1)"``.
"""

from __future__ import annotations

import itertools
import json
import math
import re
import string
from collections.abc import Mapping
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

from agents.rewards import transform_config
from agents.transform_fields import TransformFieldError, check_field_value, transform_fields
from baselines.registry import METHODS, get_method
from baselines.sb3_transforms import SB3_REFUSED
from empathy_zoo.engine.arguments import argument_types, own_arguments
from empathy_zoo.environments import DEFAULT_ENVIRONMENT, ENGINES, default_policies
from empathy_zoo.experiment.log_backends import parse_log
from empathy_zoo.experiment.model import Budget, EnvVariant, MethodEntry, RunSpec
from empathy_zoo.experiment.values import (
    PolicyTable,
    Seeds,
    SweepConfigError,
    check_keys,
    check_value,
    field_types,
    read_toml,
    type_name,
)
from empathy_zoo.limits import MAX_RUNS, MAX_SEEDS, not_a_regular_file
from empathy_zoo.names import check_path_name

__all__ = [
    "CONFIG_DIR",
    "DEFAULT_SEEDS",
    "ENV_KEYS",
    "METHOD_KEYS",
    "LABEL_FORMAT_SPEC",
    "REWARD_TABLE",
    "SWEEP_KEYS",
    "expand_label",
    "label_fields",
    "variant_of_table",
    "load_sweep",
    "parse_sweep",
    "sweep_log",
    "profile_path",
    "profiles",
]

CONFIG_DIR = Path(__file__).resolve().parents[1] / "profiles"
"""Where the named profiles (``quick``, ``paper``, …) live."""

DEFAULT_SEEDS = 5
"""Seeds per experiment when ``[sweep]`` does not say (the paper's 5 runs per method)."""

SWEEP_KEYS: dict[str, Any] = {"name": str, "seeds": Seeds, **field_types(Budget), "log": str | list[str]}
"""Keys of ``[sweep]`` and their types (the run budget's fields, the sweep's name and seeds, and
where runs log their scalars: :mod:`empathy_zoo.experiment.log_backends`)."""
ENV_KEYS: dict[str, Any] = {
    "env": str,
    **{name: kind for engine in ENGINES.values() for name, kind in argument_types(engine).items()},
    "fixed": PolicyTable,
    "methods": list[str],
}
"""Keys of an ``[envs.<variant>]`` table: ``env``, every argument some environment declares, the
fixed agents and the methods that run there."""
METHOD_KEYS: dict[str, Any] = {"method": str, "envs": list[str], "label": str}
"""Keys of a ``[[methods]]`` entry besides the method's settings fields and its reward transform's."""
REWARD_TABLE = "reward"
"""The key of a ``[[methods]]`` entry that holds reward-transform fields as a table (``reward.<field> = ...``)."""
TOP_TABLES = ("sweep", "settings", "envs", "methods")
LABEL_FORMAT_SPEC = re.compile(r"[<>^=]?[-+ ]?#?0?(?:[1-9][0-9]?)?[,_]?(?:\.[0-9]{1,2})?[bdeEfFgGnosxX%]?")
"""The format spec a ``label`` placeholder may carry: Python's alignment, sign, ``#``, ``0``, a
width below 100, a grouping, a precision below 100 and a type (``{selfishness:g}``,
``{learning_rate:.0e}``, ``{penalty:>6.1f}``), or none; no fill character, no nested field."""


# ---------------------------------------------------------------------------- profiles
def profiles() -> list[str]:
    """Names of the sweep files shipped in :data:`CONFIG_DIR`."""
    return sorted(p.stem for p in CONFIG_DIR.glob("*.toml"))


def profile_path(profile: str | Path) -> Path:
    """The sweep file of a profile name (``quick``, ``paper``, …) or a path to a ``.toml`` file."""
    text = str(profile)
    if text in profiles():
        return CONFIG_DIR / f"{text}.toml"
    path = Path(text)
    if path.suffix == ".toml" or path.exists():
        if path.is_dir():
            raise SweepConfigError(f"{path} is a directory, not a sweep file (give a .toml file or a shipped profile)")
        what = not_a_regular_file(path)
        if what is not None:  # (a FIFO, a device, a dangling link: said as what it is)
            raise SweepConfigError(f"sweep file {path} {what}")
        return path
    raise SweepConfigError(f"unknown profile {text!r}; shipped: {', '.join(profiles())} (or give a path to a .toml file)")


# ---------------------------------------------------------------------------- the sweep
def load_sweep(path: str | Path, seeds: int | None = None) -> list[RunSpec]:
    """The runs of the sweep file ``path`` (see the module documentation); ``seeds = N``
    replaces the file's seeds with ``0..N-1``."""
    path = Path(path)
    return parse_sweep(read_toml(path), source=str(path), seeds=seeds)


def parse_sweep(data: Mapping[str, Any], source: str = "<sweep>", seeds: int | None = None) -> list[RunSpec]:
    """The runs declared by the parsed TOML ``data``; ``source`` names the file in errors."""
    check_keys(data, TOP_TABLES, f"{source}: top level")
    for table in ("sweep", "settings", "envs"):
        if not isinstance(data.get(table, {}), dict):
            raise SweepConfigError(f"{source}: [{table}] must be a table, got {type_name(data[table])}")
    run = _sweep_table(data.get("sweep", {}), source)
    if seeds is not None:
        if isinstance(seeds, bool) or not isinstance(seeds, int) or seeds < 1:
            raise SweepConfigError(f"--seeds must be a positive int, got {seeds!r}")
        if seeds > MAX_SEEDS:
            raise SweepConfigError(f"--seeds: an experiment has at most {MAX_SEEDS:,} seeds (docs/limits.md), got {seeds:,}")
        run["seeds"] = list(range(seeds))
    entries = data.get("methods")
    if not isinstance(entries, list) or not entries or not all(isinstance(e, dict) for e in entries):
        raise SweepConfigError(f'{source}: declare at least one [[methods]] table (method = "empathic_dqn", …)')
    methods = [_method_entry(entry, i, source) for i, entry in enumerate(entries)]
    defaults = _settings_table(data.get("settings", {}), methods, source)
    envs = data.get("envs", {})
    if not envs:
        raise SweepConfigError(f"{source}: declare at least one [envs.<variant>] table (e.g. [envs.{DEFAULT_ENVIRONMENT}])")
    variants = {name: _env_table(name, table, methods, source) for name, table in envs.items()}
    for entry in methods:
        unknown = [v for v in entry["envs"] or () if v not in variants]
        if unknown:
            raise SweepConfigError(f"{entry['where']} envs: unknown variant(s) {unknown}; declared: {sorted(variants)}")

    try:
        budget = Budget(run["steps"], run["eval_interval"], run["eval_episodes"])
    except ValueError as error:
        raise SweepConfigError(f"{source}: [sweep] {error}") from None
    _check_run_count(variants, methods, len(run["seeds"]), source)
    specs: list[RunSpec] = []
    origin: dict[str, str] = {}  # what a run trains (its config but the label) -> where declared
    labels: dict[tuple[str, str], str] = {}
    for variant, env in variants.items():
        chosen = [
            m
            for m in methods
            if (m["envs"] is None or variant in m["envs"]) and (env["methods"] is None or m["method"] in env["methods"])
        ]
        if not chosen:
            raise SweepConfigError(f"{source}: [envs.{variant}] has no method to run (check `methods`/`envs` lists)")
        for entry in chosen:
            for point in entry["grid"]:
                settings = {k: v for k, v in defaults.items() if k not in entry["preset"]}
                settings |= point["settings"]
                shown = {**point["settings"], **{f"{REWARD_TABLE}.{k}": v for k, v in point["reward"].items()}}
                where = f"{entry['where']} on [envs.{variant}]" + (f" with {shown}" if shown else "")
                first = _spec(budget, env["variant"], entry, settings, point["reward"], run["seeds"][0], where)
                experiment = [replace(first, seed=seed) for seed in run["seeds"]]
                label = experiment[0].display_label()
                if (variant, label) in labels:
                    raise SweepConfigError(
                        f"{where} and {labels[variant, label]} have the same label {label!r}: the leaderboard "
                        "could not tell them apart (give distinct labels; a label may use {field} placeholders)"
                    )
                labels[variant, label] = where
                for spec in experiment:
                    trains = json.dumps({**spec.config(), "label": None}, sort_keys=True, default=str)
                    if trains in origin:
                        raise SweepConfigError(f"{where} duplicates {origin[trains]} (same runs)")
                    origin[trains] = where
                specs += experiment
    return specs


def _check_run_count(variants: Mapping[str, Any], methods: list[dict[str, Any]], seeds: int, source: str) -> None:
    """Refuse a sweep of more than :data:`~empathy_zoo.limits.MAX_RUNS` runs, counted before any is built."""
    count = sum(
        len(m["grid"]) * seeds
        for variant, env in variants.items()
        for m in methods
        if (m["envs"] is None or variant in m["envs"]) and (env["methods"] is None or m["method"] in env["methods"])
    )
    if count > MAX_RUNS:
        raise SweepConfigError(
            f"{source}: the sweep declares {count:,} runs, more than {MAX_RUNS:,} (docs/limits.md): "
            "split it, or give fewer seeds or grid values"
        )


def _sweep_table(table: dict[str, Any], source: str) -> dict[str, Any]:
    where = f"{source}: [sweep]"
    check_keys(table, SWEEP_KEYS, where)
    run: dict[str, Any] = {
        "name": Path(source).stem,
        "seeds": list(range(DEFAULT_SEEDS)),
        "steps": Budget.steps,
        "eval_interval": Budget.eval_interval,
        "eval_episodes": Budget.eval_episodes,
    }
    for key, value in table.items():
        run[key] = check_value(value, SWEEP_KEYS[key], f"{where} {key}")
        if SWEEP_KEYS[key] is int and value < 1:
            raise SweepConfigError(f"{where} {key}: expected a positive int, got {value}")
    if "log" in run:
        try:
            run["log"] = parse_log(run["log"], f"{where} log")
        except ValueError as error:
            raise SweepConfigError(str(error)) from None
    return run


def sweep_log(path: str | Path) -> tuple[str, ...]:
    """The backends the sweep file ``path`` logs its runs to (its ``[sweep]`` table's ``log``; ``()``
    without one), checked as :func:`load_sweep` checks it."""
    data = read_toml(path)
    table = data.get("sweep", {})
    if not isinstance(table, dict):
        raise SweepConfigError(f"{path}: [sweep] must be a table, got {type_name(table)}")
    return tuple(_sweep_table(table, str(path)).get("log", ()))


def _method_entry(entry: dict[str, Any], index: int, source: str) -> dict[str, Any]:
    where = f"{source}: [[methods]] #{index + 1}"
    if "method" not in entry:
        raise SweepConfigError(f"{where}: missing key 'method' (a registered method or package.module:NAME)")
    name = check_value(entry["method"], str, f"{where} method")
    where += f" ({name})"
    try:
        method = get_method(name)
    except ValueError as error:
        raise SweepConfigError(f"{where} method: {error}") from None
    types = field_types(method.settings)
    reward_types = method.reward_fields()
    # the transform's fields that are keys of their own (a setting of the same name keeps its key)
    flat = {key: kind for key, kind in reward_types.items() if key not in types and key not in METHOD_KEYS}
    has_table = bool(reward_types) and REWARD_TABLE not in types
    if isinstance(entry.get(REWARD_TABLE), str) and REWARD_TABLE not in types:
        raise SweepConfigError(f"{where} {REWARD_TABLE}: {_composed_hint(name, entry[REWARD_TABLE])}")
    for key in entry:
        if key not in METHOD_KEYS and key not in types and key not in flat and not (key == REWARD_TABLE and has_table):
            raise SweepConfigError(f"{where}: unknown key {key!r}; {_method_keys(method, types, reward_types)}")
    nested = entry.get(REWARD_TABLE, {}) if has_table else {}
    if not isinstance(nested, dict):
        raise SweepConfigError(
            f"{where} {REWARD_TABLE}: expected a table of the reward transform's fields "
            f"(reward.<field> = value), got {type_name(nested)} {nested!r}"
        )
    for key in nested:
        if key not in reward_types:
            raise SweepConfigError(
                f"{where} {REWARD_TABLE}.{key}: unknown field {key!r} of the reward transform "
                f"{getattr(method.reward, 'name', None)!r}; its fields: {', '.join(reward_types)}"
            )
        if key in flat and key in entry:
            raise SweepConfigError(f"{where} {REWARD_TABLE}.{key}: {key} is given twice (as {key} and {REWARD_TABLE}.{key})")
    given = [("settings", key, value, types[key], key) for key, value in entry.items() if key in types]
    given += [("reward", key, value, flat[key], key) for key, value in entry.items() if key in flat]
    given += [("reward", key, value, reward_types[key], f"{REWARD_TABLE}.{key}") for key, value in nested.items()]
    for key in METHOD_KEYS:
        if key in entry:
            check_value(entry[key], METHOD_KEYS[key], f"{where} {key}")
    axes: list[list[tuple[str, str, Any]]] = []
    for part, key, value, kind, shown in given:
        values = value if isinstance(value, list) else [value]
        if not values:
            raise SweepConfigError(f"{where} {shown}: empty grid (give at least one value)")
        checked = [check_value(v, kind, f"{where} {shown}") for v in values]
        if part == "reward":  # (the bound of every transform's field, said here with the key that gives it)
            checked = [_reward_value(method, key, v, f"{where} {shown}") for v in checked]
        if len(set(map(repr, checked))) != len(checked):
            raise SweepConfigError(f"{where} {shown}: value listed twice in the grid {values}")
        axes.append([(part, key, v) for v in checked])
    points = math.prod(len(axis) for axis in axes)
    if points > MAX_RUNS:
        raise SweepConfigError(
            f"{where}: its grid has {points:,} points, more than the {MAX_RUNS:,} runs a sweep may declare (docs/limits.md)"
        )
    grid = []
    for point in itertools.product(*axes):
        grid.append({part: {key: v for p, key, v in point if p == part} for part in ("settings", "reward")})
    swept = [axis[0][1] for axis in axes if axis[0][0] == "reward" and len(axis) > 1]
    return {
        "method": name,
        "where": where,
        "types": types,
        "preset": method.preset,
        "envs": entry.get("envs"),
        "label": entry.get("label"),
        "grid": grid,
        "swept_reward": swept,
    }


def _reward_value(method: Any, field: str, value: Any, where: str) -> Any:
    """``value`` of the reward field ``field`` of ``method``, as :func:`agents.transform_fields.check_field_value`
    takes it (within :data:`agents.transform_fields.MAX_TRANSFORM_WEIGHT`, ...), else :class:`SweepConfigError`
    naming ``where`` (the file, its ``[[methods]]`` entry and the key)."""
    try:
        return check_field_value(method.reward, field, value)
    except TransformFieldError as error:
        raise SweepConfigError(f"{where}: {error.problem}") from None


def _composed_hint(method: str, transform: str) -> str:
    """Why ``reward = "<transform>"`` names no transform, and the registered method that composes
    ``method``'s learner with it, where there is one (``sb3_ppo`` and ``harm_penalty``: ``sb3_ppo_harm_penalty``)."""
    composed = f"{method}_{transform.removeprefix('dqn_')}"
    text = (
        "a method's reward transform is part of the method (a registered method composes a learner with "
        f"one); {REWARD_TABLE} holds the transform's fields, as {REWARD_TABLE}.<field> = value"
    )
    if composed in METHODS:
        return f'{text}: write method = "{composed}"'
    if composed in SB3_REFUSED:
        return f"{text}; {SB3_REFUSED[composed]}"
    return f"{text}; `empathy-zoo methods` lists the compositions (sb3_ppo_<name>, sb3_dqn_<name>, dqn_<name>)"


def _method_keys(method: Any, types: Mapping[str, Any], reward_types: Mapping[str, Any]) -> str:
    """What a ``[[methods]]`` entry of ``method`` takes, for an error message."""
    text = f"allowed keys: {', '.join(METHOD_KEYS)}; the settings of {method.name}: {', '.join(types)}"
    if not reward_types:
        return text + ("; its reward transform has no fields" if method.reward is not None else "; it has no reward transform")
    shadowed = [key for key in reward_types if key in types or key in METHOD_KEYS]
    text += (
        f"; the fields of its reward transform {method.reward.name!r}: {', '.join(reward_types)} "
        f"(each also as {REWARD_TABLE}.<field>"
    )
    return text + (f"; {', '.join(shadowed)} only so: alone it is the setting)" if shadowed else ")")


def _settings_table(table: dict[str, Any], methods: list[dict[str, Any]], source: str) -> dict[str, Any]:
    where = f"{source}: [settings]"
    types: dict[str, Any] = {}
    for entry in methods:
        types |= entry["types"]
    check_keys(table, types, where)
    checked = {}
    for key, value in table.items():
        if isinstance(value, list):
            raise SweepConfigError(f"{where} {key}: [settings] takes single values; put a grid in a [[methods]] entry")
        checked[key] = check_value(value, types[key], f"{where} {key}")
    for entry in methods:  # a default is applied to every method, or refused: never dropped
        foreign = [key for key in checked if key not in entry["types"]]
        if foreign:
            raise SweepConfigError(
                f"{where} {foreign[0]}: {entry['where']} has no such setting (its settings: "
                f"{', '.join(entry['types'])}); move {foreign[0]} into the [[methods]] entries that take it "
                "(an SB3 method takes its own keyword arguments as algorithm_kwargs = { ... })"
            )
    return checked


def _env_table(variant: str, table: Any, methods: list[dict[str, Any]], source: str) -> dict[str, Any]:
    where = f"{source}: [envs.{variant}]"
    if not isinstance(table, dict):
        raise SweepConfigError(f"{where}: must be a table (env = ..., size = ...), got {type_name(table)}")
    try:
        check_path_name(variant, "variant name")
    except ValueError as error:
        raise SweepConfigError(f"{where}: {error}") from None
    check_keys(table, ENV_KEYS, where)
    checked = {key: check_value(value, ENV_KEYS[key], f"{where} {key}") for key, value in table.items()}
    env = checked.get("env", variant)
    if env not in ENGINES:
        key = "env" if "env" in checked else "variant name (or set env = ...)"
        raise SweepConfigError(f"{where} {key}: unknown environment {env!r}; registered: {sorted(ENGINES)}")
    if variant in ENGINES and variant != env:
        raise SweepConfigError(
            f"{where} env: {env!r}, but the variant is named as another environment ({variant}), whose table "
            "its runs would be read in; name the variant otherwise"
        )
    kwargs = {key: value for key, value in checked.items() if key not in ("env", "fixed", "methods")}
    own = own_arguments(ENGINES[env])
    for key in kwargs:
        if key not in argument_types(ENGINES[env]):
            own_text = ", ".join(own) or "none"
            raise SweepConfigError(f"{where} {key}: {env} takes no argument {key!r} (its own arguments: {own_text})")
    environment = variant_of_table(env, kwargs, checked.get("fixed"), variant, where)
    names = checked.get("methods")
    if names is not None:
        declared = {m["method"] for m in methods}
        unknown = [n for n in names if n not in declared]
        if unknown:
            raise SweepConfigError(f"{where} methods: {unknown} not declared in any [[methods]]; declared: {sorted(declared)}")
    return {"variant": environment, "methods": names}


def variant_of_table(env: str, kwargs: Mapping[str, Any], fixed: Mapping[str, Any] | None, name: str, where: str) -> EnvVariant:
    """The environment variant a table (``where``) declares: ``env`` with ``kwargs`` and, beside
    the environment's default fixed agents, those of ``fixed``; its errors as
    :class:`SweepConfigError` naming the table (an error of the arguments first, naming no agent)."""
    try:
        EnvVariant(env, kwargs)
    except ValueError as error:
        raise SweepConfigError(f"{where}: {error}") from None
    try:
        return EnvVariant(env, kwargs, None if fixed is None else {**default_policies(env, kwargs), **fixed}, name)
    except ValueError as error:
        raise SweepConfigError(f"{where} {error}") from None


def _spec(
    budget: Budget,
    variant: EnvVariant,
    entry: dict[str, Any],
    settings: dict[str, Any],
    reward: dict[str, Any],
    seed: int,
    where: str,
) -> RunSpec:
    try:
        spec = RunSpec(variant, MethodEntry.resolve(entry["method"], settings, reward), budget, seed)
    except ValueError as error:
        raise SweepConfigError(f"{where}: {error}") from None
    if entry["label"] is None:
        if not entry["swept_reward"]:
            return spec
        # a grid of a transform's field: every run's label shows its value, the default's too
        label = spec.entry.display_label(entry["swept_reward"])
    else:
        label = expand_label(entry["label"], spec, f"{where} label")
    try:
        return replace(spec, entry=replace(spec.entry, label=label))
    except ValueError as error:  # (a label the result-file reader would refuse: empathy_zoo.names.check_label)
        raise SweepConfigError(f"{where} label: {error}") from None


def expand_label(template: str, spec: RunSpec, where: str) -> str:
    """``template`` with each ``{field}`` or ``{field:spec}`` placeholder replaced by that field of
    :func:`label_fields` of ``spec``, formatted with ``spec`` (one :data:`LABEL_FORMAT_SPEC`);
    ``{{`` and ``}}`` are braces. Anything else in braces (an index, an attribute, a conversion,
    a nested field, a wider spec) raises :class:`SweepConfigError` naming ``where`` (a file, its
    table and key): a template is data, never evaluated."""
    fields = label_fields(spec)
    try:
        parts = list(string.Formatter().parse(template))
    except ValueError as error:
        raise SweepConfigError(
            f"{where}: bad placeholder in {template!r} ({error}); write a brace that is no placeholder as {{{{ or }}}}"
        ) from None
    names = ", ".join(fields)
    pieces = []
    for literal, name, format_spec, conversion in parts:
        pieces.append(literal)
        if name is None:
            continue
        placeholder = "{" + name + (f"!{conversion}" if conversion else "") + (f":{format_spec}" if format_spec else "") + "}"
        if name not in fields:
            raise SweepConfigError(
                f"{where}: bad placeholder {placeholder} in {template!r}: {name!r} is no field; placeholders are "
                f"{{field}} or {{field:spec}} of the settings fields and the reward transform's fields: {names}"
            )
        if conversion is not None or not LABEL_FORMAT_SPEC.fullmatch(format_spec or ""):
            raise SweepConfigError(
                f"{where}: bad placeholder {placeholder} in {template!r}: a placeholder takes a short format spec "
                "(alignment, sign, width and precision below 100, a type: {selfishness:g}, {learning_rate:.0e}) "
                "and no conversion"
            )
        try:
            pieces.append(format(fields[name], format_spec or ""))
        except (ValueError, TypeError) as error:
            raise SweepConfigError(
                f"{where}: bad placeholder {placeholder} in {template!r}: cannot format {fields[name]!r} ({error})"
            ) from None
    return "".join(pieces)


def label_fields(spec: RunSpec) -> dict[str, Any]:
    """What a ``label`` template of ``spec`` may name, and their values: its settings' fields, its
    reward transform's fields (a field named like a setting as ``reward.<field>`` only) and
    ``reward.<field>`` for each of them."""
    transform = spec.reward_transform()
    fields_of_reward = transform_config(transform) or {}
    fields_of_reward.pop("name", None)
    values: dict[str, Any] = {**fields_of_reward, **asdict(spec.method_settings())}
    for name in transform_fields(transform):
        values[f"{REWARD_TABLE}.{name}"] = getattr(transform, name)
    return values
