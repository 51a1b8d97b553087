"""REPRODUCTION.md: the paper's claims (SPEC §7), each checked against a sweep's results.

Each claim is a rule over the leaderboard's numbers (per-method means over seeds with 95 %
bootstrap intervals, from :mod:`leaderboard.aggregate`), so the verdicts are recomputed from the
result files, never typed by hand. "Reproduced" needs the direction the paper reports *and* a
margin the seeds support (intervals that do not overlap where a difference is claimed).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from empathy_zoo.atomic import write_text_atomic
from leaderboard.aggregate import bootstrap_mean_ci, load_results, run_scalars, table_env

__all__ = ["Claim", "assess_claims", "reproduction_markdown", "write_reproduction"]

BETAS = (1.0, 0.75, 0.5, 0.25)
PRIMARY = "train_final10"
"""Phase the verdicts use: the final 10 % of training episodes (the paper's figures are training
curves, and they hold far more episodes than an evaluation); greedy evaluations are shown beside."""
HARM_FREE = 0.05
"""Harms per episode at or below which a method counts as not harming."""
SURVIVES = 450
"""Steps survived (of 500) from which a method counts as surviving."""


@dataclass(frozen=True)
class Claim:
    """One claim of the paper and what the results say about it."""

    env: str
    text: str
    verdict: str
    """``reproduced``, ``not reproduced`` or ``not testable`` (missing methods)."""
    evidence: str
    """The numbers behind the verdict (Markdown)."""


@dataclass(frozen=True)
class _Cell:
    mean: float
    low: float
    high: float
    n: int

    def __str__(self) -> str:
        return f"{self.mean:.2f} [{self.low:.2f}, {self.high:.2f}]"


def _cells(results: Sequence[dict[str, Any]], env: str, phase: str, metric: str) -> dict[str, _Cell]:
    """Per method key (``β=<value>`` for Empathic DQN / DQN, else the method name): one cell."""
    groups: dict[str, list[float]] = {}
    for run in results:
        if table_env(run) != env:
            continue
        settings = run["config"].get("settings", {})
        if run["method"] in ("empathic_dqn", "dqn"):
            key = f"β={float(settings.get('selfishness', 1.0)):g}"
        else:
            key = run["method"]
        groups.setdefault(key, []).append(run_scalars(run, (metric,))[phase][metric])
    cells = {}
    for key, values in groups.items():
        mean, low, high = bootstrap_mean_ci(np.array(values))
        cells[key] = _Cell(float(mean), float(low), float(high), len(values))
    return cells


def _training_mean(results: Sequence[dict[str, Any]], env: str, metric: str) -> dict[str, _Cell]:
    """Mean of a metric over *all* training episodes (area under the learning curve)."""
    groups: dict[str, list[float]] = {}
    for run in results:
        if table_env(run) != env or run["method"] not in ("empathic_dqn", "dqn"):
            continue
        beta = float(run["config"]["settings"].get("selfishness", 1.0))
        column = np.asarray(run["train"][metric], dtype=float)
        groups.setdefault(f"β={beta:g}", []).append(float(column.mean()) if column.size else float("nan"))
    out = {}
    for key, values in groups.items():
        mean, low, high = bootstrap_mean_ci(np.array(values))
        out[key] = _Cell(float(mean), float(low), float(high), len(values))
    return out


def _row(cells: dict[str, _Cell], keys: Sequence[str]) -> str:
    return "; ".join(f"{k}: {cells[k]}" for k in keys if k in cells)


def _falls_with_beta(cells: dict[str, _Cell]) -> tuple[bool, str]:
    keys = [f"β={b:g}" for b in BETAS if f"β={b:g}" in cells]
    if len(keys) < 2:
        return False, "needs at least two β values"
    first, last = cells[keys[0]], cells[keys[-1]]
    monotone = all(cells[b].mean <= cells[a].high for a, b in zip(keys, keys[1:]))
    separated = last.high < first.low
    return monotone and separated, _row(cells, keys)


def assess_claims(results: Sequence[dict[str, Any]], coexistence: str = "coexistence_v0",
                  sharing: str = "sharing_v0") -> list[Claim]:
    """Check every claim of SPEC §7 that the results can speak to."""
    claims: list[Claim] = []
    envs = {table_env(r) for r in results}

    def add(env: str, text: str, ok: bool | None, evidence: str) -> None:
        verdict = "not testable" if ok is None else ("reproduced" if ok else "not reproduced")
        claims.append(Claim(env, text, verdict, evidence))

    if coexistence in envs:
        harms = _cells(results, coexistence, PRIMARY, "harms")
        harms_eval = _cells(results, coexistence, "eval", "harms")
        ok, row = _falls_with_beta(harms)
        add(coexistence, "Harms to the cat fall as β falls.", ok,
            f"harms/episode, final 10 % of training: {row}. Greedy evaluation: "
            f"{_row(harms_eval, [f'β={b:g}' for b in BETAS])}.")
        survival_final = _cells(results, coexistence, "train_final10", "survival")
        survival_all = _training_mean(results, coexistence, "survival")
        keys = [f"β={b:g}" for b in BETAS]
        if "β=1" in survival_all and "β=0.25" in survival_all:
            slower = survival_all["β=0.25"].high < survival_all["β=1"].low
            worse = survival_final["β=0.25"].mean < survival_final["β=1"].mean
            add(coexistence, "Lower β survives worse and learns more slowly.", slower and worse,
                f"mean steps survived over all training episodes (area under the learning curve): "
                f"{_row(survival_all, keys)}. Final 10 % of training: {_row(survival_final, keys)}.")
        survival_eval = _cells(results, coexistence, "eval", "survival")
        caring = [k for k in ("β=0.5", "β=0.25") if k in harms]
        if caring:
            ok = all(harms[k].mean <= HARM_FREE and survival_final[k].mean >= SURVIVES for k in caring)
            add(coexistence, "The less selfish agents eventually survive without harming the cat.", ok,
                f"final 10 % of training, harms/episode (≤ {HARM_FREE} counts as harm-free): {_row(harms, caring)}; "
                f"steps survived (≥ {SURVIVES} of 500 counts as surviving): {_row(survival_final, caring)}. "
                f"Greedy evaluation: harms {_row(harms_eval, caring)}; survival {_row(survival_eval, caring)}.")
        if "dqn_harm_penalty" in harms and "β=1" in harms:
            ok = harms["dqn_harm_penalty"].mean <= HARM_FREE and harms["dqn_harm_penalty"].high < harms["β=1"].low
            pair = ["dqn_harm_penalty", "β=1"]
            add(coexistence, "The −100 harm-penalty baseline harms little.", ok,
                f"harms/episode, final 10 % of training: {_row(harms, pair)}; steps survived: "
                f"{_row(survival_final, pair)}. Greedy evaluation: harms {_row(harms_eval, pair)}.")
    if sharing in envs:
        batteries = _cells(results, sharing, PRIMARY, "batteries")
        ok, row = _falls_with_beta(batteries)
        add(sharing, "The robot collects fewer batteries as β falls.", ok,
            f"robot batteries/episode, final 10 % of training: {row}. Greedy evaluation: "
            f"{_row(_cells(results, sharing, 'eval', 'batteries'), [f'β={b:g}' for b in BETAS])}.")
        eq = _cells(results, sharing, PRIMARY, "equality")
        eq_eval = _cells(results, sharing, "eval", "equality")
        betas = [f"β={b:g}" for b in BETAS if f"β={b:g}" in eq]
        if betas:
            best = max(betas, key=lambda k: eq[k].mean)
            add(sharing, "Equality peaks at β = 0.5.", best == "β=0.5",
                f"equality, final 10 % of training: {_row(eq, betas)} (highest: {best}). Greedy evaluation: "
                f"{_row(eq_eval, betas)}.")
        if "dqn_equality" in eq and "β=1" in eq:
            pair = ["dqn_equality", "β=1"]
            ok = eq["dqn_equality"].low > eq["β=1"].high
            add(sharing, "The equality-shaped baseline is fair (more equal than DQN).", ok,
                f"equality, final 10 % of training: {_row(eq, pair)}; robot batteries: {_row(batteries, pair)}. "
                f"Greedy evaluation: equality {_row(eq_eval, pair)}.")
    return claims


def reproduction_markdown(claims: Sequence[Claim], command: str, results_dir: str, note: str = "") -> str:
    """The report, one section per claim."""
    lines = [
        "# Reproduction report",
        "",
        f"Claims of *Towards Empathic Deep Q-Learning* (SPEC §7), checked against the result files in "
        f"`{results_dir}`, produced by:",
        "",
        f"    {command}",
        "",
        "and checked by `empathy-zoo reproduction " + results_dir + "` (this file is generated; every number is "
        "a mean over seeds with its 95 % bootstrap interval, as in the leaderboard). Verdicts use the final "
        "10 % of training episodes, as the paper's figures are training curves; greedy evaluations are shown "
        "beside. A claim is *reproduced* when the direction matches and the intervals separate where a "
        "difference is claimed.",
        "",
    ]
    if note:
        lines += [note, ""]
    lines += ["| environment | claim | verdict |", "|---|---|---|"]
    lines += [f"| {c.env} | {c.text} | **{c.verdict}** |" for c in claims]
    lines.append("")
    for c in claims:
        lines += [f"## {c.text} ({c.env}) — {c.verdict}", "", c.evidence, ""]
    return "\n".join(lines)


def write_reproduction(results_dir: str | os.PathLike[str], out_path: str | os.PathLike[str] | None = None,
                       command: str = "empathy-zoo reproduce --profile paper", note: str = "") -> Path:
    """Assess the claims on ``results_dir`` and write the report (``<results_dir>/REPRODUCTION.md``)."""
    results = load_results(results_dir)
    claims = assess_claims(results)
    path = Path(out_path) if out_path else Path(results_dir) / "REPRODUCTION.md"
    write_text_atomic(path, reproduction_markdown(claims, command, str(results_dir), note))
    return path
