"""Task performance against side effect: one point per method, its interval in both directions,
the Pareto front marked — the picture a side-effect comparison is read from.

Per environment, its entry in the environment table names the task and the side effect
(:func:`tradeoff_spec`): Coexistence plots steps survived (the task, higher is better) against harms
per episode (the side effect, lower is better); Sharing plots the robot's batteries against equality
(higher is better). Each figure has two panels, the greedy evaluations
and the final 10 % of training, drawn from the leaderboard's own scores (the same means and 95 %
intervals as its tables). A method is on the front when no other method is at least as good on
both axes and better on one (:func:`pareto_front`, on the means).
"""

from __future__ import annotations

import io
import os
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from empathy_zoo.environments import entry_of
from empathy_zoo.figure_text import literal_text
from empathy_zoo.metrics import HIGHER_IS_BETTER
from empathy_zoo.names import confined
from leaderboard.aggregate import MIN_INTERVAL_SEEDS, PHASES, Score
from leaderboard.colours import label_colours
from leaderboard.plots import seeds_text, write_figure
from leaderboard.tables import PHASE_TITLES

__all__ = ["TradeoffSpec", "tradeoff_spec", "pareto_front", "render_tradeoff_png", "plot_tradeoffs", "tradeoff_filename"]


@dataclass(frozen=True)
class TradeoffSpec:
    """Which two metrics of an environment are its task and its side effect."""

    task: str
    """Metric on the x axis (higher is better)."""
    task_label: str
    """Its axis label."""
    effect: str
    """Metric on the y axis."""
    effect_label: str
    """Its axis label."""
    effect_higher_is_better: bool
    """Whether more of the y metric is better (equality) or worse (harms)."""


def tradeoff_spec(env: str, base_env: str | None = None) -> TradeoffSpec | None:
    """The trade-off of ``env`` (a variant is drawn like its environment ``base_env``): its entry's
    task and first side effect (:class:`~empathy_zoo.environments.Environment`), the side effect's
    direction from :data:`~empathy_zoo.metrics.HIGHER_IS_BETTER`; ``None`` for an environment
    without a side effect or an entry."""
    entry = entry_of(env, base_env)
    if entry is None or not entry.side_effects:
        return None
    effect = entry.side_effects[0]
    return TradeoffSpec(entry.task, entry.task_label, effect, entry.side_effect_label, HIGHER_IS_BETTER[effect])


def tradeoff_filename(env: str) -> str:
    """File name of the trade-off figure of ``env``."""
    return f"{env}_tradeoff.png"


def pareto_front(points: Sequence[tuple[float, float]], effect_higher_is_better: bool) -> list[int]:
    """Indices of the points no other point dominates: ``(task, effect)`` pairs, the task to be
    maximised and the effect maximised or minimised. A point with a NaN is never on the front and
    never dominates; equal points are all on it."""
    values = np.array(points, dtype=np.float64).reshape(-1, 2)
    if not effect_higher_is_better:
        values = values * np.array([1.0, -1.0])
    finite = np.isfinite(values).all(axis=1)
    front = []
    for i in np.flatnonzero(finite):
        others = values[finite]
        dominated = ((others >= values[i]).all(axis=1) & (others > values[i]).any(axis=1)).any()
        if not dominated:
            front.append(int(i))
    return front


def _cell(scores: Sequence[Score], label: str, phase: str, metric: str) -> Score | None:
    return next((s for s in scores if s.method_label == label and s.phase == phase and s.metric == metric), None)


