"""The evaluation file: one trained agent scored beside held-out partners, and reading it back.

``empathy-zoo evaluate`` (:mod:`empathy_zoo.training.heldout`) writes one JSON file per run and
scenario set, atomically: ``<results>/evaluations/<scenario set>/<run id>.json``
(:func:`evaluation_path`). Its fields (docs/formats.md, "The evaluation file"):

* ``format`` (:data:`FORMAT`), ``schema`` (:data:`SCHEMA`), ``version`` (the empathy-zoo that wrote it);
* the run: ``run_id``, ``env``, ``variant``, ``method``, ``method_label``, ``seed`` (as its result file has them);
* ``agent``: ``{"file": name, "sha256": hex}``, the agent file evaluated (the result file's record);
* ``scenario_set``: the set's definition (``name``, ``env``, ``description``, ``scenarios``: each
  ``name``, ``reason``, ``env_kwargs``, ``fixed``), as its file gave it;
* ``episodes`` (per scenario) and ``stream`` (the random-stream id of the start seeds:
  episode ``e`` of every scenario starts from ``derive_key(seed, stream, e)``);
* ``scenarios``: one entry per scenario played, :data:`TRAINED_WITH` first:
  ``name``, ``reason``, ``held_out`` (``false`` for the run's own partners, and for a scenario that
  is the same world), ``env_kwargs`` and ``fixed`` (what was played: the environment's arguments and
  ``{agent: policy label}``), and ``metrics``: ``{metric: [one value per episode]}`` for every
  metric of :data:`empathy_zoo.metrics.METRIC_NAMES`.

:func:`read_evaluation` refuses anything else with one ``ValueError`` line naming the file and the
field. The file holds no time stamp: evaluating the same agent again writes the same bytes.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Protocol

from empathy_zoo.atomic import read_json
from empathy_zoo.data_files import data_files
from empathy_zoo.document_checks import DocumentChecker, shown
from empathy_zoo.engine.arguments import argument_defaults
from empathy_zoo.environments import DEFAULT_POLICIES, ENGINES, default_policies, is_fixed_agent
from empathy_zoo.evaluation_record import EvaluationResult, ScenarioScores
from empathy_zoo.limits import MAX_EVAL_EPISODES, MAX_SCENARIOS, MAX_SEED
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.names import check_path_name, resolved
from empathy_zoo.randomness import STREAMS
from empathy_zoo.record_parts import AgentRef
from empathy_zoo.result_file import RUNS_DIR, check_agent_record, check_env_kwargs, episode_bounds, results_root


class RunFacts(Protocol):
    """What :func:`evaluation_mismatch` reads of a run: the fields of its
    :class:`~empathy_zoo.experiment.records.RunResult` (a record of a higher layer, not imported here)."""

    @property
    def run_id(self) -> str: ...
    @property
    def env(self) -> str: ...
    @property
    def variant(self) -> str | None: ...
    @property
    def method(self) -> str: ...
    @property
    def seed(self) -> int: ...
    @property
    def agent(self) -> AgentRef | None: ...
    @property
    def config(self) -> Any: ...


__all__ = [
    "TRAINED_WITH",
    "FORMAT",
    "SCHEMA",
    "EVALUATIONS_DIR",
    "EvaluationFileError",
    "evaluation_path",
    "evaluations_root",
    "check_no_stray_json",
    "check_not_read_folder",
    "evaluation_files",
    "check_evaluation",
    "check_scenario_set",
    "check_scenario_definition",
    "evaluation_mismatch",
    "read_evaluation",
]

TRAINED_WITH = "trained_with"
"""The name of the scenario every run is scored in besides a set's: its own partners and world
(:func:`empathy_zoo.scenarios.trained_with`); no scenario of a file may take it."""

FORMAT = "empathy_zoo.evaluation"
"""The ``format`` field of every evaluation file."""
SCHEMA = 1
"""The schema of the evaluation files this suite writes (and the newest it reads)."""
EVALUATIONS_DIR = "evaluations"
"""The folder, beside a results directory's ``runs/``, that holds ``<scenario set>/<run id>.json``."""
OPTIONAL_FIELDS = ("variant", "version")
"""Top-level fields an evaluation file may have besides :data:`REQUIRED_FIELDS`."""
REQUIRED_FIELDS = (
    "format",
    "schema",
    "run_id",
    "env",
    "method",
    "method_label",
    "seed",
    "agent",
    "scenario_set",
    "episodes",
    "stream",
    "scenarios",
)
"""Top-level fields every evaluation file has (``variant`` and ``version`` are written too)."""
SCENARIO_FIELDS = ("name", "reason", "held_out", "env_kwargs", "fixed", "metrics")
"""Fields of every entry of ``scenarios`` (and no others)."""
DEFINITION_FIELDS = ("name", "reason", "env_kwargs", "fixed")
"""Fields of every scenario definition of ``scenario_set.scenarios`` (and no others)."""
SET_FIELDS = ("name", "env", "description", "scenarios")
"""Fields ``scenario_set`` may have (``description`` may be left out; no others)."""
STREAM = STREAMS["heldout_eval"]
"""The random stream of every evaluation's start seeds (``stream``): ``empathy-zoo evaluate`` plays
every scenario from ``derive_key(seed, STREAM, episode)`` and refuses a file made with another."""


