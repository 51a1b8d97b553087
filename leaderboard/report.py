"""Write the whole leaderboard of a results directory (or of several): Markdown, CSV, HTML and PNG figures."""

from __future__ import annotations

import os
import re
import secrets
import shutil
import stat
import sys
from collections.abc import Callable, Collection, Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path

from empathy_zoo.atomic import (
    TEMP_MARKER,
    TEMP_SUFFIX,
    check_output_dir,
    check_output_folders,
    process_alive,
    remove_stale_temp_files,
    write_text_atomic,
)
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.names import GIF_OPENING, PNG_OPENING, check_no_links, check_own_file, check_replaceable
from empathy_zoo.output_lock import hold_output_dir
from empathy_zoo.policies import check_allowed_imports_named
from empathy_zoo.provenance import git_commit, package_version
from leaderboard.aggregate import (
    CONFIDENCE,
    DEFAULT_SEED,
    FINAL_FRACTION,
    N_POINTS,
    N_RESAMPLES,
    group_runs,
    score_runs,
)
from leaderboard.budgets import budgets_of
from leaderboard.constraint_section import constraint_section
from leaderboard.discrimination_section import discrimination_section
from leaderboard.episodes import episodes_section
from leaderboard.evaluation_dirs import MatchedEvaluation, match_evaluations
from leaderboard.heldout import heldout_section
from leaderboard.improvement import improvements_over_dqn, uncompared_rows
from leaderboard.leaderboard_page import TITLE, TRADEOFF, definitions_section, leaderboard_page, score_sections
from leaderboard.page import Section
from leaderboard.page_html import to_html
from leaderboard.page_markdown import markdown_text, to_markdown
from leaderboard.plots import plot_learning_curves
from leaderboard.profile_section import profile_section
from leaderboard.reference_curves import reference_refusals
from leaderboard.row_names import dqn_rows_of, renaming_note
from leaderboard.sources import ResultSet, load_results_dirs
from leaderboard.tables import Provenance, RowFacts, csv_text, env_metrics
from leaderboard.tradeoff import plot_tradeoffs

__all__ = ["MARKDOWN_NAME", "CSV_NAME", "HTML_NAME", "FIGURES_DIR", "write_leaderboard"]

MARKDOWN_NAME = "LEADERBOARD.md"
CSV_NAME = "leaderboard.csv"
HTML_NAME = "leaderboard.html"
FIGURES_DIR = "figures"
STAGE_PREFIX = ".leaderboard."
"""Name prefix of the directory a leaderboard is rendered into inside its output directory
(``.leaderboard.ezoo-<pid>-<random>.tmp``) before its files are moved into place."""
PAGES = ("csv", "markdown", "html")
"""The pages, in the order they are put in place (after every figure)."""
_STAGE = re.compile(rf"{re.escape(STAGE_PREFIX)}{TEMP_MARKER}-(?P<pid>[1-9][0-9]{{0,9}})-[0-9a-f]{{8}}{re.escape(TEMP_SUFFIX)}")
_ATOMIC_TEMP = re.compile(rf"\.{TEMP_MARKER}-\d+-[0-9a-f]{{8}}{re.escape(TEMP_SUFFIX)}$")


