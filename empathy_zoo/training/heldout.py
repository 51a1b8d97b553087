"""Held-out evaluation: every kept agent of a results directory played greedily beside partners it
never trained with (the scenarios of :mod:`empathy_zoo.scenarios`), one evaluation file per run
and scenario set (:mod:`empathy_zoo.evaluation_file`).

:func:`evaluate_results` is what ``empathy-zoo evaluate`` runs. For each run whose result file
names an agent file (``"agent": {"file", "sha256"}``) and each scenario set of its environment
(by default the shipped one), it loads the agent, refusing a file whose SHA-256 is not the one the
result file records (the message names both files), and plays ``episodes`` greedy episodes in the
run's own world and partners (:data:`~empathy_zoo.scenarios.TRAINED_WITH`) and in every scenario of
the set, through :func:`~empathy_zoo.training.evaluation.evaluate_greedy`: the agent acts as the
learner did (ε = 0). Episode ``e`` of every scenario starts from the seed
``derive_key(run seed, STREAMS["heldout_eval"], e)``: a stream of its own, the same for every
scenario (so the run's scenarios differ in their partners, not in their luck at the start).

It is resumable: an evaluation file is written atomically once all of its run's scenarios are
played, and a later call skips every run whose file is there and was made of the same agent, set
and episode count; a file that was made otherwise is refused by name, never overwritten.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch

from empathy_zoo.agent_file import load_run_agent
from empathy_zoo.atomic import check_output_dir, remove_stale_temp_files, write_json_atomic
from empathy_zoo.data_files import check_input_dir, data_files
from empathy_zoo.environments import DEFAULT_ARGUMENTS
from empathy_zoo.evaluation_file import (
    FORMAT,
    SCHEMA,
    check_not_read_folder,
    evaluation_mismatch,
    evaluation_path,
    evaluations_root,
    read_evaluation,
)
from empathy_zoo.evaluation_record import EvaluationResult
from empathy_zoo.experiment.agent_method import check_agent_method
from empathy_zoo.experiment.model import EnvVariant
from empathy_zoo.experiment.records import AgentRef, RunResult
from empathy_zoo.experiment.result_reader import read_result
from empathy_zoo.limits import MAX_EVAL_EPISODES, MAX_EVALUATE_CYCLES, check_at_most, cpu_count
from empathy_zoo.names import resolved
from empathy_zoo.output_lock import command_line, hold_output_dir
from empathy_zoo.policies import check_allowed_imports_named, entry_label
from empathy_zoo.provenance import package_version
from empathy_zoo.randomness import STREAMS
from empathy_zoo.result_file import AGENT_SUFFIXES, RUNS_DIR, results_root
from empathy_zoo.scenarios import Scenario, ScenarioSet, default_set_name, load_scenario_set, trained_with
from empathy_zoo.training.evaluation import evaluate_greedy
from empathy_zoo.training.progress import progress_bar

__all__ = [
    "STREAM_HELDOUT",
    "DEFAULT_EPISODES",
    "EvaluationSummary",
    "GreedyAgent",
    "evaluate_results",
    "evaluate_run",
    "results_of",
    "same_world",
]

STREAM_HELDOUT = STREAMS["heldout_eval"]
"""The random stream of a held-out evaluation's start seeds (its own id in :data:`empathy_zoo.randomness.STREAMS`)."""
DEFAULT_EPISODES = 100
"""Greedy episodes per scenario and run unless told otherwise: a run's per-scenario mean is one
number of the seeds the leaderboard's intervals are over; 100 episodes keep its own noise well
below the spread between seeds (a harm rate of 0.1 is then known to about ±0.03)."""