class EvaluationFileError(ValueError):
    """An evaluation file is not what this suite writes; the message names the file and the field."""


def evaluations_root(results_dir: str | os.PathLike[str]) -> Path:
    """Where the evaluation files of ``results_dir`` go: ``<results_dir>/evaluations`` (a results
    directory holds its result files in ``runs/``, or is itself a folder of result files), and
    ``DIR/evaluations`` for ``DIR/runs``, the runs folder of ``DIR``
    (:func:`empathy_zoo.result_file.results_root`): a directory's evaluations are one place however
    it is given, and never inside a ``runs`` folder."""
    return results_root(results_dir) / EVALUATIONS_DIR


RESULT_FILE_NAME = re.compile(r"[A-Za-z0-9_.-]+__[A-Za-z0-9_.-]+-[0-9a-f]{8}__s[0-9]+\.json")
"""The name of a result file (its run id, :func:`empathy_zoo.run_ids.run_id`, and ``.json``)."""


def check_not_read_folder(folder: str | os.PathLike[str], what: str, runs_by_name: bool = True) -> None:
    """Refuse (``ValueError`` naming ``what``, the file or folder to write) a ``folder`` whose JSON
    files a results directory reads as its own: a ``runs`` folder, an ``evaluations`` folder or an
    evaluation set's folder (``evaluations/<set>``), as typed and where ``..`` and links lead, or a folder of result files
    (one with no ``runs`` folder that holds a file named as a result file is: every JSON file in
    it is read as a result). A file written there would be read as a broken result or evaluation,
    and refuse the whole directory. Looking stops at the first result file's name. With
    ``runs_by_name`` false, a folder named ``runs`` is refused only where it holds result files (an
    output directory of ``train``, whose default is ``runs``)."""
    typed = Path(folder)
    names = (RUNS_DIR, EVALUATIONS_DIR) if runs_by_name else (EVALUATIONS_DIR,)
    for place in (typed, resolved(typed.absolute())):
        if place.name in names or place.parent.name == EVALUATIONS_DIR:
            raise ValueError(
                f"{what} lies in a folder of a results directory ({place}), whose JSON files are read as results "
                "or evaluations: write it elsewhere"
            )
    if typed.is_dir() and not (typed / RUNS_DIR).is_dir():
        try:
            with os.scandir(typed) as entries:
                found = next((entry.name for entry in entries if RESULT_FILE_NAME.fullmatch(entry.name)), None)
        except OSError:  # (a folder that cannot be listed: writing into it says what is wrong)
            found = None
        if found is not None:
            raise ValueError(
                f"{what} lies in a folder of result files ({typed}, which holds {found}), whose JSON files are all read "
                "as results: write it elsewhere"
            )


