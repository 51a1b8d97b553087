"""Learning-curve figures (PNG): one line per method, a shaded Student-t band over seeds (the leaderboard's interval of the mean).

Uses matplotlib's object API with the Agg canvas directly (no ``pyplot``, no global backend
switch), so it is safe headless and in worker processes. Every PNG is written atomically.
"""

from __future__ import annotations

import io
import os
from collections.abc import Collection, Iterable, Mapping, Sequence
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from empathy_zoo.atomic import write_bytes_atomic
from empathy_zoo.environments import entry_of
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.figure_text import literal_text
from empathy_zoo.names import confined
from leaderboard.aggregate import (
    CONFIDENCE,
    MIN_INTERVAL_SEEDS,
    N_POINTS,
    Curve,
    group_runs,
    learning_curves,
)
from leaderboard.colours import label_colours
from leaderboard.reference_curves import reference_curve, reference_refusals
from leaderboard.row_names import dqn_rows_of

__all__ = [
    "figure_spec",
    "FALLBACK_SPEC",
    "figure_filename",
    "seeds_text",
    "render_curves_png",
    "plot_metric",
    "plot_learning_curves",
    "write_figure",
]

FigureSpec = tuple[tuple[str, str], ...]

FALLBACK_SPEC: FigureSpec = (("return", "Return per episode (robot)"),)
"""Drawn for an env without an entry in the environment table."""


def figure_spec(env: str, base_env: str) -> FigureSpec:
    """The ``(metric, y-axis label)`` pairs drawn for ``env`` (a variant is drawn like its environment
    ``base_env``): its entry's :attr:`~empathy_zoo.environments.Environment.curves`, else
    :data:`FALLBACK_SPEC`."""
    entry = entry_of(env, base_env)
    return FALLBACK_SPEC if entry is None else entry.curves


