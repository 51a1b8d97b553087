"""The C5 sensitivity table: rows per fidelity condition and β, verdicts per condition."""

from __future__ import annotations

import pytest
from helpers_results import derive_run_id, record, synthetic_document, synthetic_result

from empathy_zoo.experiment.records import RunResult
from leaderboard.sensitivity import DEFAULT_CONDITION, condition_of, sensitivity_markdown, sensitivity_rows


def _condition_runs(start: str, encoding: str, human: str, equality_at_half: float) -> list[RunResult]:
    runs = []
    for seed in range(3):
        for beta, robot, eq in ((1.0, 6, 0.75), (0.75, 5, 0.9), (0.5, 4.5, equality_at_half), (0.25, 3, 0.75)):
            run = synthetic_document(
                "sharing_v0",
                "empathic_dqn",
                beta,
                seed,
                fixed={"human_0": human},
                batteries=robot,
                other_batteries=9 - robot,
                equality=eq,
            )
            run["config"]["env_kwargs"] = {"start": start, "inventory_encoding": encoding}
            if (start, encoding, human) == DEFAULT_CONDITION:
                run["config"]["env_kwargs"] = {}
            runs.append(record(derive_run_id(run)))
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
        write_json_atomic(tmp_path / "runs" / f"{run.run_id}.json", run.to_document())
    assert main(["sensitivity", str(tmp_path), "--produced-by", "empathy-zoo reproduce --profile x"]) == 0
    text = (tmp_path / "SENSITIVITY.md").read_text()
    assert "**The rules**" in text and "empathy-zoo reproduce --profile x" in text and "human `random_walk`" in text


def _split_run(beta: float, seed: int, takes: list[int], human_takes: list[float] | None = None) -> RunResult:
    """A Sharing run whose every scored episode (training and greedy) has these robot takes of 9."""
    from empathy_zoo.metrics import equality

    def value(n: int) -> float:
        return sum(1.1 - 0.1 * k for k in range(1, n + 1))

    run = synthetic_document("sharing_v0", "empathic_dqn", beta, seed)
    robot = [float(t) for t in takes]
    human = [9.0 - t for t in robot] if human_takes is None else human_takes
    fair = [float(equality(value(int(r)), value(int(h)))) for r, h in zip(robot, human, strict=True)]
    run["train"].update(batteries=robot, other_batteries=human, equality=fair)
    greedy = {name: values[:4] for name, values in run["eval"][-1].items() if name != "step"}  # (four greedy episodes)
    run["eval"][-1].update(greedy, batteries=robot[:4], other_batteries=human[:4], equality=fair[:4])
    return record(run)


def test_the_mean_take_closest_to_half_need_not_be_the_most_equal() -> None:
    from leaderboard.sensitivity import fair_split_rows, fair_split_summary

    # β = 1 takes 4.5 on average but 2 or 7 in every episode; β = 0.75 takes 4 every time
    runs = [_split_run(1.0, s, [2, 7] * 20) for s in range(3)] + [_split_run(0.75, s, [4] * 40) for s in range(3)]
    runs += [_split_run(0.5, s, [3] * 40) for s in range(3)] + [_split_run(0.25, s, [2] * 40) for s in range(3)]
    rows = fair_split_rows(runs)[DEFAULT_CONDITION]
    for phase in ("greedy", "training"):
        table = rows[phase]
        assert table[1.0].take == pytest.approx(4.5) and table[1.0].distance == pytest.approx(2.5)
        assert table[0.75].take == pytest.approx(4.0) and table[0.75].distance == pytest.approx(0.5)
        assert table[1.0].fair == pytest.approx(4.5) and table[1.0].all_collected == 1.0
        assert table[0.75].equality > table[1.0].equality
        assert fair_split_summary(table) == (1.0, 0.75, 0.75)
    text = sensitivity_markdown(runs, "x")
    assert "### Is equality set by the robot's mean take?" in text
    row = next(line for line in text.splitlines() if "| training | β = 1 (4.50)" in line)
    assert "| β = 0.75 (0.50) | β = 0.75 (" in row and row.endswith("| 100.0 % |")
    assert (
        "Greedy: in 1 of 1 conditions the β whose mean take is closest to the fair split is not the most equal, "
        "and in 0 of 1 the β closest episode by episode is not; training: in 1 of 1"
    ) in text


def test_the_fair_split_counts_episodes_where_not_all_batteries_were_collected() -> None:
    from leaderboard.sensitivity import fair_split_rows

    run = _split_run(1.0, 0, [4] * 40, human_takes=[3.0] * 40)  # 7 collected in every episode: the fair take is 3.5
    table = fair_split_rows([run])[DEFAULT_CONDITION]["training"]
    assert table[1.0].fair == pytest.approx(3.5) and table[1.0].distance == pytest.approx(0.5)
    assert table[1.0].all_collected == 0.0
