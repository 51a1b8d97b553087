"""REPRODUCTION.md: the paper's claims (SPEC §7), each judged on a sweep's results by the rules
of :mod:`leaderboard.verdicts`, on greedy evaluations and on the final 10 % of training.

Only a sweep that contains the paper's experiments (both environments with their default
arguments and fixed agents; Empathic DQN at β = 1, 0.75, 0.5, 0.25; the −100 penalty and the
equality-scaled baselines) gets paper verdicts; for any other sweep :func:`write_reproduction`
refuses with :class:`NotThePaperSweep`, naming what is missing. Runs of other variants in the
same directory (a sensitivity study, a user's own method) are left out of the verdicts.
"""

from __future__ import annotations

import inspect
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from empathy_zoo.atomic import write_text_atomic
from empathy_zoo.environments import DEFAULT_POLICIES, ENGINES
from empathy_zoo.schedules import linear_epsilon
from leaderboard.aggregate import final_episode_count, load_results, run_scalars
from leaderboard.verdicts import RULES, Cell, below, cell_of, falls, matches_reference, peaks

__all__ = [
    "Claim", "Verdict", "PHASES", "BETAS", "NotThePaperSweep", "paper_runs", "missing_paper_experiments",
    "assess_claims", "reproduction_markdown", "write_reproduction", "training_window_epsilons",
]

BETAS = (1.0, 0.75, 0.5, 0.25)
PHASES = {"greedy": "eval", "training": "train_final10"}
"""Verdict phase → the leaderboard phase it reads."""
COEXISTENCE, SHARING = "coexistence_v0", "sharing_v0"
EMPATHIC = ("empathic_dqn", "dqn")
PENALTY, EQUALITY_SHAPED = "dqn_harm_penalty", "dqn_equality"
_DEFAULT_MAX_CYCLES = inspect.signature(ENGINES[COEXISTENCE]).parameters["max_cycles"].default
Reference = Callable[..., Any]
"""``coexistence_optimum(selfishness, epsilon, *, gamma, max_cycles)`` → ``.harms``, ``.survival``."""


class NotThePaperSweep(ValueError):
    """The results do not contain the paper's experiments, so there is no paper verdict to give."""


@dataclass(frozen=True)
class Verdict:
    """One phase's verdict on a claim."""

    ok: bool | None
    """``None``: not testable (no finite numbers in this phase)."""
    evidence: str

    @property
    def word(self) -> str:
        return "not testable" if self.ok is None else ("reproduced" if self.ok else "not reproduced")


@dataclass(frozen=True)
class Claim:
    """A claim and its verdict in each phase."""

    env: str
    text: str
    verdicts: Mapping[str, Verdict]
    """Keyed by phase name (``greedy``, ``training``)."""
    papers: bool = True
    """``False`` for the suite's own questions (not claimed by the paper)."""


def _key(run: dict[str, Any]) -> str:
    if run["method"] in EMPATHIC:
        return f"β={float(run['config']['settings'].get('selfishness', 1.0)):g}"
    return str(run["method"])


def _is_paper_setting(run: dict[str, Any]) -> bool:
    """The run's env is one of the paper's with every argument at its default and the default fixed agents."""
    if run["env"] not in (COEXISTENCE, SHARING):
        return False
    config = run.get("config", {})
    defaults = inspect.signature(ENGINES[run["env"]]).parameters
    arguments = dict(config.get("env_kwargs") or {})
    return (all(name in defaults and defaults[name].default == value for name, value in arguments.items())
            and dict(config.get("fixed") or {}) == DEFAULT_POLICIES[run["env"]])


def paper_runs(results: Sequence[dict[str, Any]]) -> dict[str, dict[str, list[dict[str, Any]]]]:
    """``{env: {method key: runs}}`` of the runs made in the paper's setting."""
    out: dict[str, dict[str, list[dict[str, Any]]]] = {COEXISTENCE: {}, SHARING: {}}
    for run in results:
        if _is_paper_setting(run):
            out[run["env"]].setdefault(_key(run), []).append(run)
    return out


def missing_paper_experiments(results: Sequence[dict[str, Any]]) -> list[str]:
    """The paper's experiments that ``results`` lack (empty: the paper's sweep is there)."""
    runs = paper_runs(results)
    needed = {env: [f"β={b:g}" for b in BETAS] + [baseline]
              for env, baseline in ((COEXISTENCE, PENALTY), (SHARING, EQUALITY_SHAPED))}
    return [f"{env} {key}" for env, keys in needed.items() for key in keys if key not in runs[env]]