def write_figure(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write a figure's bytes ``data`` to ``path`` atomically; an ``OSError`` (a full disk) names
    ``path``, not the temporary file it was writing."""
    try:
        return write_bytes_atomic(path, data)
    except OSError as error:
        raise OSError(error.errno, error.strerror or str(error), os.fspath(path)) from None


def seeds_text(n_seeds: int) -> str:
    """How a legend names a row's seeds: ``"n=5"``, or ``"n=2: no interval"`` below
    :data:`~leaderboard.aggregate.MIN_INTERVAL_SEEDS` (no interval is drawn then)."""
    return f"n={n_seeds}" if n_seeds >= MIN_INTERVAL_SEEDS else f"n={n_seeds}: no interval"


def figure_filename(env: str, metric: str) -> str:
    """File name of the figure of ``metric`` on ``env``."""
    return f"{env}_{metric}.png"


def render_curves_png(
    curves: Sequence[Curve],
    *,
    title: str,
    references: Sequence[np.ndarray | None] | None = None,
    ylabel: str,
    xlabel: str = "training env steps",
    confidence: float = CONFIDENCE,
    dpi: int = 110,
    dqn_labels: Collection[str] = (),
) -> bytes:
    """PNG bytes of ``curves``: a line per curve (its mean) in its label's colour
    (:func:`leaderboard.colours.label_colours`; ``dqn_labels`` are the DQN reference rows, said so
    in the legend) with its interval shaded (none below
    :data:`~leaderboard.aggregate.MIN_INTERVAL_SEEDS` seeds, said in the legend), and, where
    ``references[i]`` is given, that curve's exact reference dashed in the same colour. The labels,
    ``title``, ``ylabel`` and ``xlabel`` are drawn as written, never as mathtext
    (:func:`~empathy_zoo.figure_text.literal_text`)."""
    figure = Figure(figsize=(7.5, 4.2), layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.add_subplot()
    by_label = label_colours([curve.method_label for curve in curves], dqn_labels)
    colours = [by_label[curve.method_label] for curve in curves]
    for curve, colour in zip(curves, colours, strict=True):
        role = ", the DQN reference" if curve.method_label in dqn_labels else ""
        label = literal_text(f"{curve.method_label} ({seeds_text(curve.n_seeds)}{role})")
        axes.plot(curve.steps, curve.mean, color=colour, linewidth=1.8, label=label)
        if curve.n_seeds >= MIN_INTERVAL_SEEDS:
            axes.fill_between(curve.steps, curve.ci_low, curve.ci_high, color=colour, alpha=0.2, linewidth=0)
    drawn = [reference for reference in references or [] if reference is not None]
    for curve, colour, reference in zip(curves, colours, references or [None] * len(curves), strict=True):
        if reference is not None:
            axes.plot(curve.steps, reference, color=colour, linewidth=1.2, linestyle="--")
    if drawn:  # one neutral legend entry for every dashed line
        axes.plot([], [], color="0.4", linewidth=1.2, linestyle="--", label="exact optimum of that β at the run's ε")
    axes.set_title(literal_text(title))
    axes.set_xlabel(literal_text(xlabel))
    axes.set_ylabel(literal_text(ylabel))
    axes.grid(True, alpha=0.3)
    axes.ticklabel_format(axis="x", style="sci", scilimits=(-3, 4))
    if curves:
        axes.legend(
            loc="upper left",
            bbox_to_anchor=(1.01, 1.0),
            fontsize="small",
            frameon=False,
            title=f"method (shaded: {confidence:.0%} CI over seeds)",
            title_fontsize="small",
        )
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=dpi, metadata={"Software": None})
    return buffer.getvalue()


def plot_metric(
    results: Iterable[RunResult],
    env: str,
    metric: str,
    path: str | os.PathLike[str],
    *,
    ylabel: str | None = None,
    title: str | None = None,
    n_points: int = N_POINTS,
    confidence: float = CONFIDENCE,
    refused: Collection[tuple[str, str]] | None = None,
) -> Path:
    """Draw the training curves of ``metric`` on ``env`` (every method, with the exact reference
    where it applies: :mod:`leaderboard.reference_curves`) and write the PNG to ``path``.
    ``refused``: the ``(env, label)`` groups drawn without it (by default those of
    :func:`~leaderboard.reference_curves.reference_refusals` over ``results``)."""
    results = list(results)
    curves = learning_curves(
        results,
        metric,
        env=env,
        n_points=n_points,
        confidence=confidence,
    )
    if not curves:
        raise ValueError(f"no runs on env {env!r} to plot")
    groups = group_runs(results)
    refused = reference_refusals(groups, n_points) if refused is None else refused
    references = []
    for curve in curves:
        key = (curve.env, curve.method_label)
        references.append(None if key in refused else reference_curve(groups[key], metric, curve.steps))
    ylabel = ylabel or f"{metric} per episode"
    png = render_curves_png(
        curves,
        title=title or f"{env}: {ylabel.lower()}",
        ylabel=ylabel,
        confidence=confidence,
        references=references,
        dqn_labels={label for row_env, label in dqn_rows_of(results) if row_env == env},
    )
    return write_figure(path, png)


def plot_learning_curves(
    results: Iterable[RunResult],
    figures_dir: str | os.PathLike[str],
    *,
    specs: Mapping[str, FigureSpec] | None = None,
    n_points: int = N_POINTS,
    confidence: float = CONFIDENCE,
) -> dict[tuple[str, str], Path]:
    """The figures of every env present in ``results``: ``specs``'s, by default the environment
    table's (:func:`figure_spec`).

    Returns ``{(env, metric): path}``, envs sorted, metrics in spec order.
    """
    results = list(results)
    refused = reference_refusals(group_runs(results), n_points)
    envs = sorted({env for env, _ in group_runs(results)})
    base_env = {run.table_env: run.env for run in results}  # a variant is drawn like its env
    paths: dict[tuple[str, str], Path] = {}
    for env in envs:
        spec = figure_spec(env, base_env[env]) if specs is None else specs.get(env, specs.get(base_env[env], FALLBACK_SPEC))
        for metric, ylabel in spec:
            paths[(env, metric)] = plot_metric(
                results,
                env,
                metric,
                confined(figures_dir, figure_filename(env, metric)),
                ylabel=ylabel,
                n_points=n_points,
                confidence=confidence,
                refused=refused,
            )
    return paths
