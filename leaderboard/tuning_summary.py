"""Many tuning studies at a glance: one table line per study and one figure of where each study
searched and what it chose.

    python -m leaderboard.tuning_summary DIR [--figure PATH]

reads every ``study.json`` under ``DIR`` (:mod:`empathy_zoo.training.tuning`'s; the methods
profile's are ``docs/results/methods/tuning/<variant>/<method>/``), prints a Markdown table (per
study: its trials finished / pruned / refused, the env steps it spent against its budget, the best
value and the settings chosen) and, with ``--figure``, draws the trials of studies that tune one
numeric parameter: one panel per variant, one line per study, each trial a dot at its value of
the parameter (finished filled, pruned hollow), the chosen one a star, the range's ends dotted. Read from the study files
alone; nothing is trained or tested. A study file may come from anyone: each is read bounded and
checked field by field (:func:`check_study`) before anything is printed or drawn; the figure's size
is checked against its bound before it is drawn (:func:`check_figure_size`), and the text it shows
from the files is drawn as that text, never as mathtext.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import os
import sys
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import LogLocator

from empathy_zoo.atomic import write_bytes_atomic
from empathy_zoo.data_files import check_input_dir
from empathy_zoo.document_checks import DocumentChecker, finite_float, shown
from empathy_zoo.limits import (
    MAX_CYCLES,
    MAX_FIGURE_PIXELS,
    MAX_FIGURE_SIDE,
    MAX_RANGE_END,
    MAX_SEED,
    MAX_SEEDS,
    MAX_STEPS,
    MAX_TRIALS,
    MAX_WALL_TIME_S,
)
from empathy_zoo.metrics import METRIC_NAMES, METRIC_RANGES
from empathy_zoo.names import PNG_OPENING, check_output_file, resolved, terminal_line
from empathy_zoo.training.study_plan import DIRECTIONS, curve_value, objective_direction
from empathy_zoo.training.trials_figure import literal_text
from leaderboard.tables import markdown_text

__all__ = [
    "StudySummary",
    "StudyFileError",
    "check_figure_path",
    "check_figure_size",
    "check_study",
    "find_studies",
    "study_files",
    "study_notes",
    "summarise",
    "study_names",
    "summary_table",
    "render_studies_png",
    "main",
]

STUDY_FILE = "study.json"
"""A study's file (:data:`empathy_zoo.training.tuning.STUDY_FILE`)."""


@dataclass(frozen=True)
class StudySummary:
    """What one study did and chose."""

    variant: str
    label: str
    """The tuned experiment's label (untuned)."""
    metric: str
    over: str
    """``last`` or ``curve`` (:data:`empathy_zoo.training.study_plan.OBJECTIVE_OVER`)."""
    trials: int
    """Trials that count (finished, pruned or refused)."""
    finished: int
    pruned: int
    refused: int
    env_steps_trained: int
    env_steps_at_most: int
    wall_time_s: float
    """The trials' wall time, summed."""
    best_value: float | None
    best_params: Mapping[str, Any]
    study: str = ""
    """Where its ``study.json`` lies (its folder, relative to the directory read): how a table tells
    two studies of one variant and label apart."""


def find_studies(root: str | os.PathLike[str]) -> list[Path]:
    """Every study file under ``root``, sorted, each file once (:func:`study_files`); ``ValueError``
    where there is none."""
    return study_files(root)[0]


def study_files(root: str | os.PathLike[str]) -> tuple[list[Path], list[tuple[Path, Path]]]:
    """Every ``study.json`` under ``root``, sorted, each file once, and the paths left out:
    ``(path, the path read in its place)``. A file reached by two paths (a symbolic link to it, a
    second hard link: one device and inode) is read by one of them, the first that is no symbolic
    link (the first of all where each is one). A path that cannot be looked at (a dangling link)
    is kept, for the read to refuse (``Path.rglob`` skips a name that does not exist: it is not used). Folders are
    walked without following links to them, as ``rglob`` walks. ``ValueError`` where there is none, or ``root`` is a loop
    of symbolic links, or is a file or missing (:func:`empathy_zoo.data_files.check_input_dir`)."""
    check_input_dir(root, "tuning directory", "name the directory holding study.json files (what tune --out wrote into)")
    found = sorted(
        Path(folder) / name for folder, folders, files in os.walk(root) for name in (*folders, *files) if name == STUDY_FILE
    )
    if not found:
        raise ValueError(f"no {STUDY_FILE} under {root}: run empathy-zoo tune first")
    by_file: dict[tuple[int, int], list[Path]] = {}
    for path in found:
        try:
            status = path.stat()
        except OSError:
            by_file[(-1, len(by_file))] = [path]  # (its own; the read names what is wrong with it)
            continue
        by_file.setdefault((status.st_dev, status.st_ino), []).append(path)
    kept: list[Path] = []
    left_out: list[tuple[Path, Path]] = []
    for paths in by_file.values():
        read = next((path for path in paths if not path.is_symlink()), paths[0])
        kept.append(read)
        left_out.extend((path, read) for path in paths if path != read)
    return sorted(kept), sorted(left_out)


MAX_NOTED = 10
"""The most study files a note names one by one; past it, the rest are counted."""


def _named(items: Sequence[str]) -> str:
    """``items`` joined, at most :data:`MAX_NOTED` of them named, then ``and N more``."""
    shown = "; ".join(items[:MAX_NOTED])
    return shown + (f"; and {len(items) - MAX_NOTED:,} more" if len(items) > MAX_NOTED else "")