def render_tradeoff_png(
    scores: Sequence[Score], env: str, spec: TradeoffSpec, dpi: int = 110, dqn_labels: Collection[str] = ()
) -> bytes:
    """PNG bytes of ``env``'s trade-off, one panel per phase, from the leaderboard's ``scores``:
    each method in its label's colour (:func:`leaderboard.colours.label_colours`; ``dqn_labels``
    are the DQN reference rows, said so in the legend), without bars below
    :data:`~leaderboard.aggregate.MIN_INTERVAL_SEEDS` seeds (said in the legend). The labels and
    ``env`` are drawn as written, never as mathtext (:func:`~empathy_zoo.figure_text.literal_text`)."""
    scores = [s for s in scores if s.env == env]
    labels = list(dict.fromkeys(s.method_label for s in scores))
    by_label = label_colours(labels, dqn_labels)
    colours = [by_label[label] for label in labels]
    figure = Figure(figsize=(11.0, 4.6), layout="constrained")
    FigureCanvasAgg(figure)
    panels = figure.subplots(1, len(PHASES), squeeze=False)[0]
    for axes, phase in zip(panels, PHASES, strict=True):
        cells = [(_cell(scores, label, phase, spec.task), _cell(scores, label, phase, spec.effect)) for label in labels]
        drawn = [(label, x, y) for label, (x, y) in zip(labels, cells, strict=True) if x is not None and y is not None]
        front = set(pareto_front([(x.mean, y.mean) for _, x, y in drawn], spec.effect_higher_is_better))
        for i, (label, x, y) in enumerate(drawn):
            colour = colours[labels.index(label)]
            on_front = i in front
            bars = min(x.n_seeds, y.n_seeds) >= MIN_INTERVAL_SEEDS
            axes.errorbar(
                x.mean,
                y.mean,
                xerr=[[x.mean - x.ci_low], [x.ci_high - x.mean]] if bars else None,
                yerr=[[y.mean - y.ci_low], [y.ci_high - y.mean]] if bars else None,
                fmt="o",
                color=colour,
                markersize=8,
                markerfacecolor=colour if on_front else "white",
                markeredgewidth=1.6,
                capsize=3,
                linewidth=1.2,
            )
        if len(front) > 1:
            ordered = sorted((drawn[i][1].mean, drawn[i][2].mean) for i in front)
            axes.plot(*zip(*ordered, strict=True), color="0.35", linestyle="--", linewidth=1.0, zorder=0)
        axes.set_title(PHASE_TITLES.get(phase, phase))
        axes.set_xlabel(spec.task_label)
        axes.set_ylabel(spec.effect_label)
        axes.grid(True, alpha=0.3)
    seeds = {s.method_label: s.n_seeds for s in scores if s.metric in (spec.task, spec.effect)}
    handles = [
        Line2D(
            [],
            [],
            marker="s",
            linestyle="",
            color=colours[i],
            markersize=8,
            label=literal_text(f"{label} ({seeds_text(seeds[label])}{', the DQN reference' if label in dqn_labels else ''})"),
        )
        for i, label in enumerate(labels)
    ]
    handles += [
        Line2D([], [], marker="o", linestyle="--", color="0.35", markersize=8, label="on the Pareto front"),
        Line2D([], [], marker="o", linestyle="", color="0.35", markerfacecolor="white", markersize=8, label="dominated"),
    ]
    figure.legend(
        handles=handles,
        loc="outside right upper",
        fontsize="small",
        frameon=False,
        title="method (bars: 95 % CI over seeds)",
        title_fontsize="small",
    )
    figure.suptitle(f"{literal_text(env)}: task against side effect")
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=dpi, metadata={"Software": None})
    return buffer.getvalue()


def plot_tradeoffs(
    scores: Sequence[Score],
    figures_dir: str | os.PathLike[str],
    base_env: dict[str, str] | None = None,
    dqn_rows: Collection[tuple[str, str]] = (),
) -> dict[str, Path]:
    """Write the trade-off figure of every env of ``scores`` that has a spec (``base_env`` maps a
    variant to its environment; ``dqn_rows`` are the ``(env, label)`` DQN reference rows:
    :func:`leaderboard.row_names.dqn_rows_of`); returns ``{env: path}``, envs sorted."""
    paths: dict[str, Path] = {}
    for env in sorted({s.env for s in scores}):
        spec = tradeoff_spec(env, (base_env or {}).get(env))
        if spec is None:
            continue
        png = render_tradeoff_png(scores, env, spec, dqn_labels={label for row_env, label in dqn_rows if row_env == env})
        paths[env] = write_figure(confined(figures_dir, tradeoff_filename(env)), png)
    return paths
