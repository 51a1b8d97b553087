"""A result or evaluation file read once, into a typed, frozen record
(empathy_zoo.experiment.records, empathy_zoo.evaluation_record): the shipped files give back their
documents field for field, nothing in a record can be changed, and every document the checker
accepts becomes a record the leaderboard reads."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from helpers_results import derive_run_id, synthetic_document

from empathy_zoo.atomic import read_json
from empathy_zoo.evaluation_file import check_evaluation, evaluation_files, read_evaluation
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.experiment.result_reader import check_result, read_result
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.result_file import STEP_REWARD_BOUND
from leaderboard.aggregate import group_runs, learning_curves, result_files, run_scalars, score_runs

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = [path for name in ("quick", "paper") for path in result_files(ROOT / "docs" / "results" / name)]
EVALUATIONS = [path for name in ("quick", "paper") for path in evaluation_files(ROOT / "docs" / "results" / name)]


def test_the_shipped_directories_hold_result_files() -> None:
    assert len(SHIPPED) >= 80  # (30 quick runs, 50 of the paper)


@pytest.mark.parametrize("path", SHIPPED, ids=lambda path: f"{path.parents[1].name}/{path.stem}")
def test_a_shipped_file_reads_back_as_its_document_field_for_field(path: Path) -> None:
    document = check_result(read_json(path), path)
    run = RunResult.from_checked(document)  # (what read_result gives: test_the_series_cost_eight_bytes_a_value)
    assert run.to_document() == document
    assert json.dumps(run.to_document()) == json.dumps(document)  # (its numbers as written: ints, floats, order)
    assert run.to_document(series=False) == {k: v for k, v in document.items() if k not in ("train", "eval")}


def test_a_record_is_frozen_and_its_series_and_tables_are_read_only() -> None:
    run = RunResult.from_checked(synthetic_document("coexistence_v0", "empathic_dqn", 0.5, 0, harms=0.5))
    with pytest.raises(dataclasses.FrozenInstanceError):
        run.method_label = "another"  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        run.config.settings = {}  # type: ignore[misc]
    for series in [run.train.episode_end_step, *run.train.metrics.values(), *(m for e in run.eval for m in e.metrics.values())]:
        assert not series.flags.writeable
        with pytest.raises(ValueError, match="read-only"):
            series[0] = 0
    for table in (run.config.settings, run.config.env_kwargs, run.config.fixed, run.config.description, run.train.metrics):
        with pytest.raises(TypeError):
            table["x"] = 1  # type: ignore[index]
    with pytest.raises(TypeError):
        run.config.description["exploration"]["start"] = 0.5  # (at every depth)
    shipped = read_result(SHIPPED[0])  # (what training writes: its counts as integers)
    assert shipped.train.metrics["harms"].dtype == np.int64 and shipped.train.metrics["equality"].dtype == np.float64
    assert shipped.eval[0].metrics["harms"].dtype == np.float64  # (a greedy evaluation writes its counts as floats)


def test_a_relabelled_run_is_a_new_record_sharing_the_series() -> None:
    run = RunResult.from_checked(synthetic_document("coexistence_v0", "dqn", 1.0, 0))
    shown = dataclasses.replace(run, method_label="Q DQN")
    assert (run.method_label, shown.method_label) == ("dqn 1.0", "Q DQN")
    assert shown.train is run.train and shown.eval is run.eval
    assert shown.to_document() == {**run.to_document(), "method_label": "Q DQN"}


def _edge_document() -> dict:
    """A document the checker accepts with everything a file may hold that this suite does not
    write: integers in a column of floats (one past int64's range), floats in a column of counts,
    fields this suite does not name, no variant, no agent and no evaluation."""
    document = synthetic_document("coexistence_v0", "dqn", 1.0, 3)
    document["train"]["return"] = [int(STEP_REWARD_BOUND)] + [1] * (len(document["train"]["return"]) - 1)
    document["train"]["harms"] = [float(value) for value in document["train"]["harms"]]
    document["train"]["equality"] = [1] * len(document["train"]["equality"])
    document.update(variant=None, agent=None, eval=[], notes={"who": ["me", {"why": 1}]})
    document["config"] = {**document["config"], "comment": "by hand"}
    return derive_run_id(document)


def test_every_document_the_checker_accepts_is_a_record_the_leaderboard_reads() -> None:
    document = check_result(_edge_document(), "edge.json")
    run = RunResult.from_checked(document)
    assert run.to_document() == document
    assert run.variant is None and run.table_env == "coexistence_v0" and run.agent is None and run.last_eval is None
    assert run.extra["notes"]["who"] == ("me", {"why": 1}) and run.config.extra == {"comment": "by hand"}
    assert run.train.metrics["return"].dtype == np.float64  # (read as a double, as every computation read it)
    assert run.train.metrics["harms"].dtype == np.float64 and run.train.metrics["equality"].dtype == np.int64
    scalars = run_scalars(run)
    assert all(np.isnan(scalars["eval"][metric]) for metric in METRIC_NAMES)
    assert scalars["train_final10"]["harms"] == pytest.approx(
        np.mean(document["train"]["harms"][-len(document["train"]["harms"]) // 10 :])
    )
    others = [RunResult.from_checked(synthetic_document("coexistence_v0", "dqn", 1.0, seed)) for seed in range(3)]
    assert list(group_runs([run, *others])) == [("coexistence_v0", "dqn 1.0")]
    assert len(score_runs([run, *others])) == 2 * len(METRIC_NAMES)
    assert learning_curves([run, *others], "harms")[0].n_seeds == 4


def test_the_series_cost_eight_bytes_a_value() -> None:
    path = SHIPPED[0]
    run = read_result(path)
    values = run.train.episodes * (1 + len(METRIC_NAMES)) + sum(e.episodes * len(METRIC_NAMES) for e in run.eval)
    held = run.train.episode_end_step.nbytes + sum(s.nbytes for s in run.train.metrics.values())
    held += sum(s.nbytes for e in run.eval for s in e.metrics.values())
    assert held == 8 * values


# ---------------------------------------------------------------------------- evaluation files
def test_the_shipped_directories_hold_evaluation_files() -> None:
    assert len(EVALUATIONS) >= 80  # (one per run of the quick and paper results)


@pytest.mark.parametrize("path", EVALUATIONS, ids=lambda path: f"{path.parents[2].name}/{path.stem}")
def test_a_shipped_evaluation_reads_back_as_its_document_field_for_field(path: Path) -> None:
    document = check_evaluation(read_json(path, "evaluation file"), path)
    evaluation = read_evaluation(path)
    assert evaluation.to_document() == document
    assert json.dumps(evaluation.to_document()) == json.dumps(document)
    assert evaluation.scenario(evaluation.scenarios[-1].name) is evaluation.scenarios[-1] and evaluation.scenario("x") is None


def test_an_evaluation_is_frozen_and_its_scores_read_only() -> None:
    evaluation = read_evaluation(EVALUATIONS[0])
    with pytest.raises(dataclasses.FrozenInstanceError):
        evaluation.episodes = 1  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        evaluation.scenarios[0].held_out = True  # type: ignore[misc]
    for entry in evaluation.scenarios:
        for series in entry.metrics.values():
            with pytest.raises(ValueError, match="read-only"):
                series[0] = 0
        with pytest.raises(TypeError):
            entry.fixed["cat_0"] = "stay"  # type: ignore[index]
    assert evaluation.scenario_set == read_evaluation(EVALUATIONS[1]).scenario_set  # (one set: one definition)
