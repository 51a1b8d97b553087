"""The figures of a tuning study, beside its ``study.json``: every trial's objective in the order
the trials ran (``trials.png``) and how much each tuned parameter mattered to it (``importance.png``).

``trials.png`` is drawn from ``study.json`` alone (:mod:`empathy_zoo.training.tuning`): a
finished trial is a filled dot at its value; a pruned one a hollow dot at the last value it
reported (its objective up to the evaluation where it was stopped: at fewer env steps, so it is
not comparable with the finished ones, and the best-so-far line ignores it); a refused or
interrupted trial has no value and is named in the legend's count only. The best so far is a step line.

``importance.png`` is drawn from ``study.json`` and the distributions the parameters were drawn
from. The importances are Optuna's :func:`optuna.importance.get_param_importances` with
:class:`optuna.importance.PedAnovaImportanceEvaluator` (Optuna's default evaluator from 5.0 on,
named here so that Optuna 4 computes the same), over the finished trials only. PED-ANOVA draws no
random number, so the figure is the same for the same study; fANOVA, Optuna 4's default, needs
scikit-learn and a seed. The figure is skipped, with a one-line reason
(:func:`importance_skipped`), for a study of one parameter, a study with fewer than two finished
trials, and a study whose finished trials cannot tell the parameters apart (PED-ANOVA's own
warning).

Text a figure shows from a sweep or study file (a label, a parameter's name or spec) is drawn as
that text, never as mathtext (:func:`~empathy_zoo.figure_text.literal_text`, imported here for
the callers that import it from this module). Matplotlib and Optuna are imported when a figure is
drawn, never when this module is imported.
"""

from __future__ import annotations

import io
import os
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from empathy_zoo.atomic import write_bytes_atomic
from empathy_zoo.figure_text import literal_text
from empathy_zoo.names import IMPORTANCE_MARK, TRIALS_MARK

__all__ = [
    "IMPORTANCE_FIGURE",
    "TRIALS_FIGURE",
    "importance_skipped",
    "literal_text",
    "param_importances",
    "render_importance_png",
    "render_trials_png",
    "write_importance_figure",
    "write_trials_figure",
]

TRIALS_FIGURE = "trials.png"
"""The trials figure's file name beside ``study.json``."""
IMPORTANCE_FIGURE = "importance.png"
"""The parameter-importance figure's file name beside ``study.json``."""
_CANNOT_TELL = "importances will be equal"
"""What PED-ANOVA warns when the finished trials cannot tell the parameters apart."""


