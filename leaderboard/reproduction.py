"""REPRODUCTION.md: the paper's claims (SPEC §7), each judged on a sweep's results by the rules
of :mod:`leaderboard.verdicts`, on greedy evaluations and on the final 10 % of training.

Only a sweep that contains the paper's experiments (both environments with their default
arguments and fixed agents; Empathic DQN at β = 1, 0.75, 0.5, 0.25; the −100 harm-penalty and the
equality-scaled DQN) gets paper verdicts; for any other sweep :func:`write_reproduction`
refuses with :class:`NotThePaperSweep`, naming what is missing. Runs of other variants in the
same directory (a sensitivity study, a user's own method) are left out of the verdicts. Which runs
are Empathic DQN at which β, and with which γ and ε schedule, their result files' descriptions say
(:mod:`leaderboard.run_facts`): a plug-in method that declares Empathic DQN's target is judged
with it; the penalty and equality-scaled runs are those of the paper sweep's methods :data:`PENALTY` and
:data:`EQUALITY_SHAPED`.

Beside the harm-free/surviving verdict, which is judged against the exact optimum with evenly
broken ties, the evidence states what the rule's reference leaves out: the share of the steps
that the final 10 % of training episodes are (:func:`training_window_share`), the optimum's range
over every tie-break (:func:`tie_break_range`), and the learners' survival across the training
phase beside the optimum's at the ε of the same episodes, which separates learning from the ε
schedule (:func:`survival_rise`).

Three claims are judged by :mod:`leaderboard.claim_rules`, not by the rules they were judged by
before, and the report shows the old verdict beside the new one where it differs
(:attr:`Verdict.old`; :func:`claim_verdicts_markdown` lists both for every claim, and ``python -m
leaderboard.reproduction DIR`` prints that list without writing anything):

* C3 (β = 0.5, 0.25 eventually survive without harming) on intervals
  (:func:`leaderboard.claim_rules.reference_reading`): undecided where an interval straddles the
  reference's threshold, where the old rule read the means alone.
* C4 (the harm penalty harms less than DQN) and C7 (the equality-scaled DQN is more equal than
  DQN) by the leaderboard's exact permutation test (:func:`leaderboard.claim_rules.less_than`),
  where the old rule asked for non-overlapping 95 % intervals. Why this test rather than keeping
  non-overlap and naming it the stricter rule: it is the test behind every ▲ / ▼ of the
  leaderboard, so the report cannot call "not reproduced" what the leaderboard marks ▲ for the
  same rows; its size is exactly at most 5 % with no assumption of normal data, where non-overlap
  holds about a tenth of that and so misses real but modest differences (the measured rates are
  in :data:`leaderboard.verdicts.BELOW_NOTE`).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from empathy_zoo.atomic import write_text_atomic
from empathy_zoo.environments import DEFAULT_ARGUMENTS
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.result_file import result_checker
from leaderboard.aggregate import final_episode_count, load_result_files, longest_episode, run_scalars
from leaderboard.claim_rules import less_than, reference_reading
from leaderboard.run_facts import (
    check_one_experiment,
    description_of,
    empathic_selfishness,
    env_argument,
    exploration_of,
    in_paper_setting,
)
from leaderboard.verdicts import RULES, Cell, below, cell_of, falls, matches_reference, peaks

__all__ = [
    "Claim",
    "Verdict",
    "PHASES",
    "BETAS",
    "NotThePaperSweep",
    "paper_runs",
    "missing_paper_experiments",
    "assess_claims",
    "coexistence_claims",
    "method_key",
    "reproduction_markdown",
    "claim_verdicts_markdown",
    "CLAIM_RULES",
    "write_reproduction",
    "training_window_epsilons",
    "training_window_share",
    "check_run_steps",
    "load_checked_results",
    "TieRange",
    "tie_break_range",
    "SurvivalRise",
    "survival_rise",
]

REPORT_TITLE = "# Reproduction report"
"""The report's first line (a file that does not begin so is no report: ``--out`` never replaces it)."""
BETAS = (1.0, 0.75, 0.5, 0.25)
PHASES = {"greedy": "eval", "training": "train_final10"}
"""Verdict phase → the leaderboard phase it reads."""
COEXISTENCE, SHARING = "coexistence_v0", "sharing_v0"
PENALTY, EQUALITY_SHAPED = "dqn_harm_penalty", "dqn_equality"
"""The paper sweep's baseline methods (``empathy_zoo/profiles/paper.toml``), by the name its runs record."""
_DEFAULT_MAX_CYCLES: int = DEFAULT_ARGUMENTS[COEXISTENCE]["max_cycles"]
Reference = Callable[..., Any]
"""``coexistence_optimum(selfishness, epsilon, *, gamma, max_cycles)`` → ``.harms``, ``.survival``."""
TieRangeOf = Callable[..., "TieRange"]
"""``tie_break_range(selfishness, epsilons, *, gamma, max_cycles)`` → :class:`TieRange`."""


