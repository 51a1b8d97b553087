"""The helping task end to end on the command line: ``empathy-zoo train --env helping_v0`` for a few
hundred steps (DQN and Empathic DQN), ``evaluate`` beside every held-out partner of its shipped
scenario set, and ``leaderboard`` over both, every figure drawn from the environment's entry."""

from __future__ import annotations

import json

from helpers_cli_method import TINY

from empathy_zoo.cli import main
from empathy_zoo.environments import ENVIRONMENT_TABLE
from empathy_zoo.scenarios import load_scenario_set

ENV = "helping_v0"


def test_helping_trains_is_evaluated_and_makes_a_leaderboard(tmp_path, capsys) -> None:
    out = tmp_path / "results"
    assert main(["train", "--env", ENV, "--method", "dqn", "--out", str(out), *TINY]) == 0
    assert main(["train", "--env", ENV, "--selfishness", "0.5", "--out", str(out), *TINY]) == 0
    summary = capsys.readouterr().out
    assert summary.count("final 10% of training: return ") == 2  # the entry's table metrics, task first
    assert ", harms " in summary and ", other_return " in summary and "batteries" not in summary

    assert main(["evaluate", str(out), "--scenarios", ENV, "--episodes", "2", "--no-progress"]) == 0
    evaluations = sorted((out / "evaluations" / ENV).glob("*.json"))
    assert len(evaluations) == 2
    held_out = [scenario.name for scenario in load_scenario_set(ENV).scenarios]
    for path in evaluations:
        record = json.loads(path.read_text())
        assert record["env"] == ENV
        assert [s["name"] for s in record["scenarios"]] == ["trained_with", *held_out]
        for scenario in record["scenarios"]:
            assert len(scenario["metrics"]["harms"]) == len(scenario["metrics"]["return"]) == 2
            assert all(h in (0.0, 1.0) for h in scenario["metrics"]["harms"])  # one human, harmed once at most
        (stays,) = [s for s in record["scenarios"] if s["name"] == "human_stays"]
        assert stays["metrics"]["other_return"] == [0.0, 0.0]  # a human that never moves never reaches the pad

    board = tmp_path / "board"
    assert main(["leaderboard", str(out), "--out", str(board)]) == 0
    page = (board / "LEADERBOARD.md").read_text(encoding="utf-8")
    assert f"## {ENV}" in page and "| return | harms | other_return |" in page
    for metric, _ in ENVIRONMENT_TABLE[ENV].curves:
        assert (board / "figures" / f"{ENV}_{metric}.png").is_file(), metric
    assert (board / "figures" / f"{ENV}_tradeoff.png").is_file()
