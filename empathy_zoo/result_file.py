"""The per-run result file: where it lives, its schema (:data:`SCHEMA`, 3; schemas 1 and 2 are read too), and reading it back.

A sweep writes one JSON file per finished run, ``<out_dir>/runs/<run id>.json`` (the schema is
documented field by field in ``docs/formats.md``); everything that reads results (the leaderboard,
the verdicts, the command line) reads them through
:func:`empathy_zoo.experiment.result_reader.read_result`, never the training code.

:func:`check_result_fields` checks every field against what
:func:`empathy_zoo.training.results.build_result` writes; anything else raises one ``ValueError``
line naming the file and the field, e.g.
``runs/x.json: field eval[2].step: expected an int >= 1, got 'late'``. The reader adds the one
check this layer cannot make: a registered method's settings, by its settings class (the method
registry sits above the environments). A result file is data, so checking it never imports a
plug-in: the settings of a ``package.module:NAME`` method are checked only for their shape.

Since schema 3, ``config.description`` says what the run was, as its method describes it
(:mod:`empathy_zoo.method_description`): the leaderboard reads that, never a method's name. A file
of schema 1 or 2 gets its description when it is read (:func:`upgrade_schema_2`): the one place
that knows the methods built in at schema 2 (:data:`SCHEMA_2_METHODS`).
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable, Mapping
from pathlib import Path
from types import SimpleNamespace
from typing import Any

from empathy_zoo import run_ids
from empathy_zoo.document_checks import DocumentChecker, finite_float, shown
from empathy_zoo.engine.arguments import GRID_ARGUMENTS, argument_defaults, check_grid_arguments
from empathy_zoo.environments import ENGINES, ENVIRONMENT_TABLE
from empathy_zoo.limits import (
    MAX_CYCLES,
    MAX_EVAL_EPISODES,
    MAX_EVALUATIONS,
    MAX_HIDDEN_SIZE,
    MAX_LEARNER_BYTES,
    MAX_SEED,
    MAX_STEPS,
    MAX_WALL_TIME_S,
)
from empathy_zoo.method_description import DescriptionError, check_description, default_description
from empathy_zoo.metrics import COUNT_PER_STEP, INTEGER_METRICS, METRIC_NAMES
from empathy_zoo.names import check_path_name, resolved

__all__ = [
    "AGENT_SUFFIXES",
    "KNOWN_FIELDS",
    "PRICE_COLUMN",
    "SCHEMA",
    "REQUIRED_FIELDS",
    "RUNS_DIR",
    "ResultFileError",
    "check_agent_record",
    "check_result_fields",
    "result_checker",
    "results_root",
    "check_env_kwargs",
    "episode_bounds",
    "evaluation_steps",
    "others_room",
    "result_path",
    "experiment_of",
    "check_one_experiment_per_label",
]

SCHEMA = 3
"""The result-file schema this suite writes. Files of schema 1 (empathy-zoo 0.1) and 2 (0.2, 0.3) are
read too, upgraded in memory by :func:`upgrade_schema_1` and :func:`upgrade_schema_2`."""
REQUIRED_FIELDS = ("schema", "run_id", "env", "method", "method_label", "seed", "steps", "config", "train", "eval")
"""Top-level fields every result file has (``variant``, ``memory_bytes``, ``wall_time_s``,
``version``, ``commit``, ``plugin_sha256``, ``update_kernel``, ``agent`` and ``created`` are written
too, and checked when present, as are the fields of ``config`` beyond :data:`CONFIG_TABLES`)."""
PRICE_COLUMN = "lambda"
"""The optional ``train`` column of a run whose reward transform prices a cost when it is sampled
(:class:`agents.rewards.PricedTransform`; the Lagrangian method's multiplier λ): the price of one
unit of cost after each training episode, a finite number >= 0 per episode. Files without it
(every other method's, and those made before it was recorded) are read as they are."""
UPDATE_KERNELS_RECORDED = ("numba", "torch")
"""The update kernels a result file may name (``update_kernel``; ``null``: the learner has no choice)."""
KNOWN_FIELDS = (
    *REQUIRED_FIELDS,
    "variant",
    "memory_bytes",
    "wall_time_s",
    "version",
    "commit",
    "plugin_sha256",
    "update_kernel",
    "agent",
    "created",
)
"""Every top-level field this checker reads; any other is kept as written (a record's ``extra``),
checked as plain data (:meth:`~empathy_zoo.document_checks.DocumentChecker.plain`: finite numbers,
printable text)."""
MEMORY_FIGURES = ("replay_per_run", "learner_per_run")
"""The figures of ``memory_bytes`` (bytes of a run's replay memory and of its whole learner): no others."""
CONFIG_TABLES = ("settings", "env_kwargs", "fixed", "description")
"""Tables of ``config`` every result file has."""
_SHA256 = re.compile(r"[0-9a-f]{64}")
"""A plug-in module's source hash (``plugin_sha256``: :mod:`empathy_zoo.training.fingerprint`)."""


class ResultFileError(ValueError):
    """A result file is not what this suite writes; the message names the file and the field."""


def result_checker(path: Path) -> DocumentChecker:
    """Checks of one result file, each raising :class:`ResultFileError` naming ``path`` and the field."""
    return DocumentChecker(
        path,
        ResultFileError,
        "a result file",
        "a result of this suite",
        "move it away (its run is redone on the next reproduce/train)",
    )


def check_result_fields(document: Any, path: str | Path) -> dict[str, Any]:
    """``document`` (a parsed result file) if it follows the schema, else :class:`ResultFileError`;
    a registered method's settings are checked by :func:`empathy_zoo.experiment.result_reader.check_result`,
    which every reader calls (the method registry sits above this module)."""
    check = result_checker(Path(path))
    result = dict(check.table(document, "(the whole file)"))
    check.has(result, REQUIRED_FIELDS, "")
    if result["schema"] == 1 and not isinstance(result["schema"], bool):
        result = upgrade_schema_1(result, path)
    if result["schema"] == 2 and not isinstance(result["schema"], bool):
        check_schema_2_settings(check, result)
        result = upgrade_schema_2(result)
    if result["schema"] != SCHEMA or isinstance(result["schema"], bool):
        raise ResultFileError(
            f"{path}: field schema: this suite reads result schemas 1, 2 and {SCHEMA}, "
            f"got {shown(result['schema'])}; move the file away"
        )
    check.name(result["run_id"], "run_id")
    seed = check.integer(result["seed"], "seed", 0, MAX_SEED)
    if not result["run_id"].endswith(f"__s{seed}"):
        raise check.fail("run_id", f"the run id of seed {seed} (a run id ends with __s<seed>: __s{seed})", result["run_id"])
    if check.name(result["env"], "env") not in ENGINES:
        raise check.fail("env", f"a registered environment ({', '.join(ENGINES)})", result["env"])
    if result.get("variant") is not None:
        check.name(result["variant"], "variant")
        if result["variant"] in ENGINES and result["variant"] != result["env"]:
            raise check.fail("variant", f"a variant of {result['env']} (not named as another environment)", result["variant"])
    check.text(result["method"], "method")
    check.label(result["method_label"], "method_label")
    steps = check.integer(result["steps"], "steps", 1, MAX_STEPS)
    _check_config(check, result)
    if "steps" in result["config"] and result["config"]["steps"] != steps:
        raise check.fail("steps", f"the run's config.steps ({result['config']['steps']:,})", steps)
    schedule = evaluation_steps(steps, result["config"].get("eval_interval"))
    _check_optional(check, result, "", {"version": check.text, "created": check.date_time, "wall_time_s": _wall_time(check)})
    if result.get("commit") is not None:
        check.text(result["commit"], "commit")
    if result.get("update_kernel") is not None and result["update_kernel"] not in UPDATE_KERNELS_RECORDED:
        raise check.fail("update_kernel", f"one of {', '.join(UPDATE_KERNELS_RECORDED)} or null", result["update_kernel"])
    for module, digest in check.table(result.get("plugin_sha256", {}), "plugin_sha256").items():
        check.text(module, f"plugin_sha256 (the name {module!r})")
        if digest is not None and not (isinstance(digest, str) and _SHA256.fullmatch(digest)):
            raise check.fail(f"plugin_sha256.{module}", "a SHA-256 (64 lowercase hex digits) or null", digest)
    for name, count in check.table(result.get("memory_bytes", {}), "memory_bytes").items():
        if name not in MEMORY_FIGURES:
            raise check.fail(f"memory_bytes (the name {name[:60]!r})", f"one of {', '.join(MEMORY_FIGURES)}", name)
        check.integer(count, f"memory_bytes.{name}", 0, MAX_LEARNER_BYTES)
    _check_agent(check, result)
    bounds = episode_bounds(result["env"], result["config"]["env_kwargs"])
    train = check.table(result["train"], "train")
    check.has(train, ("episode_end_step", *METRIC_NAMES), "train.")
    ends = check.numbers(train["episode_end_step"], "train.episode_end_step", integral=True)
    check.increasing(ends, "train.episode_end_step", 1, steps)
    for name, column in train.items():
        if name in METRIC_NAMES:
            check.metric(column, f"train.{name}", name, bounds[name])
        elif name == PRICE_COLUMN:
            for i, value in enumerate(check.numbers(column, f"train.{name}")):
                check.finite(value, f"train.{name}[{i}]", 0.0)
        elif name != "episode_end_step":
            raise check.fail(
                f"train.{name}",
                f"no such column (a run records episode_end_step, {', '.join(METRIC_NAMES)}, {PRICE_COLUMN})",
                name,
            )
    lengths = {name: len(column) for name, column in train.items()}
    if len(set(lengths.values())) > 1:
        raise ResultFileError(f"{path}: field train: columns of different lengths {lengths}; move the file away")
    for i, (start, end, survival) in enumerate(zip([0, *ends], ends, train["survival"], strict=False)):
        if survival > end - start:  # (a robot operative past its episode's end)
            expected = f"survival, at most the episode's {end - start:,} steps (it ends at step {end:,})"
            raise check.fail(f"train.survival[{i}]", expected, survival)
    if not isinstance(result["eval"], list):
        raise check.fail("eval", "an array of evaluations", result["eval"])
    episodes, previous = result["config"].get("eval_episodes"), 0
    for i, evaluation in enumerate(result["eval"]):
        entry = check.table(evaluation, f"eval[{i}]")
        check.has(entry, ("step", *METRIC_NAMES), f"eval[{i}].")
        if check.integer(entry["step"], f"eval[{i}].step", 1) > steps:
            raise check.fail(f"eval[{i}].step", f"a step <= steps ({steps})", entry["step"])
        if entry["step"] <= previous:
            raise check.fail(f"eval[{i}].step", f"a step after the evaluation before it (step {previous})", entry["step"])
        previous = entry["step"]
        for name in entry:
            if name != "step" and name not in METRIC_NAMES:
                raise check.fail(
                    f"eval[{i}].{name}", f"no such metric (an evaluation records step, {', '.join(METRIC_NAMES)})", name
                )
        for name in METRIC_NAMES:
            values = check.metric(entry[name], f"eval[{i}].{name}", name, bounds[name], length=episodes)
            if episodes is None and not values:
                raise check.fail(f"eval[{i}].{name}", "at least one greedy episode (an evaluation plays 1 or more)", values)
            episodes = len(values) if episodes is None else episodes
    for name in [name for name in result if name not in KNOWN_FIELDS]:  # (kept as written: plain data, like a method's records)
        check.plain(result[name], name)
    made = [entry["step"] for entry in result["eval"]]
    if schedule is not None and made != schedule:
        interval = result["config"]["eval_interval"]
        raise check.fail(
            "eval",
            f"the run's {len(schedule):,} evaluation(s), every config.eval_interval ({interval:,}) steps and at its "
            f"last step {steps:,} (evaluations at steps {_steps_shown(schedule)})",
            f"evaluations at steps {_steps_shown(made)}" if made else "no evaluation",
        )
    return result


def evaluation_steps(steps: int, eval_interval: Any) -> list[int] | None:
    """The steps a run of ``steps`` steps evaluated at, ``eval_interval`` apart and at its last step
    (as :mod:`empathy_zoo.training.ensemble` evaluates), or ``None`` when ``eval_interval`` is not
    recorded (files made before it was); counted before they are listed (at most
    :data:`~empathy_zoo.limits.MAX_EVALUATIONS`, checked with the config)."""
    if eval_interval is None:
        return None
    every = list(range(eval_interval, steps + 1, eval_interval))
    return every if every and every[-1] == steps else [*every, steps]


def _steps_shown(steps: list[int]) -> str:
    """A list of steps for a message: the first and last three of a long one."""
    shown_steps = [f"{step:,}" for step in steps]
    if len(steps) > 6:
        shown_steps = [*shown_steps[:3], "...", *shown_steps[-3:]]
    return ", ".join(shown_steps)


AGENT_SUFFIXES = (".agent.pt", ".agent.zip")
"""How the name of a run's agent file ends (:mod:`empathy_zoo.agent_file`)."""


def _check_agent(check: DocumentChecker, result: Mapping[str, Any]) -> None:
    """``agent``: the agent file the run kept beside its result file, ``{"file": "<run id>.agent.pt",
    "sha256": ...}``, or null when its method keeps none (absent in files made before runs kept
    their agents)."""
    if result.get("agent") is not None:
        check_agent_record(check, result["agent"], result["run_id"])


def check_agent_record(check: DocumentChecker, value: Any, run_id: str) -> dict[str, Any]:
    """``agent`` (``value``), the record of run ``run_id``'s agent file, as a result or an
    evaluation file holds it: ``{"file": "<run id>.agent.pt", "sha256": ...}``, the file's name
    the run's id and one of :data:`AGENT_SUFFIXES`; any other field plain data."""
    entry = check.table(value, "agent")
    check.has(entry, ("file", "sha256"), "agent.")
    name = check.name(check.text(entry["file"], "agent.file"), "agent.file")
    if name not in {run_id + suffix for suffix in AGENT_SUFFIXES}:
        raise check.fail("agent.file", f"the run's agent file, {run_id} + one of {AGENT_SUFFIXES}", name)
    if not (isinstance(entry["sha256"], str) and _SHA256.fullmatch(entry["sha256"])):
        raise check.fail("agent.sha256", "a SHA-256 (64 lowercase hex digits)", entry["sha256"])
    for key in [key for key in entry if key not in ("file", "sha256")]:  # (kept as written: plain data)
        check.plain(entry[key], f"agent.{key}")
    return entry


LEGACY_SHAPING = {"harm_penalty": 0.0, "equality_shaping": False}
"""Settings of schema 1 that are reward transforms since schema 2, with their "no shaping" values."""


def upgrade_schema_1(result: dict[str, Any], path: str | Path) -> dict[str, Any]:
    """A schema-1 result as schema 2 (:func:`upgrade_schema_2` takes it on to 3): the settings
    ``harm_penalty`` and ``equality_shaping`` become ``config.reward`` (``{"name": "harm_penalty",
    "penalty": p}``, ``{"name": "equality_scaling"}`` or ``None``), as the method's reward transform
    records it now; a penalty that is no finite number or a shaping that is no boolean raises
    :class:`ResultFileError` (never read as "no shaping"). The run id stays as written."""
    config = result.get("config")
    if not isinstance(config, dict) or not isinstance(config.get("settings"), dict):
        return {**result, "schema": 2}  # (the checks that follow say what is wrong)
    settings = dict(config["settings"])
    shaping = {name: settings.pop(name, default) for name, default in LEGACY_SHAPING.items()}
    penalty, scaled = shaping["harm_penalty"], shaping["equality_shaping"]
    if finite_float(penalty) is None:  # (math.isfinite raises on an int past a float's range: finite_float does not)
        raise ResultFileError(
            f"{path}: field config.settings.harm_penalty: a finite number, got {shown(penalty)}; move the file away"
        )
    if not isinstance(scaled, bool):
        raise ResultFileError(
            f"{path}: field config.settings.equality_shaping: true or false, got {scaled!r}; move the file away"
        )
    if penalty != 0.0 and scaled is True:
        raise ResultFileError(
            f"{path}: field config.settings: a schema-1 run with both a harm penalty and equality "
            "shaping has no schema-2 form (no registered method trained one); move the file away"
        )
    reward = (
        {"name": "harm_penalty", "penalty": penalty}
        if penalty != 0.0
        else {"name": "equality_scaling"}
        if scaled is True
        else None
    )
    return {**result, "schema": 2, "config": {**config, "settings": settings, "reward": reward}}


SCHEMA_2_METHODS: dict[str, tuple[str, str | None, bool, bool]] = {
    **{
        name: ("empathic_dqn", rule, in_view_only, name == "empathic_dqn")
        for name, rule, in_view_only in (
            ("empathic_dqn", "golden", False),
            ("empathic_dqn_in_view", "golden", True),
            ("empathic_dqn_silver", "silver", False),
        )
    },
    "dqn": ("dqn", "golden", False, True),
    **{
        f"dqn_{name}": ("dqn", "golden", False, False)
        for name in (
            "harm_penalty",
            "equality",
            "inequity_aversion",
            "social_value",
            "aup",
            "relative_reachability",
            "considerate",
            "lagrangian",
        )
    },
    "sb3_dqn": ("sb3", None, False, False),
    "sb3_ppo": ("sb3", None, False, False),
}
"""The methods built in at schema 2, as their descriptions have them: ``{name: (family, target,
in_view_only, dqn_reference at β = 1 on the environment's reward)}``. Those of family
``empathic_dqn`` and ``dqn`` take β, γ and the ε schedule from the file's settings."""
SCHEMA_2_SETTINGS = {
    "selfishness": 1.0,
    "gamma": 0.99,
    "learning_starts": 20_000,
    "epsilon_start": 1.0,
    "epsilon_end": 0.01,
    "epsilon_decay_steps": 980_000,
}
"""The Empathic DQN settings a schema-2 description reads, at their defaults of that schema (where
a file's ``config.settings`` leaves one out, the run had the default)."""


def schema_2_description(method: str, config: Mapping[str, Any]) -> dict[str, Any]:
    """The description of a schema-2 run of ``method`` with ``config``: what its method's
    :meth:`~agents.base.Method.describe` gives a run of that config now, from the file's own values
    for a method of :data:`SCHEMA_2_METHODS`; for any other (a ``package.module:NAME`` plug-in
    of then), the description of a method that declares nothing, with the file's reward."""
    settings: Mapping[str, Any] = config["settings"] if isinstance(config.get("settings"), dict) else {}
    reward = config.get("reward")
    if method not in SCHEMA_2_METHODS:
        return {**default_description(method), "reward": reward}
    family, target, in_view_only, reference = SCHEMA_2_METHODS[method]
    description = {**default_description(family), "target": target, "in_view_only": in_view_only, "reward": reward}
    if family == "sb3":
        return description
    value = {**SCHEMA_2_SETTINGS, **{k: v for k, v in settings.items() if k in SCHEMA_2_SETTINGS}}
    return {
        **description,
        "dqn_reference": reference and reward is None and value["selfishness"] == 1.0,
        "selfishness": value["selfishness"],
        "gamma": value["gamma"],
        "exploration": {
            "kind": "linear",
            "start": value["epsilon_start"],
            "end": value["epsilon_end"],
            "warmup": value["learning_starts"],
            "decay_steps": value["epsilon_decay_steps"],
        },
    }


SCHEMA_2_RANGES: dict[str, tuple[bool, int | float, int | float]] = {
    "selfishness": (False, 0.0, 1.0),
    "gamma": (False, 0.0, 1.0),
    "epsilon_start": (False, 0.0, 1.0),
    "epsilon_end": (False, 0.0, 1.0),
    "learning_starts": (True, 0, MAX_STEPS),
    "epsilon_decay_steps": (True, 1, MAX_STEPS),
}
"""What each setting of :data:`SCHEMA_2_SETTINGS` may be, ``(whole (an int), low, high)``: the
description :func:`schema_2_description` builds of it is checked by the same ranges
(:func:`empathy_zoo.method_description.check_description`)."""


def check_schema_2_settings(check: DocumentChecker, result: Mapping[str, Any]) -> None:
    """The settings of a schema-2 (or upgraded schema-1) ``result`` that its description is built from
    (:data:`SCHEMA_2_SETTINGS`, for a method of :data:`SCHEMA_2_METHODS` that reads them), each within
    :data:`SCHEMA_2_RANGES`, so that a bad one is named as the setting the file holds, never as a
    description field it does not; anything else is left to the checks that follow."""
    config = result.get("config")
    method = result.get("method")
    if not isinstance(config, dict) or not isinstance(config.get("settings"), dict) or method not in SCHEMA_2_METHODS:
        return
    if SCHEMA_2_METHODS[method][0] == "sb3":
        return
    for name, (whole, low, high) in SCHEMA_2_RANGES.items():
        if name not in config["settings"]:
            continue
        value = config["settings"][name]
        if whole:
            check.integer(value, f"config.settings.{name}", int(low), int(high))
        elif finite_float(value) is None or not low <= value <= high:
            raise check.fail(f"config.settings.{name}", f"a number in [{low:g}, {high:g}]", value)


def upgrade_schema_2(result: dict[str, Any]) -> dict[str, Any]:
    """A schema-2 result as schema 3: ``config.description`` (:func:`schema_2_description`) added.
    The run id stays as written (the description is no part of a run's identity)."""
    config = result.get("config")
    if not isinstance(config, dict) or not isinstance(result.get("method"), str):
        return {**result, "schema": SCHEMA}  # (the checks that follow say what is wrong)
    return {**result, "schema": SCHEMA, "config": {**config, "description": schema_2_description(result["method"], config)}}


def _check_optional(check: DocumentChecker, table: Mapping[str, Any], prefix: str, checks: Mapping[str, Any]) -> None:
    """Fields nobody needs, written by this suite: checked when present."""
    for name, check_field in checks.items():
        if name in table:
            check_field(table[name], f"{prefix}{name}")


def _wall_time(check: DocumentChecker) -> Any:
    """The check of ``wall_time_s``: a finite number of seconds in ``[0, MAX_WALL_TIME_S]``."""

    def check_wall_time(value: Any, field: str) -> float:
        if check.finite(value, field, 0.0) > MAX_WALL_TIME_S:
            raise check.fail(field, f"seconds <= {MAX_WALL_TIME_S:,} (ten years; docs/limits.md)", value)
        return value

    return check_wall_time


def check_env_kwargs(check: DocumentChecker, env: str, value: Any, field: str, grid: bool = True) -> dict[str, Any]:
    """``value``, the arguments ``env`` was built with (``field`` names them in a message), if each
    is an argument of its engine within its range: a grid argument or the count of other agents an
    int in ``[1, MAX_CYCLES]``, then (with ``grid``) all of them within what the environment builds
    (:func:`_check_grid`); an argument of choices one of them. Checked as data: nothing is built."""
    env_kwargs = check.table(value, field)
    engine = ENGINES.get(env)
    if engine is None:
        return env_kwargs
    for name, argument in env_kwargs.items():
        where = f"{field}.{name}"
        if name in GRID_ARGUMENTS or name == engine.count_argument:
            check.integer(argument, where, 1, MAX_CYCLES)
        elif name in engine.extra_arguments:
            if argument not in engine.extra_arguments[name]:
                raise check.fail(where, f"one of {', '.join(engine.extra_arguments[name])}", argument)
        else:
            known = (*GRID_ARGUMENTS, *engine.extra_arguments, *filter(None, [engine.count_argument]))
            raise check.fail(where, f"an argument of {env} ({', '.join(known)})", name)
    if grid:
        _check_grid(check, engine, env_kwargs, field)
    return env_kwargs


STEP_REWARD_BOUND = float.fromhex("0x1.fffffep+127")
"""The most one step can pay an agent as the engines pay it: its reward is a float32
(:attr:`empathy_zoo.engine.base.StepEvents.rewards`), so at most float32's largest value. The
environment table records no tighter per-step bound (Coexistence, Sharing and Charger pay at most 1
a step), so returns are bounded by this one: what keeps a forged return from overflowing the
leaderboard's sums (docs/limits.md)."""


def episode_bounds(env: str, env_kwargs: Mapping[str, Any]) -> dict[str, float | None]:
    """The most each metric of :data:`~empathy_zoo.metrics.METRIC_NAMES` can be in one episode of
    ``env`` built with ``env_kwargs`` (checked by :func:`check_env_kwargs`; the others at their
    defaults): a count (``survival``, ``harms``, ``batteries``, ``other_batteries``) at most
    ``max_cycles`` times what one step adds to it (:data:`~empathy_zoo.metrics.COUNT_PER_STEP`);
    ``harms`` also at most :meth:`~empathy_zoo.environments.Environment.most_harms` (each other agent
    once, Vase's vase besides; none where the environment harms no one); ``batteries`` and
    ``other_batteries`` 0 where it has none;
    ``return`` at most ``max_cycles`` times :data:`STEP_REWARD_BOUND`, ``other_return`` that for each
    other agent (it is their sum); ``None`` (no bound beyond the metric's range) for the others.
    Every count is bounded, so no forged count overflows the leaderboard's sums, and none holds
    what its environment cannot give."""
    engine = ENGINES[env]
    arguments = {**argument_defaults(engine), **env_kwargs}
    cycles = int(arguments["max_cycles"])
    others = int(arguments[engine.count_argument]) if engine.count_argument else 1
    bounds: dict[str, float | None] = dict.fromkeys(METRIC_NAMES)
    for name, (own, per_other) in COUNT_PER_STEP.items():
        bounds[name] = cycles * (own + per_other * others)
    entry = ENVIRONMENT_TABLE[env]
    bounds["harms"] = min(bounds["harms"] or 0, entry.most_harms(others))
    if not entry.batteries:
        bounds["batteries"] = bounds["other_batteries"] = 0
    bounds["return"] = cycles * STEP_REWARD_BOUND
    bounds["other_return"] = others * cycles * STEP_REWARD_BOUND
    return bounds


def constant_metrics(env: str, env_kwargs: Mapping[str, Any]) -> dict[str, float]:
    """The metrics every episode of ``env`` built with ``env_kwargs`` gives one value, by
    construction, with that value: a count whose bound is 0 (:func:`episode_bounds`: ``harms``
    where no one can be harmed, ``batteries`` and ``other_batteries`` where there is none) is 0, and
    ``equality`` of no batteries at all is 1 (its definition, :data:`~empathy_zoo.metrics.METRIC_DOCS`).
    Nothing tuned or compared on one of them can tell runs apart."""
    bounds = episode_bounds(env, env_kwargs)
    constant = {name: 0.0 for name in METRIC_NAMES if name in INTEGER_METRICS and bounds[name] == 0}
    if "batteries" in constant and "other_batteries" in constant:
        constant["equality"] = 1.0
    return constant


def _check_config(check: DocumentChecker, result: Mapping[str, Any]) -> None:
    """``config``: its tables and fields, each within what a run is built with."""
    config = check.table(result["config"], "config")
    check.has(config, CONFIG_TABLES, "config.")
    settings = check.table(config["settings"], "config.settings")
    if "env" in config and config["env"] != result["env"]:
        raise check.fail("config.env", f"the run's env ({result['env']!r})", config["env"])
    check_env_kwargs(check, result["env"], config["env_kwargs"], "config.env_kwargs")
    for agent, policy in check.table(config["fixed"], "config.fixed").items():
        check.name(agent, f"config.fixed (the agent {agent!r})")
        check.policy_label(policy, f"config.fixed.{agent}")
    check.plain(settings, "config.settings")  # (a plug-in's settings are checked for their shape only)
    if "hidden_size" in settings:
        check.integer(settings["hidden_size"], "config.settings.hidden_size", 1, MAX_HIDDEN_SIZE)
    _check_optional(
        check,
        config,
        "config.",
        {
            "env": check.name,
            "method": check.text,
            "label": check.label,
            "seed": lambda v, f: check.integer(v, f, 0, MAX_SEED),
            "steps": lambda v, f: check.integer(v, f, 1, MAX_STEPS),
            "eval_interval": lambda v, f: check.integer(v, f, 1, MAX_STEPS),
            "eval_episodes": lambda v, f: check.integer(v, f, 1, MAX_EVAL_EPISODES),
        },
    )
    if config.get("variant") is not None:
        check.name(config["variant"], "config.variant")
    for name, top in (("seed", "seed"), ("method", "method"), ("label", "method_label"), ("variant", "variant")):
        if config.get(name) is not None and result.get(top) is not None and config[name] != result[top]:
            raise check.fail(f"config.{name}", f"the run's {top} ({shown(result[top])})", config[name])
    if "eval_interval" in config:
        evaluations = -(-result["steps"] // config["eval_interval"])
        if evaluations > MAX_EVALUATIONS:
            raise check.fail(
                "config.eval_interval",
                f"at most {MAX_EVALUATIONS:,} evaluations of the run's {result['steps']:,} steps (docs/limits.md)",
                config["eval_interval"],
            )
    if config.get("reward") is not None:
        check.text(check.table(config["reward"], "config.reward").get("name"), "config.reward.name")
        check.plain(config["reward"], "config.reward")
    try:
        check_description(config["description"])
    except DescriptionError as error:
        raise check.fail(
            "config.description" + ("" if error.field.startswith("(") else f".{error.field}"), error.expected, error.value
        ) from None
    check.plain(config["description"], "config.description")


def check_run_id(check: DocumentChecker, result: Mapping[str, Any], config: Mapping[str, Any]) -> None:
    """``run_id`` (its seed checked already) if it is the id :func:`~empathy_zoo.run_ids.run_id`
    derives from ``config`` as the file holds it (before any schema upgrade: the trainer named the
    run from that record), the variant and the method: a configuration changed after the run,
    which would pool the run with another experiment's, is refused. Every value of ``config`` is
    plain data first (a field a schema upgrade replaced, or one no check reads, is hashed too).
    Checked last, by
    :func:`empathy_zoo.experiment.result_reader.check_result`, so a value out of its range is named
    as such first."""
    check.plain(config, "config")  # (what the hash reads: a field the upgrade replaced, or one no check knows)
    variant = config.get("variant") or result.get("variant") or result["env"]
    expected = run_ids.run_id(str(variant), result["method"], config, result["seed"])
    if result["run_id"] != expected:
        raise check.fail(
            "run_id",
            f"{expected} (the id its config gives: a hash of the config without seed and description)",
            result["run_id"],
        )


def _check_grid(check: DocumentChecker, engine: Any, env_kwargs: Mapping[str, Any], field: str = "config.env_kwargs") -> None:
    """The grid arguments of ``env_kwargs`` (each an int already) within what the environment
    builds (:func:`~empathy_zoo.engine.arguments.check_grid_arguments`: a size of at most
    :data:`~empathy_zoo.limits.MAX_SIZE`, an odd view below it, lookup tables within their bound),
    and as many other agents as the grid holds; checked as numbers, nothing is built."""
    grid = {**{name: argument_defaults(engine)[name] for name in GRID_ARGUMENTS}, **env_kwargs}
    try:
        check_grid_arguments(grid["size"], grid["view"], grid["max_cycles"], engine.min_size)
    except ValueError as error:
        raise check.fail(field, f"arguments {engine.name} is built with ({error})", dict(env_kwargs)) from None
    count = engine.count_argument
    if count is not None and count in env_kwargs:
        most, room = others_room(engine, grid["size"])
        if env_kwargs[count] > most:
            raise check.fail(f"{field}.{count}", f"at most {most:,} ({room})", env_kwargs[count])


def others_room(engine: Any, size: int) -> tuple[int, str]:
    """The most other agents ``engine``'s environment starts on a grid of side ``size``, and why: the
    engine's own bound (its ``_room_for_others``, which reads the size alone), asked of a stand-in
    holding only ``size``, so nothing is built."""
    most, room = engine._room_for_others(SimpleNamespace(size=size))
    return int(most), str(room)


RUNS_DIR = "runs"


def read_folder(results_dir: str | os.PathLike[str]) -> Path:
    """The folder whose result files a results directory's readers read, resolved (every link
    followed, :func:`~empathy_zoo.names.resolved`): ``results_dir/runs`` where it is a directory,
    else ``results_dir`` itself. Two directories are one where their read folders are one
    (``DIR`` and ``DIR/runs``), so a directory given twice is told however it is written."""
    folder = resolved(results_dir)
    return folder / RUNS_DIR if (folder / RUNS_DIR).is_dir() else folder


def results_root(results_dir: str | os.PathLike[str]) -> Path:
    """The results directory a results path stands for: the folder above it where the path, every
    link followed, is a directory named ``runs`` that holds no ``runs`` folder of its own (``DIR/runs``,
    the runs folder ``train --out DIR`` makes, stands for ``DIR``), else ``results_dir`` itself. Its
    evaluations lie in ``<results root>/evaluations`` (:func:`empathy_zoo.evaluation_file.evaluations_root`)
    however the directory is given. A folder named ``runs`` is always read this way, a user's flat
    folder of result files so named too: its evaluations go beside it, never inside it (a ``runs``
    folder's JSON files are read as results). The folder above is as written where the path's own
    name is ``runs``, else the resolved one (``.`` inside a runs folder, or a link to one)."""
    path = Path(results_dir)
    folder = resolved(path)
    if folder.name != RUNS_DIR or not folder.is_dir() or (folder / RUNS_DIR).is_dir():
        return path
    return path.parent if path.name == RUNS_DIR else folder.parent


def result_path(out_dir: Path, run_id: str) -> Path:
    """Where the result file of ``run_id`` lives (a ``run_id`` that is no file name raises ``ValueError``)."""
    return Path(out_dir) / RUNS_DIR / f"{check_path_name(run_id, 'run id')}.json"


def experiment_of(run_id: str) -> str:
    """The run id without its seed: the runs of one experiment (all but the seed equal) share it."""
    return run_id.rsplit("__s", 1)[0]


def check_one_experiment_per_label(runs: Iterable[tuple[str, str, str, str]]) -> None:
    """Raise ``ValueError`` when two of ``runs`` (``(table env, label, run id, where it is)``) share
    a table row, i.e. an env and a label, but come from different experiments: the leaderboard
    groups runs by env and label, so it would mix them (or count one seed twice)."""
    seen: dict[tuple[str, str], tuple[str, str, str]] = {}
    for env, label, run_id, where in runs:
        first = seen.setdefault((env, label), (experiment_of(run_id), run_id, where))
        if first[0] != experiment_of(run_id):
            raise ValueError(
                f"{where} and {first[2]} have the same label {label!r} on {env} but come from two experiments "
                f"(run ids {run_id} and {first[1]}: other settings); the tables could not tell them apart: give one "
                "its own label (train --label, or label in its sweep entry) or move one away"
            )