def write_leaderboard(
    results_dir: str | os.PathLike[str] | Sequence[str | os.PathLike[str]],
    out_dir: str | os.PathLike[str] | None = None,
    command: str | None = None,
    *,
    labels: Mapping[str | os.PathLike[str], str] | None = None,
    n_points: int = N_POINTS,
    random_state: int = DEFAULT_SEED,
    n_resamples: int = N_RESAMPLES,
    confidence: float = CONFIDENCE,
    final_fraction: float = FINAL_FRACTION,
    on_note: Callable[[str], None] | None = None,
    allowed_imports: Collection[str] = (),
    evaluations: Sequence[str | os.PathLike[str]] = (),
) -> dict[str, Path]:
    """Score every result file of ``results_dir`` and write the leaderboard into ``out_dir``.

    ``results_dir`` holds the ``*.json`` result files, or is a sweep's output directory with
    them in ``runs/``; or it is a list of such directories, read into one leaderboard
    (:func:`leaderboard.sources.load_results_dirs`: ``labels`` maps a directory to the prefix of
    its labels; rows of different budgets are kept apart). ``out_dir`` defaults to ``results_dir``
    for one directory and is required for several (``ValueError``: nothing is written into a
    directory read unless asked). ``command`` is printed as the command that produced the
    leaderboard (default: the equivalent Python call). A leaderboard of several directories, of
    several budgets or with prefixed labels names every directory read (with the versions and
    commits its files record) and the budgets in its header, each row's DQN row in its
    probability-of-improvement tables, and each row's budget and directories in its CSV
    (:data:`leaderboard.tables.COMPARISON_CSV_COLUMNS`); that of one directory of one budget is
    written as it always was. A DQN reference row is shown as DQN whatever its result files label
    it (:mod:`leaderboard.row_names`; the CSV too, as it shows prefixes), and the pages say which
    rows are the reference and which labels were shown as DQN.

    Writes, all atomically: ``LEADERBOARD.md``, ``leaderboard.csv``, ``leaderboard.html`` and
    ``figures/<env>_<metric>.png`` (learning curves) and ``figures/<env>_tradeoff.png`` (task against
    side effect, :mod:`leaderboard.tradeoff`); ``figures/<env>_profiles.png`` (performance profiles,
    beside an optimality-gap table, where the env has a normalized metric:
    :mod:`leaderboard.profile_section`); where runs kept their trained agents, one greedy
    episode per variant and row, ``figures/<env>_<row slug>_episode.gif``, in a "Greedy episodes"
    section (:mod:`leaderboard.episodes`; an agent file changed since its run wrote it raises
    ``ValueError``). Returns ``{"markdown", "csv", "html": path}`` plus ``"figure:<env>:<metric>": path``
    for every figure (``<metric>`` is ``tradeoff`` for the trade-off, ``profiles`` for the
    performance profiles, ``episode_<row slug>`` for an episode). No result file raises ``ValueError``.

    Every input is read and checked before anything is written (result files, labels, agent
    files, the output directory and its links): the leaderboard is rendered into a directory of its
    own inside ``out_dir`` (``.leaderboard.ezoo-<pid>-<random>.tmp``), and only once all of it is there
    are its files moved into place, figures first, pages last. A refusal (``ValueError``) or a write
    that fails (an ``OSError`` naming the file, e.g. on a full disk) leaves ``out_dir`` as it was:
    the staging directory is removed, and so is ``out_dir`` when this call created it. A run whose
    curves get no exact reference because its γ is 1, its grid or episodes are beyond
    :data:`~empathy_zoo.limits.MAX_REFERENCE_SIZE` or :data:`~empathy_zoo.limits.MAX_REFERENCE_CYCLES`,
    or the page's reference curves would pass :data:`~empathy_zoo.limits.MAX_REFERENCE_WORK`,
    is said in one line through ``on_note`` (default: stderr). A second leaderboard into the same
    ``out_dir`` meanwhile is refused, naming this one (the lock is ``figures/``'s, so training may
    go on in the directory: :func:`empathy_zoo.output_lock.hold_output_dir`). A run whose recorded partner is a
    plug-in policy gets no greedy episode unless the plug-in is in ``allowed_imports``: a result
    file never makes the leaderboard import code.

    ``evaluations`` names directories of evaluation files kept apart from their runs (what
    ``empathy-zoo evaluate --out DIR`` wrote): each file is read, checked and matched to its run by
    run id and agent hash (:func:`leaderboard.evaluation_dirs.match_evaluations`) before anything is
    written, and the "Held-out partners" section reads it as if it lay beside its run. An
    evaluation of no run read, or of another agent than its run's result file records, raises
    ``ValueError`` naming the file.
    """
    several = not isinstance(results_dir, (str, os.PathLike))
    dirs: list[str | os.PathLike[str]] = [results_dir] if isinstance(results_dir, (str, os.PathLike)) else list(results_dir)
    if len(dirs) > 1 and out_dir is None:
        raise ValueError(
            f"a leaderboard of {len(dirs)} results directories needs an output directory (--out OUT): "
            "it is written into none of the directories it reads unless asked"
        )
    read = load_results_dirs(dirs, labels, dqn_named=True)
    matched = match_evaluations(evaluations, read.results, dirs, read.origins)
    out = _checked_out(Path(dirs[0] if out_dir is None else out_dir))
    for (env, label), refusal in reference_refusals(group_runs(read.results), n_points).items():
        (on_note or _print_note)(f"no reference curve (the exact optimum) beside {label} on {env}: {refusal}")
    call = repr(str(dirs[0])) if not several else repr([str(directory) for directory in dirs])
    call += f", {str(out_dir)!r}" if several and out_dir is not None else ""
    command = command if command is not None else f"leaderboard.write_leaderboard({call})"
    created = [directory for directory in (out / FIGURES_DIR, out, *out.parents) if not directory.exists()]
    try:
        with hold_output_dir(out / FIGURES_DIR, command), _staging(out) as stage:  # (one leaderboard at a time)
            staged = _render(
                dirs,
                read,
                stage,
                command,
                comparison=len(dirs) > 1 or bool(labels) or read.budget_in_labels,
                n_points=n_points,
                random_state=random_state,
                n_resamples=n_resamples,
                confidence=confidence,
                final_fraction=final_fraction,
                allowed_imports=allowed_imports,
                evaluations=matched,
            )
            _check_targets(staged, stage, out)  # (every file's place, before a directory is made or a file moved)
            check_output_dir(out, (FIGURES_DIR,))
            for directory in (out, out / FIGURES_DIR):  # what writes killed mid-way left here
                remove_stale_temp_files(directory)
            return _publish(staged, stage, out)
    except BaseException:
        for directory in created:  # (only the directories this call made, and only while empty)
            if not directory.is_dir() or directory.is_symlink():
                continue  # (not made before the refusal)
            try:
                directory.rmdir()
            except OSError:
                break
        raise