def study_notes(left_out: Sequence[tuple[Path, Path]], read: Sequence[tuple[Path, Any]]) -> list[str]:
    """The notes a summary prints beside its table (none where each file is a study of its own): the
    paths left out, each a file read by another path (:func:`study_files`), and the files read
    (``(path, document)``) that hold the same study document as one before them, a copy (listed,
    each on its own line, as a study). At most :data:`MAX_NOTED` named a note, the rest counted."""
    notes = []
    if left_out:
        pairs = [f"{path} is {kept}" for path, kept in left_out]
        notes.append(
            f"{len(left_out):,} path(s) lead to a study file read already (a symbolic or hard link), not read again: "
            f"{_named(pairs)}"
        )
    first: dict[str, Path] = {}
    copies = []
    for path, study in read:
        key = json.dumps(study, sort_keys=True, allow_nan=False)
        if key in first:
            copies.append(f"{path} is a copy of {first[key]}")
        else:
            first[key] = path
    if copies:
        notes.append(
            f"{len(copies):,} study file(s) hold the same study as another (one document, copied), each on a line of "
            f"its own: {_named(copies)}; move a copy away"
        )
    return notes


def summarise(study: Mapping[str, Any], where: str = "") -> StudySummary:
    """The :class:`StudySummary` of a ``study.json`` document, ``where`` its folder (relative to the directory read)."""
    plan = study["plan"]
    counted = [t for t in study["trials"] if t["state"] != "INTERRUPTED"]
    states = [t["state"] for t in counted]
    best = study.get("best")
    return StudySummary(
        variant=plan["variant"],
        label=plan["label"],
        metric=plan["objective"]["metric"],
        over=plan["objective"].get("over", "last"),
        trials=len(counted),
        finished=states.count("COMPLETE"),
        pruned=states.count("PRUNED"),
        refused=states.count("REFUSED"),
        env_steps_trained=int(study["env_steps_trained"]),
        env_steps_at_most=int(plan["budget"]["env_steps_at_most"]),
        wall_time_s=float(sum(t.get("wall_time_s") or 0.0 for t in counted)),
        best_value=None if best is None else float(best["value"]),
        best_params={} if best is None else dict(best["params"]),
        study=where,
    )


def _value(value: Any) -> str:
    return f"{value:.3g}" if isinstance(value, float) else str(value)


def study_names(studies: Sequence[tuple[str, str, str]]) -> list[str]:
    """Each study's label (of ``(variant, label, folder)``), followed by its folder (``DQN (study
    a/DQN)``) where another study has its variant and label: their lines would read alike."""
    shared = [(variant, label) for variant, label, _ in studies]
    return [
        f"{label} (study {folder or '.'})" if shared.count((variant, label)) > 1 else label for variant, label, folder in studies
    ]


def summary_table(summaries: Sequence[StudySummary]) -> str:
    """Markdown: one line per study, in the order given; its text (a label, a parameter's name or
    chosen value: data) escaped (:func:`~leaderboard.tables.markdown_text`), so a ``|`` is no cell.
    Two studies of one variant and label are told apart by their folders (:func:`study_names`)."""
    lines = [
        "| variant | method | trials: finished / pruned / refused | env steps (of at most) | trials' wall time | "
        "best value | chosen |",
        "|---|---|---|---|---|---|---|",
    ]
    for s, name in zip(summaries, study_names([(s.variant, s.label, s.study) for s in summaries]), strict=True):
        best = "none finished" if s.best_value is None else f"{s.metric} {s.best_value:.4g} ({s.over})"
        chosen = ", ".join(f"{name} = {_value(value)}" for name, value in s.best_params.items()) or "—"
        lines.append(
            f"| {markdown_text(s.variant)} | {markdown_text(name)} | {s.trials}: {s.finished} / {s.pruned} / {s.refused} | "
            f"{s.env_steps_trained:,} ({s.env_steps_at_most:,}) | {s.wall_time_s / 60:.1f} min | {best} | "
            f"{markdown_text(chosen)} |"
        )
    return "\n".join(lines)


def _parameter(studies: Sequence[Mapping[str, Any]]) -> tuple[str, bool, tuple[float, float]]:
    """The one numeric parameter every study tunes, whether its scale is logarithmic, and its range."""
    spaces = {tuple(sorted(study["plan"]["params"].items())) for study in studies}
    if len(spaces) != 1 or len(next(iter(spaces))) != 1:
        raise ValueError(
            "the figure draws studies of one and the same parameter and range; these tune "
            + "; ".join(sorted(", ".join(f"{n}={r}" for n, r in space) for space in spaces))
        )
    ((name, spec),) = next(iter(spaces))
    kind = spec.partition(":")[0]
    if kind not in ("log", "float", "int"):
        raise ValueError(f"the figure draws a numeric parameter; {name} is {spec}")
    low, high = (float(end) for end in spec.split(":")[1:3])
    return name, kind == "log", (low, high)


PANEL_WIDTH = 6.2
"""Inches of the figure's width per variant (one panel each)."""
ROW_HEIGHT = 0.38
"""Inches of the figure's height per study of the variant with the most."""
TITLE_HEIGHT = 0.9
"""Inches of the figure's height above and below the studies' lines (title, axis, labels)."""


def _figure_inches(studies: Sequence[Mapping[str, Any]]) -> tuple[float, float]:
    """Width and height, in inches, of the figure of ``studies``: :data:`PANEL_WIDTH` per variant and
    :data:`ROW_HEIGHT` per study of the variant with the most, past :data:`TITLE_HEIGHT`."""
    rows: dict[str, int] = {}
    for study in studies:
        rows[study["plan"]["variant"]] = rows.get(study["plan"]["variant"], 0) + 1
    return PANEL_WIDTH * len(rows), TITLE_HEIGHT + ROW_HEIGHT * max(rows.values(), default=0)


