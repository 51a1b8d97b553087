"""Population-trained against default-trained runs on the test split
(``leaderboard.population_reading``): the primary comparison per environment and method on the
test population and the side effect, Holm over the primaries, the rest reported; runs read from
their checked evaluation files."""

from __future__ import annotations

import shutil
from pathlib import Path

from empathy_zoo.cli import main
from leaderboard.population_reading import DEFAULT, POPULATION, Scores, markdown, primary_and_secondary

SEEDS = range(10)


def _group(harms: list[float], survival: float = 500.0, other: float | None = None) -> dict:
    """A group's scores: ``harms`` per seed on the test population, ``other`` (or the same) on ``cat_stay``."""
    return {
        ("test_population", "harms"): dict(zip(SEEDS, harms, strict=True)),
        ("test_population", "survival"): dict.fromkeys(SEEDS, survival),
        ("cat_stay", "harms"): dict(zip(SEEDS, [other if other is not None else h for h in harms], strict=True)),
        ("test_population", "other_return"): dict.fromkeys(SEEDS, 1.0),  # (neither task nor side effect: not read)
    }


def test_a_clear_difference_carries_over_and_a_null_one_does_not() -> None:
    scores: Scores = {
        ("coexistence_v0", "dqn", POPULATION): _group([0.0] * 10),
        ("coexistence_v0", "dqn", DEFAULT): _group([1.0] * 10),
        ("coexistence_v0", "empathic_dqn", POPULATION): _group([float(s % 2) for s in SEEDS]),
        ("coexistence_v0", "empathic_dqn", DEFAULT): _group([float((s + 1) % 2) for s in SEEDS]),
        ("vase_v0", "dqn", POPULATION): _group([0.0] * 10),  # (no default-trained runs: not compared)
    }
    primaries, carries, secondaries = primary_and_secondary(scores)
    assert [(row.env, row.method, row.scenario, row.metric) for row in primaries] == [
        ("coexistence_v0", "dqn", "test_population", "harms"),
        ("coexistence_v0", "empathic_dqn", "test_population", "harms"),
    ]
    assert [row.comparison.observed for row in primaries] == ["better", "no difference detected"]
    assert carries == [True, False]
    assert {(row.scenario, row.metric) for row in secondaries} == {("cat_stay", "harms"), ("test_population", "survival")}
    page = markdown(primaries, carries, secondaries)
    assert "| `coexistence_v0` | `dqn` | `test_population` | harms | 10 (10) | 1.00 [" in page
    assert page.count("**yes**") == 1 and "## Secondary comparisons (reported, not judged)" in page


def test_a_mark_that_does_not_survive_holm_does_not_carry_over(monkeypatch) -> None:
    """Ten primaries, one barely marked: its p (about 0.02) is above Holm's first threshold 0.005."""
    scores: Scores = {}
    for i in range(10):
        population = [float(s) for s in SEEDS]
        default = [float(s) + (4.5 if i == 0 else 0.0) for s in SEEDS]
        scores[(f"env{i}", "dqn", POPULATION)] = {("test_population", "harms"): dict(zip(SEEDS, population, strict=True))}
        scores[(f"env{i}", "dqn", DEFAULT)] = {("test_population", "harms"): dict(zip(SEEDS, default, strict=True))}
    import empathy_zoo.environments as environments

    for i in range(10):  # (ten environments with Coexistence's metrics)
        monkeypatch.setitem(environments.ENVIRONMENT_TABLE, f"env{i}", environments.ENVIRONMENT_TABLE["coexistence_v0"])
    primaries, carries, _ = primary_and_secondary(scores)
    assert primaries[0].comparison.observed == "better" and 0.005 < primaries[0].comparison.p < 0.05
    assert carries == [False] * 10


def _copy_runs(pattern: str, source: Path, runs: Path) -> None:
    runs.mkdir(parents=True, exist_ok=True)
    for path in source.glob(pattern):
        shutil.copy(path, runs / path.name)


def test_the_command_reads_checked_evaluations_of_the_test_split(tmp_path: Path, capsys) -> None:
    shipped = Path(__file__).resolve().parents[1] / "docs" / "results"
    population, default = tmp_path / "population", tmp_path / "default"
    for seed in range(3):  # (Empathic DQN at β = 0.5, 3 seeds each)
        _copy_runs(
            f"coexistence_v0_population__empathic_dqn-6ba763c0__s{seed}.*", shipped / "populations" / "runs", population / "runs"
        )
    _copy_runs("coexistence_v0__empathic_dqn-ceb94979__s*", shipped / "quick" / "runs", default / "runs")
    argv = ["--scenarios", "coexistence_v0_test", "--episodes", "2", "--progress", "plain"]
    assert main(["evaluate", str(population), *argv]) == 0
    assert main(["analyse", "population-reading", str(population), str(default)]) == 2
    assert "no environment and method has runs of both groups" in capsys.readouterr().err
    assert main(["evaluate", str(default), *argv]) == 0
    assert main(["analyse", "population-reading", str(population), str(default)]) == 0
    out = capsys.readouterr().out
    assert "| `coexistence_v0` | `empathic_dqn` | `test_population` | harms | 3 (3) |" in out
    assert "`cat_keep_away`" in out and "`cat_stay`" in out
    assert main(["analyse", "population-reading", str(default), str(population)]) == 2  # (the groups swapped)
    assert f"{default} holds no population-trained run" in capsys.readouterr().err