def evaluation_path(results_dir: str | os.PathLike[str], scenario_set: str, run_id: str) -> Path:
    """``<results_dir>/evaluations/<scenario set>/<run id>.json`` (names that are no file names raise ``ValueError``)."""
    return (
        evaluations_root(results_dir)
        / check_path_name(scenario_set, "scenario set name")
        / f"{check_path_name(run_id, 'run id')}.json"
    )


def evaluation_files(results_dir: str | os.PathLike[str]) -> list[Path]:
    """Every evaluation file of ``results_dir``, sorted (``[]`` when it has no ``evaluations/``,
    :func:`evaluations_root`); names starting with ``.`` (writes in progress) are left out. Anything
    else named ``evaluations/*/*.json`` that is no regular file (a FIFO, a directory, a dangling
    symbolic link) raises ``ValueError`` naming it (:func:`empathy_zoo.data_files.data_files`), and
    so does an ``evaluations`` folder inside the directory's ``runs`` folder (where ``empathy-zoo
    evaluate DIR/runs`` once wrote them): it is not read, so it is named rather than passed over."""
    root = evaluations_root(results_dir)
    runs = root.parent / RUNS_DIR
    misplaced = runs / EVALUATIONS_DIR
    if runs.is_dir() and not (runs / RUNS_DIR).is_dir() and os.path.lexists(misplaced):
        raise ValueError(
            f"{misplaced} lies inside the runs folder, where no evaluation is read: move its set folders into {root} "
            f"(where the evaluations of {results_dir} are read)"
        )
    check_no_stray_json(root)
    return data_files(root, "*/*.json", "evaluation file")


def check_no_stray_json(root: Path) -> None:
    """Refuse (``ValueError`` naming it) a JSON file at the top of an ``evaluations`` folder
    ``root``: evaluations lie in ``<root>/<scenario set>/``, so it would be passed over without a
    word (an export written there, a file moved up by hand). Names starting with ``.`` are left out."""
    if not root.is_dir():
        return
    stray = sorted(path for path in root.glob("*.json") if not path.name.startswith("."))
    if stray:
        raise ValueError(
            f"{stray[0]} lies at the top of the evaluations folder {root}, where no evaluation is read "
            f"(they lie in {root}/<scenario set>/): move it away"
        )


def _checker(path: Path) -> DocumentChecker:
    """Checks of one evaluation file, each raising :class:`EvaluationFileError` naming ``path`` and the field."""
    return DocumentChecker(
        path,
        EvaluationFileError,
        "an evaluation file",
        "an evaluation of this suite",
        "move it away (empathy-zoo evaluate writes it again)",
    )