def check_figure_size(studies: Sequence[Mapping[str, Any]], dpi: int = 110) -> tuple[float, float]:
    """The figure's size in inches (:func:`_figure_inches`), or a ``ValueError`` naming ``--figure``
    where at ``dpi`` a side would pass :data:`~empathy_zoo.limits.MAX_FIGURE_SIDE` pixels or the
    whole :data:`~empathy_zoo.limits.MAX_FIGURE_PIXELS` (the figure is drawn in memory, 4 bytes a
    pixel). Only the studies' count per variant is read; nothing is drawn."""
    width, height = _figure_inches(studies)
    pixels = (math.ceil(width * dpi), math.ceil(height * dpi))
    if max(pixels) > MAX_FIGURE_SIDE or pixels[0] * pixels[1] > MAX_FIGURE_PIXELS:
        variants = sorted({study["plan"]["variant"] for study in studies})
        most = max(sum(1 for study in studies if study["plan"]["variant"] == variant) for variant in variants)
        raise ValueError(
            f"--figure: {len(studies):,} studies on {len(variants):,} variants (at most {most:,} on one) make a "
            f"{pixels[0]:,} × {pixels[1]:,} px figure, past its bound of {MAX_FIGURE_SIDE:,} px a side and "
            f"{MAX_FIGURE_PIXELS:,} px in all (docs/limits.md); draw fewer: point DIR at a part of them"
        )
    return width, height


class _FiniteLogLocator(LogLocator):
    """Matplotlib's :class:`~matplotlib.ticker.LogLocator`, less the ticks that are no float.
    It places ticks a stride of decades past each end of the axis (outside the view, never drawn):
    past 1e308 for a range that ends near :data:`~empathy_zoo.limits.MAX_RANGE_END`, an overflow
    that fails the figure. Those ticks are dropped, unwarned; every other is kept."""

    def tick_values(self, vmin: float, vmax: float) -> Sequence[float]:
        """The ticks :class:`~matplotlib.ticker.LogLocator` places from ``vmin`` to ``vmax``, each finite."""
        with np.errstate(over="ignore"):
            ticks = np.asarray(super().tick_values(vmin, vmax), dtype=float)
        return ticks[np.isfinite(ticks)]


def render_studies_png(studies: Sequence[Mapping[str, Any]], dpi: int = 110, folders: Sequence[str] = ()) -> bytes:
    """PNG bytes of the figure of ``studies`` (``study.json`` documents of one parameter), its size
    checked before anything is drawn (:func:`check_figure_size`). Text read from the studies (a
    label, the parameter's name) is drawn as that text (:func:`~empathy_zoo.training.trials_figure.literal_text`).
    ``folders`` (each study's, relative to the directory read) tell two studies of one variant and
    label apart (:func:`study_names`)."""
    if not studies:
        raise ValueError("no studies to draw")
    if folders and len(folders) != len(studies):
        raise ValueError(f"{len(folders)} folders for {len(studies)} studies")
    where = list(folders) or [""] * len(studies)
    named = study_names([(s["plan"]["variant"], s["plan"]["label"], f) for s, f in zip(studies, where, strict=True)])
    name_of = {id(study): text for study, text in zip(studies, named, strict=True)}
    name, log, (low, high) = _parameter(studies)
    size = check_figure_size(studies, dpi)
    variants = sorted({study["plan"]["variant"] for study in studies})
    rows = {v: [s for s in studies if s["plan"]["variant"] == v] for v in variants}
    figure = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(figure)
    axes_row = figure.subplots(1, len(variants), squeeze=False)[0]
    for axes, variant in zip(axes_row, variants, strict=True):
        labels = [literal_text(name_of[id(s)]) for s in rows[variant]]
        for y, study in enumerate(rows[variant]):
            trials = [t for t in study["trials"] if name in t["params"] and t["state"] != "INTERRUPTED"]
            done = [t["params"][name] for t in trials if t["state"] == "COMPLETE"]
            stopped = [t["params"][name] for t in trials if t["state"] == "PRUNED"]
            axes.plot(done, [y] * len(done), "o", color="#0072B2", markersize=6, label="finished" if y == 0 else None)
            axes.plot(
                stopped,
                [y] * len(stopped),
                "o",
                color="#D55E00",
                markerfacecolor="white",
                markersize=6,
                label="pruned" if y == 0 else None,
            )
            best = study.get("best")
            if best is not None:
                axes.plot([best["params"][name]], [y], "*", color="black", markersize=13, label="chosen" if y == 0 else None)
        axes.set_yticks(range(len(labels)), labels, fontsize="small")
        axes.set_ylim(len(labels) - 0.5, -0.5)
        if log:
            axes.set_xscale("log")
            axes.set_xlim(low / 1.25, high * 1.25)
            axes.xaxis.set_major_locator(_FiniteLogLocator())
            axes.xaxis.set_minor_locator(_FiniteLogLocator(subs="auto"))
        else:
            axes.set_xlim(low - 0.05 * (high - low), high + 0.05 * (high - low))
        for end in (low, high):
            axes.axvline(end, color="0.6", linewidth=0.8, linestyle=":")
        axes.set_xlabel(literal_text(name))
        metric = rows[variant][0]["plan"]["objective"]
        axes.set_title(literal_text(f"{variant}: objective {metric['metric']} ({metric.get('over', 'last')})"), fontsize="medium")
        axes.grid(True, axis="x", alpha=0.3)
        axes.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.0, 1.0), frameon=False)
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=dpi, metadata={"Software": None})
    return buffer.getvalue()


