"""The figure of a tuning study (``trials.png``): every trial's objective, in the order the trials
ran, with the best so far as a step line.

Drawn from ``study.json`` alone (:mod:`empathy_zoo.training.tuning`): a finished trial is a filled
dot at its value; a pruned one a hollow dot at the last value it reported (its objective up to
the evaluation where it was stopped: at fewer env steps, so
it is not comparable with the finished ones, and the best-so-far line ignores it); a refused or
interrupted trial has no value and is named in the legend's count only.
"""

from __future__ import annotations

import io
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from empathy_zoo.atomic import write_bytes_atomic

__all__ = ["TRIALS_FIGURE", "render_trials_png", "write_trials_figure"]

TRIALS_FIGURE = "trials.png"
"""The figure's file name beside ``study.json``."""


def render_trials_png(study: Mapping[str, Any], dpi: int = 110) -> bytes:
    """PNG bytes of the study document ``study`` (``study.json``'s)."""
    plan = study["plan"]
    metric, direction = plan["objective"]["metric"], plan["objective"]["direction"]
    trials = [t for t in study["trials"] if t["state"] != "INTERRUPTED"]
    complete = [(i, t["value"]) for i, t in enumerate(trials) if t["state"] == "COMPLETE" and t["value"] is not None]
    pruned = [(i, t["last_value"]) for i, t in enumerate(trials) if t["state"] == "PRUNED" and t["last_value"] is not None]
    others = len(trials) - len(complete) - len(pruned)
    figure = Figure(figsize=(7.5, 4.2), layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.subplots()
    if complete:
        axes.plot(*zip(*complete), "o", color="#0072B2", markersize=7, label=f"finished ({len(complete)})")
        best, line = None, []
        for i, value in complete:
            if best is None or (value > best if direction == "maximize" else value < best):
                best = value
            line.append((i, best))
        line.append((len(trials) - 1, line[-1][1]))
        axes.step(*zip(*line), where="post", color="0.2", linewidth=1.3, label=f"best so far ({direction})")
    if pruned:
        axes.plot(
            *zip(*pruned),
            "o",
            color="#D55E00",
            markerfacecolor="white",
            markeredgewidth=1.5,
            markersize=7,
            label=f"pruned, at its last evaluation ({len(pruned)})",
        )
    if others:
        axes.plot([], [], " ", label=f"refused ({others}): no value")
    axes.set_xlabel("trial (in the order run)")
    where = "mean of its greedy evaluations" if plan["objective"].get("over") == "curve" else "last greedy evaluation"
    axes.set_ylabel(f"{metric}, {where}\n(mean of {len(plan['tuning_seeds'])} tuning seed(s))")
    axes.set_xlim(-0.5, max(len(trials), 1) - 0.5)
    axes.xaxis.set_major_locator(MaxNLocator(integer=True))
    axes.grid(True, alpha=0.3)
    axes.legend(fontsize="small", frameon=False)
    budget = plan["budget"]
    axes.set_title(
        f"{plan['label']} on {plan['variant']}: {len(trials)} of {budget['trials']} trials × "
        f"{len(plan['tuning_seeds'])} seeds × {budget['steps']:,} steps",
        fontsize="medium",
    )
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=dpi, metadata={"Software": None})
    return buffer.getvalue()


def write_trials_figure(study: Mapping[str, Any], path: str | os.PathLike[str]) -> Path:
    """Write :func:`render_trials_png` of ``study`` to ``path`` (atomically); returns the path."""
    return write_bytes_atomic(path, render_trials_png(study))
