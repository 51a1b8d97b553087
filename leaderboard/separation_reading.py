"""# Trained runs against the exact separation tables

Reads a results directory (the scenarios profile's, or any with runs on a task that has an exact
separation table) by the rule of :mod:`leaderboard.trained_separation`: every prediction the
tables make, judged on the per-seed harms of each run's final greedy evaluation against DQN's.

    python -m leaderboard.separation_reading RESULTS [--tables docs/results/separation]

Runs are matched to a prediction by task (the run's environment, its own variant only: a
variant is another world), method and, for a method with a selfishness weight, β = 0.5
(:data:`~leaderboard.trained_separation.BETA`). A run is read against its task's table only where
it was trained in the world the table models (:func:`in_table_world`: the same environment, every
environment argument, ``max_cycles`` included, equal once the defaults are filled in on both
sides, and the world's default partners); every other run is named in the page's closing notes.
A prediction with no runs of its method or of DQN is listed as such, never judged. The rule
reads harms, so a task whose robot cannot harm (the environment table's ``can_harm``: Sharing) is
listed as not read (its runs are checked against its default world: :func:`reading_world`).
Prints Markdown: per task, every judgement, then whether the task separates in trained runs.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from empathy_zoo.experiment.records import RunResult
from empathy_zoo.markdown_escape import code_span, markdown_text
from empathy_zoo.names import terminal_line
from leaderboard.trained_separation import (
    BETA,
    FEWER,
    MORE,
    Judgement,
    Prediction,
    at_beta,
    judge,
    predictions,
    task_separates,
)

__all__ = [
    "NOT_READ",
    "OTHER_WORLD",
    "Reading",
    "World",
    "can_harm",
    "final_harms",
    "in_table_world",
    "markdown",
    "not_read_notes",
    "read_runs",
    "reading_world",
    "run_world",
    "selfish_methods",
    "table_world",
    "why_not_read",
    "world_difference",
    "main",
]

TABLES = Path(__file__).resolve().parents[1] / "docs" / "results" / "separation"
"""The shipped separation tables (``<task>.json``)."""

_SHOWN = {FEWER: "▲ fewer", MORE: "▼ more"}


@dataclass(frozen=True)
class Reading:
    """One prediction and what trained runs say of it."""

    prediction: Prediction
    seeds: int
    """Seeds of the method's runs read (0: none, and no judgement)."""
    dqn_seeds: int
    """Seeds of DQN's runs on the same task."""
    judgement: Judgement | None
    """``None`` when either side has no runs."""


Tables = Mapping[str, Mapping[str, Any]]
"""Separation tables by task (the run environment they are read against: a table file's stem)."""


def final_harms(
    results: Sequence[RunResult], selfish_methods: Mapping[str, bool], tables: Tables | None = None
) -> dict[tuple[str, str], list[float]]:
    """``{(task, method): per-seed harms}``: each run's mean harms per episode over its final greedy
    evaluation, in seed order, for runs of a task's own variant in the world its task is read in
    (:func:`reading_world`: its table's in ``tables``; without ``tables``, or for a task they do not
    hold, the default world: every environment argument and partner at its default); a method
    ``selfish_methods`` marks ``True`` is read at β = :data:`~leaderboard.trained_separation.BETA`
    only. A task with two runs of one method and seed, or runs of one method from two experiments
    (another label, setting or budget), raises ``ValueError`` naming them."""
    found: dict[tuple[str, str], dict[int, float]] = {}
    experiments: dict[tuple[str, str], RunResult] = {}
    for run in results:
        if why_not_read(run, selfish_methods, tables) is not None:
            continue
        first = experiments.setdefault((run.env, run.method), run)
        if first.experiment != run.experiment:
            raise ValueError(
                f"runs {first.run_id} and {run.run_id} are both {run.method} on {run.env} but of two experiments "
                "(another label, setting or budget): a prediction is read on one experiment's seeds; keep one of them"
            )
        seeds = found.setdefault((run.env, run.method), {})
        if run.seed in seeds:
            raise ValueError(f"two runs of {run.method} on {run.env} with seed {run.seed} (one is {run.run_id})")
        seeds[run.seed] = float(np.mean(run.eval[-1].metrics["harms"]))
    return {key: [seeds[seed] for seed in sorted(seeds)] for key, seeds in found.items()}


