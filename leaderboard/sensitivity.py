"""C5's conditions: the Sharing claims judged separately under each of the env's fidelity options.

The paper's Sharing differs from the authors' code in ways SPEC resolved one way (start cells,
how an agent's inventory is drawn, the human's policy). A sensitivity sweep
(``empathy_zoo/profiles/sharing_sensitivity.toml``) trains Empathic DQN at every β under every
combination; :func:`sensitivity_markdown` tables the robot/human battery split and equality per
condition and β, with the verdicts of "fewer batteries as β falls" and "equality peaks at β =
0.5" in each, by the same rules as REPRODUCTION.md (:mod:`leaderboard.verdicts`).

:func:`fair_split_rows` asks whether equality is set by the robot's mean take: per condition,
phase and β, the mean take, how far the takes lie from the fair split episode by episode, and
the mean equality (the β closest to a fair mean take need not be the most equal: equality is a
mean over episodes, so the spread of the per-episode takes counts too).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from empathy_zoo.atomic import write_text_atomic
from empathy_zoo.environments import DEFAULT_ARGUMENTS, DEFAULT_POLICIES
from empathy_zoo.experiment.records import RunResult
from leaderboard.aggregate import final_episode_count, run_scalars
from leaderboard.reproduction import load_checked_results
from leaderboard.run_facts import check_one_experiment, empathic_selfishness
from leaderboard.verdicts import RULES, Cell, cell_of, falls, peaks

__all__ = [
    "Condition",
    "condition_of",
    "sensitivity_rows",
    "FairSplit",
    "fair_split_rows",
    "fair_split_summary",
    "sensitivity_markdown",
    "write_sensitivity",
]

REPORT_TITLE = "# Sharing under its fidelity options"
"""The report's first line (a file that does not begin so is no report: ``--out`` never replaces it)."""
BETAS = (1.0, 0.75, 0.5, 0.25)
PHASES = {"greedy": "eval", "training": "train_final10"}
SHARING = "sharing_v0"
Condition = tuple[str, str, str]
"""(start cells, inventory encoding, human policy)."""
DEFAULT_CONDITION: Condition = (
    DEFAULT_ARGUMENTS[SHARING]["start"],
    DEFAULT_ARGUMENTS[SHARING]["inventory_encoding"],
    DEFAULT_POLICIES[SHARING]["human_0"],
)
"""Sharing's defaults (the paper's setting)."""


def condition_of(run: RunResult) -> Condition:
    """The fidelity condition a Sharing run was trained under (its env's default where it sets none)."""
    kwargs = run.config.env_kwargs
    human = run.config.fixed.get("human_0", DEFAULT_CONDITION[2])
    start, encoding = (
        str(kwargs.get(name, default))
        for name, default in zip(("start", "inventory_encoding"), DEFAULT_CONDITION[:2], strict=True)
    )
    return start, encoding, str(human)


def _empathic_sharing_runs(results: Sequence[RunResult]) -> dict[Condition, dict[float, list[RunResult]]]:
    """``{condition: {β: runs}}`` of the Sharing runs that learn Empathic DQN's target
    (:func:`leaderboard.run_facts.empathic_selfishness`)."""
    groups: dict[Condition, dict[float, list[RunResult]]] = {}
    for run in results:
        beta = empathic_selfishness(run) if run.env == SHARING else None
        if beta is None:
            continue
        others = {agent: policy for agent, policy in run.config.fixed.items() if agent != "human_0"}
        paper_others = {agent: policy for agent, policy in DEFAULT_POLICIES[SHARING].items() if agent != "human_0"}
        if others != paper_others or not _defaults_but_conditions(run):
            raise ValueError(
                f"run {run.run_id} sets what no condition varies (env_kwargs {dict(run.config.env_kwargs)}, "
                f"fixed {dict(run.config.fixed)}): a condition is a start, an inventory encoding and a human policy, "
                "the rest at its default"
            )
        groups.setdefault(condition_of(run), {}).setdefault(beta, []).append(run)
    for condition, cells in groups.items():
        check_one_experiment({f"β={beta:g} under {_condition_text(condition)}": runs for beta, runs in cells.items()})
    return groups


def _defaults_but_conditions(run: RunResult) -> bool:
    """Whether every environment argument of ``run`` but the conditions' is at its default."""
    defaults = DEFAULT_ARGUMENTS[SHARING]
    return all(
        name in ("start", "inventory_encoding") or (name in defaults and defaults[name] == value)
        for name, value in run.config.env_kwargs.items()
    )


def _condition_text(condition: Condition) -> str:
    start, encoding, human = condition
    marks = [f"start `{start}`", f"inventory `{encoding}`", f"human `{human}`"]
    return ", ".join(marks) + (" (the defaults)" if condition == DEFAULT_CONDITION else "")


