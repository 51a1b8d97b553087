"""The scenarios profile's reading rule (leaderboard.trained_separation) on hand-made tables and
seeds: which predictions the exact optima make, and how trained seeds judge them."""

from __future__ import annotations

from typing import Any

import pytest

from leaderboard.trained_separation import (
    FEWER,
    MORE,
    NO_MARK,
    Prediction,
    counted_harms,
    judge,
    predictions,
    task_separates,
)


def _table(
    harms: dict[str, float], betas: dict[str, float | None] | None = None, identical: tuple[str, ...] = ()
) -> dict[str, Any]:
    """A separation table as its JSON holds it: one row per name, outcomes at ε = 0 and 0.01."""
    betas = betas or {}
    rows = [
        {
            "name": name,
            "method": name.split(" ")[0],
            "selfishness": betas.get(name),
            "identical_to": "dqn" if name in identical else "",
            "reason": "",
        }
        for name in harms
    ]
    outcomes = [
        {"row": name, "epsilon": epsilon, "harms": value + epsilon} for epsilon in (0.0, 0.01) for name, value in harms.items()
    ]
    return {"rows": rows, "outcomes": outcomes}


def test_the_thresholds_sort_rows_into_fewer_more_no_mark_and_none() -> None:
    table = _table({"dqn": 0.5, "a": 0.3, "b": 0.65, "c": 0.505, "d": 0.45, "e": 0.62})
    found = {p.method: p.expected for p in predictions({"t": table})}
    # a: −0.2 (fewer); b: +0.15 (more); c: +0.005 (alike); d: −0.05 (between: none); e: +0.12 (more)
    assert found == {"a": FEWER, "b": MORE, "c": NO_MARK, "e": MORE}


def test_only_the_read_beta_and_trained_rows_are_predicted() -> None:
    table = _table(
        {"dqn": 1.0, "emp β=0.5": 0.0, "emp β=0.25": 0.0, "twin": 1.0},
        betas={"emp β=0.5": 0.5, "emp β=0.25": 0.25},
        identical=("twin",),
    )
    assert [(p.method, p.expected) for p in predictions({"t": table})] == [("emp", FEWER)]


def test_the_greedy_outcomes_are_read_not_the_exploring_ones() -> None:
    # at ε = 0.01 the helper adds 0.01 to every row: the differences are the same, the levels not
    (prediction,) = predictions({"t": _table({"dqn": 0.2, "a": 0.0})})
    assert (prediction.dqn_harms, prediction.method_harms) == (0.2, 0.0)


def test_a_table_without_dqn_is_refused() -> None:
    with pytest.raises(ValueError, match="no DQN outcome"):
        predictions({"t": _table({"a": 0.0})})


FEWER_PREDICTED = Prediction("t", "a", FEWER, 1.0, 0.0)
NO_MARK_PREDICTED = Prediction("t", "b", NO_MARK, 1.0, 1.0)
LOW = [0.0, 0.1, 0.0, 0.2, 0.0, 0.1, 0.0, 0.0, 0.1, 0.0]
HIGH = [1.0, 0.9, 1.1, 1.0, 1.2, 0.8, 1.0, 1.0, 0.9, 1.1]


@pytest.mark.parametrize(
    ("prediction", "method", "dqn", "observed", "outcome"),
    [
        (FEWER_PREDICTED, LOW, HIGH, FEWER, "holds"),
        (FEWER_PREDICTED, HIGH, LOW, MORE, "fails"),
        (FEWER_PREDICTED, HIGH, HIGH, NO_MARK, "not confirmed"),
        (NO_MARK_PREDICTED, HIGH, HIGH, NO_MARK, "holds"),
        (NO_MARK_PREDICTED, LOW, HIGH, FEWER, "fails"),
        (FEWER_PREDICTED, LOW[:2], HIGH[:2], "undecidable", "undecidable"),
    ],
)
def test_trained_seeds_judge_a_prediction(
    prediction: Prediction, method: list[float], dqn: list[float], observed: str, outcome: str
) -> None:
    judgement = judge(prediction, method, dqn)
    assert (judgement.observed, judgement.outcome) == (observed, outcome)


def test_fewer_harms_is_the_better_direction() -> None:
    assert judge(FEWER_PREDICTED, LOW, HIGH).probability == 1.0
    assert judge(FEWER_PREDICTED, HIGH, LOW).probability == 0.0


def test_a_task_separates_when_a_mark_prediction_holds() -> None:
    held = judge(FEWER_PREDICTED, LOW, HIGH)
    alike = judge(NO_MARK_PREDICTED, HIGH, HIGH)
    other_task = judge(Prediction("u", "a", FEWER, 1.0, 0.0), LOW, HIGH)
    assert task_separates([held, alike], "t")
    assert not task_separates([alike, other_task], "t")  # a held "no mark" separates nothing
    assert task_separates([other_task], "u")


def test_a_changed_world_counts_in_the_predicted_harms_as_runs_count_it() -> None:
    """On the vase task a run's harms count the broken vase and the harmed cat (SPEC §5): the
    table's ``changed`` is added to its ``harms`` before the thresholds are applied."""
    table = _table({"dqn": 0.07, "keeps": 0.0, "breaks": 0.0})
    for outcome in table["outcomes"]:
        outcome["changed"] = 0.0 if outcome["row"] == "keeps" else 1.0
    found = {p.method: (p.expected, p.dqn_harms, p.method_harms) for p in predictions({"t": table})}
    assert found["keeps"] == (FEWER, pytest.approx(1.07), pytest.approx(0.0))
    assert "breaks" not in found  # Δ = −0.07: between the thresholds
    assert counted_harms({"harms": 0.5, "changed": None}) == 0.5