class NotThePaperSweep(ValueError):
    """The results do not contain the paper's experiments, so there is no paper verdict to give."""


CLAIM_RULES = """\
**Rules changed since earlier reports** (`leaderboard/claim_rules.py`, tested in `tests/test_claim_rules.py`;
where a verdict differs from the old rule's, the table says so):

* *Harm-free and surviving* (C3) is judged on intervals: reproduced when the harms interval lies
  wholly at or under the reference's + the tolerance and the survival interval wholly at or above
  the reference's − the tolerance; not reproduced when either lies wholly beyond; **undecided**
  when an interval straddles its threshold (the old rule read the means).
* *A less than B* (C4, C7) is the leaderboard's exact two-sided permutation test at 5 % (the ▲ of
  its P(improves on DQN) tables), not separated intervals (the old rule, about ten times stricter
  than its 5 %)."""
"""The text of the changed rules, printed after :data:`leaderboard.verdicts.RULES`."""


@dataclass(frozen=True)
class Verdict:
    """One phase's verdict on a claim."""

    ok: bool | None
    """``None``: not testable (no finite numbers in this phase), or undecided."""
    evidence: str
    undecided: bool = False
    """The numbers are there but their intervals straddle the rule's threshold."""
    old: Verdict | None = None
    """The verdict of the rule this claim was judged by before; ``None`` where the rule is unchanged."""

    @property
    def word(self) -> str:
        if self.undecided:
            return "undecided"
        return "not testable" if self.ok is None else ("reproduced" if self.ok else "not reproduced")

    @property
    def old_word(self) -> str:
        """The old rule's word (the same as :attr:`word` where the rule is unchanged)."""
        return (self.old or self).word


@dataclass(frozen=True)
class Claim:
    """A claim and its verdict in each phase."""

    env: str
    text: str
    verdicts: Mapping[str, Verdict]
    """Keyed by phase name (``greedy``, ``training``)."""
    papers: bool = True
    """``False`` for the suite's own questions (not claimed by the paper)."""


def method_key(run: RunResult) -> str:
    """``β=…`` for a run of Empathic DQN's target (:func:`leaderboard.run_facts.empathic_selfishness`),
    else the method's name."""
    beta = empathic_selfishness(run)
    return run.method if beta is None else f"β={beta:g}"


def paper_runs(results: Sequence[RunResult]) -> dict[str, dict[str, list[RunResult]]]:
    """``{env: {method key: runs}}`` of the runs made in the paper's setting
    (:func:`leaderboard.run_facts.in_paper_setting`); a cell the claims read (Empathic DQN at each of
    :data:`BETAS`, the two shaped baselines) of two experiments raises ``ValueError`` naming them."""
    out: dict[str, dict[str, list[RunResult]]] = {COEXISTENCE: {}, SHARING: {}}
    for run in results:
        if run.env in out and in_paper_setting(run):
            out[run.env].setdefault(method_key(run), []).append(run)
    judged = {f"β={beta:g}" for beta in BETAS} | {PENALTY, EQUALITY_SHAPED}
    for env, cells in out.items():  # (one experiment a cell the claims read: two would be pooled into one claim)
        check_one_experiment({f"the paper's {key} in {env}": runs for key, runs in cells.items() if key in judged})
    return out


def missing_paper_experiments(results: Sequence[RunResult]) -> list[str]:
    """The paper's experiments that ``results`` lack (empty: the paper's sweep is there)."""
    runs = paper_runs(results)
    needed = {
        env: [f"β={b:g}" for b in BETAS] + [baseline] for env, baseline in ((COEXISTENCE, PENALTY), (SHARING, EQUALITY_SHAPED))
    }
    return [f"{env} {key}" for env, keys in needed.items() for key in keys if key not in runs[env]]