def sensitivity_rows(results: Sequence[RunResult]) -> dict[Condition, dict[str, dict[str, dict[float, Cell]]]]:
    """``{condition: {phase: {metric: {β: cell}}}}`` over the Empathic DQN runs of Sharing."""
    groups = _empathic_sharing_runs(results)
    rows: dict[Condition, dict[str, dict[str, dict[float, Cell]]]] = {}
    for condition in sorted(groups, key=lambda c: (c != DEFAULT_CONDITION, c)):
        by_beta = groups[condition]
        rows[condition] = {
            name: {
                metric: {
                    beta: cell_of([run_scalars(r, (metric,))[phase][metric] for r in runs], metric)
                    for beta, runs in sorted(by_beta.items(), reverse=True)
                }
                for metric in ("batteries", "other_batteries", "equality")
            }
            for name, phase in PHASES.items()
        }
    return rows


@dataclass(frozen=True)
class FairSplit:
    """One β's battery split in one condition and phase (each run's mean over its episodes, then
    the mean over runs)."""

    take: float
    """The robot's batteries per episode."""
    fair: float
    """Half of robot + human batteries per episode (the fair take; 4.5 when all 9 are collected)."""
    distance: float
    """How far the robot's take lies from the fair split, episode by episode: mean |robot − human| / 2."""
    equality: float
    """Mean equality per episode (SPEC §5)."""
    all_collected: float
    """Fraction of the episodes in which robot + human collected all 9 batteries."""


def _episodes(run: RunResult, phase: str) -> dict[str, np.ndarray]:
    """The episodes a phase scores (:func:`leaderboard.aggregate.run_scalars`'s): the final 10 %
    of training episodes, or the last greedy evaluation."""
    metrics = ("batteries", "other_batteries", "equality")
    if phase == "eval":
        source = run.last_eval
        return {m: np.asarray(() if source is None else source.metrics[m], dtype=np.float64) for m in metrics}
    columns = {m: np.asarray(run.train.metrics[m], dtype=np.float64) for m in metrics}
    return {m: c[len(c) - final_episode_count(len(c)) :] for m, c in columns.items()}


def fair_split_rows(results: Sequence[RunResult]) -> dict[Condition, dict[str, dict[float, FairSplit]]]:
    """``{condition: {phase: {β: FairSplit}}}`` over the Empathic DQN runs of Sharing."""
    groups = _empathic_sharing_runs(results)
    rows: dict[Condition, dict[str, dict[float, FairSplit]]] = {}
    for condition in sorted(groups, key=lambda c: (c != DEFAULT_CONDITION, c)):
        rows[condition] = {}
        for name, phase in PHASES.items():
            table: dict[float, FairSplit] = {}
            for beta, runs in sorted(groups[condition].items(), reverse=True):
                per_run = []
                for run in runs:
                    e = _episodes(run, phase)
                    robot, human = e["batteries"], e["other_batteries"]
                    if not len(robot) or len(robot) != len(human):
                        continue
                    per_run.append(
                        (
                            robot.mean(),
                            ((robot + human) / 2).mean(),
                            (np.abs(robot - human) / 2).mean(),
                            np.nanmean(e["equality"]) if len(e["equality"]) else np.nan,
                            np.isclose(robot + human, 9).mean(),
                        )
                    )
                if per_run:
                    table[beta] = FairSplit(*(float(np.mean(column)) for column in zip(*per_run, strict=True)))
            rows[condition][name] = table
    return rows


def fair_split_summary(table: dict[float, FairSplit]) -> tuple[float, float, float]:
    """``(β whose mean take is closest to its fair split, β whose takes lie closest to it episode
    by episode, most equal β)`` of one condition and phase."""
    closest_mean = min(table, key=lambda b: abs(table[b].take - table[b].fair))
    closest_episodes = min(table, key=lambda b: table[b].distance)
    most_equal = max(table, key=lambda b: table[b].equality)
    return closest_mean, closest_episodes, most_equal


