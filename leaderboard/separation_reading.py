"""# Trained runs against the exact separation tables

Reads a results directory (the scenarios profile's, or any with runs on a task that has an exact
separation table) by the rule of :mod:`leaderboard.trained_separation`: every prediction the
tables make, judged on the per-seed harms of each run's final greedy evaluation against DQN's.

    python -m leaderboard.separation_reading RESULTS [--tables docs/results/separation]

Runs are matched to a prediction by task (the run's environment, its own variant only: a
variant is another world), method and, for a method with a selfishness weight, β = 0.5
(:data:`~leaderboard.trained_separation.BETA`). A prediction with no runs of its method or of
DQN is listed as such, never judged. The rule reads harms, so a task whose robot cannot harm
(the environment table's ``can_harm``: Sharing) is listed as not read. Prints Markdown: per task, every judgement, then whether
the task separates in trained runs.
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
from leaderboard.run_facts import in_paper_setting
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
    "Reading",
    "can_harm",
    "final_harms",
    "markdown",
    "not_read_notes",
    "read_runs",
    "selfish_methods",
    "why_not_read",
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


def final_harms(results: Sequence[RunResult], selfish_methods: Mapping[str, bool]) -> dict[tuple[str, str], list[float]]:
    """``{(task, method): per-seed harms}``: each run's mean harms per episode over its final greedy
    evaluation, in seed order, for runs of a task's own variant in its default world (the world
    the exact tables model: every environment argument and partner at its default); a method
    ``selfish_methods`` marks ``True`` is read at β = :data:`~leaderboard.trained_separation.BETA`
    only. A task with two runs of one method and seed, or runs of one method from two experiments
    (another label, setting or budget), raises ``ValueError`` naming them."""
    found: dict[tuple[str, str], dict[int, float]] = {}
    experiments: dict[tuple[str, str], RunResult] = {}
    for run in results:
        if why_not_read(run, selfish_methods) is not None:
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


def why_not_read(run: RunResult, selfish_methods: Mapping[str, bool]) -> str | None:
    """The key of :data:`NOT_READ` that keeps ``run`` out of :func:`final_harms`, else ``None``."""
    if (run.variant or run.env) != run.env:
        return "variant"
    if not in_paper_setting(run):
        return "world"
    if not run.eval:
        return "evaluation"
    if selfish_methods.get(run.method, False):
        beta = run.config.settings.get("selfishness")
        if beta is None or not at_beta(beta):  # (the number itself: 0.5000001 is not 0.5)
            return "beta"
    return None


def not_read_notes(
    results: Sequence[RunResult], selfish_methods: Mapping[str, bool], tasks: Sequence[str], methods: Sequence[str]
) -> list[str]:
    """One line per reason some runs of ``results`` are not read against the tables of ``tasks``
    (naming ``methods``): its count and why (:data:`NOT_READ`, an environment no table models, a
    method no table has a row of), so that no run is left out without a word."""
    counts: dict[str, int] = {}
    names: dict[str, set[str]] = {}
    for run in results:
        if run.env not in tasks:
            why, name = "of an environment no table models", run.env
        elif run.method not in methods:
            why, name = "of a method no table has a row of", run.method
        else:
            key = why_not_read(run, selfish_methods)
            if key is None:
                continue
            why, name = NOT_READ[key], ""
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
    harms = final_harms(results, selfish_methods(tables))
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
        notes = not_read_notes(results, selfish, list(tables), methods)
        print(markdown(read_runs(tables, results), tables, notes), end="")
    except ValueError as error:
        print(f"{parser.prog}: error: {terminal_line(error)}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