def check_run_steps(run: RunResult, where: str | os.PathLike[str] | None = None) -> None:
    """Refuse a run whose steps the report cannot read as its environment makes them: a ``ValueError``
    naming ``where`` (its file; by default the run's id) and the field when a training episode is
    longer than its environment's ``max_cycles`` (``train.episode_end_step``: no episode of the
    suite's lasts longer), or when the ε schedule its description records (if any) has a start or
    an end outside 0–1 or a warm-up or decay that is no finite number."""
    check = result_checker(Path(where if where is not None else f"run {run.run_id or '?'}"))
    cycles = int(env_argument(run, "max_cycles"))
    ends = np.asarray(run.train.episode_end_step, dtype=np.int64)
    lengths = np.diff(ends, prepend=0)
    longest = int(lengths.argmax()) if lengths.size else 0
    if lengths.size and lengths[longest] > cycles:
        before = int(ends[longest - 1]) if longest else 0
        raise check.fail(
            f"train.episode_end_step[{longest}]",
            f"the end of an episode of at most the environment's max_cycles ({cycles:,}) steps after step {before:,}",
            int(ends[longest]),
        )
    schedule = run.config.description.get("exploration")
    if schedule is None:
        return
    for name in ("start", "end", "warmup", "decay_steps"):
        value = schedule.get(name) if isinstance(schedule, Mapping) else None
        probability = name in ("start", "end")
        if isinstance(value, int | float) and not isinstance(value, bool):
            finite = not isinstance(value, float) or math.isfinite(value)  # (an int of any size is compared as an int)
            if finite and (not probability or 0 <= value <= 1):
                continue
        expected = "an ε between 0 and 1" if probability else "a finite number"
        raise check.fail(f"config.description.exploration.{name}", expected, value)


def load_checked_results(results_dir: str | os.PathLike[str]) -> list[RunResult]:
    """:func:`leaderboard.aggregate.load_results`, every run also checked by :func:`check_run_steps`
    (a ``ValueError`` naming the first file refused): what the report reads, checked before
    anything is judged or written."""
    read = load_result_files(results_dir)
    for path, run in read:
        check_run_steps(run, path)
    return [run for _, run in read]


def training_window_epsilons(run: RunResult, digits: int = 3) -> dict[float, int]:
    """The ε schedule over the env steps of a run's final 10 % of training episodes, as
    ``{ε rounded to digits: steps}`` (the schedule its description records, read before each step).

    Counted in closed form, not step by step: the schedule is constant during its warm-up and
    monotone after it, so each rounded ε holds over one run of steps on either side, whose end is
    found by bisection; the work grows with the number of distinct values (at most about
    ``10 ** digits``), not with the steps (up to :data:`~empathy_zoo.limits.MAX_STEPS`). The
    counts are exactly those of reading the schedule at every step. A run refused by
    :func:`check_run_steps` is a ``ValueError`` naming it."""

    ends = run.train.episode_end_step
    if not ends.size:
        return {}
    check_run_steps(run)
    first = len(ends) - final_episode_count(len(ends))
    start = int(ends[first - 1]) if first > 0 else 0
    epsilon_at = exploration_of(run)  # (a ValueError naming the run where it records no schedule)
    schedule = description_of(run)["exploration"]
    if schedule["kind"] != "linear":  # pragma: no cover - the only kind there is (schedules.SCHEDULE_KINDS)
        raise ValueError(f"no closed form of the ε schedule of kind {schedule['kind']!r}")

    def rounded(step: int) -> float:
        return round(epsilon_at(step), digits)

    counts: dict[float, int] = {}
    warm_end = min(max(start, math.ceil(schedule["warmup"])), int(ends[-1]))  # (steps before it: s < warmup)
    for low, high in ((start, warm_end), (warm_end, int(ends[-1]))):
        for epsilon, steps in _runs_of_monotone(rounded, low, high):
            counts[epsilon] = counts.get(epsilon, 0) + steps
    return counts


def _runs_of_monotone(value: Callable[[int], float], low: int, high: int) -> list[tuple[float, int]]:
    """``[(v, steps)]``: the runs of equal values of ``value`` over the steps ``low`` … ``high - 1``,
    in order, for a ``value`` monotone there (each value then holds over one run of steps, whose
    end is found by bisection)."""
    runs: list[tuple[float, int]] = []
    step = low
    while step < high:
        current = value(step)
        after, beyond = step + 1, high  # (the run's end lies in [after, beyond])
        while after < beyond:
            middle = (after + beyond) // 2
            if value(middle) == current:
                after = middle + 1
            else:
                beyond = middle
        runs.append((current, after - step))
        step = after
    return runs


def training_window_share(run: RunResult) -> float:
    """The fraction of a run's env steps that its final 10 % of training episodes take up (not
    10 % in general: it depends on the lengths of the episodes); NaN for a run without episodes."""
    ends = run.train.episode_end_step
    if not ends.size or not ends[-1]:
        return float("nan")
    return sum(training_window_epsilons(run).values()) / float(ends[-1])