def check_evaluation(document: Any, path: str | Path) -> dict[str, Any]:
    """``document`` (a parsed evaluation file) if it follows the schema (see the module page), else
    :class:`EvaluationFileError` naming ``path`` and the field."""
    check = _checker(Path(path))
    evaluation = check.table(document, "(the whole file)")
    check.has(evaluation, REQUIRED_FIELDS, "")
    _only(check, evaluation, (*REQUIRED_FIELDS, *OPTIONAL_FIELDS), "")
    if evaluation["format"] != FORMAT:
        raise check.fail("format", repr(FORMAT), evaluation["format"])
    if evaluation["schema"] != SCHEMA or isinstance(evaluation["schema"], bool):
        raise EvaluationFileError(
            f"{path}: field schema: this suite reads evaluation schema {SCHEMA}, got {evaluation['schema']!r}; move the file away"
        )
    for field in ("run_id", "env"):
        check.name(evaluation[field], field)
    if evaluation["env"] not in ENGINES:
        raise check.fail("env", f"a registered environment ({', '.join(ENGINES)})", evaluation["env"])
    if evaluation.get("variant") is not None:
        check.name(evaluation["variant"], "variant")
    check.text(evaluation["method"], "method")
    check.label(evaluation["method_label"], "method_label")
    if "version" in evaluation:
        check.text(evaluation["version"], "version")
    seed = check.integer(evaluation["seed"], "seed", 0, MAX_SEED)
    if not evaluation["run_id"].endswith(f"__s{seed}"):
        raise check.fail("seed", f"the seed its run id {evaluation['run_id']!r} ends with (__s<seed>)", seed)
    check_agent_record(check, evaluation["agent"], evaluation["run_id"])
    scenario_set = check_scenario_set(check, evaluation["scenario_set"], "scenario_set")
    if scenario_set["env"] != evaluation["env"]:
        raise check.fail("scenario_set.env", f"the run's environment {evaluation['env']!r}", scenario_set["env"])
    episodes = check.integer(evaluation["episodes"], "episodes", 1, MAX_EVAL_EPISODES)
    if check.integer(evaluation["stream"], "stream", 0) != STREAM:
        raise check.fail("stream", f"{STREAM}, the stream empathy-zoo evaluate plays every evaluation from", evaluation["stream"])
    scenarios = evaluation["scenarios"]
    if not isinstance(scenarios, list) or not scenarios or len(scenarios) > MAX_SCENARIOS + 1:
        raise check.fail("scenarios", f"a non-empty array of at most {MAX_SCENARIOS + 1:,} scenarios", scenarios)
    names = []
    for i, entry in enumerate(scenarios):
        where = f"scenarios[{i}]"
        entry = check.table(entry, where)
        check.has(entry, SCENARIO_FIELDS, f"{where}.")
        _only(check, entry, SCENARIO_FIELDS, f"{where}.")
        names.append(_check_scenario(check, evaluation["env"], entry, where, played=True))
        if not isinstance(entry["held_out"], bool):
            raise check.fail(f"{where}.held_out", "true or false", entry["held_out"])
        bounds = episode_bounds(evaluation["env"], entry["env_kwargs"])
        metrics = check.table(entry["metrics"], f"{where}.metrics")
        check.has(metrics, METRIC_NAMES, f"{where}.metrics.")
        for metric in metrics:
            if metric not in METRIC_NAMES:
                raise check.fail(f"{where}.metrics.{metric}", f"no such metric (one of {', '.join(METRIC_NAMES)})", metric)
        for metric in METRIC_NAMES:
            check.metric(metrics[metric], f"{where}.metrics.{metric}", metric, bounds[metric], length=episodes)
    for i, definition in enumerate(scenario_set["scenarios"]):  # (after what was played: a field of it is named first)
        _check_scenario(check, evaluation["env"], definition, f"scenario_set.scenarios[{i}]", played=False)
    if names[0] != TRAINED_WITH or scenarios[0]["held_out"]:
        raise check.fail("scenarios[0]", f"the run's own partners ({TRAINED_WITH!r}, held_out false) first", names[0])
    own = _world(evaluation["env"], scenarios[0])
    for i, entry in enumerate(scenarios[1:], start=1):  # (one marked held out in the run's own world: evaluation_mismatch)
        if not entry["held_out"] and _world(evaluation["env"], entry) != own:
            raise check.fail(
                f"scenarios[{i}].held_out",
                f"true: a scenario of a held-out set is held out unless it is the run's own world ({TRAINED_WITH!r}: "
                "the same arguments and partners), and this one is not",
                entry["held_out"],
            )
    if len(set(names)) != len(names):
        raise check.fail("scenarios", "distinct scenario names", names)
    declared = [definition.get("name") if isinstance(definition, dict) else None for definition in scenario_set["scenarios"]]
    if declared != names[1:]:
        raise check.fail("scenarios", f"the set's scenarios {declared} after {TRAINED_WITH!r}", names)
    for i, (entry, definition) in enumerate(zip(scenarios[1:], scenario_set["scenarios"], strict=True), start=1):
        _check_played_as_defined(check, evaluation["env"], scenarios[0], entry, definition, i)
    return evaluation