def _named_path(text: str) -> str:
    """A path argument, refused when empty (an empty ``DIR`` would silently read the current
    directory, an empty ``--figure`` silently draw nothing)."""
    if not text:
        raise argparse.ArgumentTypeError("an empty path: name it ('.' for the current directory, a .png file for --figure)")
    return text


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m leaderboard.tuning_summary DIR [--figure PATH]``."""
    parser = argparse.ArgumentParser(prog="python -m leaderboard.tuning_summary", description=__doc__.splitlines()[0])
    parser.add_argument("root", metavar="DIR", type=_named_path, help="a directory holding study.json files, at any depth")
    parser.add_argument("--figure", metavar="PATH", type=_named_path, help="draw the trials of every study into this PNG")
    args = parser.parse_args(argv)
    try:
        if args.figure is not None:
            check_figure_path(args.figure)
        paths, left_out = study_files(args.root)
        if args.figure is not None:
            check_figure_path(args.figure, paths)
        read = [(path, check_study(read_study(path), path)) for path in paths]
        studies = [study for _, study in read]
        folders = [_folder(path, args.root) for path, _ in read]
        pairs = zip(read, folders, strict=True)
        table = summary_table([_checked(path, lambda s, f=folder: summarise(s, f), study) for (path, study), folder in pairs])
        figure = None
        if args.figure is not None:
            figure = _checked(Path(args.root), lambda s: render_studies_png(s, folders=folders), studies)
    except (ValueError, OSError) as error:  # (a refusal: a study or the figure's place, one line)
        print(f"{parser.prog}: error: {terminal_line(error)}", file=sys.stderr)
        return 2
    if figure is not None:
        try:
            write_bytes_atomic(args.figure, figure)
        except ValueError as error:  # (something but a regular file put in its place meanwhile: a refusal)
            print(f"{parser.prog}: error: {terminal_line(error)}", file=sys.stderr)
            return 2
        except OSError as error:  # (a full disk: a machine failure, not a refusal; nothing half-written is left)
            line = f"cannot write {args.figure} ({error.strerror or error}): nothing half-written is left; "
            print(f"{parser.prog}: error: {terminal_line(line + 'free space or give another --figure')}", file=sys.stderr)
            return 1
    for note in study_notes(left_out, read):
        print(f"{parser.prog}: note: {terminal_line(note)}", file=sys.stderr)
    print(table)
    if figure is not None:
        print(f"\nwrote {args.figure}")
    return 0


def _folder(path: Path, root: str) -> str:
    """The folder of the study file ``path``, relative to ``root`` (``.`` for ``root`` itself); a
    name holding a character that is not printable (an escape sequence) as Python writes it."""
    folder = path.parent.relative_to(root).as_posix()
    return folder if folder.isprintable() else ascii(folder)


def check_figure_path(figure: str | os.PathLike[str], studies: Sequence[Path] = ()) -> Path:
    """``figure`` as a path if the figure can be written there; ``ValueError`` naming it otherwise
    (before anything is read or written): a name not ending in ``.png``, an existing directory,
    anything but a regular file in its place (a symbolic link, named with its target, a FIFO, a
    device: :func:`empathy_zoo.names.check_replaceable`), a parent that is a file, or one of the
    ``studies`` read (the same file, by its resolved path or, once there, by device and inode:
    drawing would replace it)."""
    path = Path(figure)
    for study in studies:
        if resolved(path) == resolved(study) or (path.exists() and _same_file(path, study)):
            raise ValueError(
                f"{figure} lies where the study file {study} is read (it is that file): the figure would replace it; "
                "write it elsewhere"
            )
    return check_output_file(path, "PNG", ".png", "studies.png", PNG_OPENING)


def _same_file(path: Path, other: Path) -> bool:
    """Whether ``path`` and ``other`` are one file (a hard link); ``False`` where either cannot be looked at."""
    try:
        return os.path.samefile(path, other)
    except OSError:
        return False


MAX_STUDY_BYTES = 64 * 2**20
"""The largest ``study.json`` read (``tune`` writes a few KB per trial)."""


def read_study(path: Path) -> Any:
    """A ``study.json``: a regular file of at most :data:`MAX_STUDY_BYTES`, JSON nested within the
    suite's bound, else a ``ValueError`` naming it."""
    from empathy_zoo.bounded_read import check_json_depth, parse_json
    from empathy_zoo.limits import read_bounded

    data = read_bounded(path, MAX_STUDY_BYTES, "study file")
    check_json_depth(data, str(path))
    try:
        return parse_json(data)
    except (UnicodeDecodeError, ValueError) as error:  # (no JSON, a key given twice)
        raise ValueError(f"{path} is not JSON ({error})") from None


class StudyFileError(ValueError):
    """A ``study.json`` is not what ``tune`` writes; the message names the file and the field."""


TRIAL_STATES = ("COMPLETE", "PRUNED", "REFUSED", "INTERRUPTED")
"""The states a ``study.json`` records of a trial (:func:`empathy_zoo.training.tuning.study_document`)."""
MAX_ENV_STEPS = MAX_TRIALS * MAX_SEEDS * MAX_STEPS
"""The most env steps a study may spend: its trials, each on its tuning seeds, each of its steps."""
RANGE_KINDS = ("log", "float", "int")
"""The kinds of a parameter spec that give a range (``choice`` lists its values)."""
STUDY_SCHEMA = 1
"""The layout of ``study.json`` that ``tune`` writes (:data:`empathy_zoo.training.tuning.STUDY_SCHEMA`;
a study written before it held none)."""


@dataclass(frozen=True)
class _Spec:
    """A parameter's spec as read: its kind, a range's ends, a choice's values (each as its text
    and, where the text is a TOML literal, that value)."""

    kind: str
    low: float = 0.0
    high: float = 0.0
    choices: tuple[tuple[str, Any], ...] = ()