class GreedyAgent:
    """A loaded agent (``act_batch``) as :func:`evaluate_greedy` drives a learner: ``act(observations
    (K, M, V), greedy=True) -> (K, M)``."""

    def __init__(self, agent: Any) -> None:
        self.agent = agent
        """The trained agent (:class:`~empathy_zoo.trained_agent.TrainedAgent` or ``SB3Agent``)."""

    def act(self, observations: np.ndarray, greedy: bool = True) -> np.ndarray:
        if not greedy:
            raise ValueError("a loaded agent acts greedily only (it keeps no exploration schedule)")
        k, m, v = observations.shape
        return self.agent.act_batch(observations.reshape(k * m, v)).reshape(k, m)


@dataclass
class EvaluationSummary:
    """What :func:`evaluate_results` did."""

    written: list[Path] = field(default_factory=list)
    """Evaluation files written by this call."""
    done: list[Path] = field(default_factory=list)
    """Evaluation files already there (made of the same agent, set and episodes): skipped."""
    without_agent: list[str] = field(default_factory=list)
    """Runs whose result file names no agent file (a run that kept none, or of an older empathy-zoo)."""
    without_set: list[str] = field(default_factory=list)
    """Runs of an environment none of the scenario sets is for."""

    @property
    def files(self) -> list[Path]:
        """Every evaluation file of the runs evaluated: written or already there."""
        return sorted(self.written + self.done)


def results_of(results_dir: str | Path) -> list[tuple[Path, RunResult]]:
    """``(result file, result)`` of every result file of ``results_dir`` (its ``runs/``, or itself
    when it holds the files), read and checked (:func:`empathy_zoo.experiment.result_reader.read_result`), in
    file-name order; a directory without result files raises ``ValueError``, and so does a result or
    agent file there that is no regular file (:func:`empathy_zoo.data_files.data_files`)."""
    root = check_input_dir(results_dir, "results directory", "name the directory that holds the result files")
    runs = root / RUNS_DIR if (root / RUNS_DIR).is_dir() else root
    for suffix in AGENT_SUFFIXES:
        data_files(runs, f"*{suffix}", "agent file")
    paths = data_files(runs, "*.json", "result file")
    if not paths:
        raise ValueError(f"no result files (*.json) in {runs}: train runs first")
    return [(path, read_result(path)) for path in paths]


def check_evaluations_folder(results_dir: str | Path, out: Path) -> None:
    """Refuse (``ValueError`` naming it) an ``out`` other than the results directory of
    ``results_dir`` (:func:`empathy_zoo.result_file.results_root`: ``DIR`` for ``DIR/runs``) where
    evaluations of its runs would be read as another directory's: a results directory (one holding
    a ``runs`` folder), a folder of result files, a ``runs`` folder (``DIR/runs`` itself too) or an
    evaluation set's folder (:func:`empathy_zoo.evaluation_file.check_not_read_folder`). Their
    leaderboard would take the files for evaluations of its own runs; the results directory itself,
    or a folder of no runs, is the place (``leaderboard --evaluations`` reads the latter)."""
    root = results_root(results_dir)
    if resolved(out) == resolved(root):
        return
    check_not_read_folder(out, f"the evaluations' folder {out}")
    if (out / RUNS_DIR).is_dir():
        raise ValueError(
            f"the evaluations' folder {out} is another results directory (it holds {out / RUNS_DIR}): its leaderboard "
            f"would read evaluations of {results_dir}'s runs as its own; write them into {root} or a folder "
            "of no runs (leaderboard --evaluations reads it)"
        )


def same_world(a: EnvVariant, b: EnvVariant) -> bool:
    """Whether two variants are the same world: one environment, equal arguments (those left out
    at their defaults) and the same fixed agents with the same policies."""
    defaults = DEFAULT_ARGUMENTS.get(a.env, {})

    def world(variant: EnvVariant) -> tuple[Any, ...]:
        fixed = {agent: entry_label(entry) for agent, entry in variant.fixed_policies().items()}
        return variant.env, {**defaults, **variant.kwargs}, fixed

    return world(a) == world(b)