def _render(
    dirs: Sequence[str | os.PathLike[str]],
    read: ResultSet,
    out: Path,
    command: str,
    *,
    comparison: bool,
    n_points: int,
    random_state: int,
    n_resamples: int,
    confidence: float,
    final_fraction: float,
    allowed_imports: Collection[str] = (),
    evaluations: Sequence[MatchedEvaluation] = (),
) -> dict[str, Path]:
    """Write every file of the leaderboard of ``read`` into ``out`` (a staging directory: the
    pages link their figures relative to it); returns them as :func:`write_leaderboard` names them."""
    results = read.results
    fixed = (label for run in results for label in run.config.fixed.values())
    check_allowed_imports_named(allowed_imports, fixed, "of the result files read")  # (before any figure)
    dqn_rows = dqn_rows_of(results)
    provenance = Provenance(
        command=command,
        version=package_version(),
        commit=git_commit(),
        n_resamples=n_resamples,
        confidence=confidence,
        random_state=random_state,
        final_fraction=final_fraction,
        directories=read.directories if comparison else (),
        budgets=read.budgets if comparison else (),
    )
    scores = score_runs(results, final_fraction=final_fraction, confidence=confidence)
    curves = plot_learning_curves(results, out / FIGURES_DIR, n_points=n_points, confidence=confidence)
    base_env = {run.table_env: run.env for run in results}  # a variant is shown like its env
    improvements = improvements_over_dqn(
        results, {env: env_metrics(env, base_env, METRIC_NAMES) for env in base_env}, confidence=confidence
    )
    uncompared = uncompared_rows(results)  # (named with one directory too: no row is left out without a word)
    rows = None
    if comparison:
        directories = read.row_directories()
        rows = {row: RowFacts(budgets_of(runs)[0], directories[row]) for row, runs in group_runs(results).items()}
    discrimination = discrimination_section(results)  # (before any figure is written: it reads the tables)
    tradeoffs = plot_tradeoffs(scores, out / FIGURES_DIR, base_env, dqn_rows)
    figures = {**{(env, TRADEOFF): path for env, path in tradeoffs.items()}, **curves}
    files = {key: (path.relative_to(out).as_posix(), path.read_bytes()) for key, path in figures.items()}
    sections = score_sections(
        scores,
        provenance,
        files,
        base_env=base_env,
        improvements=improvements,
        uncompared=uncompared,
        reference_note=renaming_note(read.renamed, bool(dqn_rows), markdown_text),
    )
    constraint = constraint_section(results)
    profiles, profile_figures = profile_section(
        results, out, random_state=random_state, n_resamples=n_resamples, confidence=confidence
    )
    heldout = heldout_section(dirs, results, out, read.origins, extra=evaluations)
    episodes = episodes_section(results, out, read.origins, allowed_imports=allowed_imports)
    added: list[Section | None] = [
        constraint,
        discrimination,
        profiles,
        heldout.section if heldout else None,
        episodes.section if episodes else None,
    ]
    page = leaderboard_page([*sections, *(section for section in added if section is not None), definitions_section()])
    markdown, html = to_markdown(page), to_html(page)
    paths = {
        "csv": _write_page(out / CSV_NAME, csv_text(scores, provenance, rows)),
        "markdown": _write_page(out / MARKDOWN_NAME, markdown),
        "html": _write_page(out / HTML_NAME, html),
    }
    paths.update({f"figure:{env}:{metric}": path for (env, metric), path in figures.items()})
    paths.update(profile_figures)
    paths.update(heldout.figures if heldout is not None else {})
    paths.update(episodes.figures if episodes is not None else {})
    return paths


