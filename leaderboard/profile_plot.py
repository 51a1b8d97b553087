"""The performance-profile figure: per environment, a small panel per row and normalized metric,
the row's profile (the fraction of its runs whose normalized score lies above τ, against τ) in its
colour with its bootstrap band shaded, and the DQN reference's profile dashed beside it.

Overlaid in one panel, the profiles of a handful of seeds hid one another: they are step
functions that often coincide, and their wide bands covered the whole panel. One panel per row
keeps each readable, and the DQN line in every panel keeps them comparable. A metric's panels
form one row of the figure (wrapped after :data:`MAX_COLUMNS`). Drawn from
:mod:`leaderboard.profiles`' numbers; matplotlib's object API on the Agg canvas, written atomically.
"""

from __future__ import annotations

import io
import os
import textwrap
from collections.abc import Collection, Mapping, Sequence
from pathlib import Path

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from empathy_zoo.figure_text import literal_text
from empathy_zoo.names import confined
from leaderboard.aggregate import CONFIDENCE, MIN_INTERVAL_SEEDS
from leaderboard.colours import label_colours
from leaderboard.plots import seeds_text, write_figure
from leaderboard.profiles import Profile

__all__ = ["MAX_COLUMNS", "profile_filename", "render_profiles_png", "plot_profiles"]

MAX_COLUMNS = 5
"""The most panels side by side; a metric of more rows takes several lines of panels."""


def profile_filename(env: str) -> str:
    """File name of the performance-profile figure of ``env``."""
    return f"{env}_profiles.png"


def render_profiles_png(
    panels: Sequence[tuple[str, Mapping[str, Profile]]],
    *,
    title: str,
    dqn_labels: Collection[str] = (),
    confidence: float = CONFIDENCE,
    dpi: int = 110,
) -> bytes:
    """PNG bytes of one environment's figure: ``panels`` is ``[(metric's axis label, {row: profile})]``;
    rows in the order given, each in its label's colour (:func:`leaderboard.colours.label_colours`),
    its band shaded (none below :data:`~leaderboard.aggregate.MIN_INTERVAL_SEEDS` runs, said in the
    panel's title); ``dqn_labels``' profiles dashed in every other panel of their metric. The labels,
    axis labels and ``title`` are drawn as written, never as mathtext
    (:func:`~empathy_zoo.figure_text.literal_text`)."""
    labels = list(dict.fromkeys(label for _, profiles in panels for label in profiles))
    colours = label_colours(labels, dqn_labels)
    columns = max(1, min(MAX_COLUMNS, len(labels)))
    lines_per_metric = max(1, -(-len(labels) // columns))
    rows = len(panels) * lines_per_metric
    figure = Figure(figsize=(2.75 * columns + 0.6, 2.45 * rows + 0.9), layout="constrained")
    FigureCanvasAgg(figure)
    grid = figure.subplots(rows, columns, squeeze=False, sharex=True, sharey=True)
    for axes in grid.ravel():
        axes.set_visible(False)
    for m, (xlabel, profiles) in enumerate(panels):
        references = [(label, profile) for label, profile in profiles.items() if label in dqn_labels]
        for i, label in enumerate(labels):
            axes = grid[m * lines_per_metric + i // columns, i % columns]
            axes.set_visible(True)
            profile = profiles.get(label)
            for reference, theirs in references:
                if reference != label:
                    axes.plot(
                        theirs.taus,
                        theirs.fraction,
                        drawstyle="steps-post",
                        color=colours[reference],
                        linestyle="--",
                        linewidth=1.0,
                    )
            if profile is not None:
                colour = colours[label]
                if profile.runs >= MIN_INTERVAL_SEEDS:
                    axes.fill_between(profile.taus, profile.low, profile.high, step="post", color=colour, alpha=0.25, linewidth=0)
                axes.plot(profile.taus, profile.fraction, drawstyle="steps-post", color=colour, linewidth=2.0)
            runs = seeds_text(profile.runs) if profile is not None else "no runs"
            axes.set_title(literal_text("\n".join(textwrap.wrap(f"{label} ({runs})", 30))), fontsize="small")
            axes.set_xlim(0.0, 1.0)
            axes.set_ylim(-0.03, 1.03)
            axes.grid(True, alpha=0.3)
            axes.tick_params(labelsize="small", labelbottom=True, labelleft=i % columns == 0)
            axes.set_xlabel(f"τ: {literal_text(xlabel)}", fontsize="small")
            if i % columns == 0:
                axes.set_ylabel("fraction of runs > τ", fontsize="small")
    handles = [Line2D([], [], color="0.35", linewidth=2.0), Patch(color="0.35", alpha=0.25, linewidth=0)]
    names = ["the row's runs", f"{confidence:.0%} bootstrap band"]
    if dqn_labels:
        handles.append(Line2D([], [], color="black", linestyle="--", linewidth=1.0))
        names.append("the DQN reference, for comparison")
    figure.legend(handles, names, loc="outside lower center", ncols=len(handles), fontsize="small", frameon=False)
    figure.suptitle(literal_text(title))
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=dpi, metadata={"Software": None})
    return buffer.getvalue()


def plot_profiles(
    env: str,
    panels: Sequence[tuple[str, Mapping[str, Profile]]],
    figures_dir: str | os.PathLike[str],
    dqn_labels: Collection[str] = (),
    confidence: float = CONFIDENCE,
) -> Path:
    """Draw ``env``'s figure (:func:`render_profiles_png`) into ``figures_dir``; returns its path."""
    png = render_profiles_png(
        panels, title=f"{env}: performance profiles, final greedy evaluation", dqn_labels=dqn_labels, confidence=confidence
    )
    return write_figure(confined(figures_dir, profile_filename(env)), png)
