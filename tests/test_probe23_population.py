"""``analyse population-reading`` reads one experiment's seeds per environment, method and group:
runs of another setting or population beside them are refused naming two runs, runs of another
world are not the default group's, and a run of a group without a test-split evaluation is named
in a note (before, all of them were pooled or dropped without a word, exit 0)."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from helpers_heldout import population_dirs

from empathy_zoo.cli import main
from empathy_zoo.run_ids import run_id

SPLIT = "coexistence_v0_test"
ROW = "| `coexistence_v0` | `dqn` | `test_population` | harms |"


def _copy_as(
    source: Path, target: Path, experiment: str, seeds: range, offset: int, edit: Callable[[dict[str, Any]], None]
) -> None:
    """Seeds ``seeds`` of ``experiment`` (its result and test-split evaluation files) of ``source``
    as another experiment in ``target``: its config edited by ``edit``, seeds moved by ``offset``,
    under the run ids the trainer would give them, the evaluation's own world the run's."""
    for seed in seeds:
        old = f"{experiment}__s{seed}"
        result = json.loads((source / "runs" / f"{old}.json").read_text())
        edit(result["config"])
        result["seed"] = result["config"]["seed"] = seed + offset
        new = run_id(result["variant"], result["method"], result["config"], seed + offset)
        result["run_id"], result["agent"]["file"] = new, f"{new}.agent.pt"
        (target / "runs").mkdir(parents=True, exist_ok=True)
        (target / "runs" / f"{new}.json").write_text(json.dumps(result))
        evaluation = json.loads((source / "evaluations" / SPLIT / f"{old}.json").read_text())
        evaluation["run_id"], evaluation["seed"], evaluation["agent"]["file"] = new, seed + offset, f"{new}.agent.pt"
        evaluation["scenarios"][0]["fixed"] = result["config"]["fixed"]
        evaluation["scenarios"][0]["env_kwargs"] = result["config"]["env_kwargs"]
        (target / "evaluations" / SPLIT).mkdir(parents=True, exist_ok=True)
        (target / "evaluations" / SPLIT / f"{new}.json").write_text(json.dumps(evaluation))


def _experiment(directory: Path, prefix: str) -> str:
    (first,) = sorted((directory / "runs").glob(f"{prefix}-*__s0.json"))
    return first.name.removesuffix("__s0.json")


def _gamma(config: dict[str, Any]) -> None:
    config["settings"]["gamma"] = config["description"]["gamma"] = 0.9


def _chase(config: dict[str, Any]) -> None:
    config["fixed"] = {"cat_0": "chase"}


def _other_population(config: dict[str, Any]) -> None:
    config["fixed"] = {"cat_0": 'population(members=["random_walk", "chase"])'}


@pytest.mark.parametrize(("group", "edit"), [("default", _gamma), ("population", _other_population)])
def test_two_experiments_of_one_group_are_refused_naming_two_runs(tmp_path: Path, capsys, group: str, edit: Any) -> None:
    population, default = population_dirs(tmp_path)
    source = default if group == "default" else population
    prefix = "coexistence_v0__dqn" if group == "default" else "coexistence_v0_population__dqn"
    other = tmp_path / "other"
    _copy_as(source, other if group == "default" else population, _experiment(source, prefix), range(3), 20, edit)
    argv = ["analyse", "population-reading", str(population), str(default), *([str(other)] if group == "default" else [])]
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1
    assert f"the {group}-trained runs of dqn on coexistence_v0 but of two experiments" in captured.err
    assert f"{prefix}-" in captured.err and "__s20" in captured.err


def test_runs_beside_another_partner_are_not_default_trained(tmp_path: Path, capsys) -> None:
    population, default = population_dirs(tmp_path)
    other = tmp_path / "other"
    _copy_as(default, other, _experiment(default, "coexistence_v0__dqn"), range(5), 20, _chase)
    assert main(["analyse", "population-reading", str(population), str(default), str(other)]) == 0
    assert f"{ROW} 10 (10) |" in capsys.readouterr().out


def test_a_run_without_a_test_split_evaluation_is_named_in_a_note(tmp_path: Path, capsys) -> None:
    population, default = population_dirs(tmp_path)
    missing = f"{_experiment(default, 'coexistence_v0__dqn')}__s3"
    (default / "evaluations" / SPLIT / f"{missing}.json").unlink()
    assert main(["analyse", "population-reading", str(population), str(default)]) == 0
    out = capsys.readouterr().out
    assert f"{ROW} 10 (9) |" in out
    (note,) = [line for line in out.splitlines() if line.startswith("Note: ")]
    assert missing in note and "default-trained dqn on coexistence_v0, seed 3" in note and "counts 9 of its 10 runs" in note


def test_a_group_none_of_whose_runs_was_evaluated_is_named_in_a_note(tmp_path: Path, capsys) -> None:
    population, default = population_dirs(tmp_path)
    experiment = _experiment(default, "coexistence_v0__dqn")
    for path in (default / "evaluations" / SPLIT).glob(f"{experiment}__s*.json"):
        path.unlink()
    main(["analyse", "population-reading", str(population), str(default)])
    out = capsys.readouterr().out
    notes = [line for line in out.splitlines() if line.startswith("Note: ")]
    assert any("no run of the 10 default-trained runs of dqn on coexistence_v0 has an evaluation" in note for note in notes), out