def run_agent(result_file: Path, result: RunResult, allowed_imports: Collection[str] = ()) -> Any:
    """The trained agent of the run whose result file (read as ``result``) is ``result_file``: loaded
    from the agent file it names and checked against the SHA-256 recorded there, of a method
    registered here or a plug-in kept as text (:func:`~empathy_zoo.experiment.agent_method.check_agent_method`),
    of the run's environment and observation window; else a ``ValueError`` naming the file."""
    agent = check_agent_method(load_run_agent(result_file))
    described = agent.describe().get("env")
    if described is not None and described != result.env:
        raise ValueError(
            f"agent file {agent.describe().get('file')} is of {described}, but its run {result_file} is of {result.env}"
        )
    home = trained_with(result, allowed_imports).variant
    view = int({**DEFAULT_ARGUMENTS[result.env], **home.kwargs}["view"])
    if agent.obs_size != view * view:
        raise ValueError(
            f"agent file {agent.describe().get('file')} takes observations of {agent.obs_size} values, but its run "
            f"{result_file} sees a {view}×{view} window ({view * view}): the agent file is not this run's"
        )
    return agent


def evaluate_run(
    result_file: Path,
    result: RunResult,
    scenario_set: ScenarioSet,
    episodes: int = DEFAULT_EPISODES,
    on_scenario: Callable[[str], None] | None = None,
    allowed_imports: Collection[str] = (),
    agent: Any = None,
) -> dict[str, Any]:
    """The evaluation document of one run (see :mod:`empathy_zoo.evaluation_file`): its agent,
    loaded from the agent file its result file names and checked against the SHA-256 recorded
    there, played ``episodes`` greedy episodes in its own world and in every scenario of
    ``scenario_set``; ``on_scenario(name)`` is called after each. ``ValueError`` for a run that kept
    no agent, an agent file changed since, or a scenario the run's world cannot hold. A partner the
    result file records resolves only to a registered policy or one of ``allowed_imports``
    (:func:`empathy_zoo.scenarios.trained_with`). ``agent``: the run's agent already loaded and
    checked (:func:`run_agent`), else it is loaded here."""
    if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 1:
        raise ValueError(f"episodes must be a positive int, got {episodes!r}")
    check_at_most("episodes", episodes, MAX_EVAL_EPISODES, "greedy episodes per run and scenario, played at once")
    if result.env != scenario_set.env:
        raise ValueError(f"scenario set {scenario_set.name!r} is for {scenario_set.env}; run {result.run_id} is of {result.env}")
    if agent is None:
        agent = run_agent(result_file, result, allowed_imports)
    own = trained_with(result, allowed_imports)
    home = own.variant
    learner = GreedyAgent(agent)
    entries = []
    scenarios: list[Scenario] = [own, *scenario_set.scenarios]
    variants = [scenario.for_run(home.kwargs) for scenario in scenarios]  # (every scenario checked before one is played)
    for scenario, variant in zip(scenarios, variants, strict=True):
        columns = evaluate_greedy(
            learner,
            result.env,
            [result.seed],
            episodes,
            variant.fixed_policies(),
            dict(variant.kwargs),
            STREAM_HELDOUT,
        )[0]
        entries.append(
            {
                "name": scenario.name,
                "reason": scenario.reason,
                "held_out": scenario is not own and not same_world(variant, home),
                "env_kwargs": dict(variant.kwargs),
                "fixed": {agent_name: entry_label(entry) for agent_name, entry in variant.fixed_policies().items()},
                "metrics": columns,
            }
        )
        if on_scenario is not None:
            on_scenario(scenario.name)
    return {
        "format": FORMAT,
        "schema": SCHEMA,
        "version": package_version(),
        "run_id": result.run_id,
        "env": result.env,
        "variant": result.table_env,
        "method": result.method,
        "method_label": result.method_label,
        "seed": result.seed,
        "agent": _agent_entry(result).to_document(),
        "scenario_set": scenario_set.definition(),
        "episodes": episodes,
        "stream": STREAM_HELDOUT,
        "scenarios": entries,
    }