def _check_played_as_defined(
    check: DocumentChecker, env: str, own: Mapping[str, Any], entry: Mapping[str, Any], definition: Mapping[str, Any], i: int
) -> None:
    """The played scenario ``entry`` (``scenarios[i]``, checked) is its ``definition`` (the set's
    scenario of the same name) in the run's world (``own``, :data:`TRAINED_WITH`), as
    :meth:`empathy_zoo.scenarios.Scenario.for_run` plays it: its reason the definition's, its
    arguments the run's but for the count of other agents, updated with the definition's own, and
    its partners the definition's; else :class:`EvaluationFileError` naming the field."""
    where, defined = f"scenarios[{i}]", f"scenario_set.scenarios[{i - 1}]"
    if entry["reason"] != definition["reason"]:
        raise check.fail(
            f"{where}.reason", f"the reason of {defined} ({entry['name']}), {shown(definition['reason'])}", entry["reason"]
        )
    count = ENGINES[env].count_argument
    expected = {key: value for key, value in own["env_kwargs"].items() if key != count} | dict(definition["env_kwargs"])
    played = entry["env_kwargs"]
    for key in sorted({*expected, *played}):
        if key not in played or key not in expected or played[key] != expected[key]:
            raise check.fail(
                f"{where}.env_kwargs.{key}",
                f"{shown(expected.get(key, '(left out)'))}: the run's own arguments ({TRAINED_WITH}) but the count of "
                f"other agents, updated with {defined}'s, as evaluate plays {entry['name']}",
                played.get(key, "(left out)"),
            )
    if entry["fixed"] != definition["fixed"]:
        raise check.fail(
            f"{where}.fixed", f"the partners of {defined} ({entry['name']}), {shown(definition['fixed'])}", entry["fixed"]
        )


def _only(check: DocumentChecker, table: Mapping[str, Any], fields: tuple[str, ...], prefix: str) -> None:
    """No field of ``table`` (at ``prefix``) but ``fields``: the first other one is named."""
    for name in table:
        if name not in fields:
            raise check.fail(f"{prefix}{name}", f"no such field (one of {', '.join(fields)})", name)


def _world(env: str, entry: Mapping[str, Any] | ScenarioScores) -> tuple[dict[str, Any], dict[str, str]]:
    """The world of a played scenario (checked; a document's entry or a record's): its arguments
    over ``env``'s defaults, and its fixed agents' policy labels, as ``empathy-zoo evaluate``
    compares them (``same_world``) to mark it ``held_out``."""
    if isinstance(entry, ScenarioScores):
        return {**argument_defaults(ENGINES[env]), **entry.env_kwargs}, dict(entry.fixed)
    return {**argument_defaults(ENGINES[env]), **entry["env_kwargs"]}, dict(entry["fixed"])


def check_scenario_set(check: DocumentChecker, value: Any, where: str) -> dict[str, Any]:
    """A scenario set's definition (:meth:`empathy_zoo.scenarios.ScenarioSet.definition`) at ``where``:
    the fields of :data:`SET_FIELDS` only; its ``name`` a file name, its ``description`` (which may be
    ``""`` or left out) one line of printable text, and at most :data:`MAX_SCENARIOS` scenario
    definitions. Its scenarios are checked by the caller, against the environment. The loader of
    scenario files (:func:`empathy_zoo.scenarios.parse_scenario_set`) checks a set it reads with
    this too, so a set it accepts is one an evaluation file of it may hold."""
    scenario_set = check.table(value, where)
    check.has(scenario_set, ("name", "env", "scenarios"), f"{where}.")
    _only(check, scenario_set, SET_FIELDS, f"{where}.")
    check.name(scenario_set["name"], f"{where}.name")
    if scenario_set.get("description", "") != "":  # (a set may have none: "")
        check.text(scenario_set["description"], f"{where}.description")
    if not isinstance(scenario_set["scenarios"], list) or len(scenario_set["scenarios"]) > MAX_SCENARIOS:
        raise check.fail(
            f"{where}.scenarios", f"an array of at most {MAX_SCENARIOS:,} scenario definitions", scenario_set["scenarios"]
        )
    return scenario_set


