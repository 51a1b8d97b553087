"""The C5 sensitivity table: rows per fidelity condition and β, verdicts per condition."""

from __future__ import annotations

import pytest

from helpers_results import synthetic_result
from leaderboard.sensitivity import DEFAULT_CONDITION, condition_of, sensitivity_markdown, sensitivity_rows


def _condition_runs(start: str, encoding: str, human: str, equality_at_half: float) -> list[dict]:
    runs = []
    for seed in range(3):
        for beta, robot, eq in ((1.0, 6, 0.75), (0.75, 5, 0.9), (0.5, 4.5, equality_at_half), (0.25, 3, 0.75)):
            run = synthetic_result("sharing_v0", "empathic_dqn", beta, seed, fixed={"human_0": human},
                                   batteries=robot, other_batteries=9 - robot, equality=eq)
            run["config"]["env_kwargs"] = {"start": start, "inventory_encoding": encoding}
            if (start, encoding, human) == DEFAULT_CONDITION:
                run["config"]["env_kwargs"] = {}
            runs.append(run)
    return runs


def test_each_condition_gets_its_own_rows_and_verdicts() -> None:
    runs = _condition_runs("random", "count_plus_one", "patrol", equality_at_half=0.8)  # no peak
    runs += _condition_runs("centre", "authors", "patrol", equality_at_half=1.0)  # a clear peak
    rows = sensitivity_rows(runs)
    assert list(rows) == [DEFAULT_CONDITION, ("centre", "authors", "patrol")]
    assert rows[DEFAULT_CONDITION]["training"]["batteries"][1.0].mean == pytest.approx(6, abs=0.01)
    assert condition_of(runs[0]) == DEFAULT_CONDITION
    text = sensitivity_markdown(runs, "empathy-zoo reproduce --profile sharing_sensitivity")
    default_row = next(line for line in text.splitlines() if "(the defaults)" in line)
    centre_row = next(line for line in text.splitlines() if "start `centre`" in line)
    assert default_row.endswith("| reproduced | not reproduced |")
    assert centre_row.endswith("| reproduced | reproduced |")
    assert text.count("| 0.25 |") == 4  # two conditions × two phases


def test_no_sharing_runs_is_an_error() -> None:
    with pytest.raises(ValueError, match="no Empathic DQN runs of sharing_v0"):
        sensitivity_markdown([synthetic_result("coexistence_v0", "empathic_dqn", 0.5, 0)], "x")


def test_sensitivity_command_writes_the_file(tmp_path) -> None:
    from empathy_zoo.atomic import write_json_atomic
    from empathy_zoo.cli import main

    for run in _condition_runs("centre", "authors", "random_walk", equality_at_half=1.0):
        write_json_atomic(tmp_path / "runs" / f"{run['run_id']}.json", run)
    assert main(["sensitivity", str(tmp_path), "--produced-by", "empathy-zoo reproduce --profile x"]) == 0
    text = (tmp_path / "SENSITIVITY.md").read_text()
    assert "**The rules**" in text and "empathy-zoo reproduce --profile x" in text and "human `random_walk`" in text
