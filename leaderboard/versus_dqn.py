"""Every method against DQN in one compact table per environment: for each metric, the mean of the
last greedy evaluation and of the final 10 % of training episodes, each with its ▲ / ▼ / ⊘ marker
(:func:`leaderboard.improvement.improvement_verdict`), DQN's own means in the heading; a mark that
survives Holm's adjustment over every cell shown is followed by ◆, and the legend says how many false
marks the cells would give where nothing differed (:func:`leaderboard.legends.multiplicity_note`).

    python -m leaderboard.versus_dqn docs/results/methods

prints the tables the methods NOTE quotes (a view of the leaderboard's cells, nothing new computed).
A directory of which no row is compared with DQN (no DQN row of its variant, world and budget, or
DQN runs only) is refused (:func:`check_something_compared`).
"""

from __future__ import annotations

import sys
from collections.abc import Mapping, Sequence

from empathy_zoo.environments import ENVIRONMENT_TABLE, entry_of
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.markdown_escape import markdown_text
from empathy_zoo.metrics import WHOLE_NUMBER_METRICS
from empathy_zoo.names import positional_tool, tool_help
from leaderboard.aggregate import group_runs, load_results, score_runs
from leaderboard.improvement import VERDICT_MARKS, Improvement, improvements_over_dqn, is_dqn, uncompared_rows
from leaderboard.legends import holm_survivors, multiplicity_note
from leaderboard.multiplicity import HOLM_MARK
from leaderboard.tables import uncompared_note

PROG = "python -m leaderboard.versus_dqn"

__all__ = ["check_something_compared", "versus_dqn_tables", "compact_metrics"]


def compact_metrics(variant: str, env: str, metrics_of: Mapping[str, Sequence[str]] | None = None) -> tuple[str, ...]:
    """The metrics shown for ``variant`` of environment ``env``: ``metrics_of``'s, else the entry's
    :attr:`~empathy_zoo.environments.Environment.compact_metrics` (without ``metrics_of``, the
    variant's own entry first)."""
    given = (metrics_of or {}).get(variant)
    if given:
        return tuple(given)
    entry = entry_of(variant, env) if metrics_of is None else ENVIRONMENT_TABLE[env]
    return () if entry is None else entry.compact_metrics


def _format(value: float, metric: str) -> str:
    return f"{value:.0f}" if metric in WHOLE_NUMBER_METRICS else f"{value:.2f}"


def versus_dqn_tables(results: Sequence[RunResult], metrics_of: Mapping[str, Sequence[str]] | None = None) -> str:
    """Markdown: per variant, one row per method, a cell per metric ``▲ greedy / ▼ training``."""
    groups = group_runs(results)
    envs = {env: runs[0].env for (env, _), runs in groups.items()}
    metrics_of = {variant: compact_metrics(variant, env, metrics_of) for variant, env in envs.items()}
    scores = {(s.env, s.method_label, s.phase, s.metric): s for s in score_runs(results)}
    verdicts = {(c.env, c.method_label, c.phase, c.metric): c for c in improvements_over_dqn(results, metrics_of)}
    shown: list[Improvement] = []
    for variant, metrics in metrics_of.items():
        labels = [label for (env, label) in groups if env == variant]
        shown += [
            verdicts[key]
            for label in labels
            for metric in metrics
            for phase in ("eval", "train_final10")
            if (key := (variant, label, phase, metric)) in verdicts
        ]
    holm = {id(cell) for cell, keep in zip(shown, holm_survivors(shown), strict=True) if keep}
    uncompared = uncompared_rows(results)
    lines: list[str] = []
    for variant, metrics in metrics_of.items():
        labels = [label for (env, label) in groups if env == variant]
        dqn = [label for label in labels if all(is_dqn(run) for run in groups[(variant, label)])]
        seeds = {label: len(groups[(variant, label)]) for label in labels}

        def heading(row: str, metrics: Sequence[str] = metrics, variant: str = variant) -> str:
            return ", ".join(
                f"{m} {_format(scores[(variant, row, 'eval', m)].mean, m)} / "
                f"{_format(scores[(variant, row, 'train_final10', m)].mean, m)}"
                for m in metrics
            )

        if len(dqn) == 1:
            headings = [f"DQN ({seeds[dqn[0]]} seeds): {heading(dqn[0])} (greedy / training)."]
        else:  # (several DQN rows, of other budgets or worlds: each row is compared with its own)
            headings = [f"{markdown_text(row)} ({seeds[row]} seeds): {heading(row)} (greedy / training)." for row in dqn]
        lines += [
            f"### {variant}",
            "",
            "\n".join(headings),
            "",
            "| method | seeds | " + " | ".join(metrics) + " |",
            "|---|---|" + "---|" * len(metrics),
        ]
        for label in labels:
            if label in dqn:
                continue
            cells = []
            for metric in metrics:
                parts = []
                for phase in ("eval", "train_final10"):
                    cell = verdicts.get((variant, label, phase, metric))
                    mark = VERDICT_MARKS.get(cell.verdict, "") if cell is not None else ""
                    mark += HOLM_MARK if id(cell) in holm else ""
                    parts.append(f"{mark} {_format(scores[(variant, label, phase, metric)].mean, metric)}".strip())
                cells.append(" / ".join(parts))
            lines.append(f"| {markdown_text(label)} | {seeds[label]} | " + " | ".join(cells) + " |")
        lines.append("")
        note = uncompared_note(uncompared, variant, markdown=True)
        lines += [note, ""] if note else []
    if shown:
        lines += [
            "▲ / ▼: better / worse than DQN by the exact two-sided Mann–Whitney permutation test at 5 %; "
            "⊘: too few seeds for a verdict. " + multiplicity_note(shown, where="these tables hold"),
            "",
        ]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m leaderboard.versus_dqn RESULTS_DIR``: the tables against DQN, printed."""
    args = list(sys.argv[1:] if argv is None else argv)
    usage = f"usage: {PROG} RESULTS_DIR"
    if args in (["-h"], ["--help"]):
        print(tool_help(usage, __doc__))
        return 0
    return positional_tool(PROG, usage, args, 1, _print_tables)


def _print_tables(paths: list[str]) -> int:
    results = load_results(paths[0])
    check_something_compared(results, paths[0])
    print(versus_dqn_tables(results))
    return 0


def check_something_compared(results: Sequence[RunResult], where: str) -> None:
    """Refuse (``ValueError`` naming ``where`` and the rows) results of which no row but DQN's has a
    DQN row of its variant, budget and world to be compared with: the tables would mark nothing."""
    rows = [row for row, runs in group_runs(results).items() if not all(is_dqn(run) for run in runs)]
    uncompared = uncompared_rows(results)
    if len(uncompared) < len(rows):
        return
    if not rows:
        raise ValueError(f"{where} holds DQN runs only: no method to compare with DQN")
    named = ", ".join(f"{label} ({variant})" for variant, label in uncompared[:5])
    more = f" and {len(uncompared) - 5} more" if len(uncompared) > 5 else ""
    raise ValueError(
        f"{where} holds no DQN row of the variant, world and budget of any of its rows ({named}{more}): nothing is "
        "compared with DQN; add the DQN runs of the same sweep"
    )


if __name__ == "__main__":
    raise SystemExit(main())
