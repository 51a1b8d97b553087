"""Whether two sets of runs of the same experiments differ detectably, and whether they are
equivalent within stated margins: the check that a change of summation order (another update
kernel, :attr:`RunnerOptions.update_kernel
<empathy_zoo.training.options.RunnerOptions.update_kernel>`) changed nothing but the last bits.

Two kernels that sum in another order give runs that part ways after a few hundred updates (a
hidden unit near its ReLU threshold falls on the other side), so a run of one kernel is not
expected to equal the same seed's run of the other: each is another draw of the same process. The
rule, fixed before the runs it judges:

* **Cells.** Runs are matched by experiment (variant, method, β, aggregation of the others, reward
  transform and budget: :func:`leaderboard.compare_runs.run_key` without the seed, with the steps). For every experiment found
  in both sets, both phases (:data:`leaderboard.aggregate.PHASES`) and the metrics that mean
  something in its environment (:attr:`empathy_zoo.environments.Environment.table_metrics`), a cell holds each set's
  per-seed values (:func:`leaderboard.aggregate.run_scalars`). A cell whose values are all equal on
  both sides (every run harm-free, say) says nothing and is counted as *constant*, not tested.
  Two sets with no experiment in common are refused: nothing would be compared.
* **Test.** Each cell: the exact two-sided Mann–Whitney permutation test of one set's values
  against the other's (:func:`leaderboard.improvement.permutation_test`: midranks for ties, the
  exact null distribution of every split).
* **Verdict.** Holm's step-down over every tested cell at a family-wise 5 %
  (:func:`holm_rejections`): a cell *differs* when it is rejected. The verdict is **no difference
  detected** when no cell differs, else **different**, naming the cells. The family-wise level
  holds whatever the dependence between cells (survival and return of one run, say). "No
  difference detected" is a failure to reject, not a finding of equivalence: its power is printed
  beside it (:func:`smallest_p_value`: the smallest p the exact test can reach at the cells' seed
  counts, ``2 / C(n + m, n)``; :func:`holm_can_reject`: whether Holm's first threshold, ``5 % /
  cells``, is within reach at all). At 5 seeds a side the smallest p is 2/252 = 0.008, above
  0.05/7 = 0.007 already: over 7 cells or more (77, say) no cell can be rejected whatever the
  runs show.
* **Equivalence (TOST), ``--tost``.** Equivalence is claimed only by two one-sided Welch t tests
  per cell (:func:`leaderboard.tost.tost`) within margins stated here before any data
  (:data:`TOST_MARGINS`: ±25 steps of survival, ±0.1 harms, ±0.5 batteries, ±0.05 equality per
  episode; metrics without a margin are not tested). A cell is **equivalent** when both one-sided
  tests reject at 5 % (its 90 % Welch interval of the difference lies inside the margins), and
  the two sets are **equivalent** when every such cell is: an intersection–union test, whose level
  is the per-cell 5 % without a multiplicity correction (Berger 1982), since the claim needs every
  cell. Each cell's own verdict is at its 5 % (not family-wise). A cell with fewer than 2 seeds a
  side gives **too few seeds**, and so does the set. The word "equivalent" is used only for this
  test's verdict.
* **Verdicts of the leaderboard.** Beside it, the verdicts against DQN
  (:func:`leaderboard.improvement.improvements_over_dqn`, ▲ / ▼ / no clear difference) of each set
  are listed where they differ (:func:`verdict_flips`): reported with their p-values, not folded
  into the verdict, since two draws of a cell near the test's threshold may fall on either side;
  :func:`split_flips` says how many flip between two random halves of the pooled runs, what
  redrawing the seeds alone does.

What it can see (:func:`simulated_power`): with 10 seeds a side and about 60 tested cells, a cell
whose metric moved by 2 standard deviations is rejected in roughly half of the draws, one moved by
1 in a few percent: the check finds a kernel that changes what runs learn, not one that moves a
metric by a fraction of its seed-to-seed spread.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from empathy_zoo.experiment.records import RunResult
from empathy_zoo.metrics import EQUIVALENCE_MARGINS
from empathy_zoo.names import positional_tool, tool_help
from empathy_zoo.result_file import read_folder
from leaderboard.aggregate import PHASES, run_scalars, table_env
from leaderboard.compare_runs import (
    check_one_experiment_per_key,
    check_same_settings,
    check_something_matched,
    compare_runs,
    run_key,
    runs_by_key,
)
from leaderboard.improvement import improvements_over_dqn, permutation_test
from leaderboard.tables import table_metrics
from leaderboard.tost import EQUIVALENT, NOT_SHOWN, TOO_FEW, TostResult, tost

__all__ = [
    "FAMILY_LEVEL",
    "NO_DIFFERENCE",
    "TOST_MARGINS",
    "TOST_LEVEL",
    "Cell",
    "Equivalence",
    "TostCell",
    "TostSummary",
    "equivalence",
    "tost",
    "tost_cells",
    "smallest_p_value",
    "holm_can_reject",
    "holm_rejections",
    "report",
    "simulated_power",
    "split_flips",
    "verdict_flips",
]

FAMILY_LEVEL = 0.05
"""The chance, when nothing differs, that any cell is called different (Holm's family-wise level)."""
NO_DIFFERENCE = "no difference detected"
"""The difference test's verdict when no cell is rejected (a failure to reject, not equivalence)."""
TOST_MARGINS: dict[str, float] = EQUIVALENCE_MARGINS
"""Practical margins of the TOST, per episode (:data:`empathy_zoo.metrics.EQUIVALENCE_MARGINS`)."""
TOST_LEVEL = 0.05
"""The level of each one-sided test of the TOST (its 90 % interval)."""


@dataclass(frozen=True)
class Cell:
    """One experiment, phase and metric: both sets' per-seed values and the test between them."""

    experiment: tuple
    """:func:`leaderboard.compare_runs.run_key` without the seed, then the run's steps."""
    phase: str
    metric: str
    old: tuple[float, ...]
    new: tuple[float, ...]
    p_value: float
    """Two-sided p of the exact permutation test; NaN for a constant cell (not tested)."""
    differs: bool = False
    """Rejected by Holm's step-down at :data:`FAMILY_LEVEL`."""

    @property
    def constant(self) -> bool:
        return math.isnan(self.p_value)


@dataclass(frozen=True)
class Equivalence:
    """The verdict over every cell."""

    cells: tuple[Cell, ...]
    only_old: tuple[tuple, ...]
    """Experiments of the first set without a partner (not compared)."""
    only_new: tuple[tuple, ...]

    @property
    def tested(self) -> list[Cell]:
        return [cell for cell in self.cells if not cell.constant]

    @property
    def differing(self) -> list[Cell]:
        return [cell for cell in self.cells if cell.differs]

    @property
    def verdict(self) -> str:
        """:data:`NO_DIFFERENCE` when no tested cell differs, else ``"different"``; ``"nothing
        compared"`` when no cell could be tested."""
        if not self.tested:
            return "nothing compared"
        return "different" if self.differing else NO_DIFFERENCE

    @property
    def seed_counts(self) -> list[tuple[int, int]]:
        """``(n, m)``: the finite values of each tested cell on each side."""
        return [(_finite(cell.old), _finite(cell.new)) for cell in self.tested]

    @property
    def can_reject(self) -> bool:
        """Whether Holm over the tested cells could reject any cell at all (:func:`holm_can_reject`)."""
        return holm_can_reject(self.seed_counts)


def _finite(values: Sequence[float]) -> int:
    return sum(math.isfinite(v) for v in values)


def smallest_p_value(n: int, m: int) -> float:
    """The smallest two-sided p the exact permutation test can reach with ``n`` runs against ``m``
    (every run of one side beyond every run of the other, no ties): ``2 / C(n + m, n)``, at most 1."""
    if n < 1 or m < 1:
        return 1.0
    return min(1.0, 2.0 / math.comb(n + m, n))


def holm_can_reject(seed_counts: Sequence[tuple[int, int]], level: float = FAMILY_LEVEL) -> bool:
    """Whether Holm's step-down over cells of these ``(n, m)`` seed counts can reject any cell,
    whatever the runs show: its first step needs a p at most ``level / cells``."""
    if not seed_counts:
        return False
    return min(smallest_p_value(n, m) for n, m in seed_counts) <= level / len(seed_counts) + 1e-15


def power_line(result: Equivalence, level: float = FAMILY_LEVEL) -> str:
    """What the difference test could find: the smallest reachable p at the cells' seed counts
    beside Holm's first threshold."""
    counts = result.seed_counts
    if not counts:
        return "Power: no cell tested."
    pairs = sorted(set(counts))
    smallest = min(smallest_p_value(n, m) for n, m in counts)
    threshold = level / len(counts)
    seeds = ", ".join(f"{n} v {m}" for n, m in pairs[:4]) + (" …" if len(pairs) > 4 else "")
    can = "can reject" if result.can_reject else "cannot reject any cell, whatever the runs show"
    return (
        f"Power: at {seeds} seeds the smallest p the exact test can reach is {smallest:.2g}; Holm's first "
        f"threshold over {len(counts)} cells is {level:g}/{len(counts)} = {threshold:.2g}, so it {can}. "
        f'"{NO_DIFFERENCE}" is a failure to reject, not equivalence (for that: --tost).'
    )


@dataclass(frozen=True)
class TostCell:
    """One experiment, phase and metric with a margin: the TOST of the two sets' per-seed values."""

    experiment: tuple
    phase: str
    metric: str
    result: TostResult

    @property
    def verdict(self) -> str:
        return self.result.verdict


@dataclass(frozen=True)
class TostSummary:
    """The TOST of every cell with a margin, and the set's verdict (intersection–union)."""

    cells: tuple[TostCell, ...]

    @property
    def verdict(self) -> str:
        """:data:`~leaderboard.tost.EQUIVALENT` when every cell is; :data:`~leaderboard.tost.TOO_FEW`
        when any cell has too few seeds; else :data:`~leaderboard.tost.NOT_SHOWN`
        (``"nothing compared"`` without cells)."""
        if not self.cells:
            return "nothing compared"
        verdicts = {cell.verdict for cell in self.cells}
        if TOO_FEW in verdicts:
            return TOO_FEW
        return EQUIVALENT if verdicts == {EQUIVALENT} else NOT_SHOWN


def holm_rejections(p_values: Sequence[float], level: float = FAMILY_LEVEL) -> list[bool]:
    """Holm's step-down: sorted ascending, the ``i``-th smallest p (from 0) is rejected while every
    p up to it is at most ``level / (m − i)``; the first that is not stops the procedure. In the
    order given."""
    order = sorted(range(len(p_values)), key=lambda i: p_values[i])
    rejected = [False] * len(p_values)
    m = len(p_values)
    for rank, index in enumerate(order):
        if p_values[index] > level / (m - rank):
            break
        rejected[index] = True
    return rejected


def _experiment(run: RunResult) -> tuple:
    """The run's experiment: :func:`leaderboard.compare_runs.run_key` without the seed, and its
    budget (runs of another length are another experiment)."""
    return (*run_key(run)[:-1], run.steps)


def _per_experiment(runs: Sequence[RunResult]) -> dict[tuple, list[RunResult]]:
    """``runs`` by experiment (:func:`_experiment`); a seed twice in one is refused (:func:`runs_by_key`),
    and so are two experiments that the key takes for one (:func:`~leaderboard.compare_runs.check_one_experiment_per_key`)."""
    runs_by_key(runs, lambda run: (*_experiment(run), run.seed))
    check_one_experiment_per_key(runs, _experiment)
    groups: dict[tuple, list[RunResult]] = {}
    for run in runs:
        groups.setdefault(_experiment(run), []).append(run)
    return groups


def equivalence(old: Sequence[RunResult], new: Sequence[RunResult], level: float = FAMILY_LEVEL) -> Equivalence:
    """The verdict of the rule (module documentation) on two sets of result documents."""
    a, b = _per_experiment(old), _per_experiment(new)
    raw: list[Cell] = []
    for experiment in sorted(set(a) & set(b), key=repr):
        check_same_settings(a[experiment][0], b[experiment][0])
        env = table_env(a[experiment][0])
        metrics = table_metrics(env, a[experiment][0].env)
        scalars_a = [run_scalars(run) for run in a[experiment]]
        scalars_b = [run_scalars(run) for run in b[experiment]]
        for phase in PHASES:
            for metric in metrics:
                x = tuple(float(s[phase][metric]) for s in scalars_a)
                y = tuple(float(s[phase][metric]) for s in scalars_b)
                finite = [v for v in x + y if math.isfinite(v)]
                p = math.nan if len(set(finite)) <= 1 else permutation_test(x, y)[1]
                raw.append(Cell(experiment, phase, metric, x, y, p))
    tested = [i for i, cell in enumerate(raw) if not cell.constant]
    rejected = holm_rejections([raw[i].p_value for i in tested], level)
    cells = list(raw)
    for i, reject in zip(tested, rejected, strict=True):
        if reject:
            cells[i] = Cell(**{**raw[i].__dict__, "differs": True})
    return Equivalence(
        tuple(cells),
        tuple(sorted(set(a) - set(b), key=repr)),
        tuple(sorted(set(b) - set(a), key=repr)),
    )


def tost_cells(
    old: Sequence[RunResult],
    new: Sequence[RunResult],
    margins: dict[str, float] | None = None,
    level: float = TOST_LEVEL,
) -> TostSummary:
    """The TOST (:func:`leaderboard.tost.tost`) of every experiment found in both sets, both
    phases and every metric of its tables that has a margin (``margins``, default
    :data:`TOST_MARGINS`)."""
    margins = TOST_MARGINS if margins is None else margins
    a, b = _per_experiment(old), _per_experiment(new)
    cells = []
    for experiment in sorted(set(a) & set(b), key=repr):
        check_same_settings(a[experiment][0], b[experiment][0])
        env = table_env(a[experiment][0])
        metrics = table_metrics(env, a[experiment][0].env)
        scalars_a = [run_scalars(run) for run in a[experiment]]
        scalars_b = [run_scalars(run) for run in b[experiment]]
        for phase in PHASES:
            for metric in metrics:
                if metric not in margins:
                    continue
                x = [float(s[phase][metric]) for s in scalars_a]
                y = [float(s[phase][metric]) for s in scalars_b]
                cells.append(TostCell(experiment, phase, metric, tost(x, y, margins[metric], level)))
    return TostSummary(tuple(cells))


def tost_report(old: Sequence[RunResult], new: Sequence[RunResult]) -> str:
    """Markdown: the TOST's verdict and every cell, with its difference, 90 % interval and p."""
    summary = tost_cells(old, new)
    counts = {v: sum(c.verdict == v for c in summary.cells) for v in (EQUIVALENT, NOT_SHOWN, TOO_FEW)}
    margins = ", ".join(f"±{m:g} {metric}" for metric, m in TOST_MARGINS.items())
    lines = [
        f"**TOST: {summary.verdict}** ({counts[EQUIVALENT]} of {len(summary.cells)} cells equivalent, "
        f"{counts[NOT_SHOWN]} not shown equivalent, {counts[TOO_FEW]} with too few seeds; margins {margins} per episode; "
        f"two one-sided Welch t tests at {TOST_LEVEL:.0%} each, so a 90 % interval; the set is equivalent only when "
        "every cell is, an intersection–union test at 5 %)",
        "",
        "| experiment | phase | metric | first − second | 90 % interval | margin | p | verdict |",
        "|---|---|---|---:|---|---:|---:|---|",
    ]
    for cell in summary.cells:
        r = cell.result
        name = ", ".join(str(part) for part in cell.experiment if part not in (None, "closest"))
        lines.append(
            f"| {name} | {cell.phase} | {cell.metric} | {r.difference:.3f} | [{r.low:.3f}, {r.high:.3f}] "
            f"| ±{r.margin:g} | {r.p_value:.4f} | {r.verdict} |"
        )
    return "\n".join(lines)


def verdict_flips(old: Sequence[RunResult], new: Sequence[RunResult]) -> list[tuple[tuple, str, str, float, float]]:
    """The leaderboard's verdicts against DQN that differ between the sets: ``(cell key, old
    verdict, new verdict, old p, new p)``, the key ``(variant, label, phase, metric, DQN row)``."""
    metrics_of = {run.table_env: table_metrics(run.env) for run in [*old, *new]}
    before = {(c.env, c.method_label, c.phase, c.metric, c.baseline_label): c for c in improvements_over_dqn(old, metrics_of)}
    after = {(c.env, c.method_label, c.phase, c.metric, c.baseline_label): c for c in improvements_over_dqn(new, metrics_of)}
    return [
        (key, before[key].verdict, after[key].verdict, before[key].p_value, after[key].p_value)
        for key in sorted(set(before) & set(after))
        if before[key].verdict != after[key].verdict
    ]


def split_flips(old: Sequence[RunResult], new: Sequence[RunResult], trials: int = 40, seed: int = 0) -> list[int]:
    """How many verdicts against DQN differ between two draws of the same process, for reading
    :func:`verdict_flips`: the runs of both sets pooled per row (variant and label), split at
    random into two halves of equal size (each row's seeds renumbered), and the halves' verdicts
    compared; one count per split (``trials`` splits, seeded). Where the two sets are draws of one
    process, this is what redrawing the seeds alone does."""
    rng = np.random.default_rng(seed)
    pooled: dict[tuple[str, str], list[RunResult]] = {}
    for run in [*old, *new]:
        pooled.setdefault((run.table_env, run.method_label), []).append(run)
    counts = []
    for _ in range(trials):
        halves: tuple[list[RunResult], list[RunResult]] = ([], [])
        for runs in pooled.values():
            half = len(runs) // 2
            for position, index in enumerate(rng.permutation(len(runs))[: 2 * half]):
                halves[position // half].append(replace(runs[index], seed=position % half))
        counts.append(len(verdict_flips(*halves)))
    return counts


def simulated_power(shift: float, seeds: int, cells: int, trials: int = 400, seed: int = 0, level: float = FAMILY_LEVEL) -> float:
    """How often one cell whose values moved by ``shift`` standard deviations (normal data, ``seeds``
    runs a side) is found to differ among ``cells`` tested cells, the others unchanged: the share
    of ``trials`` draws (seeded) in which Holm's step-down rejects it."""
    rng = np.random.default_rng(seed)
    found = 0
    for _ in range(trials):
        p_values = [permutation_test(list(rng.normal(shift, 1.0, seeds)), list(rng.normal(0.0, 1.0, seeds)))[1]]
        p_values += [
            permutation_test(list(rng.normal(0.0, 1.0, seeds)), list(rng.normal(0.0, 1.0, seeds)))[1] for _ in range(cells - 1)
        ]
        found += holm_rejections(p_values, level)[0]
    return found / trials


def _mean_text(values: Sequence[float] | np.ndarray) -> str:
    """The mean of ``values``' finite numbers to 3 decimals, or ``—`` where none is (a run too short
    for a window of training episodes records none)."""
    finite = np.asarray(values, dtype=float)
    finite = finite[np.isfinite(finite)]
    return f"{finite.mean():.3f}" if finite.size else "—"


def report(old_dir: str, new_dir: str, every_cell: bool = False, with_tost: bool = False) -> str:
    """Markdown: the verdict of :func:`equivalence` on two results directories with its power, its
    ten smallest p-values (every cell, in experiment order, with ``every_cell``), every differing
    cell and every flipped verdict against DQN; with ``with_tost``, the TOST of every cell with a
    margin (:func:`tost_report`)."""
    from leaderboard.aggregate import load_results

    if read_folder(old_dir) == read_folder(new_dir):  # (DIR and DIR/runs are one directory)
        raise ValueError(f"{new_dir} is given twice (as {old_dir} too): its runs would be compared with themselves")
    old, new = load_results(old_dir), load_results(new_dir)
    result = equivalence(old, new)
    if not result.cells:
        check_something_matched(old_dir, new_dir, result.only_old, result.only_new, "experiment")
    tested = sorted(result.tested, key=lambda cell: cell.p_value)
    pairs = compare_runs(old, new)
    copies = bool(pairs["same"]) and not pairs["different"]
    lines = [
        *(
            [
                f"Every matched pair of runs ({len(pairs['same'])}) is identical column for column: the two sets hold "
                "the same numbers (a copy, or a kernel that changed nothing), so no test below tells two processes apart.",
                "",
            ]
            if copies
            else []
        ),
        f"**{result.verdict}**: {len(result.differing)} of {len(tested)} tested cells differ at a family-wise "
        f"{FAMILY_LEVEL:.0%} (Holm; {len(result.cells) - len(tested)} constant cells not tested; "
        f"{len(old)} runs against {len(new)}; experiments without a partner: {len(result.only_old)} + {len(result.only_new)})",
        "",
        power_line(result),
        "",
        "| experiment | phase | metric | mean (first) | mean (second) | p | differs |",
        "|---|---|---|---:|---:|---:|---|",
    ]
    shown = list(result.cells) if every_cell else tested[:10] + [c for c in result.differing if c not in tested[:10]]
    for cell in shown:
        name = ", ".join(str(part) for part in cell.experiment if part not in (None, "closest"))
        lines.append(
            f"| {name} | {cell.phase} | {cell.metric} | {_mean_text(cell.old)} | {_mean_text(cell.new)} "
            f"| {'constant' if cell.constant else f'{cell.p_value:.4f}'} | {'yes' if cell.differs else ''} |"
        )
    flips = verdict_flips(old, new)
    lines += ["", f"Verdicts against DQN that differ: {len(flips)}"]
    lines += [f"- {key}: {a} (p = {pa:.3f}) → {b} (p = {pb:.3f})" for key, a, b, pa, pb in flips]
    redrawn = split_flips(old, new)
    lines += [
        "",
        f"For reading them (not part of the rule): between two random halves of the pooled runs, {len(redrawn)} splits, "
        f"{int(np.median(redrawn))} verdicts differ at the median (range {min(redrawn)}–{max(redrawn)}).",
    ]
    if with_tost:
        lines += ["", tost_report(old, new)]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m leaderboard.equivalence FIRST_DIR SECOND_DIR [--all] [--tost]``: the report, printed."""
    import sys

    given = list(sys.argv[1:] if argv is None else argv)
    options = {"--all", "--tost"}
    usage = (
        "usage: python -m leaderboard.equivalence FIRST_DIR SECOND_DIR [--all] [--tost]   "
        "(--all: every cell, not the ten smallest p; --tost: the equivalence test within TOST_MARGINS)"
    )
    if given in (["-h"], ["--help"]):
        print(tool_help(usage, __doc__))
        return 0

    def print_report(paths: list[str]) -> int:
        print(report(paths[0], paths[1], every_cell="--all" in given, with_tost="--tost" in given))
        return 0

    return positional_tool("python -m leaderboard.equivalence", usage, [a for a in given if a not in options], 2, print_report)


if __name__ == "__main__":
    raise SystemExit(main())
