"""The task-against-side-effect figure: the Pareto front on hand-made points, and the figure in
every leaderboard."""

from __future__ import annotations

import math

import pytest

from empathy_zoo.environments import ENVIRONMENT_TABLE
from leaderboard.aggregate import PHASES, Score
from leaderboard.tradeoff import pareto_front, render_tradeoff_png, tradeoff_spec

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize(
    ("points", "higher_is_better", "front"),
    [
        # (survival, harms): more survival and fewer harms win
        ([(450, 0.9), (300, 0.1), (250, 0.2), (460, 0.95), (300, 0.5)], False, [0, 1, 3]),
        # (batteries, equality): both higher is better
        ([(3.2, 0.68), (2.2, 0.57), (4.5, 1.0), (1.8, 0.49)], True, [2]),
        ([(1, 1), (1, 1), (0, 0)], True, [0, 1]),  # equal points are all on the front
        ([(1, math.nan), (0, 0)], True, [1]),  # a NaN is never on it and never dominates
        ([], True, []),
    ],
)
def test_pareto_front(points, higher_is_better, front) -> None:
    assert pareto_front(points, higher_is_better) == front


def _scores(env: str, spec, values: dict[str, tuple[float, float]]) -> list[Score]:
    return [
        Score(env, label, "m", phase, metric, mean, mean - 0.1, mean + 0.1, 3)
        for label, pair in values.items()
        for phase in PHASES
        for metric, mean in zip((spec.task, spec.effect), pair, strict=True)
    ]


@pytest.mark.parametrize("env", sorted(ENVIRONMENT_TABLE))
def test_the_figure_is_a_png(env: str) -> None:
    spec = tradeoff_spec(env)
    assert spec is not None
    png = render_tradeoff_png(_scores(env, spec, {"A": (1.0, 0.5), "B": (2.0, 0.7), "C": (0.5, 0.1)}), env, spec)
    assert png.startswith(PNG_SIGNATURE) and len(png) > 10_000


def test_every_method_of_a_figure_gets_its_own_colour() -> None:
    from matplotlib.colors import to_rgba

    from leaderboard.colours import distinct_colours, label_colours

    for count in (3, 10, 11, 20, 27):
        assert len({to_rgba(c) for c in distinct_colours(count)}) == count
        labels = [f"method {i}" for i in range(count)]
        assert len({to_rgba(c) for c in label_colours(labels, dqn_labels=labels[:2]).values()}) == count