def training_window_epsilons(run: dict[str, Any], digits: int = 3) -> dict[float, int]:
    """The ε schedule over the env steps of a run's final 10 % of training episodes, as
    ``{ε rounded to digits: steps}`` (its settings' schedule, read before each step)."""

    ends = run["train"]["episode_end_step"]
    if not ends:
        return {}
    first = len(ends) - final_episode_count(len(ends))
    start = int(ends[first - 1]) if first > 0 else 0
    settings = SimpleNamespace(**run["config"]["settings"])
    counts: dict[float, int] = {}
    for step in range(start, int(ends[-1])):
        epsilon = round(linear_epsilon(settings, step), digits)
        counts[epsilon] = counts.get(epsilon, 0) + 1
    return counts


def _reference_over(reference: Reference, selfishness: float, epsilons: Mapping[float, int], gamma: float,
                    max_cycles: int) -> tuple[float, float]:
    """The reference's harms and survival averaged over an ε schedule (weights: steps at each ε)."""
    total = sum(epsilons.values())
    harms = survival = 0.0
    for epsilon, steps in epsilons.items():
        outcome = reference(selfishness, epsilon, gamma=gamma, max_cycles=max_cycles)
        harms += outcome.harms * steps / total
        survival += outcome.survival * steps / total
    return harms, survival


def _curve_mean(run: dict[str, Any], phase: str, metric: str) -> float:
    """Mean over the whole learning curve: every training episode, or every greedy evaluation."""
    if phase == "eval":
        values = [float(np.mean(e[metric])) for e in run["eval"] if len(e[metric])]
    else:
        values = [float(v) for v in run["train"][metric]]
    return float(np.mean(values)) if values else float("nan")


class _Table:
    """Cells of the paper's runs of one env, per phase, metric and method key."""

    def __init__(self, runs: Mapping[str, list[dict[str, Any]]]) -> None:
        self.runs = runs

    def cell(self, phase: str, metric: str, key: str) -> Cell:
        return cell_of([run_scalars(run, (metric,))[phase][metric] for run in self.runs[key]])

    def curve(self, phase: str, metric: str, key: str) -> Cell:
        return cell_of([_curve_mean(run, phase, metric) for run in self.runs[key]])

    def row(self, phase: str, metric: str, keys: Sequence[str], curve: bool = False) -> list[Cell]:
        return [(self.curve if curve else self.cell)(phase, metric, k) for k in keys]


def _line(keys: Sequence[str], cells: Sequence[Cell]) -> str:
    return "; ".join(f"{k}: {c}" for k, c in zip(keys, cells))


def _verdict(ok: bool, cells: Sequence[Cell], evidence: str) -> Verdict:
    return Verdict(ok if all(c.finite for c in cells) else None, evidence)