def _identity(evaluation: EvaluationResult) -> dict[str, Any]:
    """What must agree for an evaluation file to be the one asked for."""
    return {
        "the run": evaluation.run_id,
        "the agent file's SHA-256": evaluation.agent.sha256,
        "the scenario set": evaluation.scenario_set.to_document(),
        "the episodes per scenario": evaluation.episodes,
        "the start seeds' stream": evaluation.stream,
    }


def _check_done(path: Path, result_file: Path, result: RunResult, scenario_set: ScenarioSet, episodes: int) -> None:
    """Raise ``ValueError`` naming ``path`` when the evaluation file there was made of another agent,
    set or episode count than asked for now, or says what its run is not (its environment,
    variant, method, seed or own world: :func:`~empathy_zoo.evaluation_file.evaluation_mismatch`)."""
    existing = read_evaluation(path)
    mismatch = evaluation_mismatch(existing, result)
    if mismatch is not None:
        raise ValueError(
            f"evaluation file {path} is not of its run's result file {result_file}: {mismatch}; move it away to "
            "evaluate again, or write elsewhere (--out)"
        )
    asked = {
        "the run": result.run_id,
        "the agent file's SHA-256": _agent_entry(result).sha256,
        "the scenario set": scenario_set.definition(),
        "the episodes per scenario": episodes,
        "the start seeds' stream": STREAM_HELDOUT,
    }
    found = _identity(existing)
    for what, value in asked.items():
        if found[what] != value:
            shown = (
                f"{found[what]!r}, asked for {value!r}"
                if what != "the scenario set"
                else f"another definition of set {scenario_set.name!r} than {scenario_set.source}'s"
            )
            raise ValueError(
                f"evaluation file {path} was made with {what} {shown} (result file {result_file}): move it away "
                "to evaluate again, or write elsewhere (--out)"
            )


def _agent_entry(result: RunResult) -> AgentRef:
    """The agent file the run kept (only for a run that kept one: a ``ValueError`` otherwise)."""
    if result.agent is None:
        raise ValueError(f"run {result.run_id} kept no trained agent: its result file names no agent file")
    return result.agent