def check_scenario_definition(check: DocumentChecker, env: str, definition: Any, where: str) -> str:
    """A scenario definition of a set of ``env`` at ``where``, as an evaluation file's
    ``scenario_set.scenarios`` holds it (:data:`DEFINITION_FIELDS`); returns its name."""
    return _check_scenario(check, env, definition, where, played=False)


def _check_scenario(check: DocumentChecker, env: str, definition: Any, where: str, played: bool) -> str:
    """A scenario (a definition of the set, or an entry of ``scenarios``, ``played``) at ``where``:
    its ``name``, ``reason`` (one line of printable text), ``env_kwargs`` (as a result file's
    ``config.env_kwargs``: :func:`~empathy_zoo.result_file.check_env_kwargs`; a definition's are
    its own arguments, laid over the run's when played, so only those played are checked together
    against the grid) and ``fixed`` (policy labels of agents its world holds beside the learner:
    :func:`~empathy_zoo.environments.is_fixed_agent` with its own count, else one, as
    :meth:`empathy_zoo.scenarios.Scenario.for_run` plays it), one for each of them, as
    :meth:`~empathy_zoo.scenarios.Scenario.definition` and ``evaluate`` record every partner
    (:func:`_fixed_count`); returns its name."""
    entry = check.table(definition, where)
    check.has(entry, DEFINITION_FIELDS, f"{where}.")
    if not played:
        _only(check, entry, DEFINITION_FIELDS, f"{where}.")
    name = check.name(entry["name"], f"{where}.name")
    check.text(entry["reason"], f"{where}.reason")
    env_kwargs = check_env_kwargs(check, env, entry["env_kwargs"], f"{where}.env_kwargs", grid=played)
    for agent_name, label in check.table(entry["fixed"], f"{where}.fixed").items():
        check.name(agent_name, f"{where}.fixed (the agent {agent_name!r})")
        if not is_fixed_agent(env, env_kwargs, agent_name):
            raise check.fail(
                f"{where}.fixed (the agent {agent_name!r})",
                f"an agent {env} holds beside its learner in this scenario's world ({_others(env, env_kwargs)})",
                agent_name,
            )
        check.policy_label(label, f"{where}.fixed.{agent_name}")
    expected = _fixed_count(env, env_kwargs)
    if len(entry["fixed"]) != expected:
        raise check.fail(
            f"{where}.fixed",
            f"a policy for each of the {expected:,} fixed agents its world holds ({_others(env, env_kwargs)}), "
            "as evaluate records every partner",
            entry["fixed"],
        )
    return name


def _fixed_count(env: str, env_kwargs: Mapping[str, Any]) -> int:
    """How many fixed agents ``env`` built with ``env_kwargs`` (checked) holds: the keys of
    :func:`~empathy_zoo.environments.default_policies` (the table's agents and, for each ``<kind>_0``
    of them, ``<kind>_1 … <kind>_<count − 1>``), counted without listing them (a count read from a
    file may be up to 10⁹)."""
    table = DEFAULT_POLICIES.get(env, {})
    count = ENGINES[env].count_argument
    number = int(env_kwargs.get(count, 1)) if count else 1
    kinds = {agent.rpartition("_")[0] for agent in table if agent.rpartition("_")[2] == "0"}
    also_listed = sum(  # (an agent of the table that is one of those added too)
        1
        for agent in table
        if agent.rpartition("_")[0] in kinds
        and re.fullmatch(r"[1-9][0-9]*", index := agent.rpartition("_")[2])
        and int(index) < number
    )
    return len(table) + len(kinds) * max(number - 1, 0) - also_listed


