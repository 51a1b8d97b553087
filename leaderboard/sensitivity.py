"""C5's conditions: the Sharing claims judged separately under each of the env's fidelity options.

The paper's Sharing differs from the authors' code in ways SPEC resolved one way (start cells,
how an agent's inventory is drawn, the human's policy). A sensitivity sweep
(``empathy_zoo/profiles/sharing_sensitivity.toml``) trains Empathic DQN at every β under every
combination; :func:`sensitivity_markdown` tables the robot/human battery split and equality per
condition and β, with the verdicts of "fewer batteries as β falls" and "equality peaks at β =
0.5" in each, by the same rules as REPRODUCTION.md (:mod:`leaderboard.verdicts`).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from empathy_zoo.atomic import write_text_atomic

from leaderboard.aggregate import load_results, run_scalars
from leaderboard.verdicts import RULES, Cell, cell_of, falls, peaks

__all__ = ["Condition", "condition_of", "sensitivity_rows", "sensitivity_markdown", "write_sensitivity"]

BETAS = (1.0, 0.75, 0.5, 0.25)
PHASES = {"greedy": "eval", "training": "train_final10"}
Condition = tuple[str, str, str]
"""(start cells, inventory encoding, human policy)."""
DEFAULT_CONDITION: Condition = ("random", "count_plus_one", "patrol")


def condition_of(run: dict[str, Any]) -> Condition:
    """The fidelity condition a Sharing run was trained under."""
    config = run.get("config", {})
    kwargs = config.get("env_kwargs") or {}
    human = (config.get("fixed") or {}).get("human_0", "patrol")
    return (str(kwargs.get("start", "random")), str(kwargs.get("inventory_encoding", "count_plus_one")), str(human))


def _condition_text(condition: Condition) -> str:
    start, encoding, human = condition
    marks = [f"start `{start}`", f"inventory `{encoding}`", f"human `{human}`"]
    return ", ".join(marks) + (" (the defaults)" if condition == DEFAULT_CONDITION else "")


def sensitivity_rows(results: Sequence[dict[str, Any]]) -> dict[Condition, dict[str, dict[str, dict[float, Cell]]]]:
    """``{condition: {phase: {metric: {β: cell}}}}`` over the Empathic DQN runs of Sharing."""
    groups: dict[Condition, dict[float, list[dict[str, Any]]]] = {}
    for run in results:
        if run["env"] != "sharing_v0" or run["method"] not in ("empathic_dqn", "dqn"):
            continue
        beta = float(run["config"]["settings"].get("selfishness", 1.0))
        groups.setdefault(condition_of(run), {}).setdefault(beta, []).append(run)
    rows: dict[Condition, dict[str, dict[str, dict[float, Cell]]]] = {}
    for condition in sorted(groups, key=lambda c: (c != DEFAULT_CONDITION, c)):
        by_beta = groups[condition]
        rows[condition] = {
            name: {
                metric: {beta: cell_of([run_scalars(r, (metric,))[phase][metric] for r in runs])
                         for beta, runs in sorted(by_beta.items(), reverse=True)}
                for metric in ("batteries", "other_batteries", "equality")
            }
            for name, phase in PHASES.items()
        }
    return rows


def _word(ok: bool | None) -> str:
    return "—" if ok is None else ("reproduced" if ok else "not reproduced")


def sensitivity_markdown(results: Sequence[dict[str, Any]], command: str) -> str:
    """The sensitivity section: one table per phase, a row per condition and β."""
    rows = sensitivity_rows(results)
    if not rows:
        raise ValueError("no Empathic DQN runs of sharing_v0 in these results")
    lines = [
        "## When does C5 hold? Sharing under the fidelity options", "",
        "Empathic DQN on Sharing under every combination of the env's fidelity options (docs/SPEC.md §3; "
        "the env's docstring), judged by REPRODUCTION.md's rules (`leaderboard/verdicts.py`), produced by:", "",
        f"    {command}", "",
    ]
    for name in PHASES:
        where = "last greedy evaluation" if name == "greedy" else "final 10 % of training"
        lines += [f"### {name} ({where})", "",
                  "| condition | β | robot batteries | human batteries | equality | fewer batteries as β falls | equality peaks at β = 0.5 |",
                  "|---|---|---|---|---|---|---|"]
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
    return "\n".join(lines)


def write_sensitivity(results_dir: str | os.PathLike[str], out_path: str | os.PathLike[str] | None = None,
                      command: str = "empathy-zoo reproduce --profile sharing_sensitivity", note: str = "") -> Path:
    """Write the sensitivity section as a file of its own (``<results_dir>/SENSITIVITY.md``), with
    the rules it applies."""
    text = "\n".join(["# Sharing under its fidelity options", "", *([note, ""] if note else []), RULES, "",
                      sensitivity_markdown(load_results(results_dir), command)])
    path = Path(out_path) if out_path else Path(results_dir) / "SENSITIVITY.md"
    return write_text_atomic(path, text)