def assess_claims(results: Sequence[dict[str, Any]], reference: Reference | None = None) -> list[Claim]:
    """Judge every claim of SPEC §7 (and the suite's own questions) on the paper's runs in
    ``results``; raises :class:`NotThePaperSweep` when an experiment of the paper is missing."""
    missing = missing_paper_experiments(results)
    if missing:
        raise NotThePaperSweep(f"these results do not contain the paper's experiments (missing: {', '.join(missing)})")
    if reference is None:
        from empathy_zoo.reference import coexistence_optimum as reference
    runs = paper_runs(results)
    betas = [f"β={b:g}" for b in BETAS]
    coexistence, sharing = _Table(runs[COEXISTENCE]), _Table(runs[SHARING])
    claims: dict[tuple[str, str, bool], dict[str, Verdict]] = {}

    def judge(env: str, text: str, phase_name: str, verdict: Verdict, papers: bool = True) -> None:
        claims.setdefault((env, text, papers), {})[phase_name] = verdict

    for name, phase in PHASES.items():
        harms = coexistence.row(phase, "harms", betas)
        judge(COEXISTENCE, "Harms to the cat fall as β falls.", name,
              _verdict(falls(harms), harms, f"harms/episode: {_line(betas, harms)}."))

        survival = coexistence.row(phase, "survival", betas)
        area = coexistence.row(phase, "survival", betas, curve=True)
        slower = below(area[-1], area[0])
        judge(COEXISTENCE, "Lower β survives worse and learns more slowly.", name, _verdict(
            falls(survival) and slower, survival + area,
            f"steps survived: {_line(betas, survival)} (falls: {'yes' if falls(survival) else 'no'}). "
            f"Mean over the whole learning curve: {_line(betas, area)} (β=0.25 below β=1: {'yes' if slower else 'no'}).",
        ))

        caring = ["β=0.5", "β=0.25"]
        parts, ok, cells = [], True, []
        for key in caring:
            h, s = coexistence.cell(phase, "harms", key), coexistence.cell(phase, "survival", key)
            group = runs[COEXISTENCE][key]
            epsilons: dict[float, int] = {0.0: 1}
            if phase != "eval":
                epsilons = {}
                for run in group:
                    for epsilon, steps in training_window_epsilons(run).items():
                        epsilons[epsilon] = epsilons.get(epsilon, 0) + steps
            settings = group[0]["config"]["settings"]
            max_cycles = int(group[0]["config"]["env_kwargs"].get("max_cycles", _DEFAULT_MAX_CYCLES))
            ref_harms, ref_survival = _reference_over(
                reference, float(settings["selfishness"]), epsilons, float(settings["gamma"]), max_cycles)
            ok = ok and matches_reference(h, s, ref_harms, ref_survival, max_cycles)
            cells += [h, s]
            mean_epsilon = sum(e * n for e, n in epsilons.items()) / max(sum(epsilons.values()), 1)
            parts.append(f"{key}: harms {h} (reference {ref_harms:.3f}), survival {s} (reference {ref_survival:.1f}), "
                         f"mean ε {mean_epsilon:.4f}")
        judge(COEXISTENCE, "The less selfish agents (β = 0.5, 0.25) eventually survive without harming the cat.",
              name, _verdict(ok, cells, "; ".join(parts) + "."))

        pair = [PENALTY, "β=1"]
        penalty = coexistence.row(phase, "harms", pair)
        judge(COEXISTENCE, "The −100 harm-penalty baseline harms the cat less than DQN.", name,
              _verdict(below(penalty[0], penalty[1]), penalty, f"harms/episode: {_line(pair, penalty)}."))

        batteries = sharing.row(phase, "batteries", betas)
        judge(SHARING, "The robot collects fewer batteries as β falls.", name,
              _verdict(falls(batteries), batteries, f"robot batteries/episode: {_line(betas, batteries)}."))

        equality = sharing.row(phase, "equality", betas)
        human = sharing.row(phase, "other_batteries", betas)
        judge(SHARING, "Equality peaks at β = 0.5.", name, _verdict(
            peaks(equality[1], equality[2], equality[3]), equality,
            f"equality: {_line(betas, equality)}; human batteries/episode: {_line(betas, human)}.",
        ))

        pair = ["β=1", EQUALITY_SHAPED]
        fair = sharing.row(phase, "equality", pair)
        judge(SHARING, "The equality-scaled DQN baseline is more equal than DQN.", name,
              _verdict(below(fair[0], fair[1]), fair, f"equality: {_line(pair, fair)}."), papers=False)
    return [Claim(env, text, verdicts, papers) for (env, text, papers), verdicts in claims.items()]


def reproduction_markdown(claims: Sequence[Claim], command: str, results_dir: str, note: str = "",
                          appendix: str = "") -> str:
    """The report: how it was made, the rules, a verdict table, then the evidence per claim."""
    lines = [
        "# Reproduction report", "",
        f"Claims of *Towards Empathic Deep Q-Learning* (SPEC §7), judged on the result files in "
        f"`{results_dir}`, produced by:", "", f"    {command}", "",
        f"and checked by `empathy-zoo reproduction {results_dir}` (this file is generated from the result files).", "",
    ]
    if note:
        lines += [note, ""]
    lines += [RULES, "", "| environment | claim | greedy | training |", "|---|---|---|---|"]
    for papers, heading in ((True, None), (False, "The suite's own questions (not claims of the paper)")):
        chosen = [c for c in claims if c.papers == papers]
        if heading and chosen:
            lines += [f"| | *{heading}* | | |"]
        lines += [f"| {c.env} | {c.text} | **{c.verdicts['greedy'].word}** | **{c.verdicts['training'].word}** |"
                  for c in chosen]
    lines.append("")
    for c in claims:
        lines += [f"## {c.text} ({c.env}){'' if c.papers else ' — the suite’s own question'}", ""]
        for phase, verdict in c.verdicts.items():
            where = "last greedy evaluation" if phase == "greedy" else "final 10 % of training"
            lines += [f"* **{phase}** ({where}) — {verdict.word}: {verdict.evidence}"]
        lines.append("")
    if appendix:
        lines += [appendix, ""]
    return "\n".join(lines)


def write_reproduction(results_dir: str | os.PathLike[str], out_path: str | os.PathLike[str] | None = None,
                       command: str = "empathy-zoo reproduce --profile paper", note: str = "",
                       appendix: str = "", reference: Reference | None = None) -> Path:
    """Judge the claims on ``results_dir`` and write the report (``<results_dir>/REPRODUCTION.md``);
    raises :class:`NotThePaperSweep` (writing nothing) when the paper's experiments are not there."""
    claims = assess_claims(load_results(results_dir), reference)
    path = Path(out_path) if out_path else Path(results_dir) / "REPRODUCTION.md"
    write_text_atomic(path, reproduction_markdown(claims, command, str(results_dir), note, appendix))
    return path

