"""# Population-trained runs against default-trained runs on the test split

Reads the evaluations of the populations profile's runs and of the same methods trained beside
the default partner, both on each environment's test split (``<env>_test``), by the rule of
:mod:`leaderboard.population_transfer`: one primary comparison per environment and method, on
the test population and the environment's side effect, judged with Holm's adjustment over all of
them; every other scenario and the task metric as secondary comparisons, reported, not judged.

    python -m leaderboard.population_reading POPULATION_DIR DEFAULT_DIR [DEFAULT_DIR ...]

A run is read from its evaluation file in ``evaluations/<env>_test/``, checked against its result
file (:func:`empathy_zoo.evaluation_file.evaluation_mismatch`). Runs read: DQN, and Empathic DQN
at β = 0.5; in the default directories, only runs of an environment's own variant in its default
world (every environment argument and partner at its default); in the population directory, only
runs beside a population with every environment argument at its default. The runs read of one
environment, method and group must be one experiment's seeds (another setting, world, population
or budget beside them is refused, naming two runs), never a pool of two. A run of a group that has
no evaluation on the test split is named in a note under the tables, and so is every other run of a
directory given that is not read: counted per directory and reason (another method or β, another
world, the other group), and a directory none of whose runs is read. A seed's score is the mean
over its evaluation episodes. Prints Markdown.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from empathy_zoo.environments import DEFAULT_ARGUMENTS
from empathy_zoo.evaluation_record import EvaluationResult
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.markdown_escape import markdown_text
from empathy_zoo.names import terminal_line
from empathy_zoo.result_file import read_folder
from leaderboard.population_transfer import PRIMARY_SCENARIO, Comparison, changes_carry_over, compare
from leaderboard.run_facts import check_one_experiment, in_paper_setting

__all__ = ["METHODS", "Scores", "GroupKey", "primary_and_secondary", "markdown", "read_scores", "main"]

METHODS: dict[str, float | None] = {"dqn": None, "empathic_dqn": 0.5}
"""The methods the reading compares, and the β each is read at (``None``: no selfishness weight);
a run is read at a β only where its selfishness is that number exactly (0.5000001 is not 0.5)."""
POPULATION, DEFAULT = "population", "default"

GroupKey = tuple[str, str, str]
"""``(env, method, group)``: ``group`` is ``population`` or ``default``."""
Scores = dict[GroupKey, dict[tuple[str, str], dict[int, float]]]
"""Per group, per ``(scenario, metric)``, each seed's mean over its episodes."""


@dataclass(frozen=True)
class Row:
    """One comparison of the reading."""

    env: str
    method: str
    scenario: str
    metric: str
    seeds: tuple[int, int]
    """Seeds read: population-trained, default-trained."""
    comparison: Comparison


def _read_at(run: RunResult) -> bool:
    """Whether ``run`` is of a method the reading compares, at its β (the number itself, never a
    rounded text of it: a run at another β is not read, however close)."""
    if run.method not in METHODS:
        return False
    beta = METHODS[run.method]
    selfishness = run.config.settings.get("selfishness")
    if beta is None:
        return True
    return isinstance(selfishness, int | float) and not isinstance(selfishness, bool) and float(selfishness) == beta


def add_scores(scores: Scores, run: RunResult, evaluation: EvaluationResult, group: str) -> None:
    """Add one run's evaluation on its test split to ``scores`` (every played scenario of the set
    and metric); a second evaluation of one seed in a group raises ``ValueError``."""
    key = (run.env, run.method, group)
    played = {entry.name for entry in evaluation.scenario_set.scenarios}
    for entry in evaluation.scenarios:
        if entry.name not in played:
            continue  # (the run's own world, played first)
        for metric, values in entry.metrics.items():
            seeds = scores.setdefault(key, {}).setdefault((entry.name, metric), {})
            if run.seed in seeds:
                raise ValueError(f"two {group}-trained runs of {run.method} on {run.env} with seed {run.seed}")
            seeds[run.seed] = float(np.mean(values))


