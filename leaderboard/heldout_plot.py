"""The held-out figure: each method's score with its own partners against its held-out partners.

One panel per metric of the environment (its entry's :attr:`~empathy_zoo.environments.Environment.heldout_metrics`), one slot per
method: a black line across the slot at the method's mean with its training partners (its 95 %
interval shaded), and one coloured point per held-out scenario (its interval as a bar) joined to
that line, so the generalisation gap reads as the length of the join. A scenario that is the
method's own world is drawn hollow. Drawn from the section's own cells (the same means and
intervals as its tables); matplotlib's object API on the Agg canvas, written atomically.
"""

from __future__ import annotations

import io
import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from empathy_zoo.evaluation_file import TRAINED_WITH
from empathy_zoo.figure_text import literal_text
from empathy_zoo.metrics import HARMS_PER_100_STEPS
from empathy_zoo.names import confined
from leaderboard.aggregate import MIN_INTERVAL_SEEDS
from leaderboard.colours import distinct_colours
from leaderboard.heldout_scores import higher_is_better
from leaderboard.plots import write_figure

if TYPE_CHECKING:
    from leaderboard.heldout_scores import HeldoutCell, HeldoutGroup

__all__ = ["heldout_filename", "render_heldout_png", "plot_heldout"]


def heldout_filename(env: str, scenario_set: str) -> str:
    """File name of the held-out figure of ``env`` and a scenario set."""
    return f"{env}_heldout_{scenario_set}.png"


def render_heldout_png(group: HeldoutGroup, cells: Sequence[HeldoutCell], dpi: int = 110) -> bytes:
    """PNG bytes of the group's figure (see the module page). The labels, scenario names and
    ``env`` are drawn as written, never as mathtext (:func:`~empathy_zoo.figure_text.literal_text`)."""
    by_key = {(c.method_label, c.scenario, c.metric): c for c in cells}
    labels = list(group.runs)
    held_out = group.scenarios[1:]
    colours = distinct_colours(len(held_out))  # (one per scenario, not per method)
    width = max(8.0, 1.2 * len(labels) + 4.0)
    figure = Figure(figsize=(width, 3.4 * len(group.metrics) + 0.8), layout="constrained")
    FigureCanvasAgg(figure)
    panels = figure.subplots(len(group.metrics), 1, squeeze=False)[:, 0]
    half = 0.38
    for axes, metric in zip(panels, group.metrics, strict=True):
        for x, label in enumerate(labels):
            own = by_key[(label, TRAINED_WITH, metric)]
            interval = len(group.runs[label]) >= MIN_INTERVAL_SEEDS  # (below: no band, no bars, as the tables say)
            if interval:
                axes.fill_between([x - half, x + half], own.ci_low, own.ci_high, color="0.85", linewidth=0, zorder=1)
            axes.plot([x - half, x + half], [own.mean, own.mean], color="black", linewidth=2.0, zorder=3)
            for j, scenario in enumerate(held_out):
                cell = by_key[(label, scenario, metric)]
                offset = x - half + (j + 0.5) * (2 * half / len(held_out))
                same = scenario in group.same_world.get(label, set())
                axes.plot([offset, offset], [own.mean, cell.mean], color=colours[j], linewidth=0.8, alpha=0.6, zorder=2)
                axes.errorbar(
                    offset,
                    cell.mean,
                    yerr=[[max(0.0, cell.mean - cell.ci_low)], [max(0.0, cell.ci_high - cell.mean)]] if interval else None,
                    fmt="o",
                    color=colours[j],
                    markerfacecolor="white" if same else colours[j],
                    markersize=5,
                    capsize=2,
                    linewidth=1.0,
                    zorder=4,
                )
        better = "higher" if higher_is_better(metric) else "lower"
        unit = metric.replace("_", " ") if metric == HARMS_PER_100_STEPS else f"{metric} per episode"
        axes.set_ylabel(f"{unit}\n({better} is better)")
        axes.set_xticks(range(len(labels)))
        axes.set_xticklabels(
            [_tick(label, len(group.runs[label])) for label in labels], rotation=20, ha="right", fontsize="small"
        )
        axes.set_xlim(-0.6, len(labels) - 0.4)
        axes.grid(True, axis="y", alpha=0.3)
    handles: list[Line2D | Patch] = [
        Line2D([], [], color="black", linewidth=2.0, label="trained with (own partners)"),
        Patch(color="0.85", label="its 95 % interval over seeds"),
    ]
    handles += [
        Line2D([], [], marker="o", linestyle="", color=colours[j], label=literal_text(name)) for j, name in enumerate(held_out)
    ]
    if any(group.same_world.values()):
        handles.append(
            Line2D([], [], marker="o", linestyle="", color="0.4", markerfacecolor="white", label="= the run's own world")
        )
    figure.legend(
        handles=handles,
        loc="outside right upper",
        fontsize="small",
        frameon=False,
        title="scenario (bars: 95 % CI over seeds)",
        title_fontsize="small",
    )
    panels[0].set_title(
        literal_text(f"{group.env}, scenario set {group.scenario_set.name}: own partners against held-out ones"),
        fontsize="medium",
    )
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=dpi, metadata={"Software": None})
    return buffer.getvalue()


def _tick(label: str, seeds: int) -> str:
    """A row's label under its group: its seed count, and that it has no interval below
    :data:`~leaderboard.aggregate.MIN_INTERVAL_SEEDS`; drawn as written (never as mathtext)."""
    return literal_text(f"{label} (n={seeds})" if seeds >= MIN_INTERVAL_SEEDS else f"{label} (n={seeds}: no interval)")


def plot_heldout(group: HeldoutGroup, cells: Sequence[HeldoutCell], figures_dir: str | os.PathLike[str]) -> Path:
    """Write the group's figure into ``figures_dir``; returns its path."""
    png = render_heldout_png(group, cells)
    return write_figure(confined(figures_dir, heldout_filename(group.env, group.scenario_set.name)), png)
