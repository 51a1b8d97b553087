"""Sweeps and their reports: ``reproduce`` (train a sweep, resumable, then write its
leaderboard), ``leaderboard``, ``reproduction`` (the paper's claims) and ``sensitivity``
(Sharing's claims per fidelity condition), the last three over existing result files."""

from __future__ import annotations

import argparse
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from empathy_zoo.cli.allow_import import add_allow_import
from empathy_zoo.cli.common import (
    PROG,
    RUN_DEFAULTS,
    add_runner_options,
    path_text,
    positive,
    print_written,
    read_results,
    runner_options,
)

if TYPE_CHECKING:
    from empathy_zoo.experiment.records import RunResult
    from empathy_zoo.training.options import RunnerOptions

__all__ = [
    "add_sweep_commands",
    "check_leaderboard_inputs",
    "cmd_leaderboard",
    "cmd_reproduce",
    "cmd_reproduction",
    "cmd_sensitivity",
]

PRODUCED_BY = "(the command that trained these runs is in each result file's config)"
"""What a report says produced its results when ``--produced-by`` does not."""


def cmd_reproduce(args: argparse.Namespace, command: str) -> int:
    """Train a sweep's missing runs, then write its leaderboard and (for the paper's) REPRODUCTION.md.
    SIGINT or SIGTERM stops the whole command, its reports as well as its training (exit 130 or
    143), even in a process started with SIGINT ignored (:func:`~empathy_zoo.training.runner.stopped_by_signals`)."""
    from empathy_zoo.training.runner import stopped_by_signals

    with stopped_by_signals():
        return _reproduce(args, command)


def _reproduce(args: argparse.Namespace, command: str) -> int:
    """What :func:`cmd_reproduce` does, once SIGINT and SIGTERM stop it."""
    from empathy_zoo.experiment.budget_fit import warmup_refusal
    from empathy_zoo.experiment.model import group_specs
    from empathy_zoo.experiment.sweep_file import load_sweep, profile_path, sweep_log
    from empathy_zoo.result_file import RUNS_DIR
    from empathy_zoo.training.runner import train_runs
    from leaderboard.report import write_leaderboard
    from leaderboard.reproduction import NotThePaperSweep, write_reproduction
    from leaderboard.row_names import reserved_label_reason

    path = profile_path(args.profile)
    specs = load_sweep(path, seeds=args.seeds)
    for spec in specs:  # (train_runs refuses it too; here the message can name the file)
        refusal = warmup_refusal(spec)
        if refusal is not None:
            raise ValueError(f"{path}: {refusal} (in its [settings], or in the method's [[methods]] table)")
        label = spec.display_label()
        reserved = reserved_label_reason(label, bool(spec.config()["description"]["dqn_reference"]))
        if reserved is not None:  # (the leaderboard would refuse the runs once trained: refuse now)
            raise ValueError(f"{path}: the label {label!r} of {spec.method} {reserved}; give the entry another label")
    out = Path(args.out) if args.out else Path("results") / path.stem
    values = {**RUN_DEFAULTS, **{k: v for k, v in vars(args).items() if k in RUN_DEFAULTS and v is not None}}
    values["progress"] = not args.no_progress
    if args.log is None:  # (--log, else the sweep file's, else none)
        values["log"] = sweep_log(path)
    ensembles = len(group_specs(specs, positive("max_parallel_runs", values["max_parallel_runs"])))
    if args.workers is None:  # one process per ensemble, as many as there are CPUs
        values["workers"] = max(1, min(os.cpu_count() or 1, ensembles))
    workers = values["workers"]
    options = runner_options(args, values)
    finished, done = read_results(specs, out)  # the leaderboard reads them all: refuse now, not after training
    check_leaderboard_inputs(specs, finished, out, rerun_changed=options.rerun_changed)  # (and its agents, evaluations)
    experiments = len({spec.experiment_id for spec in specs})
    print(
        f"{PROG}: sweep {path} — {len(specs)} runs ({experiments} experiments × {len(specs) // experiments} seeds) "
        f"in {ensembles} ensemble(s) on {workers} worker process(es); {done} already finished; results in {out}",
        flush=True,
    )
    ours = {f"{spec.run_id}.json" for spec in specs}
    others = sorted(p.name for p in finished if p.name not in ours)
    if others:
        print(
            f"{PROG}: note: {len(others)} result file(s) in {out / RUNS_DIR} are not part of this sweep "
            f"(e.g. {others[0]}); the leaderboard includes them",
            flush=True,
        )
    if args.dry_run:
        _check_without_writing(specs, out, options, finished)
        print(dry_run_plan(specs, finished, out, group_specs(specs, values["max_parallel_runs"]), workers), flush=True)
        return 0
    train_runs(specs, out, options, finished=finished)
    print_written(write_leaderboard(out, command=command))
    try:
        print(f"{PROG}: wrote {write_reproduction(out, command=command)}")
    except NotThePaperSweep as reason:
        print(f"{PROG}: no REPRODUCTION.md: {reason}; the paper's claims are judged only on its own experiments")
    return 0