@dataclass(frozen=True)
class TieRange:
    """The exact optimum's figures, lowest and highest over every choice among its tied actions."""

    harms: tuple[float, float]
    survival: tuple[float, float]


def _tie_bound(
    tied: np.ndarray, epsilons: np.ndarray, weights: np.ndarray, metric: str, highest: bool, max_cycles: int, size: int
) -> float:
    """The lowest (or highest) expectation of ``metric`` per episode over every policy that, with
    probability 1 − ε, takes one of the actions marked in ``tied`` (``(size², 5)``; any choice
    among them, even a different one at every step), averaged over ``epsilons`` with ``weights``:
    a finite-horizon dynamic programme over the steps still to go (docs/reference.md's script,
    with the cat's uniform action averaged into a transition matrix once)."""
    from empathy_zoo.engine.coexistence import CAT_HARMS_ROBOT, NO_HARM, ROBOT_HARMS_CAT
    from empathy_zoo.reference import coexistence_transitions, start_distribution

    outcome, after = coexistence_transitions(size)
    cells, actions, cat_actions = outcome.shape
    kept = np.zeros((cells, actions, cells))  # P(no harm and this next displacement | displacement, action)
    d, a, _ = np.nonzero(outcome == NO_HARM)
    np.add.at(kept, (d, a, after[outcome == NO_HARM]), 1.0 / cat_actions)
    stays = kept.reshape(cells * actions, cells).T
    cat_gone = (outcome == ROBOT_HARMS_CAT).mean(axis=2)
    robot_harmed = (outcome == CAT_HARMS_ROBOT).mean(axis=2)
    sign = 1.0 if highest else -1.0
    eps = epsilons[:, None]
    togo_value = np.zeros((len(epsilons), cells))  # the metric's expectation over the steps still to go
    for togo in range(max_cycles):
        # einsum, not @: for arrays this small BLAS's threads cost more than they save
        following = np.einsum("ec,ck->ek", togo_value, stays).reshape(len(epsilons), cells, actions)
        if metric == "harms":  # noqa: SIM108 - two formulas, the second explained beside it
            per_action = cat_gone + following
        else:  # survival: 1 per step operative; with the cat gone, every step still to go as well
            per_action = (1.0 - robot_harmed) + cat_gone * togo + following
        chosen = sign * np.where(tied, sign * per_action, -np.inf).max(axis=2)
        togo_value = eps * per_action.mean(axis=2) + (1.0 - eps) * chosen
    return float(weights @ (togo_value @ start_distribution(size)))


def tie_break_range(
    selfishness: float,
    epsilons: Mapping[float, int],
    *,
    gamma: float = 0.99,
    max_cycles: int = _DEFAULT_MAX_CYCLES,
    size: int = 7,
) -> TieRange:
    """The range of the exact optimum's harms and survival per episode over every tie-break.

    ``coexistence_optimum`` takes exactly tied actions with equal probability (``ties="uniform"``,
    the verdicts' rule) or the lowest index (``ties="first"``); a learner breaks such ties its own
    way, so a figure is a property of the tie rule, not of the optimum (docs/reference.md, "Read
    them with the tie rule"). Each bound is computed separately, at every ε of ``epsilons``
    (``{ε: steps}``, as :func:`training_window_epsilons` gives), and averaged with those weights.
    """
    from empathy_zoo.reference import TIE_TOLERANCE, coexistence_values

    if not epsilons:
        raise ValueError("tie_break_range needs at least one ε")
    cells = size * size
    q_emp = coexistence_values(float(selfishness), gamma=float(gamma), size=size)[1][:cells]
    tied = q_emp >= q_emp.max(axis=1, keepdims=True) - TIE_TOLERANCE
    values = np.asarray(list(epsilons), dtype=np.float64)
    weights = np.asarray(list(epsilons.values()), dtype=np.float64)
    weights = weights / weights.sum()

    def bound(metric: str, highest: bool) -> float:
        return _tie_bound(tied, values, weights, metric, highest, int(max_cycles), size)

    return TieRange((bound("harms", False), bound("harms", True)), (bound("survival", False), bound("survival", True)))


