"""Probe 15 on ``empathy-zoo analyse population-reading`` (``leaderboard.population_reading``):
β is matched by its exact value, never by a rounded text; an evaluation of a test split that
ships no definition is refused in one line naming the file, the field and the environment."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from helpers_heldout import population_dirs

from empathy_zoo.cli import main
from empathy_zoo.run_ids import run_id

ROOT = Path(__file__).resolve().parents[1]
EDITED = "coexistence_v0__empathic_dqn-200adeaa__s0"
"""The default-trained Empathic DQN run (β = 0.5, seed 0) whose β the tests change."""


def _with_selfishness(directory: Path, old: str, selfishness: float) -> str:
    """Run ``old`` of ``directory`` (its result and test-split evaluation files) at ``selfishness``,
    under the run id its changed config gives, as the trainer would have named it; that id."""
    result = json.loads((directory / "runs" / f"{old}.json").read_text())
    result["config"]["settings"]["selfishness"] = selfishness
    result["config"]["description"]["selfishness"] = selfishness
    new = run_id(result["variant"], result["method"], result["config"], result["seed"])
    result["run_id"], result["agent"]["file"] = new, f"{new}.agent.pt"
    (directory / "runs" / f"{old}.json").unlink()
    (directory / "runs" / f"{new}.json").write_text(json.dumps(result))
    split = directory / "evaluations" / "coexistence_v0_test"
    evaluation = json.loads((split / f"{old}.json").read_text())
    evaluation["run_id"], evaluation["agent"]["file"] = new, f"{new}.agent.pt"
    (split / f"{old}.json").unlink()
    (split / f"{new}.json").write_text(json.dumps(evaluation))
    return new


@pytest.mark.parametrize("selfishness", [0.5000001, 0.25])
def test_population_reading_matches_beta_exactly_not_by_a_rounded_text(tmp_path: Path, capsys, selfishness: float) -> None:
    """A run at β = 0.5000001 (``%g``: ``0.5``) is not read as one at β = 0.5: it is left out as a
    run at any other β (0.25) is, so the default-trained Empathic DQN group has 9 seeds, not 10."""
    from leaderboard.population_reading import DEFAULT, read_scores

    population, default = population_dirs(tmp_path)
    assert main(["analyse", "population-reading", str(population), str(default)]) == 0
    assert "| `coexistence_v0` | `empathic_dqn` | `test_population` | harms | 10 (10) |" in capsys.readouterr().out
    _with_selfishness(default, EDITED, selfishness)
    seeds = read_scores(population, [default])[("coexistence_v0", "empathic_dqn", DEFAULT)][("test_population", "harms")]
    assert sorted(seeds) == list(range(1, 10))
    assert main(["analyse", "population-reading", str(population), str(default)]) == 0
    out = capsys.readouterr().out
    assert "| `coexistence_v0` | `empathic_dqn` | `test_population` | harms | 10 (9) |" in out
    assert "| `coexistence_v0` | `dqn` | `test_population` | harms | 10 (10) |" in out


def test_population_reading_refuses_an_environment_without_a_shipped_test_split(tmp_path: Path, capsys, monkeypatch) -> None:
    """Where ``coexistence_v0_test.toml`` does not ship (as for a plug-in environment), its
    evaluations are refused in one line naming the file, the field, the environment and the
    environments whose test split ships."""
    import empathy_zoo.scenarios as scenarios

    population, default = population_dirs(tmp_path)
    shipped = tmp_path / "shipped_scenarios"
    shipped.mkdir()
    for path in scenarios.SCENARIO_DIR.glob("*.toml"):
        if path.name != "coexistence_v0_test.toml":
            shutil.copy(path, shipped / path.name)
    monkeypatch.setattr(scenarios, "SCENARIO_DIR", shipped)
    assert main(["analyse", "population-reading", str(population), str(default)]) == 2
    captured = capsys.readouterr()
    err = captured.err
    assert captured.out == "" and err.count("\n") == 1 and "Traceback" not in err
    assert f"{population / 'evaluations' / 'coexistence_v0_test'}/coexistence_v0_population__" in err
    assert "field scenario_set.name" in err and "'coexistence_v0_test'" in err and "environment 'coexistence_v0'" in err
    assert "reads only the shipped test splits" in err
    assert "charger_v0, helping_v0, sharing_v0, vase_v0" in err