def _others(env: str, env_kwargs: Mapping[str, Any]) -> str:
    """The fixed agents of ``env`` built with ``env_kwargs`` (checked), as a message names them:
    ``cat_0 … cat_2`` for three (a count may be up to 10⁹, so they are never listed one by one)."""
    count = ENGINES[env].count_argument
    number = int(env_kwargs.get(count, 1)) if count else 1
    names = []
    for agent in default_policies(env):
        kind, _, index = agent.rpartition("_")
        names.append(f"{agent} … {kind}_{number - 1}" if count and index == "0" and number > 1 else agent)
    return ", ".join(names)


def evaluation_mismatch(evaluation: EvaluationResult, run: RunFacts) -> str | None:
    """What of ``evaluation`` is not of ``run`` (both records of checked files), as ``"<what>:
    <found>, its run has <value>"``, or ``None`` when it is that run's: its run id, environment,
    variant, method, seed, the agent file (name and SHA-256) its result file records, its
    :data:`TRAINED_WITH` scenario the run's own world and partners, and every other scenario
    ``held_out`` exactly when it is another world than that (what ``empathy-zoo evaluate`` writes
    of the run)."""
    own = evaluation.scenarios[0]
    expected: list[tuple[str, Any, Any]] = [
        ("run_id", evaluation.run_id, run.run_id),
        ("env", evaluation.env, run.env),
        ("variant", evaluation.variant, run.variant or run.env),
        ("method", evaluation.method, run.method),
        ("seed", evaluation.seed, run.seed),
        ("agent.file", evaluation.agent.file, None if run.agent is None else run.agent.file),
        ("agent.sha256", evaluation.agent.sha256, None if run.agent is None else run.agent.sha256),
        (f"scenarios[0].env_kwargs ({TRAINED_WITH})", dict(own.env_kwargs), dict(run.config.env_kwargs)),
        (f"scenarios[0].fixed ({TRAINED_WITH})", dict(own.fixed), dict(run.config.fixed)),
    ]
    own_world = _world(evaluation.env, own)
    for i, entry in enumerate(evaluation.scenarios[1:], start=1):
        held_out = _world(evaluation.env, entry) != own_world
        where = "another world than" if held_out else "the same world as"
        expected.append((f"scenarios[{i}].held_out ({entry.name}: {where} its run's own)", entry.held_out, held_out))
    for what, found, value in expected:
        if what == "variant" and found is None:
            continue  # (a file may leave it out: the run's environment)
        if found != value:
            return f"{what}: {shown(found)}, its run has {shown(value)}"
    return None


def read_evaluation(path: str | Path) -> EvaluationResult:
    """Read an evaluation file; a corrupted or malformed one raises ``ValueError`` naming it (and the
    field), as does one whose name is not ``<scenario set>/<run id>.json`` of the set and run it
    holds (:func:`evaluation_path`: where ``empathy-zoo evaluate`` writes it)."""
    evaluation = check_evaluation(read_json(path, "evaluation file"), path)
    where = Path(path)
    expected = f"{evaluation['scenario_set']['name']}/{evaluation['run_id']}.json"
    if f"{where.parent.name}/{where.name}" != expected:
        raise EvaluationFileError(
            f"{path}: field run_id: its file is named {where.parent.name}/{where.name}, but it holds the evaluation of run "
            f"{evaluation['run_id']} in scenario set {evaluation['scenario_set']['name']} ({expected}): renamed or copied; "
            "move it away (empathy-zoo evaluate writes it again)"
        )
    return EvaluationResult.from_checked(evaluation)