@dataclass(frozen=True)
class SurvivalRise:
    """How a group's survival changed across its training phase, beside what the reference's
    survival does at the ε of the same episodes (the ε schedule alone)."""

    learner: tuple[float, float]
    """Mean survival over the first and the second half of the final 10 % of training episodes
    (each run's mean, then the mean over runs)."""
    reference: tuple[float, float]
    """The reference's expected survival at the ε of the same episodes, averaged the same way."""
    widened: int
    """Runs whose gap to the reference (reference − learner) is larger in the second half."""
    runs: int

    @property
    def gap(self) -> tuple[float, float]:
        return self.reference[0] - self.learner[0], self.reference[1] - self.learner[1]


def survival_rise(
    runs: Sequence[RunResult], reference: Reference, *, gamma: float, max_cycles: int, digits: int = 3
) -> SurvivalRise:
    """Separate learning from the ε schedule over the training phase: each run's final 10 % of
    training episodes is split into halves (by episode), and the mean survival of each half is
    set beside the reference's at the ε of the same episodes (the schedule's ε at each episode's
    first step, rounded to ``digits``). The reference's rise is what ε's decay alone gives an
    unchanging policy; a learner that is still learning closes its gap to it."""
    cache: dict[tuple[float, float], float] = {}

    def optimum(selfishness: float, epsilon: float) -> float:
        key = (selfishness, epsilon)
        if key not in cache:
            cache[key] = float(reference(selfishness, epsilon, gamma=gamma, max_cycles=max_cycles).survival)
        return cache[key]

    learner: list[np.ndarray] = []  # per run: mean survival of each half
    optimal: list[np.ndarray] = []  # per run: the reference's at the ε of the same episodes
    for run in runs:
        ends = [int(e) for e in run.train.episode_end_step]
        survival = np.asarray(run.train.metrics["survival"], dtype=np.float64)
        final = final_episode_count(len(ends))
        if final < 2:
            continue
        first = len(ends) - final
        epsilon_at = exploration_of(run)
        selfishness = float(description_of(run)["selfishness"])
        starts = [ends[i - 1] if i > 0 else 0 for i in range(first, len(ends))]
        expected = np.array([optimum(selfishness, round(epsilon_at(step), digits)) for step in starts])
        middle = final // 2
        learner.append(np.array([survival[first : first + middle].mean(), survival[first + middle : len(ends)].mean()]))
        optimal.append(np.array([expected[:middle].mean(), expected[middle:].mean()]))
    if not learner:
        nan = float("nan")
        return SurvivalRise((nan, nan), (nan, nan), 0, 0)
    gaps = np.array(optimal) - np.array(learner)
    widened = int((gaps[:, 1] > gaps[:, 0]).sum())
    mean_learner, mean_optimal = np.mean(learner, axis=0), np.mean(optimal, axis=0)
    return SurvivalRise(
        (float(mean_learner[0]), float(mean_learner[1])), (float(mean_optimal[0]), float(mean_optimal[1])), widened, len(learner)
    )


def _reference_over(
    reference: Reference, selfishness: float, epsilons: Mapping[float, int], gamma: float, max_cycles: int
) -> tuple[float, float]:
    """The reference's harms and survival averaged over an ε schedule (weights: steps at each ε)."""
    total = sum(epsilons.values())
    harms = survival = 0.0
    for epsilon, steps in epsilons.items():
        outcome = reference(selfishness, epsilon, gamma=gamma, max_cycles=max_cycles)
        harms += outcome.harms * steps / total
        survival += outcome.survival * steps / total
    return harms, survival


def _curve_mean(run: RunResult, phase: str, metric: str) -> float:
    """Mean over the whole learning curve: every training episode, or every greedy evaluation."""
    if phase == "eval":
        values = [float(np.mean(e.metrics[metric])) for e in run.eval if len(e.metrics[metric])]
    else:
        values = [float(v) for v in run.train.metrics[metric]]
    return float(np.mean(values)) if values else float("nan")


class _Table:
    """Cells of the paper's runs of one env, per phase, metric and method key."""

    def __init__(self, runs: Mapping[str, list[RunResult]]) -> None:
        self.runs = runs

    def cell(self, phase: str, metric: str, key: str) -> Cell:
        runs = self.runs[key]
        return cell_of([run_scalars(run, (metric,))[phase][metric] for run in runs], metric, longest_episode(runs))

    def curve(self, phase: str, metric: str, key: str) -> Cell:
        runs = self.runs[key]
        return cell_of([_curve_mean(run, phase, metric) for run in runs], metric, longest_episode(runs))

    def row(self, phase: str, metric: str, keys: Sequence[str], curve: bool = False) -> list[Cell]:
        return [(self.curve if curve else self.cell)(phase, metric, k) for k in keys]

    def values(self, phase: str, metric: str, key: str) -> list[float]:
        """The per-seed values of a cell."""
        return [float(run_scalars(run, (metric,))[phase][metric]) for run in self.runs[key]]