def check_study(document: Any, path: str | os.PathLike[str]) -> dict[str, Any]:
    """``document`` (a parsed ``study.json``) if every field this tool reads is what ``tune`` writes,
    else :class:`StudyFileError` naming ``path`` and the field. Every string anywhere one line of
    printable text, every number finite; what a table or figure shows (``plan.variant`` a name,
    ``plan.label``, each parameter's name and spec, each chosen text value) a label
    (:func:`empathy_zoo.names.check_label`); the objective's metric and its reduction the suite's,
    the metric one ``tune`` takes for the study's environment (:func:`_check_moves`), its direction
    the metric's (:func:`~empathy_zoo.training.study_plan.objective_direction`); ``experiment``,
    ``variant``, ``method``, ``env`` and ``env_kwargs`` one experiment's (:func:`_worlds`);
    each env step count a whole number within ``trials × tuning seeds × steps`` at their bounds;
    each trial's state one ``tune`` writes, its wall time within ten years; every parameter value
    one of the plan's parameters, within its range (a ``choice``'s one of its values: a number or a
    boolean as :func:`tomllib` reads the spec's text, text as text), every trial but an interrupted
    one holding each of them; ``schema`` the one ``tune`` writes (or none); a range's ends ``LOW <
    HIGH`` within :data:`MAX_RANGE_END`, so the figure's margins are floats; the best value finite,
    within its metric's range.
    The fields agree with each other: ``trials`` not empty, each trial's number its own and below
    their count (``tune`` numbers them from 0); every trial's ``steps_trained`` (``tune`` writes it)
    its curve's last step, ``env_steps_trained`` the counted trials' sum times the tuning seeds; a
    finished trial's curve up to the budget's last step, its ``value`` and every trial's
    ``last_value`` what its curve gives over the objective (last point or mean, up to float
    rounding), no ``value`` for a trial that did not finish; ``best`` set once a trial finished;
    ``plan.budget.trials`` the trials ``env_steps_at_most`` holds, ``trials_done`` (an int) the
    counted ones; an ``int`` range of whole ends, a ``log`` range above 0; every value
    of a trial (``value``, ``last_value``, each point of its ``curve`` and each seed's part of it)
    within its metric's range in the study's world (:func:`metric_bounds`); each curve point's
    ``per_seed`` one value per tuning seed, its step the next of the plan's evaluation schedule (every ``eval_interval`` steps
    and the budget's last); ``best`` the finished trial its ``number`` names, with its value and
    parameters, and no finished trial better in the objective's ``direction``; the budget
    ``trials × tuning seeds × steps`` for at most :data:`MAX_TRIALS` trials, no more trials than it
    holds (an interrupted trial, run again, not counted) and ``env_steps_trained`` within it."""
    check = DocumentChecker(
        Path(path), StudyFileError, "a study file", "a study that empathy-zoo tune wrote", "move it away (tune writes it again)"
    )
    study = check.table(document, "(the whole file)")
    for key, item in study.items():
        check.plain(item, key)  # (every string one line of printable text, every number finite)
    check.has(study, ("plan", "env_steps_trained", "best", "trials"), "")
    schema = study.get("schema", STUDY_SCHEMA)
    if isinstance(schema, bool) or not isinstance(schema, int) or schema != STUDY_SCHEMA:
        raise check.fail(
            "schema", f"{STUDY_SCHEMA}, the layout tune writes (or none, a study written before it)", study["schema"]
        )
    plan = check.table(study["plan"], "plan")
    check.has(plan, ("variant", "label", "params", "objective", "budget", "tuning_seeds"), "plan.")
    check.name(plan["variant"], "plan.variant")
    check.label(plan["label"], "plan.label")
    objective = check.table(plan["objective"], "plan.objective")
    check.has(objective, ("metric", "direction"), "plan.objective.")
    metric = objective["metric"]
    if metric not in METRIC_NAMES:
        raise check.fail("plan.objective.metric", f"one of the suite's metrics ({', '.join(METRIC_NAMES)})", metric)
    if objective.get("over", "last") not in ("last", "curve"):
        raise check.fail("plan.objective.over", "last or curve", objective["over"])
    direction = objective["direction"]
    if direction not in DIRECTIONS:
        raise check.fail("plan.objective.direction", " or ".join(DIRECTIONS), direction)
    if direction != objective_direction(metric):
        raise check.fail(
            "plan.objective.direction",
            f"{objective_direction(metric)}, how tune optimises {metric} (its fixed direction)",
            direction,
        )
    worlds = _worlds(check, plan)
    _check_moves(check, worlds, metric)
    budget = check.table(plan["budget"], "plan.budget")
    check.has(budget, ("env_steps_at_most", "steps", "eval_interval"), "plan.budget.")
    at_most = check.integer(budget["env_steps_at_most"], "plan.budget.env_steps_at_most", 1, MAX_ENV_STEPS)
    steps = check.integer(budget["steps"], "plan.budget.steps", 1, MAX_STEPS)
    interval = check.integer(budget["eval_interval"], "plan.budget.eval_interval", 1, MAX_STEPS)
    seeds = _tuning_seeds(check, plan["tuning_seeds"])
    per_trial = len(seeds) * steps
    if at_most % per_trial or not 1 <= at_most // per_trial <= MAX_TRIALS:
        raise check.fail(
            "plan.budget.env_steps_at_most",
            f"trials × {len(seeds):,} tuning seeds × {steps:,} steps, for 1 to {MAX_TRIALS:,} trials",
            at_most,
        )
    if "trials" in budget and check.integer(budget["trials"], "plan.budget.trials", 1, MAX_TRIALS) != at_most // per_trial:
        raise check.fail(
            "plan.budget.trials",
            f"{at_most // per_trial:,}, the trials of env_steps_at_most ({at_most:,} = trials × {len(seeds):,} tuning "
            f"seeds × {steps:,} steps)",
            budget["trials"],
        )
    bounds = metric_bounds(metric, worlds)
    trained = check.integer(study["env_steps_trained"], "env_steps_trained", 0, at_most)
    specs = {name: _spec(check, name, spec) for name, spec in check.table(plan["params"], "plan.params").items()}
    over = objective.get("over", "last")
    trials = study["trials"]
    if not isinstance(trials, list) or not trials:
        raise check.fail("trials", "a non-empty array of trials (tune writes one once a trial has run)", trials)
    counted = sum(1 for trial in trials if not (isinstance(trial, dict) and trial.get("state") == "INTERRUPTED"))
    if counted > at_most // per_trial:
        raise check.fail(
            "trials",
            f"at most the plan's {at_most // per_trial:,} trials (an interrupted one not counted)",
            f"{counted:,} trials",
        )
    if "trials_done" in study and check.integer(study["trials_done"], "trials_done", 0, MAX_TRIALS) != counted:
        raise check.fail(
            "trials_done", f"{counted:,}, its trials but the interrupted ones (as tune counts them)", study["trials_done"]
        )
    numbers: dict[int, dict[str, Any]] = {}
    for i, trial in enumerate(trials):
        where = f"trials[{i}]"
        trial = check.table(trial, where)
        check.has(trial, ("state", "params", "steps_trained"), f"{where}.")
        if trial["state"] not in TRIAL_STATES:
            raise check.fail(f"{where}.state", f"one of {', '.join(TRIAL_STATES)}", trial["state"])
        wall = trial.get("wall_time_s")
        if wall is not None and not 0 <= check.finite(wall, f"{where}.wall_time_s") <= MAX_WALL_TIME_S:
            raise check.fail(f"{where}.wall_time_s", f"seconds in [0, {MAX_WALL_TIME_S:,}] (ten years)", wall)
        _params(check, trial["params"], specs, f"{where}.params", whole=trial["state"] != "INTERRUPTED")
        number = check.integer(trial.get("number"), f"{where}.number", 0, len(trials) - 1)  # (tune numbers them from 0)
        if number in numbers:
            raise check.fail(f"{where}.number", "a trial number of its own (each trial is numbered once)", number)
        numbers[number] = trial
        if trial["state"] == "COMPLETE" and trial.get("value") is None:
            raise check.fail(f"{where}.value", "the value of a finished trial (tune writes one)", trial.get("value"))
        if trial["state"] != "COMPLETE" and trial.get("value") is not None:
            raise check.fail(f"{where}.value", f"null: tune writes no value of a {trial['state']} trial", trial["value"])
        for name in ("value", "last_value"):
            if trial.get(name) is not None:
                _in_range(check, trial[name], f"{where}.{name}", metric, bounds)
        curve = trial.get("curve", [])
        _curve(check, curve, f"{where}.curve", metric, bounds, len(seeds), (steps, interval))
        done = curve[-1]["step"] if curve else 0
        if check.integer(trial["steps_trained"], f"{where}.steps_trained", 0, steps) != done:
            raise check.fail(
                f"{where}.steps_trained",
                f"{done:,}, the step of its curve's last point (0 without one)",
                trial["steps_trained"],
            )
        if trial["state"] == "COMPLETE" and done != steps:
            raise check.fail(
                f"{where}.curve",
                f"points up to the budget's last step ({steps:,}): a finished trial trained all of it",
                f"{len(curve):,} points, the last at step {done:,}",
            )
        _curve_values(check, trial, where, curve, over)
    counted_steps = [trial["steps_trained"] for trial in trials if trial["state"] != "INTERRUPTED"]
    if trained != sum(counted_steps) * len(seeds):
        raise check.fail(
            "env_steps_trained",
            f"{sum(counted_steps) * len(seeds):,}: each counted trial's steps_trained × {len(seeds):,} tuning seeds",
            trained,
        )
    best = study["best"]
    if best is None and any(trial["state"] == "COMPLETE" for trial in trials):
        first = next(trial["number"] for trial in trials if trial["state"] == "COMPLETE")
        raise check.fail("best", f"the best finished trial (trial {first} and maybe others finished)", best)
    if best is not None:
        best = check.table(best, "best")
        check.has(best, ("value", "params"), "best.")
        _in_range(check, best["value"], "best.value", metric, bounds)
        _params(check, best["params"], specs, "best.params")
        chosen = numbers.get(check.integer(best.get("number"), "best.number", 0))
        if chosen is None or chosen["state"] != "COMPLETE":
            raise check.fail("best.number", f"the number of a finished trial of its {len(numbers):,} trials", best["number"])
        for name in ("value", "params"):
            if best[name] != chosen.get(name):
                raise check.fail(f"best.{name}", f"its trial {best['number']}'s {name}, {shown(chosen.get(name))}", best[name])
        _check_best(check, best, numbers, direction)
    return study


