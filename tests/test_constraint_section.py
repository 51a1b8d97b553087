"""The leaderboard's constraint section: a row whose runs record λ per training episode is set
against its cost limit d in both phases, with λ at the end; other rows get no section."""

from __future__ import annotations

import json

from helpers_results import edited, synthetic_result

from empathy_zoo.experiment.records import RunResult
from leaderboard.constraint_section import SECTION_TITLE, constraint_rows, constraint_section
from leaderboard.report import write_leaderboard


def priced(document: dict) -> None:
    """A Lagrangian run's label, reward (its cost limit 0.1) and λ after each training episode."""
    document["method_label"] = "DQN-Lagrangian"
    document["config"]["reward"] = {"name": "lagrangian", "cost_limit": 0.1, "lambda_lr": 1.0, "lambda_init": 0.0}
    document["config"]["description"]["reward"] = document["config"]["reward"]
    document["train"]["lambda"] = [float(i) for i in range(len(document["train"]["harms"]))]


def lagrangian_runs(harms: float) -> list[RunResult]:
    return [
        edited(synthetic_result("coexistence_v0", "dqn_lagrangian", 1.0, seed, harms=harms, survival=400.0), priced)
        for seed in range(5)
    ]


def test_a_priced_row_is_set_against_its_limit() -> None:
    ((env, label, limit, check, ends),) = constraint_rows(lagrangian_runs(harms=2.0))
    assert (env, label, limit) == ("coexistence_v0", "DQN-Lagrangian", 0.1)
    assert check.final_training.limit_lies == "below" and ends == [39.0] * 5
    ((_, _, _, met, _),) = constraint_rows(lagrangian_runs(harms=0.0))
    assert met.final_training.limit_lies == "above"


def test_rows_without_a_price_get_no_section() -> None:
    runs = [synthetic_result("coexistence_v0", "dqn", 1.0, seed) for seed in range(3)]
    assert constraint_rows(runs) == []
    assert constraint_section(runs) is None


def test_the_page_carries_the_section(tmp_path) -> None:
    runs_dir = tmp_path / "runs"
    runs_dir.mkdir()
    for run in lagrangian_runs(harms=0.5) + [synthetic_result("coexistence_v0", "dqn", 1.0, s) for s in range(5)]:
        (runs_dir / f"{run.run_id}.json").write_text(json.dumps(run.to_document()))
    page = write_leaderboard(tmp_path, tmp_path / "board")["markdown"].read_text(encoding="utf-8")
    assert f"## {SECTION_TITLE}" in page and ": violated |" in page and "5 of 5 runs" in page
