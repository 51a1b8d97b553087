"""The ``empathy-zoo`` command line: train runs, reproduce a sweep, write the leaderboard.

    empathy-zoo train --env coexistence_v0 --method empathic_dqn --selfishness 0.5 --steps 1000000 --seed 0 --out runs/
    empathy-zoo reproduce --profile quick            # sweep + leaderboard into results/quick/
    empathy-zoo leaderboard results/quick [--out DIR] [--evaluations EVAL_DIR]
    empathy-zoo methods | policies                   # what is registered
    empathy-zoo play --env sharing_v0 --episodes 3 --render ansi
    empathy-zoo watch RUN_ID [--dir runs] [--gif episode.gif]   # a trained agent's greedy episodes
    empathy-zoo evaluate results/quick                # kept agents beside partners they never met
    empathy-zoo export results/quick --format marl-eval --out quick.json   # results in marl-eval's JSON
    empathy-zoo tune methods --method dqn --env coexistence_v0 --param learning_rate=log:1e-4:3e-3   # Optuna
    empathy-zoo analyse compare-runs OLD_DIR NEW_DIR    # the analysis tools (analyse --help lists them)

``train`` takes one ``--<field>`` option per field of the method's settings and of its reward
transform (see ``empathy-zoo train --method NAME --help``); the method is ``--method``, else
``method`` in the ``--config`` file. Its precedence: built-in defaults < the ``--config`` TOML file
(``[settings]`` for method settings, ``[reward]`` for the reward transform's fields, top-level keys
for the run) < the command line. A bad input prints
``empathy-zoo: error: <message>`` and exits with status 2, before any training; a write or an
allocation that fails later prints one such line too, with status 1. Ctrl-C (or SIGINT, SIGTERM
while runs train) stops it with status 130 (143 for SIGTERM); the same command resumes.

One module per group of subcommands: :mod:`~empathy_zoo.cli.train` (with
:mod:`~empathy_zoo.cli.settings_options`, a method's settings as options),
:mod:`~empathy_zoo.cli.sweep` (reproduce, leaderboard, reproduction, sensitivity),
:mod:`~empathy_zoo.cli.browse` (methods, policies, play), :mod:`~empathy_zoo.cli.watch` (watch),
:mod:`~empathy_zoo.cli.evaluate` (evaluate), :mod:`~empathy_zoo.cli.export` (export),
:mod:`~empathy_zoo.cli.tune` (tune), :mod:`~empathy_zoo.cli.analyse` (analyse); what they share is in
:mod:`~empathy_zoo.cli.common`.
"""

from __future__ import annotations

import argparse
import io
import shlex
import signal
import sys
from collections.abc import Sequence
from typing import NoReturn

from empathy_zoo.cli.analyse import add_analyse
from empathy_zoo.cli.browse import add_browse_commands
from empathy_zoo.cli.common import PROG, RUN_DEFAULTS
from empathy_zoo.cli.evaluate import add_evaluate
from empathy_zoo.cli.export import add_export
from empathy_zoo.cli.sweep import add_sweep_commands
from empathy_zoo.cli.train import RUN_KEYS, add_train, train_method
from empathy_zoo.cli.tune import add_tune
from empathy_zoo.cli.watch import add_watch
from empathy_zoo.names import terminal_line

__all__ = ["main", "build_parser", "parse_args", "RUN_KEYS", "RUN_DEFAULTS"]

INTERRUPTED = 128
"""An interrupted command exits with this plus the signal's number (130 for SIGINT, 143 for SIGTERM)."""


class OneLineParser(argparse.ArgumentParser):
    """An argument parser whose usage error is one line on standard error, ``PROG COMMAND: error:
    MESSAGE (see PROG COMMAND --help)`` (the hint left out where the message names a help already),
    status 2 (argparse's own prints the whole usage first);
    its subcommands' parsers are of the same class."""

    def error(self, message: str) -> NoReturn:
        see = "" if "--help" in message else f" (see {self.prog} --help)"
        self.exit(2, f"{self.prog}: error: {terminal_line(message)}{see}\n")