def _check_best(
    check: DocumentChecker, best: Mapping[str, Any], numbers: Mapping[int, Mapping[str, Any]], direction: Any
) -> None:
    """Refuse a ``best`` whose value another finished trial (each holds one) beats in the plan's ``direction``."""
    finished = [trial for trial in numbers.values() if trial["state"] == "COMPLETE"]
    top = (max if direction == "maximize" else min)(finished, key=lambda trial: trial["value"])
    if (best["value"] < top["value"]) if direction == "maximize" else (best["value"] > top["value"]):
        raise check.fail(
            "best.number", f"the best finished trial ({direction}: trial {top['number']}, value {top['value']!r})", best["number"]
        )


def _curve_values(check: DocumentChecker, trial: Mapping[str, Any], where: str, curve: list[Any], over: str) -> None:
    """A trial's ``value`` (a finished one's) and ``last_value`` what its ``curve`` gives over the
    objective (:func:`~empathy_zoo.training.study_plan.curve_value`: its last point or their mean, as
    ``tune`` computes them; equal up to float rounding), ``last_value`` null without a curve."""
    given = curve_value([point["value"] for point in curve], over) if curve else None
    for name in ("value", "last_value") if trial["state"] == "COMPLETE" else ("last_value",):
        value = trial.get(name)
        agrees = value is None if given is None else value is not None and math.isclose(value, given, rel_tol=1e-9, abs_tol=1e-12)
        if not agrees:
            expected = (
                "null, as a trial without a curve has"
                if given is None
                else f"{given!r}, what its curve gives ({'its last point' if over == 'last' else 'the mean of its points'})"
            )
            raise check.fail(f"{where}.{name}", expected, value)


