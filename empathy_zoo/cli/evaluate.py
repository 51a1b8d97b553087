"""``evaluate``: play every kept agent of a results directory beside held-out partners.

    empathy-zoo evaluate RESULTS_DIR [--scenarios NAME_OR_FILE ...] [--episodes N] [--out DIR] [--threads N] [--no-progress]
                        [--allow-import MODULE:NAME ...]

Writes ``<out>/evaluations/<scenario set>/<run id>.json`` (:mod:`empathy_zoo.training.heldout`);
run again, it skips what is done. ``empathy-zoo leaderboard`` then adds a "Held-out partners"
section per environment (:mod:`leaderboard.heldout`).
"""

from __future__ import annotations

import argparse
from typing import Any

from empathy_zoo.cli.allow_import import add_allow_import
from empathy_zoo.cli.common import PROG, add_progress_style, path_text

__all__ = ["add_evaluate", "cmd_evaluate"]


def cmd_evaluate(args: argparse.Namespace, command: str) -> int:
    """Evaluate the kept agents; print what was written, skipped and left out. SIGINT or SIGTERM
    stops it (exit 130 or 143), even in a process started with SIGINT ignored; the files it wrote
    are kept, and it removes its lock and the folders it made while empty."""
    from empathy_zoo.training.runner import stopped_by_signals

    with stopped_by_signals():
        return _evaluate(args)


def _evaluate(args: argparse.Namespace) -> int:
    """What :func:`cmd_evaluate` does, once SIGINT and SIGTERM stop it."""
    from empathy_zoo.training.heldout import evaluate_results

    if args.episodes is not None and args.episodes < 1:
        raise ValueError(f"--episodes must be positive, got {args.episodes}")
    options: dict[str, Any] = {} if args.episodes is None else {"episodes": args.episodes}
    summary = evaluate_results(
        args.results,
        args.scenarios,
        out_dir=args.out,
        progress=not args.no_progress,
        progress_style=args.progress_style,
        threads=args.threads,
        allowed_imports=frozenset(args.allow_import or ()),
        **options,
    )
    if summary.without_agent:
        print(
            f"{PROG}: note: {len(summary.without_agent)} run(s) kept no trained agent and are not evaluated "
            f"(e.g. {summary.without_agent[0]})",
            flush=True,
        )
    if summary.without_set:
        print(
            f"{PROG}: note: {len(summary.without_set)} run(s) are of an environment no scenario set is for "
            f"(e.g. {summary.without_set[0]})",
            flush=True,
        )
    if summary.done:
        print(f"{PROG}: {len(summary.done)} evaluation file(s) already there, skipped", flush=True)
    for path in summary.written:
        print(f"{PROG}: wrote {path}", flush=True)
    return 0


def add_evaluate(sub: Any) -> None:
    """The ``evaluate`` subcommand."""
    from empathy_zoo.scenarios import shipped_sets
    from empathy_zoo.training.heldout import DEFAULT_EPISODES

    parser = sub.add_parser("evaluate", help="play every kept agent beside partners it never trained with")
    parser.add_argument("results", type=path_text, metavar="RESULTS_DIR", help="results directory (with runs/ or *.json)")
    parser.add_argument(
        "--scenarios",
        action="append",
        metavar="NAME_OR_FILE",
        help=f"a shipped scenario set ({', '.join(shipped_sets())}) or a scenario TOML file; repeat for several "
        "(default: the shipped set of each environment)",
    )
    parser.add_argument(
        "--episodes", type=int, metavar="N", help=f"greedy episodes per run and scenario (default: {DEFAULT_EPISODES})"
    )
    parser.add_argument(
        "--out",
        type=path_text,
        metavar="DIR",
        help="where evaluations/ goes (default: RESULTS_DIR, DIR for DIR/runs); not another results directory",
    )
    parser.add_argument(
        "--threads",
        type=int,
        default=1,
        metavar="N",
        help="torch CPU threads (default: 1; the agents' small products gain nothing from more, and extra threads "
        "are much slower on a busy machine; what is computed does not depend on it)",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_progress_style(parser)
    add_allow_import(parser)
    parser.set_defaults(handler=cmd_evaluate)
