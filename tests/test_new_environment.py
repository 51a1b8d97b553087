"""An environment the suite was never told about is one engine, one face and one entry: Meadow
(:mod:`helpers_meadow`), registered into the environment table for the test alone, trains,
is evaluated beside a held-out partner and fills the leaderboard's tables, figures and held-out
section with the metrics its entry names."""

from __future__ import annotations

import json

from helpers_cli_method import TINY
from helpers_meadow import MEADOW, MEADOW_ENTRY, register_meadow

from empathy_zoo.cli import main
from empathy_zoo.cli.tune import default_objective
from leaderboard.aggregate import load_results
from leaderboard.versus_dqn import versus_dqn_tables

SCENARIOS = """\
[scenario_set]
env = "meadow_v0"
name = "meadow_partners"

[scenarios.sheep_stays]
reason = "A sheep that never moves."
fixed = { sheep_0 = "stay" }
"""


def test_a_registered_environment_trains_evaluates_and_fills_the_leaderboard(tmp_path, monkeypatch, capsys):
    register_meadow(monkeypatch)
    out = tmp_path / "results"
    assert main(["train", "--env", MEADOW, "--method", "dqn", "--out", str(out), *TINY]) == 0
    assert main(["train", "--env", MEADOW, "--selfishness", "0.5", "--out", str(out), *TINY]) == 0
    summary = capsys.readouterr().out
    assert "final 10% of training: return 50, other_return 50 |" in summary  # (the entry's table metrics)
    assert "survival" not in summary and "batteries" not in summary

    scenarios = tmp_path / "meadow_partners.toml"
    scenarios.write_text(SCENARIOS)
    assert main(["evaluate", str(out), "--scenarios", str(scenarios), "--episodes", "2", "--no-progress"]) == 0
    evaluations = sorted((out / "evaluations" / "meadow_partners").glob("*.json"))
    assert len(evaluations) == 2
    assert {json.loads(path.read_text())["env"] for path in evaluations} == {MEADOW}

    assert main(["leaderboard", str(out)]) == 0
    page = (out / "LEADERBOARD.md").read_text()
    assert f"## {MEADOW}\n" in page
    assert page.count("| Method | Seeds | return | other_return |") == 4  # greedy, training and their P(improves)
    assert f"![{MEADOW}: task against side effect](figures/{MEADOW}_tradeoff.png)" in page
    for metric, _ in MEADOW_ENTRY.curves:
        assert f"![{MEADOW}: {metric} vs training steps](figures/{MEADOW}_{metric}.png)" in page
        assert (out / "figures" / f"{MEADOW}_{metric}.png").is_file()
    assert (out / "figures" / f"{MEADOW}_tradeoff.png").is_file()
    assert f"### {MEADOW}: scenario set meadow_partners" in page
    assert "#### return (higher is better)" in page and "#### other return (higher is better)" in page
    assert "#### Does its other_return avoidance generalise?" in page

    header = "| method | seeds | " + " | ".join(MEADOW_ENTRY.compact_metrics) + " |"
    assert header == "| method | seeds | other_return | return |"
    assert header in versus_dqn_tables(load_results(out))
    assert default_objective(MEADOW) == ("return", "maximize")