def metric_bounds(metric: str, worlds: Sequence[tuple[str, Mapping[str, Any]]]) -> tuple[float, float | None]:
    """The range of a value of ``metric`` a study records (a mean over episodes and seeds):
    :data:`~empathy_zoo.metrics.METRIC_RANGES`, at most what one episode of its world can hold
    (:func:`~empathy_zoo.result_file.episode_bounds`; the largest of ``worlds`` where the study
    names several, :func:`_worlds`)."""
    from empathy_zoo.result_file import episode_bounds

    low, high = METRIC_RANGES[metric]
    most = [episode_bounds(env, kwargs)[metric] for env, kwargs in worlds]
    if any(bound is None for bound in most):
        return low, high
    world = max(bound for bound in most if bound is not None)
    return low, world if high is None else min(high, world)


def _largest_world(env: str) -> dict[str, Any]:
    """The arguments of ``env`` whose episodes hold the most of every count: ``max_cycles`` and its
    count of other agents at :data:`~empathy_zoo.limits.MAX_CYCLES` (the most a run is built with,
    :func:`~empathy_zoo.result_file.check_env_kwargs`)."""
    from empathy_zoo.environments import ENGINES

    count = ENGINES[env].count_argument
    return {"max_cycles": MAX_CYCLES, **({count: MAX_CYCLES} if count else {})}


def _worlds(check: DocumentChecker, plan: Mapping[str, Any]) -> list[tuple[str, Mapping[str, Any]]]:
    """The environments (with their arguments) the study's plan may have run on, checked as ``tune``
    makes a plan: ``experiment`` its ``variant`` and ``method``'s id
    (:func:`~empathy_zoo.run_ids.experiment_id`, ``<variant>__<method>-<hash>``; the two written
    together, or neither); ``env`` (which ``tune`` writes with ``env_kwargs``) a registered
    environment, the ``variant``'s own where the variant is named as one (a sweep file holds no
    other), ``env_kwargs`` its arguments within their ranges
    (:func:`~empathy_zoo.result_file.check_env_kwargs`). A study written before ``env`` was
    recorded: the variant's environment at its largest arguments (:func:`_largest_world`), or every
    environment's where the variant has a name of its own."""
    from empathy_zoo.environments import ENGINES
    from empathy_zoo.result_file import check_env_kwargs
    from empathy_zoo.run_ids import experiment_id

    variant = plan["variant"]
    if "experiment" in plan or "method" in plan:  # (tune writes both; a table of studies reads neither)
        check.has(plan, ("experiment", "method"), "plan.")
        method = check.text(plan["method"], "plan.method")
        experiment = check.text(plan["experiment"], "plan.experiment")
        head, _, digest = experiment.rpartition("-")
        if not head.startswith(f"{variant}__") or len(digest) != 8 or any(c not in "0123456789abcdef" for c in digest):
            raise check.fail(
                "plan.experiment", f"the id of an experiment of its variant ({variant}__<method>-<8 hex digits>)", experiment
            )
        if head != experiment_id(variant, method, {}).rpartition("-")[0]:
            raise check.fail("plan.method", f"the method of its experiment ({experiment})", method)
    if "env" not in plan and "env_kwargs" not in plan:
        envs = [variant] if variant in ENGINES else sorted(ENGINES)
        return [(env, _largest_world(env)) for env in envs]
    check.has(plan, ("env", "env_kwargs"), "plan.")
    env = plan["env"]
    if env not in ENGINES:
        raise check.fail("plan.env", f"one of the environments ({', '.join(sorted(ENGINES))})", env)
    if variant in ENGINES and variant != env:
        raise check.fail("plan.env", f"{variant}, the environment its variant is named as", env)
    return [(env, check_env_kwargs(check, env, plan["env_kwargs"], "plan.env_kwargs"))]


def _check_moves(check: DocumentChecker, worlds: Sequence[tuple[str, Mapping[str, Any]]], metric: str) -> None:
    """Refuse an objective's ``metric`` that every episode of the study's world gives one value
    (:func:`~empathy_zoo.result_file.constant_metrics`, as ``tune`` refuses it: every trial would tie)."""
    from empathy_zoo.result_file import constant_metrics

    if all(metric in constant_metrics(env, kwargs) for env, kwargs in worlds):
        envs = ", ".join(sorted({env for env, _ in worlds}))
        raise check.fail(
            "plan.objective.metric", f"a metric that moves in {envs} (tune refuses one every episode gives one value)", metric
        )


def _in_range(check: DocumentChecker, value: Any, field: str, metric: str, bounds: tuple[float, float | None]) -> float:
    """A finite value of ``metric`` within ``bounds``."""
    low, high = bounds
    number = check.finite(value, field)
    if number < low or (high is not None and number > high):
        span = f"a number >= {low:g}" if high is None else f"a number in [{low:g}, {high:g}]"
        raise check.fail(field, f"{metric}, {span}", value)
    return number


def _tuning_seeds(check: DocumentChecker, value: Any) -> list[int]:
    """``plan.tuning_seeds``: 1 … :data:`~empathy_zoo.limits.MAX_SEEDS` distinct seeds."""
    if not isinstance(value, list) or not 1 <= len(value) <= MAX_SEEDS:
        raise check.fail("plan.tuning_seeds", f"an array of 1 to {MAX_SEEDS:,} seeds", value)
    seeds = [check.integer(seed, f"plan.tuning_seeds[{i}]", 0, MAX_SEED) for i, seed in enumerate(value)]
    if len(set(seeds)) != len(seeds):
        raise check.fail("plan.tuning_seeds", "distinct seeds", value)
    return seeds