def check_leaderboard_inputs(
    specs: Sequence[Any], finished: Mapping[Path, RunResult], out: Path, *, rerun_changed: bool = False
) -> None:
    """Refuse now, before ``reproduce`` trains or writes anything, what its leaderboard of ``out``
    would refuse once every run of ``specs`` is trained: the same ``ValueError``, one line naming
    the file. ``finished``: the result files of ``out`` (:func:`~empathy_zoo.cli.common.read_results`).

    * Agent files: of each row (variant and label), the run whose agent its "Greedy episodes" section
      loads (:func:`leaderboard.episodes.chosen_runs`, the lowest seed that kept one) is checked as
      that section checks it, without loading the agent (:func:`leaderboard.episodes.check_row_agent`:
      its world, and its file's SHA-256 against the one its result file records). A row is skipped
      where a run trained now has a lower seed (that run, not this one, is shown); so is every finished
      run of ``specs`` with ``rerun_changed`` (it may be trained again, its agent file replaced).
    * Evaluation files (``evaluations/*/*.json``): read and checked against the runs they evaluate as
      the "Held-out partners" section reads them (:func:`leaderboard.heldout_scores.load_heldout`).

    Cost: one read and SHA-256 of one agent file per row (each at most its cap, docs/limits.md), and a
    read of every evaluation file: what the leaderboard reads of them anyway, without loading a network."""
    from empathy_zoo.result_file import result_path
    from leaderboard.episodes import check_row_agent, chosen_runs
    from leaderboard.heldout_scores import load_heldout

    trained = {s.run_id for s in specs if rerun_changed or result_path(out, s.run_id) not in finished}
    kept = [result for result in finished.values() if result.run_id not in trained]
    lowest: dict[tuple[str, str], int] = {}  # (the lowest seed a run trained now has, by row)
    for spec in specs:
        if spec.run_id in trained:
            row = (spec.variant.label, spec.display_label())
            lowest[row] = min(lowest.get(row, spec.seed), spec.seed)
    origin = str(out)  # (as write_leaderboard(out) reads the directory)
    for row, (run, directory) in chosen_runs(kept, [origin] * len(kept)).items():
        if run.seed < lowest.get(row, run.seed + 1):
            check_row_agent(run, directory)
    load_heldout(out, kept)


def cmd_reproduction(args: argparse.Namespace, command: str) -> int:
    """Write REPRODUCTION.md of existing results (with the sensitivity sweeps' tables if given)."""
    from leaderboard.aggregate import load_results
    from leaderboard.beyond_paper import beyond_the_paper
    from leaderboard.reproduction import NotThePaperSweep, load_checked_results, missing_paper_experiments, write_reproduction
    from leaderboard.sensitivity import sensitivity_markdown

    out = _report_out(args) or Path(args.results) / "REPRODUCTION.md"  # (checked before anything is read)
    note = _read_note(args.note)
    _check_sweeps_apart(args)
    appendix = ""
    if args.sensitivity:
        appendix = sensitivity_markdown(
            load_results(args.sensitivity), _sweep_source(args.sensitivity, "sharing_sensitivity"), least_conditions=2
        )
    if args.coexistence_sensitivity:
        from leaderboard.coexistence_sensitivity import reproduction_section

        rules = reproduction_section(
            load_results(args.coexistence_sensitivity),
            _sweep_source(args.coexistence_sensitivity, "coexistence_sensitivity"),
            least_conditions=2,
        )
        appendix = "\n\n".join(part for part in (appendix, rules) if part)
    missing = missing_paper_experiments(load_checked_results(args.results))  # (a forged file: refused before any figure)
    if missing:  # (refused before any figure of the held-out section is drawn)
        raise NotThePaperSweep(f"these results do not contain the paper's experiments (missing: {', '.join(missing)})")
    beyond = beyond_the_paper(args.results, out)  # (the held-out evaluation, where the directory has one)
    appendix = "\n\n".join(part for part in (appendix, beyond) if part)
    written = write_reproduction(args.results, out, command=args.produced_by or PRODUCED_BY, note=note, appendix=appendix)
    print(f"{PROG}: wrote {written}")
    return 0


