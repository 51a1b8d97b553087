"""``analyse``: the suite's analysis tools, one command each, run as ``python -m MODULE`` runs them.

    empathy-zoo analyse TOOL [ARGS ...]
    empathy-zoo analyse compare-runs OLD_DIR NEW_DIR

Each tool is a module's ``main(argv)`` (:data:`TOOLS`); ``analyse`` hands it the arguments after
its name, unchanged, so ``empathy-zoo analyse TOOL --help`` prints the tool's own help. The
modules stay runnable as ``python -m MODULE`` too.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import io
import sys
from dataclasses import dataclass
from typing import Any, TextIO

from empathy_zoo.cli.common import PROG

__all__ = ["TOOLS", "Tool", "add_analyse", "cmd_analyse"]


@dataclass(frozen=True)
class Tool:
    """One analysis tool: the module whose ``main(argv)`` runs it, and what it does in one line."""

    module: str
    summary: str


TOOLS: dict[str, Tool] = {
    "compare-runs": Tool("leaderboard.compare_runs", "which runs of two results directories computed the same thing"),
    "equivalence": Tool("leaderboard.equivalence", "per-cell tests of a difference (and TOST) between two run sets"),
    "versus-dqn": Tool("leaderboard.versus_dqn", "each method against DQN, seed for seed, as tables"),
    "verdict-changes": Tool("leaderboard.verdict_changes", "the ▲/▼ marks that differ between two leaderboard pages"),
    "heldout-verdicts": Tool("leaderboard.heldout_verdicts", "every held-out reading of a directory, old rule beside new"),
    "coexistence-sensitivity": Tool("leaderboard.coexistence_sensitivity", "the claims under the authors' Coexistence rules"),
    "tuning-summary": Tool("leaderboard.tuning_summary", "what each tuned method chose, and its trials figure"),
    "tuning-effect": Tool("leaderboard.tuning_effect", "tuned against untuned rows, verdict by verdict"),
    "exact": Tool("empathy_zoo.exact_solver", "a task's exact optimum per β and ε, from the engine's own rules"),
    "separation": Tool("baselines.separation_render", "a task's exact separation table (JSON and Markdown)"),
    "population-reading": Tool("leaderboard.population_reading", "population-trained against default-trained runs, test split"),
    "separation-reading": Tool("leaderboard.separation_reading", "trained runs judged against the exact separation tables"),
    "discrimination": Tool(
        "leaderboard.trained_discrimination", "method pairs × tasks from the exact separation tables (and trained runs)"
    ),
}
"""Every tool ``analyse`` runs, by the name it takes."""


def cmd_analyse(args: argparse.Namespace, command: str) -> int:
    """Run the chosen tool's ``main`` on the remaining arguments; its exit status is the command's."""
    tool = TOOLS[args.tool]
    main = importlib.import_module(tool.module).main
    renamed = _Renamed(sys.stderr, f"python -m {tool.module}", f"{PROG} analyse {args.tool}")
    helped = _Renamed(sys.stdout, f"python -m {tool.module}", f"{PROG} analyse {args.tool}")
    asks_help = any(
        arg in ("-h", "--help") for arg in args.args
    )  # (its help names the command typed; other output is the tool's)
    try:
        with contextlib.redirect_stderr(renamed), contextlib.redirect_stdout(helped if asks_help else sys.stdout):
            status = main(list(args.args))
    except SystemExit as exit_:  # a tool's own usage message (a string) or status
        if isinstance(exit_.code, str):
            print(renamed.rename(exit_.code), file=sys.stderr)
            return 2
        return int(exit_.code or 0)
    return int(status or 0)


class _Renamed(io.TextIOBase):
    """A text stream that writes to ``stream`` at once, with the tool's name as ``python -m``
    knows it (``old``) written as ``analyse`` names it (``new``): a message names the command
    the user typed."""

    def __init__(self, stream: TextIO, old: str, new: str) -> None:
        self._stream, self._old, self._new = stream, old, new

    def rename(self, text: str) -> str:
        """``text`` with the tool's ``python -m`` name written as ``analyse`` names it."""
        return text.replace(self._old, self._new)

    def write(self, text: str) -> int:
        self._stream.write(self.rename(text))
        return len(text)

    def flush(self) -> None:
        self._stream.flush()

    def isatty(self) -> bool:
        return self._stream.isatty()


def add_analyse(sub: Any) -> None:
    """The ``analyse`` subcommand."""
    listing = "; ".join(f"{name}: {tool.summary}" for name, tool in TOOLS.items())
    parser = sub.add_parser(
        "analyse",
        help="the analysis tools (compare runs, equivalence, separation tables, ...): TOOL --help for each",
        description=f"Run one of the suite's analysis tools. {listing}.",
    )
    parser.add_argument("tool", choices=list(TOOLS), metavar="TOOL", help=f"one of {', '.join(TOOLS)}")
    parser.add_argument("args", nargs=argparse.REMAINDER, metavar="ARGS", help="the tool's own arguments")
    parser.set_defaults(handler=cmd_analyse)