def _figure(size: tuple[float, float]) -> Any:
    """A Matplotlib figure drawn by the Agg canvas (no display needed)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(figure)
    return figure


def _png(figure: Any, dpi: int, mark: str) -> bytes:
    """PNG bytes of ``figure``, stamped with the suite's ``mark`` in place of Matplotlib's version
    (the same figure gives the same bytes; ``tune`` replaces only a figure holding its mark:
    :func:`empathy_zoo.names.check_marked_figure`)."""
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=dpi, metadata={"Software": mark})
    return buffer.getvalue()


def _finished(study: Mapping[str, Any]) -> list[Mapping[str, Any]]:
    """The trials of ``study`` that finished with a value."""
    return [t for t in study["trials"] if t["state"] == "COMPLETE" and t["value"] is not None]


def render_trials_png(study: Mapping[str, Any], dpi: int = 110) -> bytes:
    """PNG bytes of the trials figure of the study document ``study`` (``study.json``'s)."""
    from matplotlib.ticker import MaxNLocator

    plan = study["plan"]
    metric, direction = plan["objective"]["metric"], plan["objective"]["direction"]
    trials = [t for t in study["trials"] if t["state"] != "INTERRUPTED"]
    complete = [(i, t["value"]) for i, t in enumerate(trials) if t["state"] == "COMPLETE" and t["value"] is not None]
    pruned = [(i, t["last_value"]) for i, t in enumerate(trials) if t["state"] == "PRUNED" and t["last_value"] is not None]
    others = len(trials) - len(complete) - len(pruned)
    figure = _figure((7.5, 4.2))
    axes = figure.subplots()
    if complete:
        axes.plot(*zip(*complete, strict=True), "o", color="#0072B2", markersize=7, label=f"finished ({len(complete)})")
        best, line = None, []
        for i, value in complete:
            if best is None or (value > best if direction == "maximize" else value < best):
                best = value
            line.append((i, best))
        line.append((len(trials) - 1, line[-1][1]))
        axes.step(*zip(*line, strict=True), where="post", color="0.2", linewidth=1.3, label=f"best so far ({direction})")
    if pruned:
        axes.plot(
            *zip(*pruned, strict=True),
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
        literal_text(
            f"{plan['label']} on {plan['variant']}: {len(trials)} of {budget['trials']} trials × "
            f"{len(plan['tuning_seeds'])} seeds × {budget['steps']:,} steps"
        ),
        fontsize="medium",
    )
    return _png(figure, dpi, TRIALS_MARK)


def write_trials_figure(study: Mapping[str, Any], path: str | os.PathLike[str]) -> Path:
    """Write :func:`render_trials_png` of ``study`` to ``path`` (atomically); returns the path."""
    return write_bytes_atomic(path, render_trials_png(study))


def importance_skipped(study: Mapping[str, Any]) -> str | None:
    """Why the study document ``study`` has no importance figure (one line), or ``None`` when it has one."""
    params = study["plan"]["params"]
    if len(params) < 2:
        return f"no {IMPORTANCE_FIGURE}: the study tunes one parameter ({', '.join(params)})"
    finished = len(_finished(study))
    if finished < 2:
        return f"no {IMPORTANCE_FIGURE}: it needs 2 finished trials, the study has {finished}"
    return None


def param_importances(study: Mapping[str, Any], distributions: Mapping[str, Any]) -> dict[str, float] | str:
    """Each parameter's importance to the objective over the finished trials of the study document
    ``study`` (PED-ANOVA, normalised to sum to 1, the most important first), whose parameters were
    drawn from the Optuna ``distributions`` (by name); or the one-line reason there is none
    (:func:`importance_skipped`, or the trials cannot tell the parameters apart)."""
    skipped = importance_skipped(study)
    if skipped is not None:
        return skipped
    import optuna
    from optuna.importance import PedAnovaImportanceEvaluator, get_param_importances

    names = list(study["plan"]["params"])
    chosen = {name: distributions[name] for name in names}
    verbosity = optuna.logging.get_verbosity()
    optuna.logging.set_verbosity(optuna.logging.ERROR)
    try:
        memory = optuna.create_study(direction=study["plan"]["objective"]["direction"])
        memory.add_trials(
            [
                optuna.trial.create_trial(params=dict(t["params"]), distributions=chosen, value=t["value"])
                for t in _finished(study)
            ]
        )
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            importances = get_param_importances(memory, evaluator=PedAnovaImportanceEvaluator(), params=names)
    finally:
        optuna.logging.set_verbosity(verbosity)
    if any(_CANNOT_TELL in str(warning.message).lower() for warning in caught):
        return (
            f"no {IMPORTANCE_FIGURE}: the {len(_finished(study))} finished trials cannot tell the parameters apart "
            "(their best values are not set apart from the rest)"
        )
    return {name: float(value) for name, value in importances.items()}


def render_importance_png(study: Mapping[str, Any], importances: Mapping[str, float], dpi: int = 110) -> bytes:
    """PNG bytes of the importance figure: one bar per parameter of ``importances`` (as
    :func:`param_importances` gives them), the most important on top."""
    plan = study["plan"]
    names = list(importances)[::-1]  # (barh draws the first at the bottom)
    values = [importances[name] for name in names]
    figure = _figure((7.5, 1.6 + 0.45 * len(names)))
    axes = figure.subplots()
    labels = [literal_text(f"{name}\n({plan['params'][name]})") for name in names]
    bars = axes.barh(labels, values, color="#0072B2", height=0.6)
    axes.bar_label(bars, labels=[f"{value:.2f}" for value in values], padding=3, fontsize="small")
    axes.set_xlim(0, max(1.0, max(values) * 1.15))
    axes.set_xlabel("importance to the objective (PED-ANOVA, share of the total)")
    axes.grid(True, axis="x", alpha=0.3)
    objective = plan["objective"]
    axes.set_title(
        literal_text(
            f"What mattered to {objective['metric']} ({objective['direction']}): {plan['label']} on {plan['variant']},\n"
            f"over its {len(_finished(study))} finished trial(s) of {len(study['trials'])}"
        ),
        fontsize="medium",
    )
    axes.tick_params(axis="y", labelsize="small")
    return _png(figure, dpi, IMPORTANCE_MARK)


def write_importance_figure(
    study: Mapping[str, Any], distributions: Mapping[str, Any], path: str | os.PathLike[str]
) -> str | None:
    """Write the importance figure of ``study`` (whose parameters were drawn from ``distributions``)
    to ``path`` (atomically); returns ``None``, or the one-line reason it was not written."""
    importances = param_importances(study, distributions)
    if isinstance(importances, str):
        return importances
    write_bytes_atomic(path, render_importance_png(study, importances))
    return None
