"""``empathy-zoo train``: runs of one method on one environment.

Its options are the run's (environment, seeds, steps, …), one per field of the chosen method's
settings and one per field of its reward transform (:mod:`empathy_zoo.cli.settings_options`).
The method is known before the parser is built: :func:`train_method` reads ``--method``, or
``method`` in the ``--config`` file.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from empathy_zoo.cli.common import (
    PROG,
    RUN_DEFAULTS,
    RUNNER_KEYS,
    AgentPolicies,
    add_runner_options,
    agent_policy,
    path_text,
    read_results,
    run_summary,
    runner_options,
)
from empathy_zoo.cli.settings_options import (
    add_reward_options,
    add_settings_options,
    given_reward,
    given_settings,
    merged_settings,
)
from empathy_zoo.engine.arguments import argument_defaults, argument_help, argument_types
from empathy_zoo.environments import ENGINES
from empathy_zoo.experiment.model import Budget
from empathy_zoo.experiment.values import PolicyTable, Seeds, check_seeds, field_types
from empathy_zoo.training.options import RunnerOptions

__all__ = ["RUN_KEYS", "ENV_ARGUMENTS", "add_train", "cmd_train", "config_file", "train_method", "train_values"]

ENV_ARGUMENTS: dict[str, Any] = {name: kind for engine in ENGINES.values() for name, kind in argument_types(engine).items()}
"""The environment arguments some registered environment declares, and their types (each
environment checks which it takes)."""
_RUNNER_TYPES = field_types(RunnerOptions) | {"log": str | list[str]}  # (log: "tensorboard,csv" or a list of names)
RUN_KEYS: dict[str, Any] = {
    "env": str,
    "method": str,
    "seed": int,
    "seeds": Seeds,
    **field_types(Budget),
    "out": str,
    **{name: _RUNNER_TYPES[name] for name in RUNNER_KEYS},
    "label": str,
    **ENV_ARGUMENTS,
    "fixed": PolicyTable,
}
"""Top-level keys of a ``train --config`` file and their types, from the dataclasses they fill
(method settings go in ``[settings]``, the fields of its reward transform in ``[reward]``)."""
TABLES = ("settings", "reward")
"""The tables of a ``train --config`` file."""


def config_file(path: str) -> str:
    """``path`` of ``--config``, refused (``ValueError``) when it is a directory: give a file."""
    if Path(path).is_dir():
        raise ValueError(f"--config {path} is a directory, not a file: give a TOML file (FILE.toml)")
    return path


def train_method(argv: Sequence[str]) -> str:
    """The method ``train``'s arguments ``argv`` name: ``--method``, else ``method`` in the
    ``--config`` file, else the default. Other arguments are left to the full parser (so is a
    malformed ``--method`` or ``--config``: the default is returned and that parser reports it)."""
    from empathy_zoo.experiment.values import check_value, read_toml

    first = argparse.ArgumentParser(add_help=False, argument_default=argparse.SUPPRESS, exit_on_error=False)
    first.add_argument("--method")
    first.add_argument("--config")
    try:
        known, _ = first.parse_known_args(argv)
    except argparse.ArgumentError:
        return RUN_DEFAULTS["method"]
    if "method" in known:
        return known.method
    if "config" in known:
        data = read_toml(config_file(known.config))
        if "method" in data:
            return check_value(data["method"], RUN_KEYS["method"], f"{known.config}: method")
    return RUN_DEFAULTS["method"]


def train_values(args: argparse.Namespace) -> tuple[dict[str, Any], dict[str, Any]]:
    """Run keys and method settings, merged: defaults < config file < command line. The fields of
    the method's reward transform are ``run["reward"]`` (a table, empty when none is given)."""
    from baselines.registry import get_method
    from empathy_zoo.experiment.values import SweepConfigError, check_keys, check_value, field_types, read_toml

    given = vars(args)
    run: dict[str, Any] = {**RUN_DEFAULTS, "reward": {}}
    settings: dict[str, Any] = {}
    reward: dict[str, Any] = {}
    if "config" in given:
        path = given["config"]
        data = read_toml(config_file(path))
        check_keys(data, [*RUN_KEYS, *TABLES], f"{path}: top level")
        if "seed" in data and "seeds" in data:
            raise SweepConfigError(f"{path}: give 'seed' or 'seeds', not both")
        for key, value in data.items():
            if key == "seed":
                run["seeds"] = [check_value(value, int, f"{path}: seed")]
            elif key not in TABLES:
                run[key] = check_value(value, RUN_KEYS[key], f"{path}: {key}")
        if data.get("out") == "":
            raise SweepConfigError(f"{path}: out: an empty path; name the output directory ('.' for the current one)")
        for name in TABLES:
            if not isinstance(data.get(name, {}), dict):
                raise SweepConfigError(f"{path}: [{name}] must be a table")
        method = get_method(given.get("method", run["method"]))
        table = data.get("settings", {})
        types = field_types(method.settings)
        check_keys(table, types, f"{path}: [settings]")
        settings |= {k: check_value(v, types[k], f"{path}: [settings] {k}") for k, v in table.items()}
        table = data.get("reward", {})
        kinds = method.reward_fields()
        if table and not kinds:
            raise SweepConfigError(
                f"{path}: [reward]: method {method.name!r} has "
                + ("no reward transform" if method.reward is None else "a reward transform without fields")
            )
        check_keys(table, kinds, f"{path}: [reward]")
        reward |= {k: _reward_value(method, k, check_value(v, kinds[k], f"{path}: [reward] {k}"), path) for k, v in table.items()}
    for key in RUN_KEYS.keys() - {"seed", "fixed"}:
        if key in given:
            run[key] = given[key]
    if "seed" in given:
        run["seeds"] = [given["seed"]]
    if "seed" in given or "seeds" in given:  # (a --config file's are checked as it is read)
        run["seeds"] = check_seeds(list(run["seeds"]), "--seed" if "seed" in given else "--seeds")
    if "fixed" in given:
        run["fixed"] = dict(given["fixed"])
    if "no_progress" in given:
        run["progress"] = False
    run["reward"] = reward | given_reward(args)
    return run, merged_settings(settings, given_settings(args))


