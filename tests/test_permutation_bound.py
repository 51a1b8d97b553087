"""The exact permutation test's bound on seeds (F5): more than MAX_EXACT_TEST_SEEDS seeds, both sides
together, are refused in one line naming the counts and the bound, before the null distribution's
table is made (a tracemalloc peak of a few MB where the table would take gigabytes); at the bound the
test still computes; the leaderboard's cells are all checked before the first test runs, and a
refused leaderboard leaves its output directory as it was (no staging folder, no file)."""

from __future__ import annotations

import json
import math
import tracemalloc

import numpy as np
import pytest
from helpers_results import MAX_CYCLES, derive_run_id, hand_made_result

import leaderboard.improvement as improvement
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.limits import BOUNDS, MAX_EXACT_TEST_SEEDS
from leaderboard.improvement import (
    check_exact_test_seeds,
    improvement_interval,
    improvements_over_dqn,
    permutation_test,
)


def _values(count: int, seed: int) -> list[float]:
    """``count`` distinct seeded values."""
    return np.random.default_rng(seed).normal(size=count).tolist()


def _one_line_refusal(error: pytest.ExceptionInfo[ValueError], bound: int) -> str:
    message = str(error.value)
    assert "\n" not in message and f"at most {bound:,} seeds" in message and "docs/limits.md" in message, message
    return message


def test_the_bound_is_listed() -> None:
    assert MAX_EXACT_TEST_SEEDS == 200 and BOUNDS["seeds of one exact test"] == MAX_EXACT_TEST_SEEDS


@pytest.mark.parametrize(("n", "m"), [(101, 100), (200, 1), (1, 200), (1_000, 1_000), (10_000, 10_000)])
@pytest.mark.parametrize("test", [permutation_test, improvement_interval])
def test_one_seed_past_the_bound_is_refused_in_one_line_before_the_table_is_made(test, n, m) -> None:
    x, y = _values(n, 1), _values(m, 2)
    tracemalloc.start()
    try:
        with pytest.raises(ValueError) as error:
            test(x, y)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    message = _one_line_refusal(error, MAX_EXACT_TEST_SEEDS)
    assert f"got {n:,} against {m:,} ({n + m:,})" in message and f"({MAX_EXACT_TEST_SEEDS // 2:,} a side)" in message
    # (the table of 1,000 a side would take 8 GB, of 101 against 100 some 33 MB: none of it is made)
    assert peak < 8 * (n + 1) * (n + m) * (n + m + 1) // 4 and peak < 16 << 20, peak


def test_only_finite_runs_count(monkeypatch) -> None:
    monkeypatch.setattr(improvement, "MAX_EXACT_TEST_SEEDS", 10)
    x, y = _values(5, 1), _values(5, 2)
    assert permutation_test(x + [math.nan] * 50, [*y, math.inf, -math.inf]) == permutation_test(x, y)
    check_exact_test_seeds(5, 5)
    with pytest.raises(ValueError):
        check_exact_test_seeds(5, 6)


def test_at_the_bound_the_test_computes() -> None:
    # one run against 199, all distinct, the one above every other: two of the 200 splits are as far
    # from a tie (the exact two-sided p is 2/200); a small table (n = 1), so quick at N = 200
    top, rest = [1_000.0], _values(MAX_EXACT_TEST_SEEDS - 1, 3)
    probability, p = permutation_test(top, rest)
    assert probability == 1.0 and p == pytest.approx(2 / MAX_EXACT_TEST_SEEDS)
    assert improvement_interval(top, rest)[0] == 1.0
    with pytest.raises(ValueError):
        permutation_test(top, [*rest, 0.0])


def test_a_smaller_bound_is_checked_the_same_way(monkeypatch) -> None:
    x, y = _values(10, 4), _values(10, 5)
    expected = permutation_test(x, y), improvement_interval(x, y)
    improvement._null_tails.cache_clear()
    monkeypatch.setattr(improvement, "MAX_EXACT_TEST_SEEDS", 20)
    assert (permutation_test(x, y), improvement_interval(x, y)) == expected  # at the bound: the same numbers
    for test in (permutation_test, improvement_interval):
        with pytest.raises(ValueError) as error:
            test([*x, 9.0], y)
        assert "got 11 against 10 (21)" in _one_line_refusal(error, 20)
    with pytest.raises(ValueError) as error:  # (the table's own entry, for a caller that goes there directly)
        improvement._null_tails(tuple(range(2, 44, 2)), 11)
    _one_line_refusal(error, 20)


def _run(method: str, seed: int, value: float, selfishness: float = 1.0) -> RunResult:
    """A run whose one training episode and greedy evaluation survived ``value`` steps."""
    train = {"episode_end_step": [MAX_CYCLES], "survival": [value]}
    return hand_made_result(
        "coexistence_v0", method, seed, train, [{"step": MAX_CYCLES, "survival": [value]}], settings={"selfishness": selfishness}
    )


def test_the_leaderboard_cells_are_checked_before_any_test(monkeypatch) -> None:
    runs = [_run("dqn", s, 10.0 + s) for s in range(4)]
    runs += [_run("empathic_dqn", s, 11.0 + s, 0.5) for s in range(3)]  # 7 seeds with DQN's: within 10
    runs += [_run("empathic_dqn", s, 12.0 + s, 0.25) for s in range(7)]  # 11: past it
    metrics = {"coexistence_v0": ["survival"]}
    assert len(improvements_over_dqn(runs, metrics)) == 2 * len(improvement.PHASES)
    monkeypatch.setattr(improvement, "MAX_EXACT_TEST_SEEDS", 10)
    tested: list[int] = []
    monkeypatch.setattr(improvement, "improvement_interval", lambda x, *a, **k: tested.append(len(x)))
    with pytest.raises(ValueError) as error:
        improvements_over_dqn(runs, metrics)
    assert "got 7 against 4 (11)" in _one_line_refusal(error, 10) and tested == [], "refused before the first test"


def test_a_refused_leaderboard_leaves_its_directory_as_it_was(tmp_path, monkeypatch) -> None:
    from test_leaderboard_report import write_synthetic_results

    from leaderboard import write_leaderboard

    paths = write_synthetic_results(tmp_path / "runs", envs=("coexistence_v0",))
    for path in paths:  # make the "DQN" rows standard DQN (as test_improvement does)
        result = json.loads(path.read_text())
        if result["method_label"] == "DQN":
            result["method"], result["config"]["settings"] = "dqn", {"selfishness": 1.0}
            path.unlink()
            path.with_name(f"{derive_run_id(result)['run_id']}.json").write_text(json.dumps(result))
    before = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*"))
    monkeypatch.setattr(improvement, "MAX_EXACT_TEST_SEEDS", 5)  # 3 seeds against 3: past it
    with pytest.raises(ValueError) as error:
        write_leaderboard(tmp_path, command="c")
    assert "got 3 against 3 (6)" in _one_line_refusal(error, 5)
    assert sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*")) == before, "no stage, figure or page left"