def _checked_out(out: Path) -> Path:
    """``out`` once nothing in the way of writing the leaderboard there is found, creating
    nothing: ``ValueError`` when it or its ``figures`` is a file, or a symbolic link lies below it."""
    check_output_folders(out, (FIGURES_DIR,))
    return out


@contextmanager
def _staging(out: Path) -> Iterator[Path]:
    """A new directory ``out/.leaderboard.ezoo-<pid>-<random>.tmp`` to render into (``out`` created if
    missing), removed with whatever is left in it when the block ends; those of processes that
    died rendering are removed first. A directory that cannot be created is a ``ValueError``."""
    if out.is_dir():
        _remove_stale_stages(out)
    stage = out / f"{STAGE_PREFIX}{TEMP_MARKER}-{os.getpid()}-{secrets.token_hex(4)}{TEMP_SUFFIX}"
    try:
        stage.mkdir(parents=True)
    except OSError as error:
        raise ValueError(
            f"cannot write into output directory {out} ({error.strerror or error}); choose another output directory (--out)"
        ) from None
    try:
        yield stage
    except OSError as error:  # (a full disk, a file removed meanwhile): the file it was writing, named
        raise OSError(
            f"cannot write {_final_name(error, stage, out)} ({error.strerror or error}): nothing half-written is left in {out}"
        ) from None
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def _final_name(error: OSError, stage: Path, out: Path) -> Path | str:
    """Where the file a failed write was writing (``error.filename``: the file, or the temporary
    file of an atomic write, in ``stage``) would have gone in ``out``."""
    if not error.filename:
        return f"the leaderboard into {out}"
    path = Path(os.fsdecode(error.filename))
    try:
        relative = path.relative_to(stage)
    except ValueError:
        return path
    name = _ATOMIC_TEMP.sub("", relative.name)
    return out / relative.parent / (name[1:] if name != relative.name and name.startswith(".") else name)


def _write_page(path: Path, text: str) -> Path:
    """Write the page ``text`` to ``path`` atomically; an ``OSError`` names ``path``."""
    try:
        return write_text_atomic(path, text)
    except OSError as error:
        raise OSError(error.errno, error.strerror or str(error), str(path)) from None


def _check_targets(staged: dict[str, Path], stage: Path, out: Path) -> None:
    """Refuse (``ValueError`` naming it) the first place in ``out`` of a file of ``staged`` that is
    anything but nothing or a regular file (a link, named with its target; a directory; a FIFO;
    a device), or that passes through a link below ``out``: asked of every file before the first
    is moved, so a refusal publishes nothing (:func:`empathy_zoo.names.check_replaceable`)."""
    for source in staged.values():
        target = out / source.relative_to(stage)
        check_no_links(out, target)
        check_replaceable(target)
        check_own_file(target, "leaderboard file", _opening(source))