NOT_READ = {
    "variant": "of a variant, not the task's own world",
    "world": "trained outside the default world the tables model (another environment argument or partner)",
    "evaluation": "without a greedy evaluation",
    "beta": f"of a method with β at another β than {BETA}",
}
"""Why :func:`final_harms` leaves a run out, by the key :func:`why_not_read` gives."""
OTHER_WORLD = "trained in another world than the task's table models"
"""The ``world`` reason of :func:`not_read_notes` given the tables (each run then named with what of
its world is not the table's: :func:`world_difference`)."""


@dataclass(frozen=True)
class World:
    """A world a run is trained in or a table models: its environment, every argument (the defaults
    filled in) and its fixed agents' policies."""

    env: str
    arguments: Mapping[str, Any]
    partners: Mapping[str, str]


def run_world(run: RunResult) -> World | None:
    """The world ``run`` was trained in, as its result file records it: its environment's default
    arguments (:data:`~empathy_zoo.environments.DEFAULT_ARGUMENTS`) updated with those it set, and
    its fixed agents; ``None`` for an environment the suite does not have."""
    from empathy_zoo.environments import DEFAULT_ARGUMENTS

    defaults = DEFAULT_ARGUMENTS.get(run.env)
    if defaults is None:
        return None
    return World(run.env, {**defaults, **run.config.env_kwargs}, dict(run.config.fixed))


def table_world(task: str, table: Mapping[str, Any]) -> World | None:
    """The world ``table`` (of ``task``) models: its ``env`` (else ``task``), its environment's
    default arguments updated with its ``arguments`` and, where it records it, its ``max_cycles``,
    and that world's default partners (:func:`~empathy_zoo.environments.default_policies`: the
    exact model's other agent; a table records none). ``table = {}``: the task's default world.
    ``None`` for an environment the suite does not have."""
    from empathy_zoo.environments import DEFAULT_ARGUMENTS, default_policies

    env = str(table.get("env", task))
    defaults = DEFAULT_ARGUMENTS.get(env)
    if defaults is None:
        return None
    arguments = {**defaults, **{str(name): value for name, value in table.get("arguments", [])}}
    if "max_cycles" in table:
        arguments["max_cycles"] = table["max_cycles"]
    return World(env, arguments, default_policies(env, arguments))


def reading_world(task: str, tables: Tables | None) -> World | None:
    """The world runs of ``task`` are read in: the world of its table in ``tables``
    (:func:`table_world`) where its robot can harm; the task's default world without ``tables``,
    for a task they do not hold, and for a task whose robot cannot harm (nothing of its runs is read
    against its table: a smaller exact model, Sharing's, stands for the default world's cells)."""
    if tables is not None and task in tables and can_harm(task):
        return table_world(task, tables[task])
    return table_world(task, {})


def in_table_world(run: RunResult, tables: Tables | None = None) -> bool:
    """Whether ``run`` was trained in the world its task is read in (:func:`reading_world`):
    one environment, every argument equal once the defaults are filled in on both sides, and the
    same fixed agents with the same policies. The one rule both readers (``analyse
    separation-reading``, ``analyse discrimination --results``) read runs by."""
    world = run_world(run)
    return world is not None and world == reading_world(run.env, tables)


def world_difference(run: RunResult, tables: Tables | None) -> str:
    """What of ``run``'s world is not the world its task is read in (:func:`reading_world`), as a
    note names it: ``"coexistence_v0 at size 7 not 5 and max_cycles 500 not 5"``, each argument
    (``max_cycles`` last) and each fixed agent's policy that differs; where that world is the
    task's default one (its robot cannot harm, or ``tables`` hold no table of it), it says so."""
    mine, theirs = run_world(run), reading_world(run.env, tables)
    if mine is None or theirs is None:
        return f"{run.env}, an environment the suite does not have"
    names = [*sorted({*mine.arguments, *theirs.arguments} - {"max_cycles"}), "max_cycles"]
    differs = [
        f"{name} {mine.arguments.get(name, 'unset')} not {theirs.arguments.get(name, 'unset')}"
        for name in names
        if mine.arguments.get(name) != theirs.arguments.get(name)
    ]
    differs += [
        f"{agent} {mine.partners.get(agent, 'absent')} not {theirs.partners.get(agent, 'absent')}"
        for agent in sorted({*mine.partners, *theirs.partners})
        if mine.partners.get(agent) != theirs.partners.get(agent)
    ]
    read_in_table = tables is not None and run.env in tables and can_harm(run.env)
    return f"{run.env} at {' and '.join(differs)}" + ("" if read_in_table else " against its default world")


