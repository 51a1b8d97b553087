"""Every held-out reading of a results directory by the old rule and by the new one, side by side:

    python -m leaderboard.heldout_verdicts docs/results/methods

The new rule (:func:`leaderboard.heldout_scores.reading_rule`) says "generalises" only where the
method avoided the side effect beside its own partners (▲ against DQN there) and kept it beside
the held-out one; the old one (:func:`leaderboard.heldout_scores.old_reading_rule`) asked only the
second. Read from the directory's result and evaluation files; writes nothing. A directory with
no reading (no evaluation files) is refused in one line.
"""

from __future__ import annotations

import os
from collections import Counter
from collections.abc import Sequence
from dataclasses import replace

from empathy_zoo.names import positional_tool, tool_help
from leaderboard.aggregate import load_results
from leaderboard.heldout_scores import Reading, heldout_cells, load_heldout, readings
from leaderboard.tables import markdown_table

PROG = "python -m leaderboard.heldout_verdicts"

__all__ = ["heldout_verdicts", "verdicts_markdown"]


def heldout_verdicts(results_dir: str | os.PathLike[str]) -> list[Reading]:
    """The readings (old and new verdicts) of every method and held-out scenario of the directory;
    where an environment was evaluated in several scenario sets, each scenario is named with its
    set (``set: scenario``), so two sets' scenarios of one name stay apart."""
    groups, _ = load_heldout(results_dir, load_results(results_dir))
    sets = Counter(group.env for group in groups)
    return [
        reading if sets[group.env] == 1 else replace(reading, scenario=f"{group.scenario_set.name}: {reading.scenario}")
        for group in groups
        for reading in readings(group, heldout_cells(group))
    ]


def verdicts_markdown(rows: Sequence[Reading]) -> str:
    """A table of every reading's old and new verdict, and counts of each."""
    header = ["environment", "method", "scenario", "vs DQN with own partners", "vs DQN here", "old rule", "new rule"]
    body = [
        [
            r.env,
            r.method_label,
            r.scenario,
            r.trained_versus_dqn or "no DQN",
            r.versus_dqn or "no DQN",
            r.old_verdict,
            r.verdict + (" (changed)" if r.verdict != r.old_verdict else ""),
        ]
        for r in rows
    ]
    changed = sum(r.verdict != r.old_verdict for r in rows)
    counts = Counter((r.env, r.old_verdict, r.verdict) for r in rows)
    summary = [f"- {env}: {old} → {new}: {n}" for (env, old, new), n in sorted(counts.items())]
    table = markdown_table(header, body, text_columns=3)  # (environment, label, scenario: data, as text)
    return "\n".join([table, "", f"changed: {changed} of {len(rows)}", *summary])


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m leaderboard.heldout_verdicts RESULTS_DIR``: every held-out reading, old rule beside new."""
    import sys

    args = list(sys.argv[1:] if argv is None else argv)
    usage = f"usage: {PROG} RESULTS_DIR"
    if args in (["-h"], ["--help"]):
        print(tool_help(usage, __doc__))
        return 0
    return positional_tool(PROG, usage, args, 1, _print_verdicts)


def _print_verdicts(paths: list[str]) -> int:
    rows = heldout_verdicts(paths[0])
    if not rows:  # ("changed: 0 of 0" would read as "no verdict moved")
        raise ValueError(
            f"{paths[0]} holds no held-out reading (no evaluation beside held-out partners of a method and of DQN): "
            f"run empathy-zoo evaluate {paths[0]} --scenarios SET first"
        )
    print(verdicts_markdown(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