def _line(keys: Sequence[str], cells: Sequence[Cell]) -> str:
    return "; ".join(f"{k}: {c}" for k, c in zip(keys, cells, strict=True))


def _verdict(ok: bool, cells: Sequence[Cell], evidence: str) -> Verdict:
    return Verdict(ok if all(c.finite for c in cells) else None, evidence)


def _changed(new: bool | None, old: bool, cells: Sequence[Cell], evidence: str) -> Verdict:
    """A verdict of a changed rule (``new``: ``None`` for undecided) with the old rule's beside it."""
    if not all(c.finite for c in cells):
        return Verdict(None, evidence)
    return Verdict(new, evidence, undecided=new is None, old=Verdict(old, evidence))


def _less(a: Sequence[float], b: Sequence[float], names: Sequence[str]) -> tuple[bool | None, str]:
    """:func:`leaderboard.claim_rules.less_than` and its evidence."""
    verdict, p = less_than(a, b)
    said = {True: "yes", False: "no", None: "too few seeds for the test"}[verdict]
    return verdict, f"{names[0]} less than {names[1]} by the exact permutation test at 5 %: {said} (p = {p:.4f})"


def coexistence_claims(
    runs: Mapping[str, list[RunResult]], reference: Reference, tie_range: TieRangeOf | None = None
) -> dict[str, dict[str, Verdict]]:
    """The paper's Coexistence claims (C1–C4), ``{claim: {phase: verdict}}``, judged on ``runs``
    keyed as :func:`paper_runs` keys them (``β=1`` … ``β=0.25`` and :data:`PENALTY`), with
    ``reference`` the exact optimum C3 is judged against and ``tie_range`` its range over every
    tie-break (``None``: not shown). :func:`assess_claims` judges the paper sweep by it; a
    sensitivity study judges each of its conditions by it."""
    betas = [f"β={b:g}" for b in BETAS]
    coexistence = _Table(runs)
    claims: dict[str, dict[str, Verdict]] = {}

    def judge(text: str, phase_name: str, verdict: Verdict) -> None:
        claims.setdefault(text, {})[phase_name] = verdict

    for name, phase in PHASES.items():
        harms = coexistence.row(phase, "harms", betas)
        judge(
            "Harms to the cat fall as β falls.",
            name,
            _verdict(falls(harms), harms, f"harms/episode: {_line(betas, harms)}."),
        )

        survival = coexistence.row(phase, "survival", betas)
        area = coexistence.row(phase, "survival", betas, curve=True)
        slower = below(area[-1], area[0])
        judge(
            "Lower β survives worse and learns more slowly.",
            name,
            _verdict(
                falls(survival) and slower,
                survival + area,
                f"steps survived: {_line(betas, survival)} (falls: {'yes' if falls(survival) else 'no'}). "
                f"Mean over the whole learning curve: {_line(betas, area)} (β=0.25 below β=1: {'yes' if slower else 'no'}).",
            ),
        )

        caring = ["β=0.5", "β=0.25"]
        parts: list[str] = []
        ok, cells = True, []
        readings: list[bool | None] = []
        for key in caring:
            h, s = coexistence.cell(phase, "harms", key), coexistence.cell(phase, "survival", key)
            group = runs[key]
            epsilons: dict[float, int] = {0.0: 1}
            if phase != "eval":
                epsilons = {}
                for run in group:
                    for epsilon, steps in training_window_epsilons(run).items():
                        epsilons[epsilon] = epsilons.get(epsilon, 0) + steps
            described = description_of(group[0])
            beta, gamma = float(described["selfishness"]), float(described["gamma"])
            max_cycles = int(env_argument(group[0], "max_cycles"))
            ref_harms, ref_survival = _reference_over(reference, beta, epsilons, gamma, max_cycles)
            ok = ok and matches_reference(h, s, ref_harms, ref_survival, max_cycles)
            reading = reference_reading(h, s, ref_harms, ref_survival, max_cycles)
            readings.append(reading)
            cells += [h, s]
            mean_epsilon = sum(e * n for e, n in epsilons.items()) / max(sum(epsilons.values()), 1)
            on_intervals = {True: "yes", False: "no", None: "undecided (an interval straddles its threshold)"}[reading]
            part = (
                f"{key}: harms {h} (reference {ref_harms:.3f}), survival {s} (reference {ref_survival:.1f}), "
                f"mean ε {mean_epsilon:.4f}"
            )
            if phase != "eval":
                shares = [training_window_share(run) for run in group]
                part += (
                    f" over the steps of the final 10 % of training episodes "
                    f"({100 * min(shares):.1f}–{100 * max(shares):.1f} % of each run's steps)"
                )
            if tie_range is not None:
                spread = tie_range(beta, epsilons, gamma=gamma, max_cycles=max_cycles)
                part += (
                    f"; over every tie-break the optimum's harms span {spread.harms[0]:.3f}–{spread.harms[1]:.3f} "
                    f"and its survival {spread.survival[0]:.1f}–{spread.survival[1]:.1f}"
                )
            if phase != "eval":
                rise = survival_rise(group, reference, gamma=gamma, max_cycles=max_cycles)
                part += (
                    f"; across the final 10 % of training episodes (first half → second half) survival "
                    f"{rise.learner[0]:.1f} → {rise.learner[1]:.1f}, the reference at the ε of the same episodes "
                    f"{rise.reference[0]:.1f} → {rise.reference[1]:.1f} (the ε schedule alone), so the gap to it "
                    f"went {rise.gap[0]:.1f} → {rise.gap[1]:.1f}, wider in {rise.widened} of {rise.runs} runs"
                )
            parts.append(f"{part}; harm-free and surviving on intervals: {on_intervals}")
        judge(
            "The less selfish agents (β = 0.5, 0.25) eventually survive without harming the cat.",
            name,
            _changed(False if False in readings else (True if all(readings) else None), ok, cells, "; ".join(parts) + "."),
        )

        pair = [PENALTY, "β=1"]
        penalty = coexistence.row(phase, "harms", pair)
        fewer, test = _less(coexistence.values(phase, "harms", pair[0]), coexistence.values(phase, "harms", pair[1]), pair)
        judge(
            "The −100 harm-penalty baseline harms the cat less than DQN.",
            name,
            _changed(fewer, below(penalty[0], penalty[1]), penalty, f"harms/episode: {_line(pair, penalty)}; {test}."),
        )

    return claims


