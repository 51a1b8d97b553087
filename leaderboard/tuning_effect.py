"""Does tuning change a verdict? Each tuned row against its tuned DQN, beside the untuned row
against the untuned DQN.

    python -m leaderboard.tuning_effect UNTUNED_DIR TUNED_DIR [--changed-only]

A tuned row is one of ``TUNED_DIR`` whose label is ``<label>, tuned`` (what ``empathy-zoo tune``
writes: :mod:`empathy_zoo.training.tuning`); its untuned row is ``<label>`` on the same variant in
``UNTUNED_DIR``. Each directory is scored alone, by the leaderboard's rule unchanged
(:func:`leaderboard.improvement.improvements_over_dqn`: the exact two-sided Mann–Whitney test at
5 %), so a tuned row is compared with the tuned DQN of its variant and never with an untuned one.
Per metric (:func:`leaderboard.versus_dqn.compact_metrics`) and phase the table gives both rows'
means and verdicts; a verdict that differs is *changed by tuning*. The DQN rows themselves have
no verdict: their means are shown (``DQN`` → ``DQN, tuned``). A tuned row with no untuned row is
named, never dropped, and a tuned directory with no tuned method to compare is refused; a
directory with two DQN rows in one variant is refused (a verdict would be one of several), and so
is a tuned row whose method, world or budget is not its untuned row's, and a row with no DQN row
of its variant, world and budget beside it (it has no verdict to compare).
Nothing new is tested: this is a view of two leaderboards' cells.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from empathy_zoo.experiment.records import RunResult
from empathy_zoo.markdown_escape import markdown_text
from empathy_zoo.names import terminal_line
from empathy_zoo.result_file import read_folder
from leaderboard.aggregate import group_runs, load_results, score_runs
from leaderboard.improvement import VERDICT_MARKS, improvements_over_dqn, is_dqn, row_key, uncompared_rows
from leaderboard.versus_dqn import compact_metrics

__all__ = ["TUNED_SUFFIX", "VerdictPair", "TuningEffect", "tuning_effect", "tuning_effect_table"]

TUNED_SUFFIX = ", tuned"
"""How a tuned row's label ends (``tuned.toml``'s label)."""
PHASE_NAMES = {"eval": "greedy", "train_final10": "training"}
"""The phases compared, as the tables name them."""


@dataclass(frozen=True)
class VerdictPair:
    """One metric and phase of one method: untuned against DQN, tuned against the tuned DQN."""

    variant: str
    label: str
    """The untuned row's label (the tuned one's without :data:`TUNED_SUFFIX`)."""
    phase: str
    metric: str
    untuned_mean: float
    tuned_mean: float
    untuned_verdict: str | None
    """The leaderboard's verdict against DQN; ``None`` for a DQN row (the reference itself)."""
    tuned_verdict: str | None

    @property
    def changed(self) -> bool:
        """Whether tuning changed the verdict."""
        return self.untuned_verdict != self.tuned_verdict


@dataclass(frozen=True)
class TuningEffect:
    """Every pair, and the tuned rows that have no untuned row."""

    pairs: tuple[VerdictPair, ...]
    unmatched: tuple[tuple[str, str], ...]
    """``(variant, label)`` of each tuned row of ``TUNED_DIR`` with no untuned row."""


def _cells(results: Sequence[RunResult], metrics_of: Mapping[str, Sequence[str]]) -> tuple[dict, dict, set]:
    means = {(s.env, s.method_label, s.phase, s.metric): s.mean for s in score_runs(results)}
    verdicts = {(c.env, c.method_label, c.phase, c.metric): c.verdict for c in improvements_over_dqn(results, metrics_of)}
    references = {key for key, runs in group_runs(results).items() if all(is_dqn(run) for run in runs)}
    for variant in sorted({variant for variant, _ in references}):
        rows = sorted(label for v, label in references if v == variant)
        if len(rows) > 1:
            raise ValueError(
                f"{variant} has {len(rows)} DQN reference rows ({'; '.join(rows)}): a verdict would be one of several; "
                "give directories with one DQN row per variant"
            )
    return means, verdicts, references