def _check_sweeps_apart(args: argparse.Namespace) -> None:
    """Refuse a directory given as two of ``reproduction``'s inputs (the results, ``--sensitivity``,
    ``--coexistence-sensitivity``; ``DIR`` and ``DIR/runs`` are one): one set of runs is no
    sensitivity sweep of itself."""
    from empathy_zoo.result_file import read_folder

    given = [("RESULTS_DIR", args.results), ("--sensitivity", args.sensitivity)]
    given.append(("--coexistence-sensitivity", args.coexistence_sensitivity))
    seen: dict[Path, str] = {}
    for option, path in given:
        if path is None:
            continue
        folder = read_folder(path)
        if folder in seen:
            raise ValueError(f"{option} {path} is given twice (as {seen[folder]} too): a sensitivity sweep is runs of its own")
        seen[folder] = f"{option} {path}" if option != "RESULTS_DIR" else f"the results directory {path}"


def _sweep_source(directory: str, profile: str) -> str:
    """What a sensitivity section says made its runs: their files, and the profile that trains such
    a sweep (the files do not record the command that trained them)."""
    return f"the result files in {directory} (empathy-zoo reproduce --profile {profile} --out {directory} trains such a sweep)"


def cmd_sensitivity(args: argparse.Namespace, command: str) -> int:
    """Write SENSITIVITY.md of existing results."""
    from leaderboard.sensitivity import write_sensitivity

    out = _report_out(args)  # (checked before anything is read)
    note = _read_note(args.note)
    print(f"{PROG}: wrote {write_sensitivity(args.results, out, command=args.produced_by or PRODUCED_BY, note=note)}")
    return 0


def _report_out(args: argparse.Namespace) -> Path | None:
    """Where a report goes: ``--out`` as given, or the report's own name inside it when it is an
    existing directory (``None``: the report's default, inside the results directory). Only a
    Markdown file name is taken (``.md``: never a result, agent or other file the command reads),
    never the ``--note`` file it reads, and its parent must be a directory; else a ``ValueError``
    naming ``--out``, before anything is read or written."""
    from empathy_zoo.names import check_output_file

    if args.out is None:
        return None
    out = Path(args.out)
    out = out / args.report_name if out.is_dir() and not out.is_symlink() else out
    if args.note and out.exists() and Path(args.note).exists() and out.samefile(args.note):
        raise ValueError(f"--out {out} is the --note file the report reads: name another file to write")
    try:
        check_output_file(out, "Markdown", ".md", args.report_name, _report_title(args.report_name).encode())
    except ValueError as error:
        raise ValueError(f"--out {error}") from None
    return out


def _report_title(report_name: str) -> str:
    """The first line of the report ``report_name`` (a file at ``--out`` that does not begin so is
    no such report, and is never replaced)."""
    if report_name == "SENSITIVITY.md":
        from leaderboard.sensitivity import REPORT_TITLE
    else:
        from leaderboard.reproduction import REPORT_TITLE
    return REPORT_TITLE


MAX_COMMAND_CHARS = 2_000
"""The longest ``--produced-by`` command a report shows."""


def _command_text(text: str) -> str:
    """``--produced-by``: one line of printable text of at most :data:`MAX_COMMAND_CHARS`
    characters (it is shown in the report's code block), else a usage error."""
    import argparse
    import unicodedata

    from empathy_zoo.names import LABEL_REFUSED_CATEGORIES

    if not text.strip() or len(text) > MAX_COMMAND_CHARS:
        raise argparse.ArgumentTypeError(f"a command of 1 to {MAX_COMMAND_CHARS:,} characters, got {len(text):,}")
    refused = next((c for c in text if unicodedata.category(c) in LABEL_REFUSED_CATEGORIES), None)
    if refused is not None:
        raise argparse.ArgumentTypeError(f"one line of printable text, got the character {refused!r}")
    return text


def _read_note(path: str | None) -> str:
    """The ``--note`` file's text (``""`` without one); one larger than
    :data:`~empathy_zoo.limits.MAX_NOTE_BYTES` is refused (``ValueError``), never read to its end,
    and so is one holding a control or format character but a line break or a tab (a NUL, an
    escape, a right-to-left override: the report is a page people read)."""
    import unicodedata

    from empathy_zoo.limits import MAX_NOTE_BYTES, read_bounded
    from empathy_zoo.names import LABEL_REFUSED_CATEGORIES

    if not path:
        return ""
    if Path(path).is_dir() or not Path(path).exists():
        what = "is a directory, not a file" if Path(path).is_dir() else "does not exist"
        raise ValueError(f"--note {path} {what} (give a Markdown file of prose)")
    try:
        text = read_bounded(path, MAX_NOTE_BYTES, "--note").decode("utf-8")
    except UnicodeDecodeError as error:
        raise ValueError(f"--note {path} is not UTF-8 text ({error})") from None
    text = text.replace("\r\n", "\n")  # (a note saved with Windows line ends reads as the same lines)
    for number, line in enumerate(text.split("\n"), 1):
        bad = next((c for c in line if c != "\t" and unicodedata.category(c) in LABEL_REFUSED_CATEGORIES), None)
        if bad is not None:
            name = unicodedata.name(bad, "")
            raise ValueError(
                f"--note {path}, line {number}: holds U+{ord(bad):04X}{f' {name}' if name else ''}; "
                "a note is lines of printable text"
            )
    return text