CSV_OPENING = b"env,method_label,"
"""What every leaderboard CSV begins with: the first columns of its header, which one directory's
and several directories' CSVs share (the latter adds columns at the end)."""


def _opening(rendered: Path) -> bytes:
    """What every file of ``rendered``'s kind begins with: an image's signature, the CSV's first
    columns (:data:`CSV_OPENING`), the HTML page up to its title, the Markdown page's title line."""
    if rendered.suffix == ".png":
        return PNG_OPENING
    if rendered.suffix == ".gif":
        return GIF_OPENING
    if rendered.suffix == ".csv":
        return CSV_OPENING
    with open(rendered, "rb") as handle:
        head = handle.read(4096)
    end = head.find(b"</title>") + len(b"</title>") if rendered.suffix == ".html" else head.find(b"\n") + 1
    return head[:end] if end > 0 else head


def _publish(staged: dict[str, Path], stage: Path, out: Path) -> dict[str, Path]:
    """Move every file of ``staged`` from ``stage`` to its place in ``out`` (each rename atomic,
    the pages last: a reader never sees a page whose figures are not there yet), once
    :func:`_check_targets` passed; a file it replaces keeps its permissions (only a regular file is
    replaced: each place is checked again just before its rename). Returns ``staged`` with the
    paths in ``out``."""
    placed: dict[str, Path] = {}
    for key in sorted(staged, key=lambda key: (key in PAGES, PAGES.index(key) if key in PAGES else 0)):
        source = staged[key]
        target = out / source.relative_to(stage)
        try:
            if target.is_file():
                os.chmod(source, stat.S_IMODE(target.stat().st_mode))
            os.replace(source, check_replaceable(target))
        except OSError as error:
            raise OSError(error.errno, error.strerror or str(error), str(target)) from None
        placed[key] = target
    return {key: placed[key] for key in staged}


def _remove_stale_stages(out: Path) -> None:
    """Remove the staging directories that processes which died rendering left in ``out``; one
    holding anything a render does not write (a page, ``figures/`` of PNG and GIF files) is left."""
    for path in out.glob(f"{STAGE_PREFIX}*{TEMP_SUFFIX}"):
        match = _STAGE.fullmatch(path.name)
        if match and path.is_dir() and not path.is_symlink() and not process_alive(int(match["pid"])) and _rendered_only(path):
            shutil.rmtree(path, ignore_errors=True)


STAGED_OPENINGS = {
    MARKDOWN_NAME: f"# {TITLE}\n".encode(),
    CSV_NAME: CSV_OPENING,
    HTML_NAME: b"<!DOCTYPE html>",
    ".png": PNG_OPENING,
    ".gif": GIF_OPENING,
}
"""What each page (by name) and each figure (by suffix) a render stages begins with."""


def _staged_file(entry: Path, opening: bytes | None) -> bool:
    """Whether ``entry`` is a file a render writes: a temporary file of an atomic write in progress,
    or a regular file (no link) that is empty or begins with ``opening`` (``None``: none is)."""
    if _ATOMIC_TEMP.search(entry.name):
        return entry.is_file() and not entry.is_symlink()
    if opening is None or entry.is_symlink() or not entry.is_file():
        return False
    with open(entry, "rb") as handle:
        head = handle.read(len(opening))
    return head in (b"", opening)


def _rendered_only(stage: Path) -> bool:
    """Whether ``stage`` holds only what a render writes: its pages, each a regular file that begins
    as that page does, and ``figures/`` of PNG and GIF images (:data:`STAGED_OPENINGS`); anything
    else (a folder named as a page, a user's text under a page's name) keeps the stage."""
    for entry in stage.iterdir():
        if entry.name == FIGURES_DIR and entry.is_dir() and not entry.is_symlink():
            if not all(_staged_file(f, STAGED_OPENINGS.get(f.suffix)) for f in entry.iterdir()):
                return False
        elif not _staged_file(entry, STAGED_OPENINGS.get(entry.name)):
            return False
    return True


def _print_note(text: str) -> None:
    print(f"empathy-zoo: note: {text}", file=sys.stderr, flush=True)