def tuning_effect(
    untuned: Sequence[RunResult], tuned: Sequence[RunResult], metrics_of: Mapping[str, Sequence[str]] | None = None
) -> TuningEffect:
    """The pairs of :class:`VerdictPair` of every tuned row of ``tuned`` with its row in ``untuned``
    (runs, as :func:`leaderboard.aggregate.load_results` reads them)."""
    groups = group_runs(tuned)
    variants = {env: runs[0].env for (env, _), runs in groups.items()}
    metrics = {v: compact_metrics(v, env, metrics_of) for v, env in variants.items()}
    old_means, old_verdicts, old_references = _cells(untuned, metrics)
    new_means, new_verdicts, new_references = _cells(tuned, metrics)
    untuned_groups = group_runs(untuned)
    old_rows = set(untuned_groups)
    old_alone, new_alone = set(uncompared_rows(untuned)), set(uncompared_rows(tuned))
    pairs: list[VerdictPair] = []
    unmatched: list[tuple[str, str]] = []
    for variant, label in groups:
        base = label.removesuffix(TUNED_SUFFIX)
        if base == label or (variant, base) not in old_rows:
            unmatched.append((variant, label))
            continue
        _check_tuning_only(variant, groups[(variant, label)], untuned_groups[(variant, base)])
        reference = (variant, label) in new_references
        if reference != ((variant, base) in old_references):
            raise ValueError(f"{variant}: {label!r} and {base!r} are not both DQN references or both methods")
        for row, alone, which in (((variant, base), old_alone, "untuned"), ((variant, label), new_alone, "tuned")):
            if row in alone:
                raise ValueError(
                    f"{variant}: the {which} row {row[1]!r} has no DQN row of its variant, world and budget beside it, "
                    f"so it has no verdict to compare; give the {which} directory its DQN row"
                )
        for metric in metrics[variant]:
            for phase in PHASE_NAMES:
                pairs.append(
                    VerdictPair(
                        variant=variant,
                        label=base,
                        phase=phase,
                        metric=metric,
                        untuned_mean=old_means[(variant, base, phase, metric)],
                        tuned_mean=new_means[(variant, label, phase, metric)],
                        untuned_verdict=None if reference else old_verdicts.get((variant, base, phase, metric)),
                        tuned_verdict=None if reference else new_verdicts.get((variant, label, phase, metric)),
                    )
                )
    if not any(pair.untuned_verdict is not None for pair in pairs):  # ("changed: 0 of 0" would read as "tuning changed nothing")
        tuned_rows = [label for _, label in groups if label.endswith(TUNED_SUFFIX)]
        why = (
            f"its tuned rows ({', '.join(repr(label) for label in sorted(set(tuned_rows))[:5])}) have no untuned row but DQN's"
            if tuned_rows
            else f"no row of it is labelled '<label>{TUNED_SUFFIX}' (what empathy-zoo tune writes)"
        )
        raise ValueError(f"the tuned directory holds no tuned method to compare with its untuned row: {why}")
    return TuningEffect(tuple(pairs), tuple(unmatched))


def _check_tuning_only(variant: str, tuned: Sequence[RunResult], untuned: Sequence[RunResult]) -> None:
    """Refuse (``ValueError`` naming both rows) a tuned row whose runs differ from its untuned row's
    in more than settings and seeds: its method or world (environment arguments and partners) and budget.
    What ``tune`` writes changes only the tuned settings; any other difference would read as tuning's effect."""
    facts = {
        "method": lambda runs: sorted({run.method for run in runs}),
        "world and budget": lambda runs: row_key(variant, runs),
    }
    for what, fact in facts.items():
        if fact(tuned) != fact(untuned):
            raise ValueError(
                f"{variant}: the tuned row {tuned[0].method_label!r} ({tuned[0].run_id}) and the untuned row "
                f"{untuned[0].method_label!r} ({untuned[0].run_id}) differ in their {what}: tuning changes only settings, "
                "so the two are no tuned and untuned row of one method"
            )


def _cell(mean: float, verdict: str | None) -> str:
    mark = "" if verdict is None else VERDICT_MARKS.get(verdict, "")
    return f"{mark} {mean:.3g}".strip()


def tuning_effect_table(effect: TuningEffect, changed_only: bool = False) -> str:
    """Markdown: per variant, one line per method, metric and phase: untuned → tuned, each
    ``mark mean``, and whether the verdict changed; then the count of changed verdicts."""
    lines: list[str] = []
    for variant in sorted({p.variant for p in effect.pairs}):
        rows = [p for p in effect.pairs if p.variant == variant and (p.changed or not changed_only)]
        header = "| method | metric | phase | untuned vs DQN | tuned vs tuned DQN | verdict |"
        lines += [f"### {markdown_text(variant)}", "", header]
        lines.append("|---|---|---|---|---|---|")
        for p in rows:
            said = "(the reference)" if p.untuned_verdict is None else ("**changed by tuning**" if p.changed else "same")
            label = markdown_text(p.label)  # (from the result files: data)
            lines.append(
                f"| {label} | {p.metric} | {PHASE_NAMES[p.phase]} | {_cell(p.untuned_mean, p.untuned_verdict)} | "
                f"{_cell(p.tuned_mean, p.tuned_verdict)} | {said} |"
            )
        lines.append("")
    compared = [p for p in effect.pairs if p.untuned_verdict is not None]
    lines.append(f"Verdicts changed by tuning: {sum(p.changed for p in compared)} of {len(compared)}.")
    if effect.unmatched:
        shown = ", ".join(f"'{markdown_text(label)}' ({markdown_text(variant)})" for variant, label in effect.unmatched)
        lines.append(f"Rows of the tuned directory not compared (no untuned row, or no '{TUNED_SUFFIX}' label): {shown}.")
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m leaderboard.tuning_effect UNTUNED_DIR TUNED_DIR [--changed-only]``."""
    parser = argparse.ArgumentParser(prog="python -m leaderboard.tuning_effect", description=__doc__.splitlines()[0])
    parser.add_argument("untuned", help="results directory of the untuned rows (with their DQN)")
    parser.add_argument("tuned", help="results directory of the tuned rows (with the tuned DQN)")
    parser.add_argument("--changed-only", action="store_true", help="list only the verdicts tuning changed")
    args = parser.parse_args(argv)
    try:
        if read_folder(args.untuned) == read_folder(args.tuned):  # (DIR and DIR/runs are one directory)
            raise ValueError(
                f"UNTUNED_DIR and TUNED_DIR are one directory ({args.tuned}): give the untuned rows' and the tuned rows'"
            )
        table = tuning_effect_table(tuning_effect(load_results(args.untuned), load_results(args.tuned)), args.changed_only)
    except (ValueError, OSError) as error:
        print(f"{parser.prog}: error: {terminal_line(error)}", file=sys.stderr)
        return 2
    print(table)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
