"""The vase task end to end on the command line: ``empathy-zoo train --env vase_v0`` for a few
hundred steps, then ``evaluate`` beside every held-out partner of its shipped scenario set."""

from __future__ import annotations

import json

from helpers_cli_method import TINY

from empathy_zoo.cli import main
from empathy_zoo.scenarios import load_scenario_set

ENV = "vase_v0"


def test_vase_trains_and_is_evaluated_beside_its_held_out_partners(tmp_path, capsys) -> None:
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
            harms = scenario["metrics"]["harms"]
            assert len(harms) == len(scenario["metrics"]["return"]) == 2
            assert all(0.0 <= h <= 2.0 for h in harms)  # the vase and the cat, once each at most