def assess_claims(
    results: Sequence[RunResult], reference: Reference | None = None, tie_range: TieRangeOf | None = None
) -> list[Claim]:
    """Judge every claim of SPEC §7 (and the suite's own questions) on the paper's runs in
    ``results``; raises :class:`NotThePaperSweep` when an experiment of the paper is missing.

    ``reference`` is the exact optimum the harm-free/surviving claim is judged against (default
    ``empathy_zoo.reference.coexistence_optimum``, uniform ties); ``tie_range`` gives the range
    of the optimum's figures over every tie-break, shown beside it (default
    :func:`tie_break_range` when ``reference`` is the default one; with another reference and
    no ``tie_range``, no range is shown)."""
    missing = missing_paper_experiments(results)
    if missing:
        raise NotThePaperSweep(f"these results do not contain the paper's experiments (missing: {', '.join(missing)})")
    if reference is None:
        from empathy_zoo.reference import coexistence_optimum

        reference = coexistence_optimum
        tie_range = tie_break_range if tie_range is None else tie_range
    runs = paper_runs(results)
    betas = [f"β={b:g}" for b in BETAS]
    sharing = _Table(runs[SHARING])
    coexistence = coexistence_claims(runs[COEXISTENCE], reference, tie_range)
    claims: dict[tuple[str, str, bool], dict[str, Verdict]] = {
        (COEXISTENCE, text, True): verdicts for text, verdicts in coexistence.items()
    }

    def judge(env: str, text: str, phase_name: str, verdict: Verdict, papers: bool = True) -> None:
        claims.setdefault((env, text, papers), {})[phase_name] = verdict

    for name, phase in PHASES.items():
        batteries = sharing.row(phase, "batteries", betas)
        judge(
            SHARING,
            "The robot collects fewer batteries as β falls.",
            name,
            _verdict(falls(batteries), batteries, f"robot batteries/episode: {_line(betas, batteries)}."),
        )

        equality = sharing.row(phase, "equality", betas)
        human = sharing.row(phase, "other_batteries", betas)
        judge(
            SHARING,
            "Equality peaks at β = 0.5.",
            name,
            _verdict(
                peaks(equality[1], equality[2], equality[3]),
                equality,
                f"equality: {_line(betas, equality)}; human batteries/episode: {_line(betas, human)}.",
            ),
        )

        pair = ["β=1", EQUALITY_SHAPED]
        fair = sharing.row(phase, "equality", pair)
        fairer, test = _less(sharing.values(phase, "equality", pair[0]), sharing.values(phase, "equality", pair[1]), pair)
        judge(
            SHARING,
            "The equality-scaled DQN baseline is more equal than DQN.",
            name,
            _changed(fairer, below(fair[0], fair[1]), fair, f"equality: {_line(pair, fair)}; {test}."),
            papers=False,
        )
    return [Claim(env, text, verdicts, papers) for (env, text, papers), verdicts in claims.items()]