def _check_without_writing(specs: Sequence[Any], out: Path, options: RunnerOptions, finished: Mapping[Path, RunResult]) -> None:
    """What ``reproduce --dry-run`` checks of a sweep's training: every check ``train_runs`` makes
    before it writes (:func:`~empathy_zoo.training.runner.check_runs`, the same ``ValueError``), the
    checkpoints it would resume or set aside (:func:`~empathy_zoo.training.resume.survey_ensembles`), and
    of the output folders what needs no write (:func:`empathy_zoo.atomic.check_output_places`); its
    warnings are said on stderr as the real command says them. Nothing is created or written."""
    import sys

    from empathy_zoo.atomic import check_output_places
    from empathy_zoo.training.resume import survey_ensembles
    from empathy_zoo.training.runner import check_runs

    plan = check_runs(specs, out, options, finished=finished)
    check_output_places(out, plan.subdirs, plan.room)
    survey_ensembles(plan.todo, out, options.max_parallel_runs, every_run=specs)  # (the checkpoints: read, nothing changed)
    for warning in plan.warnings:
        print(f"{PROG}: {warning}", file=sys.stderr, flush=True)


def dry_run_plan(
    specs: Sequence[Any], finished: Mapping[Path, RunResult], out: Path, ensembles: Sequence[Sequence[Any]], workers: int
) -> str:
    """What ``reproduce --dry-run`` prints: one line per experiment (its runs, steps, how many are
    finished), the env steps left, and an estimate of the wall time from the rate the finished
    runs of ``out`` were trained at (their ``wall_time_s`` per step, the median), where it has any.
    Nothing is trained or written."""
    from empathy_zoo.result_file import result_path
    from empathy_zoo.training.runner import NOT_CHECKED_WITHOUT_WRITING

    done_ids = {result.run_id for result in finished.values()}
    lines = [
        f"{PROG}: dry run: nothing is trained or written",
        f"{PROG}: every check made before training passed, but those that need a write: {'; '.join(NOT_CHECKED_WITHOUT_WRITING)}",
    ]
    experiments: dict[str, list[Any]] = {}
    for spec in specs:
        experiments.setdefault(spec.experiment_id, []).append(spec)
    for runs in experiments.values():
        first = runs[0]
        done = sum(spec.run_id in done_ids for spec in runs)
        lines.append(
            f"  {first.variant.label} · {first.display_label()}: {len(runs)} run(s) × {first.budget.steps:,} steps, "
            f"{done} finished"
        )
    left = [ensemble for ensemble in ensembles if any(spec.run_id not in done_ids for spec in ensemble)]
    steps_left = sum(spec.budget.steps for spec in specs if spec.run_id not in done_ids)
    lines.append(f"{PROG}: {steps_left:,} env steps left in {len(left)} ensemble(s) on {workers} worker process(es)")
    rates = sorted(float(result.wall_time_s) / result.steps for result in finished.values() if result.wall_time_s is not None)
    if not rates:
        lines.append(
            f"{PROG}: no estimate of the time: {out} holds no finished run to measure the rate by "
            "(train one first, e.g. --seeds 1, and ask again)"
        )
        return "\n".join(lines)
    per_step = rates[len(rates) // 2]  # (seconds per env step of an ensemble, the median run's)
    seconds = sum(max(spec.budget.steps for spec in ensemble) for ensemble in left) * per_step / max(1, workers)
    lines.append(
        f"{PROG}: about {seconds / 60:,.0f} min of wall time at the rate of the {len(rates)} finished run(s) here "
        f"({per_step * 1000:.2f} ms per ensemble step); {result_path(out, 'x').parent} is where they are"
    )
    return "\n".join(lines)


def cmd_leaderboard(args: argparse.Namespace, command: str) -> int:
    """Write the leaderboard (Markdown, CSV, HTML) of existing results: one directory, or several
    into one leaderboard (``--out`` required; ``--label DIR=PREFIX`` prefixes a directory's labels);
    ``--evaluations DIR`` adds evaluation files kept apart from their runs."""
    from leaderboard.report import write_leaderboard
    from leaderboard.sources import parse_label_options

    if len(args.results) > 1 and args.out is None:
        raise ValueError(
            f"{len(args.results)} results directories: name the output directory with --out OUT "
            "(the leaderboard of several is written into none of them unless asked)"
        )
    labels = parse_label_options(args.label)
    results = args.results[0] if len(args.results) == 1 else args.results
    allowed = frozenset(args.allow_import or ())
    evaluations = args.evaluations or ()
    print_written(
        write_leaderboard(
            results, args.out, command=command, labels=labels or None, allowed_imports=allowed, evaluations=evaluations
        )
    )
    return 0


def add_sweep_commands(sub: Any) -> None:
    """The ``reproduce``, ``leaderboard``, ``reproduction`` and ``sensitivity`` subcommands."""
    reproduce = sub.add_parser("reproduce", help="train a sweep (resumable) and write its leaderboard")
    reproduce.add_argument(
        "--profile",
        required=True,
        metavar="quick|paper|PATH.toml",
        help="a shipped sweep (empathy_zoo/profiles/<name>.toml) or a sweep file",
    )
    reproduce.add_argument("--seeds", type=int, metavar="N", help="replace the sweep's seeds with 0..N-1")
    reproduce.add_argument("--out", type=path_text, metavar="DIR", help="output directory (default: results/<profile>)")
    reproduce.add_argument(
        "--dry-run",
        action="store_true",
        help="check everything the command checks before it trains (refused as it would be), then print the "
        "planned runs, what is finished and an estimate of the time; train and write nothing",
    )
    add_runner_options(reproduce)
    reproduce.set_defaults(handler=cmd_reproduce)

    board = sub.add_parser("leaderboard", help="write the leaderboard of existing results (one directory, or several into one)")
    board.add_argument(
        "results",
        type=path_text,
        metavar="DIR",
        nargs="+",
        help="results directory (with runs/ or *.json); several are read into one leaderboard, "
        "rows of different training budgets kept apart",
    )
    board.add_argument("--out", type=path_text, metavar="OUT", help="where to write (default: DIR; required with several DIRs)")
    board.add_argument(
        "--label",
        metavar="DIR=PREFIX",
        action="append",
        help="put PREFIX before every label of DIR's runs (repeatable): tells apart two directories' rows of one label",
    )
    board.add_argument(
        "--evaluations",
        type=path_text,
        metavar="EVAL_DIR",
        action="append",
        help="evaluation files kept apart from the runs (the --out of empathy-zoo evaluate; repeatable): each is "
        "matched to its run by run id and agent hash and shown in the held-out section as if it lay beside it; "
        "one of no run read, or of another agent than its run's result file records, is refused",
    )
    add_allow_import(board)
    board.set_defaults(handler=cmd_leaderboard)

    report = sub.add_parser("reproduction", help="check the paper's claims on existing results (REPRODUCTION.md)")
    _add_report_options(report, "a reproduce sweep", "REPRODUCTION.md")
    report.add_argument(
        "--sensitivity",
        metavar="DIR",
        help="results of the Sharing fidelity sweep (profile sharing_sensitivity): adds C5's table per condition",
    )
    report.add_argument(
        "--coexistence-sensitivity",
        metavar="DIR",
        help="results of the Coexistence rules sweep (profile coexistence_sensitivity): adds C1–C4's verdicts "
        "under the paper's and the authors' rules",
    )
    report.set_defaults(handler=cmd_reproduction)

    sensitivity = sub.add_parser("sensitivity", help="Sharing's claims per fidelity condition (SENSITIVITY.md)")
    _add_report_options(sensitivity, "a sharing_sensitivity sweep", "SENSITIVITY.md")
    sensitivity.set_defaults(handler=cmd_sensitivity)


def _add_report_options(parser: argparse.ArgumentParser, sweep: str, report: str) -> None:
    parser.add_argument("results", metavar="DIR", help=f"results directory of {sweep}")
    parser.add_argument(
        "--out",
        type=path_text,
        metavar="PATH",
        help=f"the file to write, or a directory to write {report} into (default: DIR/{report})",
    )
    parser.set_defaults(report_name=report)
    parser.add_argument(
        "--produced-by", metavar="COMMAND", type=_command_text, help="the command that produced the results, for the report"
    )
    parser.add_argument("--note", metavar="FILE.md", help="prose placed before the rules (how the run was made, what it shows)")
