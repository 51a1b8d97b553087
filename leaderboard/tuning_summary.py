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
checked field by field (:func:`~leaderboard.study_file.check_study`) before anything is printed or drawn; the figure's size
is checked against its bound before it is drawn (:func:`check_figure_size`), and the text it shows
from the files is drawn as that text, never as mathtext.
"""

from __future__ import annotations

import argparse
import io
import json
import math
import os
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import LogLocator

from empathy_zoo.atomic import write_bytes_atomic
from empathy_zoo.limits import MAX_FIGURE_PIXELS, MAX_FIGURE_SIDE
from empathy_zoo.names import PNG_OPENING, TUNING_SUMMARY_MARK, check_marked_figure, check_output_file, resolved, terminal_line
from empathy_zoo.training.trials_figure import literal_text
from leaderboard.study_file import check_study, read_study, study_files
from leaderboard.tables import markdown_text

__all__ = [
    "StudySummary",
    "check_figure_path",
    "check_figure_size",
    "study_notes",
    "summarise",
    "study_names",
    "summary_table",
    "render_studies_png",
    "main",
]


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


MAX_NOTED = 10
"""The most study files a note names one by one; past it, the rest are counted."""


def _named(items: Sequence[str]) -> str:
    """``items`` joined, at most :data:`MAX_NOTED` of them named, then ``and N more``."""
    shown = "; ".join(items[:MAX_NOTED])
    return shown + (f"; and {len(items) - MAX_NOTED:,} more" if len(items) > MAX_NOTED else "")


def study_notes(left_out: Sequence[tuple[Path, Path]], read: Sequence[tuple[Path, Any]]) -> list[str]:
    """The notes a summary prints beside its table (none where each file is a study of its own): the
    paths left out, each a file read by another path (:func:`~leaderboard.study_file.study_files`),
    and the files read (``(path, document)``) that hold the same study document as one before them,
    a copy (listed, each on its own line, as a study). At most :data:`MAX_NOTED` named a note, the
    rest counted."""
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
    # (the mark its replace check reads, :func:`check_figure_path`)
    figure.savefig(buffer, format="png", dpi=dpi, metadata={"Software": TUNING_SUMMARY_MARK})
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
    device: :func:`empathy_zoo.names.check_replaceable`), a file that is no tuning-summary figure
    the suite wrote (:func:`empathy_zoo.names.check_marked_figure`), a parent that is a file, or one of the
    ``studies`` read (the same file, by its resolved path or, once there, by device and inode:
    drawing would replace it)."""
    path = Path(figure)
    for study in studies:
        if resolved(path) == resolved(study) or (path.exists() and _same_file(path, study)):
            raise ValueError(
                f"{figure} lies where the study file {study} is read (it is that file): the figure would replace it; "
                "write it elsewhere"
            )
    check_output_file(path, "PNG", ".png", "studies.png")
    return check_marked_figure(path, "tuning-summary", PNG_OPENING, TUNING_SUMMARY_MARK)  # (no user's or other tool's image)


def _same_file(path: Path, other: Path) -> bool:
    """Whether ``path`` and ``other`` are one file (a hard link); ``False`` where either cannot be looked at."""
    try:
        return os.path.samefile(path, other)
    except OSError:
        return False


def _checked(where: Path, make: Any, study: Any) -> Any:
    """``make(study)``, a missing or mistyped field of the study a ``ValueError`` naming ``where``."""
    try:
        return make(study)
    except (KeyError, TypeError, AttributeError, IndexError, OverflowError) as error:
        raise ValueError(f"{where}: not a study that tune wrote ({type(error).__name__}: {error!s:.200})") from None


if __name__ == "__main__":
    raise SystemExit(main())