def _curve(
    check: DocumentChecker,
    value: Any,
    where: str,
    metric: str,
    bounds: tuple[float, float | None],
    seeds: int,
    schedule: tuple[int, int],
) -> None:
    """A trial's learning curve: one point per greedy evaluation, in order, at the steps of the plan's
    schedule (``schedule``: its steps and evaluation interval; point ``i`` at ``min((i + 1) · interval,
    steps)``, none past the last), each ``value`` and each of its ``seeds`` parts within ``bounds``."""
    steps, interval = schedule
    if not isinstance(value, list) or len(value) > -(-steps // interval):
        raise check.fail(where, f"an array of at most {-(-steps // interval):,} points (one per greedy evaluation)", value)
    for i, point in enumerate(value):
        at = f"{where}[{i}]"
        point = check.table(point, at)
        check.has(point, ("step", "value", "per_seed"), f"{at}.")
        due = min((i + 1) * interval, steps)
        if check.integer(point["step"], f"{at}.step", 1, MAX_STEPS) != due:
            raise check.fail(
                f"{at}.step",
                f"{due:,}, the next greedy evaluation of the plan's schedule (every {interval:,} steps, and the last: {steps:,})",
                point["step"],
            )
        _in_range(check, point["value"], f"{at}.value", metric, bounds)
        parts = point["per_seed"]
        if not isinstance(parts, list) or len(parts) != seeds:
            raise check.fail(f"{at}.per_seed", f"one value per tuning seed ({seeds:,})", parts)
        for j, part in enumerate(parts):
            _in_range(check, part, f"{at}.per_seed[{j}]", metric, bounds)


def _spec(check: DocumentChecker, name: str, spec: Any) -> _Spec:
    """A parameter's name and spec (``log:1e-4:1e-2``, ``choice:a,b``) as labels; a choice's values
    at least two, none empty; a range's ends finite, ``LOW < HIGH`` (as ``tune`` takes them) and
    within :data:`MAX_RANGE_END` (a ``log`` range's ``LOW`` at least its inverse)."""
    check.label(name, f"plan.params (the parameter {name[:60]!r})")
    where = f"plan.params.{name}"
    check.label(spec, where)
    kind, _, rest = spec.partition(":")
    items = [item.strip() for item in rest.split(",")]
    if kind == "choice" and len(items) >= 2 and all(items):
        return _Spec(kind, choices=tuple((item, _literal(item)) for item in items))
    ends = [_finite(end) for end in rest.split(":")] if kind in RANGE_KINDS else []
    if (
        len(ends) != 2
        or ends[0] is None
        or ends[1] is None
        or not -MAX_RANGE_END <= ends[0] < ends[1] <= MAX_RANGE_END
        or (kind == "log" and ends[0] < 1 / MAX_RANGE_END)
        or (kind == "int" and any(end != int(end) for end in ends if end is not None))
    ):
        raise check.fail(
            where,
            f"a parameter's spec (log:LOW:HIGH with 0 < LOW, float:LOW:HIGH, int:LOW:HIGH of whole ends: LOW < HIGH, each within "
            f"±{MAX_RANGE_END:g}, a log range's LOW at least {1 / MAX_RANGE_END:g}; or choice:A,B,... of two values or more)",
            spec,
        )
    return _Spec(kind, ends[0], ends[1])


_NO_LITERAL = object()
"""A choice's text that is no TOML literal (a text value)."""


def _literal(text: str) -> Any:
    """``text`` read as a TOML literal (``0.5``, ``true``), as ``tune`` reads a choice's value
    (:func:`empathy_zoo.experiment.search_space.parse_param`), or :data:`_NO_LITERAL`."""
    with contextlib.suppress(tomllib.TOMLDecodeError):
        return tomllib.loads(f"v = {text}")["v"]
    return _NO_LITERAL


def _is_choice(value: Any, choices: tuple[tuple[str, Any], ...]) -> bool:
    """Whether ``value`` is one of ``choices``: a text one of their texts, a boolean or a number one
    of their literals of its kind (a boolean is no number here, ``true`` no ``1``)."""
    if isinstance(value, str):
        return any(value == text for text, _ in choices)
    return any(
        isinstance(literal, (bool, int, float)) and isinstance(literal, bool) == isinstance(value, bool) and literal == value
        for _, literal in choices
    )


def _finite(text: str) -> float | None:
    """``text`` as a finite float, or ``None``."""
    try:
        return finite_float(float(text))
    except ValueError:
        return None


def _params(check: DocumentChecker, value: Any, specs: Mapping[str, _Spec], where: str, whole: bool = True) -> None:
    """A trial's parameter values: each of a parameter of the plan and, where ``whole`` (every trial
    but an interrupted one, which may have stopped before its parameters were drawn), every one of
    them; a range's a number within it (a whole one for an ``int``), a choice's one of its values."""
    table = check.table(value, where)
    for name, item in table.items():
        field = f"{where}.{name}" if name in specs else f"{where} (the parameter {name[:60]!r})"
        if name not in specs:
            raise check.fail(field, f"one of the plan's parameters ({', '.join(specs)})", name)
        spec = specs[name]
        kind, low, high = spec.kind, spec.low, spec.high
        if kind == "choice":
            if isinstance(item, str):
                check.label(item, field)
            elif not isinstance(item, bool):
                check.finite(item, field)
            if not _is_choice(item, spec.choices):
                texts = ", ".join(text for text, _ in spec.choices)
                raise check.fail(field, f"one of its choices ({texts}; a number as a number, text as text)", item)
            continue
        number = finite_float(item)
        if number is None or isinstance(item, bool) or not low <= number <= high or (kind == "int" and number != int(number)):
            raise check.fail(field, f"{'a whole number' if kind == 'int' else 'a number'} in [{low:g}, {high:g}]", item)
    missing = [name for name in specs if name not in table] if whole else []
    if missing:
        raise check.fail(f"{where}.{missing[0]}", f"a value of each of the plan's parameters ({', '.join(specs)})", None)


def _checked(where: Path, make: Any, study: Any) -> Any:
    """``make(study)``, a missing or mistyped field of the study a ``ValueError`` naming ``where``."""
    try:
        return make(study)
    except (KeyError, TypeError, AttributeError, IndexError, OverflowError) as error:
        raise ValueError(f"{where}: not a study that tune wrote ({type(error).__name__}: {error!s:.200})") from None


if __name__ == "__main__":
    raise SystemExit(main())