def primary_and_secondary(scores: Scores) -> tuple[list[Row], list[bool], list[Row]]:
    """The primary comparisons (environments in order, then methods), whether each changes what
    carries over (Holm over all primaries), and the secondary comparisons: every other scenario
    on the side effect, and every scenario on the task metric."""
    from empathy_zoo.environments import ENVIRONMENT_TABLE
    from empathy_zoo.metrics import HIGHER_IS_BETTER

    primaries: list[Row] = []
    secondaries: list[Row] = []
    for env, method in sorted({(env, method) for env, method, _ in scores}):
        population, default = scores.get((env, method, POPULATION)), scores.get((env, method, DEFAULT))
        if population is None or default is None:
            continue
        entry = ENVIRONMENT_TABLE[env]
        side_effect, task = entry.side_effects[0], entry.task
        for scenario, metric in sorted(set(population) & set(default)):
            if metric not in (side_effect, task):
                continue
            x, y = population[(scenario, metric)], default[(scenario, metric)]
            row = Row(
                env,
                method,
                scenario,
                metric,
                (len(x), len(y)),
                compare([x[s] for s in sorted(x)], [y[s] for s in sorted(y)], HIGHER_IS_BETTER[metric]),
            )
            (primaries if (scenario, metric) == (PRIMARY_SCENARIO, side_effect) else secondaries).append(row)
    return primaries, changes_carry_over([row.comparison for row in primaries]) if primaries else [], secondaries


def _cells(row: Row) -> str:
    c = row.comparison
    probability = "—" if np.isnan(c.probability) else f"{c.probability:.2f} [{c.low:.2f}, {c.high:.2f}]"
    where = f"| `{row.env}` | `{row.method}` | `{row.scenario}` | {row.metric} | {row.seeds[0]} ({row.seeds[1]})"
    return f"{where} | {probability} | {c.p:.4f} | {c.observed} |"


def markdown(primaries: Sequence[Row], carries: Sequence[bool], secondaries: Sequence[Row]) -> str:
    """The reading as Markdown: the primary comparisons with their Holm verdicts, then the secondary."""
    header = (
        "| environment | method | scenario | metric | seeds (default) | P(population-trained better) [interval] | p | observed |"
    )
    rule = "|---|---|---|---|---|---:|---:|---|"
    lines = ["## Primary comparisons", "", header + " changes what carries over |", rule + "---|"]
    lines += [_cells(row) + f" {'**yes**' if carry else 'no'} |" for row, carry in zip(primaries, carries, strict=True)]
    lines += ["", "## Secondary comparisons (reported, not judged)", "", header, rule]
    lines += [_cells(row) for row in secondaries]
    return "\n".join(lines) + "\n"


def _in_group(run: RunResult, group: str) -> bool:
    """Whether the reading reads ``run`` in ``group``: a compared method at its β, trained beside a
    population (``population``) or its variant's default world (``default``), every environment
    argument at its default (:func:`leaderboard.run_facts.in_paper_setting`)."""
    return _why_not_read(run, group) is None


def _why_not_read(run: RunResult, group: str) -> tuple[str, list[str]] | None:
    """Why the reading does not read ``run`` of a directory of ``group`` (:func:`_in_group`): the
    reason, said of a run, and what of the run it names (a method, a β, the arguments and partners
    outside the default world); ``None`` for a run it reads."""
    if run.method not in METHODS:
        return f"of a method other than {' and '.join(METHODS)}", [run.method]
    if not _read_at(run):
        selfishness = run.config.settings.get("selfishness")
        return f"of {run.method} at a β other than {METHODS[run.method]}", [repr(selfishness)]
    if _population_trained(run) != (group == POPULATION):
        if group == POPULATION:
            return "trained beside no population (the first directory's runs are read as population-trained only)", []
        return "trained beside a population (population-trained runs are read from the first directory only)", []
    defaults = DEFAULT_ARGUMENTS.get(run.env)
    if group == DEFAULT:
        if defaults is None:
            return "of an environment the suite does not ship", [run.env]
        if (run.variant or run.env) == run.env and in_paper_setting(run):
            return None
        return "trained outside the default world", _outside_default_world(run, defaults)
    arguments = _other_arguments(run, defaults or {})
    return None if not arguments else ("trained beside a population outside the default world", arguments)


def _other_arguments(run: RunResult, defaults: Mapping[str, Any]) -> list[str]:
    """Each environment argument of ``run`` not at its default (``name value``)."""
    return [f"{name} {value}" for name, value in run.config.env_kwargs.items() if name not in defaults or defaults[name] != value]


def _outside_default_world(run: RunResult, defaults: Mapping[str, Any]) -> list[str]:
    """What of ``run``'s world is not its environment's default world: its variant, each argument
    and each fixed agent's policy that differs from the default's."""
    from empathy_zoo.environments import DEFAULT_POLICIES

    differs = [] if (run.variant or run.env) == run.env else [f"variant {run.variant}"]
    differs += _other_arguments(run, defaults)
    partners, fixed = DEFAULT_POLICIES.get(run.env, {}), dict(run.config.fixed)
    differs += [
        f"{agent} {fixed.get(agent, 'none')}" for agent in sorted({*partners, *fixed}) if fixed.get(agent) != partners.get(agent)
    ]
    return differs