def why_not_read(run: RunResult, selfish_methods: Mapping[str, bool], tables: Tables | None = None) -> str | None:
    """The key of :data:`NOT_READ` that keeps ``run`` out of :func:`final_harms`, else ``None``;
    ``world`` for a run not of the world its task is read in (:func:`in_table_world`: the default
    world without ``tables``)."""
    if (run.variant or run.env) != run.env:
        return "variant"
    if not in_table_world(run, tables):
        return "world"
    if not run.eval:
        return "evaluation"
    if selfish_methods.get(run.method, False):
        beta = run.config.settings.get("selfishness")
        if beta is None or not at_beta(beta):  # (the number itself: 0.5000001 is not 0.5)
            return "beta"
    return None


def not_read_notes(
    results: Sequence[RunResult],
    selfish_methods: Mapping[str, bool],
    tasks: Sequence[str],
    methods: Sequence[str],
    tables: Tables | None = None,
) -> list[str]:
    """One line per reason some runs of ``results`` are not read against the tables of ``tasks``
    (naming ``methods``): its count and why (:data:`NOT_READ`, an environment no table models, a
    method no table has a row of), so that no run is left out without a word. Given ``tables``
    (``{task: table}``), a run of another world than its task's table (:func:`in_table_world`) is
    counted as :data:`OTHER_WORLD` and named by what of its world differs (:func:`world_difference`)."""
    counts: dict[str, int] = {}
    names: dict[str, set[str]] = {}
    for run in results:
        if run.env not in tasks:
            why, name = "of an environment no table models", run.env
        elif run.method not in methods:
            why, name = "of a method no table has a row of", run.method
        else:
            key = why_not_read(run, selfish_methods, tables)
            if key is None:
                continue
            why, name = NOT_READ[key], ""
            if key == "world" and tables is not None:
                why, name = OTHER_WORLD, world_difference(run, tables)
        counts[why] = counts.get(why, 0) + 1
        names.setdefault(why, set()).add(name)
    return [
        f"{count} run{'s' if count > 1 else ''} {why}"
        + (f" ({_some(sorted(names[why]))})" if "" not in names[why] else "")
        + ": not read"
        for why, count in counts.items()
    ]


def _some(names: Sequence[str], most: int = 10) -> str:
    """``names`` joined, at most ``most`` of them and a count of the rest."""
    shown = ", ".join(names[:most])
    return shown if len(names) <= most else f"{shown} and {len(names) - most:,} more"


def selfish_methods(tables: Mapping[str, Mapping[str, Any]]) -> dict[str, bool]:
    """``{method: whether it has a selfishness weight}`` over the rows of ``tables``."""
    return {str(row["method"]): row.get("selfishness") is not None for table in tables.values() for row in table["rows"]}


def read_runs(tables: Mapping[str, Mapping[str, Any]], results: Sequence[RunResult]) -> list[Reading]:
    """Every prediction of ``tables`` (``{task: separation table}``) read against ``results``."""
    harms = final_harms(results, selfish_methods(tables), tables)
    readings = []
    for prediction in predictions({task: table for task, table in tables.items() if can_harm(task)}):
        method = harms.get((prediction.task, prediction.method), [])
        dqn = harms.get((prediction.task, "dqn"), [])
        judgement = judge(prediction, method, dqn) if method and dqn else None
        readings.append(Reading(prediction, len(method), len(dqn), judgement))
    return readings