def evaluate_results(
    results_dir: str | Path,
    scenario_sets: Sequence[str | Path | ScenarioSet] | None = None,
    episodes: int = DEFAULT_EPISODES,
    out_dir: str | Path | None = None,
    progress: bool = True,
    progress_style: str = "auto",
    on_written: Callable[[Path], None] | None = None,
    on_note: Callable[[str], None] | None = None,
    threads: int = 1,
    allowed_imports: Collection[str] = (),
) -> EvaluationSummary:
    """Evaluate every kept agent of ``results_dir`` in every scenario set of its environment.

    ``episodes`` is at most :data:`~empathy_zoo.limits.MAX_EVAL_EPISODES` (checked first, before
    anything is read or created: they are played at once).

    ``scenario_sets``: shipped names, TOML files or :class:`ScenarioSet` objects; ``None`` = the
    shipped set of each environment the runs are of. ``out_dir`` (default: the results directory,
    ``DIR`` for ``results_dir`` ``DIR/runs``, :func:`empathy_zoo.result_file.results_root`, so that
    nothing is written into a ``runs`` folder and every reader finds the files) gets
    ``evaluations/<set>/<run id>.json`` (:func:`empathy_zoo.evaluation_file.evaluation_path`).
    Files already there are skipped when made of the same agent, set and episodes, refused by name
    otherwise; ``on_written(path)`` is called after each file written. Another process evaluating
    into ``out_dir`` meanwhile is refused (:func:`empathy_zoo.output_lock.hold_output_dir`, on its
    ``evaluations/``: training may go on in the same directory); ``on_note`` gets what the lock
    has to say (nothing on Linux and macOS). ``threads``: torch's CPU threads while playing (1, as
    training: the agents' small products gain nothing from more, and extra threads are many times
    slower on a busy machine; at most :func:`empathy_zoo.limits.cpu_count`); what is computed does
    not depend on it. ``progress`` draws a bar counting the scenarios played
    (``progress_style``: :data:`~empathy_zoo.training.progress.PROGRESS_STYLES`). A run's recorded
    partners resolve only to registered policies or names in ``allowed_imports`` (a result file
    never makes the suite import code); every run's are checked before anything is written.
    Raises ``ValueError`` when nothing could be evaluated (no run kept an agent, or no set is for
    their environments), and for the errors of :func:`evaluate_run`.
    """
    if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 1:
        raise ValueError(f"episodes must be a positive int, got {episodes!r}")
    check_at_most("episodes", episodes, MAX_EVAL_EPISODES, "greedy episodes per run and scenario, played at once")
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise ValueError(f"threads must be a positive int, got {threads!r}")
    check_at_most("threads", threads, cpu_count(), "the CPUs of this machine")
    if out_dir is not None and not os.fspath(out_dir):
        raise ValueError("out_dir is an empty path: name the directory ('.' for the current one)")
    runs = results_of(results_dir)
    fixed = (label for _, result in runs for label in result.config.fixed.values())
    check_allowed_imports_named(allowed_imports, fixed, f"of the result files in {results_dir}")
    out = results_root(results_dir) if out_dir is None else Path(out_dir)
    check_evaluations_folder(results_dir, out)
    summary = EvaluationSummary()
    kept = []
    for path, result in runs:
        if result.agent is None:
            summary.without_agent.append(result.run_id)
        else:
            kept.append((path, result))
    if not kept:
        raise ValueError(
            f"no run in {results_dir} kept a trained agent (their result files name no agent file): "
            "only runs trained by empathy-zoo 0.4 or later, with a method that keeps its agent, can be evaluated"
        )
    if scenario_sets is None:
        names = sorted({name for _, result in kept if (name := default_set_name(result.env)) is not None})
        sets = [load_scenario_set(name) for name in names]
    else:
        sets = [s if isinstance(s, ScenarioSet) else load_scenario_set(s) for s in scenario_sets]
    by_name: dict[str, ScenarioSet] = {}
    for scenario_set in sets:
        if scenario_set.name in by_name and by_name[scenario_set.name].definition() != scenario_set.definition():
            raise ValueError(
                f"two scenario sets are named {scenario_set.name!r} ({by_name[scenario_set.name].source}, {scenario_set.source})"
            )
        if scenario_set.name in by_name:  # (one set twice, by name or by two spellings of its file: said, not merged)
            raise ValueError(
                f"scenario set {scenario_set.name!r} is given twice ({by_name[scenario_set.name].source}, {scenario_set.source})"
            )
        by_name[scenario_set.name] = scenario_set
    envs = {s.env for s in by_name.values()}
    summary.without_set = [result.run_id for _, result in kept if result.env not in envs]
    work = [(s, path, result) for s in by_name.values() for path, result in kept if result.env == s.env]
    if not work:
        raise ValueError(
            f"no scenario set is for the environments of the kept agents in {results_dir} "
            f"({', '.join(sorted({result.env for _, result in kept}))}); sets given: "
            + ", ".join(f"{s.name} ({s.env})" for s in by_name.values())
        )
    for _, result in kept:
        trained_with(result, allowed_imports)  # (every run's own partners, checked before anything is written)
    todo = _todo(work, out, episodes, summary)
    agents = _checked_agents(todo, allowed_imports)
    directories = sorted({evaluation_path(out, s.name, "x").parent for s in by_name.values()})
    created = sorted(
        {folder for directory in directories for folder in (directory, *directory.parents) if not folder.exists()},
        key=lambda folder: len(folder.parts),
        reverse=True,
    )
    try:
        for directory in directories:
            check_output_dir(out, (directory.relative_to(out).as_posix(),))  # (no link below out)
        with hold_output_dir(evaluations_root(out), command_line(), on_note):  # (training may go on beside it)
            for directory in directories:
                remove_stale_temp_files(directory)
            before = torch.get_num_threads()
            torch.set_num_threads(threads)
            try:
                _evaluate_todo(todo, agents, episodes, (progress, progress_style), on_written, summary, allowed_imports)
            finally:
                torch.set_num_threads(before)
    except BaseException:
        for folder in created:  # (only the directories this call made, and only while empty)
            try:
                folder.rmdir()
            except OSError:
                continue
        raise
    return summary


