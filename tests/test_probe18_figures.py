"""The leaderboard's figures draw a label read from a file letter for letter: ``$\\foo$`` (not
mathtext Matplotlib can parse) does not fail the figure, and ``$x$`` is not drawn as math. Each
figure is drawn for real; the test reads back the text of the figure it saved."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
import pytest
from helpers_heldout import scenario_set, synthetic_run, write_synthetic
from matplotlib.figure import Figure
from matplotlib.text import Text

from empathy_zoo.figure_text import literal_text
from leaderboard.aggregate import PHASES, Curve, Score
from leaderboard.heldout_plot import render_heldout_png
from leaderboard.heldout_scores import heldout_cells, load_heldout
from leaderboard.plots import render_curves_png
from leaderboard.profile_plot import render_profiles_png
from leaderboard.profiles import performance_profiles
from leaderboard.tradeoff import render_tradeoff_png, tradeoff_spec

ENV = "coexistence_v0"
BAD = "$\\foo$"
"""Not mathtext Matplotlib can parse: drawn as math, the figure fails."""
MATH = "$x$"
"""Mathtext Matplotlib can parse: drawn as math, it silently shows an italic x."""
LABELS = (BAD, MATH)


@pytest.fixture
def drawn(monkeypatch) -> list[str]:
    """The text of every figure saved while the test runs (titles, legends, ticks, axis labels)."""
    texts: list[str] = []
    save: Callable[..., None] = Figure.savefig

    def savefig(self: Figure, *args, **kwargs) -> None:
        save(self, *args, **kwargs)
        texts.extend(t.get_text() for t in self.findobj(Text))

    monkeypatch.setattr(Figure, "savefig", savefig)
    return texts


def test_literal_text_escapes_every_dollar_and_is_the_one_trials_figure_exports() -> None:
    from empathy_zoo.training import trials_figure

    assert literal_text("$\\foo$ and $x$") == "\\$\\foo\\$ and \\$x\\$"
    assert literal_text("Empathic DQN (β=0.5)") == "Empathic DQN (β=0.5)"
    assert trials_figure.literal_text is literal_text and "literal_text" in trials_figure.__all__


def test_learning_curves_draw_labels_and_title_as_written(drawn) -> None:
    steps = np.linspace(0, 1000, 20)
    mean = np.linspace(0.0, 1.0, 20)
    curves = [Curve(ENV, label, "harms", steps, mean, mean - 0.2, mean + 0.2, 3) for label in LABELS]
    png = render_curves_png(curves, title=f"{MATH}: harms", ylabel="harms per episode", dqn_labels={MATH})
    assert png.startswith(b"\x89PNG")
    assert literal_text(f"{BAD} (n=3)") in drawn
    assert literal_text(f"{MATH} (n=3, the DQN reference)") in drawn
    assert literal_text(f"{MATH}: harms") in drawn


def test_the_tradeoff_draws_labels_as_written(drawn) -> None:
    spec = tradeoff_spec(ENV)
    assert spec is not None
    scores = [
        Score(ENV, label, "m", phase, metric, mean, mean - 0.1, mean + 0.1, 3)
        for i, label in enumerate(LABELS)
        for phase in PHASES
        for metric, mean in ((spec.task, 1.0 + i), (spec.effect, 0.5 + i))
    ]
    png = render_tradeoff_png(scores, ENV, spec, dqn_labels={MATH})
    assert png.startswith(b"\x89PNG")
    assert literal_text(f"{BAD} (n=3)") in drawn
    assert literal_text(f"{MATH} (n=3, the DQN reference)") in drawn


def test_the_heldout_figure_draws_labels_as_written(tmp_path, drawn) -> None:
    scenarios = {"kept": {"cat_0": "stay"}, "lost": {"cat_0": "chase"}}
    pairs = [
        (
            synthetic_run(ENV, method, beta, seed),
            {s: {"harms": 0.1 * seed, "survival": 300.0} for s in ("trained_with", *scenarios)},
        )
        for method, beta in (("dqn", 1.0), ("empathic_dqn", 0.5))
        for seed in range(3)
    ]
    write_synthetic(tmp_path, pairs, scenario_set(ENV, scenarios), {"cat_0": "random_walk"})
    (group,), _ = load_heldout(tmp_path, [run for run, _ in pairs])
    renamed = dict(zip(group.runs, LABELS, strict=True))  # the two rows, labelled as a file may label them
    group = dataclasses.replace(
        group,
        runs={renamed[label]: runs for label, runs in group.runs.items()},
        dqn_of={renamed[label]: renamed.get(dqn) if dqn else None for label, dqn in group.dqn_of.items()},
        same_world={renamed[label]: names for label, names in group.same_world.items()},
    )
    cells = heldout_cells(group)
    png = render_heldout_png(group, cells)
    assert png.startswith(b"\x89PNG")
    assert literal_text(f"{BAD} (n=3)") in drawn and literal_text(f"{MATH} (n=3)") in drawn


def test_the_profile_panels_draw_labels_as_written(drawn) -> None:
    taus = np.linspace(0, 1, 11)
    profiles = performance_profiles({label: np.array([[0.2], [0.6], [0.9]]) for label in LABELS}, taus, n_resamples=50)
    png = render_profiles_png([("survival ÷ max_cycles", profiles)], title=f"{ENV}: profiles", dqn_labels={MATH})
    assert png.startswith(b"\x89PNG")
    assert literal_text(f"{BAD} (n=3)") in drawn and literal_text(f"{MATH} (n=3)") in drawn