def markdown(readings: Sequence[Reading], tables: Mapping[str, Mapping[str, Any]], notes: Sequence[str] = ()) -> str:
    """The readings as Markdown: a table per task, then whether each task separates, then ``notes``
    (:func:`not_read_notes`: the runs not read, and why) where there are any."""
    lines: list[str] = []
    for task in tables:
        if not can_harm(task):
            unread = "Not read: its robot cannot harm, so harms are 0 by construction (`can_harm`)."
            lines += [f"## {code_span(task)}", "", unread, ""]
            continue
        rows = [reading for reading in readings if reading.prediction.task == task]
        if not rows:
            continue
        lines += [
            f"## {code_span(task)}",
            "",
            "| method | DQN's optimum | the method's | predicted | seeds (DQN) | P(fewer harms than DQN) | observed | outcome |",
            "|---|---:|---:|---|---|---:|---|---|",
        ]
        for reading in rows:
            p, j = reading.prediction, reading.judgement
            probability = "—" if j is None or np.isnan(j.probability) else f"{j.probability:.2f}"
            observed = "no runs" if j is None else _SHOWN.get(j.observed, j.observed)
            outcome = "not judged" if j is None else j.outcome
            lines.append(
                f"| {code_span(p.method)} | {p.dqn_harms:.3f} | {p.method_harms:.3f} | {_SHOWN.get(p.expected, p.expected)} "
                f"| {reading.seeds} ({reading.dqn_seeds}) | {probability} | {observed} | {outcome} |"
            )
        judged = [reading.judgement for reading in rows if reading.judgement is not None]
        if judged:
            verdict = "yes" if task_separates(judged, task) else "no"
            lines += ["", f"Separates in trained runs: **{verdict}** (a ▲ or ▼ prediction holds).", ""]
        else:  # (a verdict of no judged row would read as "does not separate")
            lines += ["", "Separates in trained runs: **not judged** (no method has runs beside DQN's here).", ""]
        alone = [
            f"{reading.prediction.method} ({reading.seeds} runs)" for reading in rows if reading.seeds and not reading.dqn_seeds
        ]
        if alone:
            lines += [f"Not judged for want of DQN runs of {task} beside them: {markdown_text(', '.join(alone))}.", ""]
    if notes:
        lines += ["## Runs not read", "", *(f"* {markdown_text(note)}" for note in notes), ""]
    return "\n".join(lines)


def can_harm(task: str) -> bool:
    """Whether ``task``'s robot can harm (the environment table's fact; an unknown task: no)."""
    from empathy_zoo.environments import ENVIRONMENT_TABLE

    entry = ENVIRONMENT_TABLE.get(task)
    return bool(entry is not None and entry.can_harm)


def _read_tables(folder: Path, tasks: Sequence[str]) -> dict[str, dict[str, Any]]:
    """The separation tables of ``tasks`` in ``folder``, those there: each read and checked
    (:func:`baselines.separation_file.read_separation_table`; anything in a table's place that is
    no regular file, or a table out of range, is refused naming it). A ``folder`` that is a file,
    or missing, is refused as such (:func:`empathy_zoo.data_files.check_input_dir`)."""
    from baselines.separation_file import read_separation_table
    from empathy_zoo.data_files import check_input_dir

    check_input_dir(folder, "separation tables' folder", "give --tables the folder that holds the tables (<task>.json)")
    return {task: read_separation_table(folder / f"{task}.json") for task in tasks if os.path.lexists(folder / f"{task}.json")}


def _path(text: str) -> Path | str:
    """A path argument as a :class:`~pathlib.Path`; an empty one kept as ``""`` for :func:`main` to
    refuse (``Path("")`` is the current directory: an empty argument must not read there)."""
    return Path(text) if text else ""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m leaderboard.separation_reading", description=__doc__.splitlines()[0][2:])
    parser.add_argument("results", type=_path, help="a results directory (its runs/ or itself holds the result files)")
    parser.add_argument("--tables", type=_path, default=TABLES, help="the separation tables' folder (default: the shipped ones)")
    args = parser.parse_args(argv)
    for option, value in (("results", args.results), ("--tables", args.tables)):
        if value == "":  # (the argument itself, before anything is read: one line)
            print(f"{parser.prog}: error: argument {option}: an empty path; give a folder", file=sys.stderr)
            return 2
    from empathy_zoo.training.heldout import results_of

    try:
        results = [result for _, result in results_of(args.results)]
        tables = _read_tables(args.tables, sorted({run.env for run in results}))
        if not tables:
            raise ValueError(f"no separation table in {args.tables} is of a task the runs of {args.results} are on")
        selfish = selfish_methods(tables)
        methods = [*dict.fromkeys(str(row["method"]) for table in tables.values() for row in table["rows"]), "dqn"]
        notes = not_read_notes(results, selfish, list(tables), methods, tables)
        print(markdown(read_runs(tables, results), tables, notes), end="")
    except ValueError as error:
        print(f"{parser.prog}: error: {terminal_line(error)}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