def _todo(
    work: Sequence[tuple[ScenarioSet, Path, RunResult]], out: Path, episodes: int, summary: EvaluationSummary
) -> list[tuple[ScenarioSet, Path, RunResult, Path]]:
    """``(set, result file, result, evaluation file)`` of what of ``work`` has no evaluation file in
    ``out`` yet; one already there is read and checked to be the one asked for (:func:`_check_done`,
    which refuses anything but a regular file in its place) and counted in ``summary.done``."""
    todo = []
    for scenario_set, path, result in work:
        target = evaluation_path(out, scenario_set.name, result.run_id)
        if os.path.lexists(target):
            _check_done(target, path, result, scenario_set, episodes)
            summary.done.append(target)
        else:
            todo.append((scenario_set, path, result, target))
    return todo


def _checked_agents(
    todo: Sequence[tuple[ScenarioSet, Path, RunResult, Path]], allowed_imports: Collection[str]
) -> dict[Path, Any]:
    """The agent of every run of ``todo`` (:func:`run_agent`), by result file, once every scenario
    of its set fits the run's world: every input is checked before the first evaluation file is
    written (``ValueError`` naming the first that is not)."""
    agents: dict[Path, Any] = {}
    for scenario_set, path, result, _ in todo:
        if path not in agents:
            agents[path] = run_agent(path, result, allowed_imports)
        home = trained_with(result, allowed_imports).variant
        worlds = [("its own world", home), *((f"scenario {s.name!r}", s.for_run(home.kwargs)) for s in scenario_set.scenarios)]
        for where, variant in worlds:
            cycles = int({**DEFAULT_ARGUMENTS[result.env], **variant.kwargs}["max_cycles"])
            if cycles > MAX_EVALUATE_CYCLES:
                raise ValueError(
                    f"result file {path}: {where} plays episodes of max_cycles {cycles:,}, beyond the "
                    f"{MAX_EVALUATE_CYCLES:,} steps evaluate plays an episode (MAX_EVALUATE_CYCLES; docs/limits.md)"
                )
    return agents


def _evaluate_todo(
    todo: Sequence[tuple[ScenarioSet, Path, RunResult, Path]],
    agents: Mapping[Path, Any],
    episodes: int,
    progress: tuple[bool, str],
    on_written: Callable[[Path], None] | None,
    summary: EvaluationSummary,
    allowed_imports: Collection[str] = (),
) -> None:
    """Play and write every evaluation of ``todo`` with the ``agents`` checked before
    (:func:`evaluate_results` holds the directory); one another process wrote meanwhile is checked
    and skipped as done."""
    total = sum(1 + len(scenario_set.scenarios) for scenario_set, *_ in todo)
    shown, style = progress
    with progress_bar(style, total=total, unit="scenario", desc="evaluate", disable=not shown or total == 0) as bar:
        for scenario_set, path, result, target in todo:
            if os.path.lexists(target):
                _check_done(target, path, result, scenario_set, episodes)
                summary.done.append(target)
                bar.update(1 + len(scenario_set.scenarios))
                continue
            bar.set_postfix_str(f"{scenario_set.name}: {result.run_id}", refresh=False)
            document = evaluate_run(
                path,
                result,
                scenario_set,
                episodes,
                on_scenario=lambda _name: bar.update(1),
                allowed_imports=allowed_imports,
                agent=agents[path],
            )
            write_json_atomic(target, document)
            summary.written.append(target)
            if on_written is not None:
                on_written(target)