def _reward_value(method: Any, field: str, value: Any, path: str) -> Any:
    """``value`` of the ``[reward]`` key ``field`` of the ``--config`` file ``path``, as the reward
    transform takes it (:func:`agents.transform_fields.check_field_value`: within its bound), else
    :class:`~empathy_zoo.experiment.values.SweepConfigError` naming the file, the table and the key."""
    from agents.transform_fields import TransformFieldError, check_field_value
    from empathy_zoo.experiment.values import SweepConfigError

    try:
        return check_field_value(method.reward, field, value)
    except TransformFieldError as error:
        raise SweepConfigError(f"{path}: [reward] {field}: {error.problem}") from None


def cmd_train(args: argparse.Namespace, command: str) -> int:
    """Train the runs and print one summary line each."""
    from empathy_zoo.environments import default_policies
    from empathy_zoo.experiment.model import EnvVariant, MethodEntry, RunSpec
    from empathy_zoo.experiment.result_reader import read_result
    from empathy_zoo.training.runner import train_runs

    run, settings = train_values(args)
    env_kwargs = {key: run[key] for key in ENV_ARGUMENTS if run.get(key) is not None}
    fixed = None if run["fixed"] is None else {**default_policies(run["env"], env_kwargs), **run["fixed"]}
    variant = EnvVariant(run["env"], env_kwargs, fixed)
    entry = MethodEntry.resolve(run["method"], settings, run["reward"], run["label"])
    budget = Budget(run["steps"], run["eval_interval"], run["eval_episodes"])
    specs = [RunSpec(variant, entry, budget, seed) for seed in run["seeds"]]
    options = runner_options(args, run)
    out = Path(run["out"])
    finished, done = read_results(specs, out)
    print(
        f"{PROG}: {len(specs)} run(s) of {entry.display_label()} on {run['env']}, {run['steps']:,} steps each"
        + (f" ({done} already finished)" if done else "")
        + f"; results in {out / 'runs'}",
        flush=True,
    )
    paths = train_runs(specs, out, options, finished=finished)
    for path in paths:
        print(run_summary(read_result(path)))
    return 0


