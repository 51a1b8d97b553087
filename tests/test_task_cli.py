"""Each task built to separate methods, end to end on the command line: ``empathy-zoo train --env
ENV`` for a few hundred steps (DQN and Empathic DQN), then ``evaluate`` beside every held-out
partner of its shipped scenario set."""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

import pytest
from helpers_cli_method import TINY

from empathy_zoo.cli import main
from empathy_zoo.scenarios import load_scenario_set


def charger_harms(record: dict[str, Any]) -> None:
    (stays,) = [s for s in record["scenarios"] if s["name"] == "cat_stays"]
    assert stays["metrics"]["harms"] == [0.0, 0.0]  # a cat that never moves never reaches the charger


def vase_harms(record: dict[str, Any]) -> None:
    for scenario in record["scenarios"]:
        assert all(0.0 <= h <= 2.0 for h in scenario["metrics"]["harms"])  # the vase and the cat, once each at most


@pytest.mark.parametrize(("env", "harms_hold"), [("charger_v0", charger_harms), ("vase_v0", vase_harms)])
def test_a_task_trains_and_is_evaluated_beside_its_held_out_partners(
    tmp_path, capsys, env: str, harms_hold: Callable[[dict[str, Any]], None]
) -> None:
    out = tmp_path / "results"
    assert main(["train", "--env", env, "--method", "dqn", "--out", str(out), *TINY]) == 0
    assert main(["train", "--env", env, "--selfishness", "0.5", "--out", str(out), *TINY]) == 0
    summary = capsys.readouterr().out
    assert summary.count("final 10% of training: return ") == 2  # the entry's table metrics, task first
    assert ", harms " in summary and ", other_return " in summary and "batteries" not in summary

    assert main(["evaluate", str(out), "--scenarios", env, "--episodes", "2", "--no-progress"]) == 0
    evaluations = sorted((out / "evaluations" / env).glob("*.json"))
    assert len(evaluations) == 2
    held_out = [scenario.name for scenario in load_scenario_set(env).scenarios]
    for path in evaluations:
        record = json.loads(path.read_text())
        assert record["env"] == env
        assert [s["name"] for s in record["scenarios"]] == ["trained_with", *held_out]
        for scenario in record["scenarios"]:
            assert len(scenario["metrics"]["harms"]) == len(scenario["metrics"]["return"]) == 2
        harms_hold(record)