def build_parser(method: str = RUN_DEFAULTS["method"]) -> argparse.ArgumentParser:
    """The whole command line, ``train`` with the settings options of ``method``."""
    parser = OneLineParser(prog=PROG, description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    add_train(sub, method)
    add_sweep_commands(sub)
    add_browse_commands(sub)
    add_watch(sub)
    add_evaluate(sub)
    add_export(sub)
    add_tune(sub)
    add_analyse(sub)
    return parser


def parse_args(argv: Sequence[str]) -> argparse.Namespace:
    """Parse ``argv`` in two stages: the method ``train`` trains, then every option (that
    method's settings included). An unknown option of ``train`` is refused naming the settings
    the method takes; argparse exits (``SystemExit``) on ``--help`` and on usage errors."""
    argv = list(argv)
    command = next((i for i, arg in enumerate(argv) if not arg.startswith("-")), None)
    method = RUN_DEFAULTS["method"]
    if command is not None and argv[command] == "train":
        method = train_method(argv[command + 1 :])
    parser = build_parser(method)
    args, unknown = parser.parse_known_args(argv)
    if unknown:
        message = f"unrecognized arguments: {' '.join(unknown)}"
        if args.command == "train":
            from baselines.registry import get_method
            from empathy_zoo.experiment.values import field_types

            chosen = get_method(method)
            names = ", ".join(field_types(chosen.settings))
            fields_of_reward = ", ".join(chosen.reward_fields())
            reward = f"; the fields of its reward transform are {fields_of_reward}" if fields_of_reward else ""
            message += f" (the settings of method {method!r} are {names}{reward}; see {PROG} train --method {method} --help)"
        parser.error(message)
    return args


def _error(error: object, status: int) -> int:
    print(f"{PROG}: error: {terminal_line(error)}", file=sys.stderr)
    return status


def _allocation_failure(error: BaseException) -> bool:
    """Whether ``error`` is an allocation that failed (torch reports one as a ``RuntimeError``,
    ``torch.OutOfMemoryError`` on a GPU), not some other ``RuntimeError``, whose traceback stays."""
    text = str(error).lower()
    return type(error).__name__ == "OutOfMemoryError" or any(
        words in text for words in ("can't allocate memory", "cannot allocate memory", "out of memory", "not enough memory")
    )


def _out_of_memory(error: BaseException) -> str:
    first = str(error).strip().splitlines()[0][:300] if str(error).strip() else type(error).__name__
    return (
        f"out of memory ({first}); train fewer runs at once (--max-parallel-runs), or smaller networks or replay "
        "memories (--hidden-size, --replay-capacity); docs/limits.md says what a run needs"
    )


def _utf8(text: str) -> bool:
    """Whether ``text`` encodes as UTF-8 (a path of undecodable bytes holds lone surrogates, which do not)."""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        return False
    return True


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line ``argv`` (default: ``sys.argv[1:]``); returns the exit status."""
    argv = list(sys.argv[1:] if argv is None else argv)
    for stream in (sys.stdout, sys.stderr):  # (a name from disk that is no UTF-8 text is printed escaped, never fatal)
        if isinstance(stream, io.TextIOWrapper):
            stream.reconfigure(errors="backslashreplace")
    unreadable = next((item for item in argv if not _utf8(item)), None)
    if unreadable is not None:  # (before anything is read or written: the command line is recorded in what it writes)
        return _error(
            ValueError(
                f"argument {unreadable!a} is not UTF-8 text; the suite records its command line in what it "
                "writes: rename the path (or give another)"
            ),
            2,
        )
    try:
        args = parse_args(argv)
    except SystemExit as exit_:  # argparse: --help (0) or a usage error (2, message printed)
        return int(exit_.code or 0)
    except ValueError as error:  # the method to train, or its --config file, is bad
        return _error(error, 2)
    command = shlex.join([PROG, *argv])
    try:
        return args.handler(args, command)
    except ValueError as error:
        return _error(error, 2)
    except OSError as error:  # a write that failed mid-way (disk full, a directory removed): no traceback
        return _error(error, 1)
    except MemoryError as error:  # an allocation the checks before training could not foresee
        return _error(_out_of_memory(error), 1)
    except RuntimeError as error:
        if not _allocation_failure(error):
            raise
        return _error(_out_of_memory(error), 1)
    except KeyboardInterrupt as interrupt:  # Ctrl-C, or a stop signal while runs train (128 + its number)
        print(f"{PROG}: interrupted; run the same command again to resume (what it finished is kept)", file=sys.stderr)
        return INTERRUPTED + int(getattr(interrupt, "signum", signal.SIGINT))