def add_train(sub: Any, method: str) -> None:
    """The ``train`` subcommand, with the options of ``method``'s settings."""
    from baselines.registry import get_method

    parser = sub.add_parser(
        "train",
        help="train one run (or several seeds as one ensemble)",
        argument_default=argparse.SUPPRESS,
        description="Train runs of one method on one environment. Precedence: defaults < --config file < command line. "
        "The settings options are the method's: see empathy-zoo train --method NAME --help.",
    )
    parser.add_argument(
        "--config",
        metavar="FILE.toml",
        help="TOML file: top-level run keys (env, method, seed(s), steps, …), a [settings] table and "
        "a [reward] table (the fields of the method's reward transform)",
    )
    parser.add_argument("--env", help=f"environment (default: {RUN_DEFAULTS['env']})")
    parser.add_argument("--method", help=f"registered method or package.module:NAME (default: {RUN_DEFAULTS['method']})")
    seeds = parser.add_mutually_exclusive_group()
    seeds.add_argument("--seed", type=int, help="seed of the run (default: 0)")
    seeds.add_argument("--seeds", type=int, nargs="+", metavar="S", help="several seeds, trained as one ensemble")
    parser.add_argument("--steps", type=int, help=f"env steps per run (default: {RUN_DEFAULTS['steps']})")
    parser.add_argument("--out", type=path_text, metavar="DIR", help=f"output directory (default: {RUN_DEFAULTS['out']})")
    parser.add_argument(
        "--eval-interval",
        type=int,
        metavar="N",
        help=f"env steps between greedy evaluations (default: {RUN_DEFAULTS['eval_interval']})",
    )
    parser.add_argument(
        "--eval-episodes",
        type=int,
        metavar="N",
        help=f"episodes per greedy evaluation (default: {RUN_DEFAULTS['eval_episodes']})",
    )
    parser.add_argument("--label", help="display name in tables (default: the method's)")
    _add_env_arguments(parser)
    parser.add_argument(
        "--fixed",
        type=agent_policy,
        action=AgentPolicies,
        metavar="AGENT=POLICY",
        help="fixed agent policy, a name or package.module:ClassName (repeatable, once per agent)",
    )
    add_runner_options(parser, default=argparse.SUPPRESS)
    add_settings_options(parser, get_method(method))
    add_reward_options(parser, get_method(method))
    parser.set_defaults(handler=cmd_train)


def _add_env_arguments(parser: argparse.ArgumentParser) -> None:
    """One option per environment argument, as the environments declare them (their help, their
    defaults, and which environments take them)."""
    group = parser.add_argument_group(
        "environment arguments", "each environment takes its own (its page: help(empathy_zoo.<env name>))"
    )
    takers: dict[str, list[str]] = {}
    for name, engine in ENGINES.items():
        for argument in argument_types(engine):
            takers.setdefault(argument, []).append(name)
    for argument, kind in ENV_ARGUMENTS.items():
        engine = ENGINES[takers[argument][0]]
        text = argument_help(engine)[argument]
        if "(default:" not in text:
            text += f" (default: {argument_defaults(engine)[argument]})"
        if len(takers[argument]) < len(ENGINES):
            text = f"{', '.join(takers[argument])} only: {text}"
        metavar = "N" if kind is int else argument.upper()
        group.add_argument("--" + argument.replace("_", "-"), type=kind, metavar=metavar, help=text)