def _not_read_notes(
    unread: Mapping[tuple[str, str], list[list[str]]], read_in: Mapping[str, int], totals: Mapping[str, int]
) -> list[str]:
    """One note per directory and reason some of its runs are not read (``unread``: per
    ``(directory, reason)``, what each such run names), giving their count (``all``: every run of
    the directory, of its ``totals``) and what they name; and one per directory none of whose runs
    is read (``read_in``: runs read per directory) for no one reason, so that no run of a directory
    given is left out without a word."""
    notes = []
    for (directory, why), named in unread.items():
        names = sorted({name for names in named for name in names})
        shown = ", ".join(names[:10]) + (f" and {len(names) - 10:,} more" if len(names) > 10 else "")
        count, every = len(named), len(named) == totals[directory]
        runs = f"all {count} runs of {directory}" if every else f"{count} run{'s' if count > 1 else ''} of {directory}"
        if every and count == 1:
            runs = f"1 run of {directory} (its only run)"
        notes.append(f"{runs} {why}" + (f" ({shown})" if shown else "") + ": not read")
    for directory, total in totals.items():
        one_reason = any(where == directory and len(named) == total for (where, _), named in unread.items())
        if not read_in.get(directory) and not one_reason:
            notes.append(
                f"none of the {total} runs of {directory} is read" if total > 1 else f"the 1 run of {directory} is not read"
            )
    return notes


def read_scores(population_dir: Path, default_dirs: Sequence[Path], notes: list[str] | None = None) -> Scores:
    """The scores of every run read (see the module page) from their test-split evaluations; each
    run of a group read that has no evaluation on the test split is named in ``notes``, where given,
    and every other run of the directories not read is counted there, per directory and reason.

    Raises ``ValueError``, naming the files, where a directory is given twice, the population
    directory holds no population-trained run of a compared method, a test split was evaluated
    with another definition than the shipped one (``empathy_zoo/scenarios/<env>_test.toml``) or of
    an environment that ships no test split, two evaluations give one group one seed twice, or the
    runs of one group are of two experiments (naming two runs)."""
    from empathy_zoo.evaluation_file import evaluation_files, evaluation_mismatch, read_evaluation
    from empathy_zoo.scenarios import scenario_set_path
    from empathy_zoo.training.heldout import results_of

    _check_distinct(population_dir, default_dirs)
    scores: Scores = {}
    shipped: dict[str, dict[str, Any]] = {}
    """Each test split's shipped definition, as an evaluation file records one."""
    read_from: dict[tuple[str, str, str, int], Path] = {}
    """The evaluation file each group's seed was read from."""
    candidates: dict[GroupKey, list[RunResult]] = {}
    """Every run each group would read, evaluated or not."""
    read: dict[GroupKey, list[RunResult]] = {}
    unread: dict[tuple[str, str], list[list[str]]] = {}
    """Per directory and reason, what each run it does not read names (:func:`_why_not_read`)."""
    read_in: dict[str, int] = {}
    """How many runs of each directory are read."""
    totals: dict[str, int] = {}
    for directory, group in [(population_dir, POPULATION), *((d, DEFAULT) for d in default_dirs)]:
        runs: Mapping[str, RunResult] = {run.run_id: run for _, run in results_of(directory)}
        totals[str(directory)] = len(runs)
        for candidate in runs.values():
            why = _why_not_read(candidate, group)
            if why is None:
                candidates.setdefault((candidate.env, candidate.method, group), []).append(candidate)
            else:
                unread.setdefault((str(directory), why[0]), []).append(why[1])
        for path in evaluation_files(directory):
            evaluation = read_evaluation(path)
            name = evaluation.scenario_set.name
            if name != f"{evaluation.env}_test":
                continue
            if name not in shipped:
                shipped[name] = _shipped_test_split(path, name, evaluation.env)
            if evaluation.scenario_set.to_document() != shipped[name]:
                raise ValueError(
                    f"{path} was made with another definition of scenario set {name!r} than the shipped one "
                    f"({scenario_set_path(name)}): move it away and run empathy-zoo evaluate again"
                )
            run = runs.get(evaluation.run_id)
            if run is None:
                raise ValueError(f"{path}: its run {evaluation.run_id} has no result file in {directory}")
            mismatch = evaluation_mismatch(evaluation, run)
            if mismatch is not None:
                raise ValueError(f"{path}: not an evaluation of run {run.run_id} ({mismatch})")
            if not _in_group(run, group):
                continue
            seed = (group, run.env, run.method, run.seed)
            if seed in read_from:
                raise ValueError(
                    f"{read_from[seed]} and {path}: two {group}-trained runs of {run.method} on {run.env} "
                    f"with seed {run.seed}; move one away"
                )
            read_from[seed] = path
            read.setdefault((run.env, run.method, group), []).append(run)
            read_in[str(directory)] = read_in.get(str(directory), 0) + 1
            add_scores(scores, run, evaluation, group)
    check_one_experiment({f"the {g}-trained runs of {method} on {env}": members for (env, method, g), members in read.items()})
    for key, members in read.items():
        evaluated = {id(member) for member in members}
        for candidate in candidates.get(key, []):
            if id(candidate) not in evaluated and notes is not None:
                notes.append(
                    f"run {candidate.run_id} ({key[2]}-trained {key[1]} on {key[0]}, seed {candidate.seed}) has no evaluation "
                    f"on {key[0]}_test, so its group counts {len(members)} of its {len(candidates[key])} runs "
                    f"(empathy-zoo evaluate --scenarios {key[0]}_test writes it)"
                )
    for key, members in candidates.items():
        if key not in read and notes is not None:  # (a group none of whose runs was evaluated: named, never dropped in silence)
            notes.append(
                f"no run of the {len(members)} {key[2]}-trained runs of {key[1]} on {key[0]} has an evaluation on "
                f"{key[0]}_test, so that group is not read and {key[1]} has no comparison that needs it "
                f"(empathy-zoo evaluate --scenarios {key[0]}_test writes them)"
            )
    if notes is not None:
        notes += _not_read_notes(unread, read_in, totals)
    if not any(group == POPULATION for (group, *_rest) in read_from):
        raise ValueError(
            f"{population_dir} holds no population-trained run of {' or '.join(METHODS)} evaluated on a test split "
            "(a run whose partner is a population: empathy-zoo reproduce --profile populations, then evaluate)"
        )
    return scores