def reproduction_markdown(claims: Sequence[Claim], command: str, results_dir: str, note: str = "", appendix: str = "") -> str:
    """The report: how it was made, the rules, a verdict table, then the evidence per claim."""
    lines = [
        REPORT_TITLE,
        "",
        f"Claims of *Towards Empathic Deep Q-Learning* (SPEC §7), judged on the result files in `{results_dir}`, produced by:",
        "",
        f"    {command}",
        "",
        f"and checked by `empathy-zoo reproduction {results_dir}` (this file is generated from the result files).",
        "",
    ]
    if note:
        lines += [note, ""]
    lines += [RULES, "", CLAIM_RULES, "", "| environment | claim | greedy | training |", "|---|---|---|---|"]
    for papers, heading in ((True, None), (False, "The suite's own questions (not claims of the paper)")):
        chosen = [c for c in claims if c.papers == papers]
        if heading and chosen:
            lines += [f"| | *{heading}* | | |"]
        lines += [f"| {c.env} | {c.text} | {_word(c.verdicts['greedy'])} | {_word(c.verdicts['training'])} |" for c in chosen]
    lines.append("")
    for c in claims:
        lines += [f"## {c.text} ({c.env}){'' if c.papers else ' — the suite’s own question'}", ""]
        for phase, verdict in c.verdicts.items():
            where = "last greedy evaluation" if phase == "greedy" else "final 10 % of training episodes"
            lines += [f"* **{phase}** ({where}) — {_word(verdict, bold=False)}: {verdict.evidence}"]
        lines.append("")
    if appendix:
        lines += [appendix, ""]
    return "\n".join(lines)


def _word(verdict: Verdict, bold: bool = True) -> str:
    """The verdict's word, with the old rule's beside it where it differs."""
    word = f"**{verdict.word}**" if bold else verdict.word
    return word if verdict.old_word == verdict.word else f"{word} (old rule: {verdict.old_word})"


def claim_verdicts_markdown(claims: Sequence[Claim]) -> str:
    """Every claim (C1, C2, … in the report's order) with its old and new verdict in each phase."""
    lines = [
        "| claim | environment | text | greedy (old rule) | greedy | training (old rule) | training |",
        "|---|---|---|---|---|---|---|",
    ]
    for number, claim in enumerate(claims, 1):
        greedy, training = claim.verdicts["greedy"], claim.verdicts["training"]
        lines.append(
            f"| C{number} | {claim.env} | {claim.text} | {greedy.old_word} | {greedy.word} "
            f"| {training.old_word} | {training.word} |"
        )
    return "\n".join(lines)


def write_reproduction(
    results_dir: str | os.PathLike[str],
    out_path: str | os.PathLike[str] | None = None,
    command: str = "empathy-zoo reproduce --profile paper",
    note: str = "",
    appendix: str = "",
    reference: Reference | None = None,
    tie_range: TieRangeOf | None = None,
) -> Path:
    """Judge the claims on ``results_dir`` and write the report (``<results_dir>/REPRODUCTION.md``);
    raises :class:`NotThePaperSweep` (writing nothing) when the paper's experiments are not there,
    and a ``ValueError`` naming the file (writing nothing) for a run :func:`check_run_steps` refuses."""
    claims = assess_claims(load_checked_results(results_dir), reference, tie_range)
    path = Path(out_path) if out_path else Path(results_dir) / "REPRODUCTION.md"
    write_text_atomic(path, reproduction_markdown(claims, command, str(results_dir), note, appendix))
    return path


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m leaderboard.reproduction RESULTS_DIR``: each claim's old and new verdict, printed."""
    import sys

    from empathy_zoo.names import positional_tool

    def verdicts(paths: list[str]) -> int:
        print(claim_verdicts_markdown(assess_claims(load_checked_results(paths[0]))))
        return 0

    prog = "python -m leaderboard.reproduction"
    usage = f"usage: {prog} RESULTS_DIR   (each claim's old and new verdict; writes nothing)"
    return positional_tool(prog, usage, list(sys.argv[1:] if argv is None else argv), 1, verdicts)


if __name__ == "__main__":
    raise SystemExit(main())