def _fair_split_markdown(results: Sequence[RunResult]) -> list[str]:
    rows = fair_split_rows(results)
    lines = [
        "### Is equality set by the robot's mean take?",
        "",
        "Robot + human collect all 9 batteries in nearly every episode, so an episode's equality is set by how far "
        "the robot's take in it lies from the fair split (half of what both collected: 4.5). A β's equality is the "
        "mean over its episodes, so the spread of its per-episode takes counts as well as its mean take. Per "
        "condition and phase: the β whose mean take is closest to the fair split (its mean take), the β whose "
        "takes lie closest to it episode by episode (mean |robot − human| / 2), and the most equal β (its equality); "
        "computed by `leaderboard.sensitivity.fair_split_rows` from the same episodes as the tables above.",
        "",
        "| condition | phase | closest mean take | closest episode by episode | most equal "
        "| episodes with all 9 collected (fewest over β) |",
        "|---|---|---|---|---|---|",
    ]
    counts = {name: [0, 0, 0] for name in PHASES}  # conditions, mean take ≠ most equal, per episode ≠ most equal
    for condition, phases in rows.items():
        for name, table in phases.items():
            if not table:
                continue
            closest_mean, closest_episodes, most_equal = fair_split_summary(table)
            counts[name][0] += 1
            counts[name][1] += closest_mean != most_equal
            counts[name][2] += closest_episodes != most_equal
            collected = min(t.all_collected for t in table.values())
            lines.append(
                f"| {_condition_text(condition)} | {name} | β = {closest_mean:g} ({table[closest_mean].take:.2f}) | "
                f"β = {closest_episodes:g} ({table[closest_episodes].distance:.2f}) | "
                f"β = {most_equal:g} ({table[most_equal].equality:.3f}) | {100 * collected:.1f} % |"
            )
    lines.append("")
    summary = "; ".join(
        f"{name}: in {c[1]} of {c[0]} conditions the β whose mean take is closest to the fair split is not the most "
        f"equal, and in {c[2]} of {c[0]} the β closest episode by episode is not"
        for name, c in counts.items()
        if c[0]
    )
    lines += [summary[0].upper() + summary[1:] + ".", ""]
    return lines


def _word(ok: bool | None) -> str:
    return "—" if ok is None else ("reproduced" if ok else "not reproduced")


def sensitivity_markdown(results: Sequence[RunResult], command: str, least_conditions: int = 1) -> str:
    """The sensitivity section: one table per phase, a row per condition and β. Results of fewer
    than ``least_conditions`` conditions raise ``ValueError`` (REPRODUCTION.md asks for two: one
    condition compares nothing)."""
    rows = sensitivity_rows(results)
    if not rows:
        raise ValueError("no Empathic DQN runs of sharing_v0 in these results")
    if len(rows) < least_conditions:
        raise ValueError(
            f"these results hold {len(rows)} fidelity condition(s) of sharing_v0 "
            f"({'; '.join(_condition_text(condition) for condition in rows)}), not the {least_conditions} or more a "
            "sensitivity sweep compares (profile sharing_sensitivity trains 8)"
        )
    lines = [
        "## When does C5 hold? Sharing under the fidelity options",
        "",
        "Empathic DQN on Sharing under every combination of the env's fidelity options (docs/SPEC.md §3; "
        "the env's docstring), judged by REPRODUCTION.md's rules (`leaderboard/verdicts.py`), produced by:",
        "",
        f"    {command}",
        "",
    ]
    for name in PHASES:
        where = "last greedy evaluation" if name == "greedy" else "final 10 % of training episodes"
        lines += [
            f"### {name} ({where})",
            "",
            "| condition | β | robot batteries | human batteries | equality "
            "| fewer batteries as β falls | equality peaks at β = 0.5 |",
            "|---|---|---|---|---|---|---|",
        ]
        for condition, phases in rows.items():
            table = phases[name]
            betas = [b for b in BETAS if b in table["equality"]]
            complete = betas == list(BETAS)
            fewer = falls([table["batteries"][b] for b in BETAS]) if complete else None
            peak = peaks(*(table["equality"][b] for b in (0.75, 0.5, 0.25))) if complete else None
            for i, beta in enumerate(betas):
                verdicts = (_word(fewer), _word(peak)) if i == 0 else ("", "")
                lines.append(
                    f"| {_condition_text(condition) if i == 0 else ''} | {beta:g} | {table['batteries'][beta]} | "
                    f"{table['other_batteries'][beta]} | {table['equality'][beta]} | {verdicts[0]} | {verdicts[1]} |"
                )
        lines.append("")
    lines += _fair_split_markdown(results)
    return "\n".join(lines)


def write_sensitivity(
    results_dir: str | os.PathLike[str],
    out_path: str | os.PathLike[str] | None = None,
    command: str = "empathy-zoo reproduce --profile sharing_sensitivity",
    note: str = "",
) -> Path:
    """Write the sensitivity section as a file of its own (``<results_dir>/SENSITIVITY.md``), with
    the rules it applies."""
    text = "\n".join(
        [
            REPORT_TITLE,
            "",
            *([note, ""] if note else []),
            RULES,
            "",
            sensitivity_markdown(load_checked_results(results_dir), command),
        ]
    )
    path = Path(out_path) if out_path else Path(results_dir) / "SENSITIVITY.md"
    return write_text_atomic(path, text)