def _shipped_test_split(path: Path, name: str, env: str) -> dict[str, Any]:
    """The shipped definition of test split ``name`` (of ``env``, named by the evaluation file
    ``path``); ``ValueError`` naming ``path`` where none ships (a plug-in environment's, say)."""
    from empathy_zoo.scenarios import load_scenario_set, shipped_sets

    sets = shipped_sets()
    if name not in sets:
        having = ", ".join(s.removesuffix("_test") for s in sets if s.endswith("_test")) or "none"
        raise ValueError(
            f"{path}: field scenario_set.name: {name!r}, but environment {env!r} ships no test split "
            f"(empathy_zoo/scenarios/{name}.toml); population-reading reads only the shipped test splits, "
            f"of the environments {having}"
        )
    return load_scenario_set(name).definition()


def _population_trained(run: RunResult) -> bool:
    """Whether a partner of ``run`` was a population (its label ``population(...)``)."""
    return any(str(label).startswith("population(") for label in run.config.fixed.values())


def _check_distinct(population_dir: Path, default_dirs: Sequence[Path]) -> None:
    """Refuse (``ValueError``) a directory given twice: its runs would be compared with themselves."""
    seen: dict[Path, Path] = {}
    for directory in (population_dir, *default_dirs):
        where = read_folder(directory)  # (DIR and DIR/runs are one directory)
        if where in seen:
            raise ValueError(f"{directory} is given twice (as {seen[where]} too): its runs would be compared with themselves")
        seen[where] = Path(directory)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m leaderboard.population_reading", description=__doc__.splitlines()[0][2:])
    parser.add_argument("population", type=Path, help="the populations profile's results directory, evaluated on <env>_test")
    parser.add_argument("default", type=Path, nargs="+", help="results directories of the methods beside the default partner")
    args = parser.parse_args(argv)
    try:
        notes: list[str] = []
        primaries, carries, secondaries = primary_and_secondary(read_scores(args.population, args.default, notes))
        if not primaries:
            unread = "".join(f"; {note}" for note in notes)
            raise ValueError(
                f"no environment and method has runs of both groups evaluated on its test split (<env>_test){unread}"
            )
        print(markdown(primaries, carries, secondaries), end="")
        if notes:
            print("\n" + "\n\n".join(f"Note: {markdown_text(note)}" for note in notes))
    except ValueError as error:
        print(f"{parser.prog}: error: {terminal_line(error)}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
