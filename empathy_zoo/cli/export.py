"""``export``: existing result files in another benchmark's exchange format.

    empathy-zoo export RESULTS_DIR [RESULTS_DIR ...] --format marl-eval --out FILE.json [--label DIR=PREFIX ...]

``marl-eval`` (:mod:`leaderboard.export_marl_eval`) is the JSON layout marl-eval and BenchMARL
read, environment → task → algorithm → run → step; the runs of several directories are read as
``empathy-zoo leaderboard`` reads them (:func:`leaderboard.sources.load_results_dirs`: a label of
two experiments in two directories is refused; ``--label DIR=PREFIX`` tells them apart).
"""

from __future__ import annotations

import argparse
from typing import Any

from empathy_zoo.cli.common import PROG, path_text

__all__ = ["EXPORT_FORMATS", "add_export", "cmd_export"]

EXPORT_FORMATS = ("marl-eval",)
"""The formats ``export --format`` writes."""


def cmd_export(args: argparse.Namespace, command: str) -> int:
    """Write the runs of the results directories in the chosen format; print what was written."""
    from leaderboard.export_marl_eval import write_marl_eval
    from leaderboard.sources import parse_label_options

    if args.format not in EXPORT_FORMATS:  # (argparse refuses it first; a caller building args may not)
        raise ValueError(f"--format {args.format!r} is not one this suite writes ({', '.join(EXPORT_FORMATS)})")
    try:
        written = write_marl_eval(args.results, args.out, parse_label_options(args.label) or None)
    except OSError as error:  # (checked before reading; a write can still fail: a full disk, no permission)
        raise OSError(f"--out {args.out}: cannot write it ({error.strerror or error})") from None
    print(
        f"{PROG}: wrote {written.path} ({args.format}: {written.runs} runs of {written.algorithms} algorithms "
        f"on {written.tasks} tasks of {written.environments} environments)"
    )
    return 0


def add_export(sub: Any) -> None:
    """The ``export`` subcommand."""
    export = sub.add_parser("export", help="write existing results in another benchmark's format (marl-eval JSON)")
    export.add_argument(
        "results",
        type=path_text,
        metavar="DIR",
        nargs="+",
        help="results directory (with runs/ or *.json); several are read into one file",
    )
    export.add_argument(
        "--format",
        required=True,
        choices=EXPORT_FORMATS,
        help="marl-eval: environment → task → algorithm → run → step JSON (docs/formats.md)",
    )
    export.add_argument("--out", type=path_text, required=True, metavar="FILE.json", help="the JSON file to write (atomically)")
    export.add_argument(
        "--label",
        metavar="DIR=PREFIX",
        action="append",
        help="put PREFIX before every label of DIR's runs (repeatable): tells apart two directories' rows of one label",
    )
    export.set_defaults(handler=cmd_export)
