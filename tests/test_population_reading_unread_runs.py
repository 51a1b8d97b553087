"""``analyse population-reading`` leaves no run of a directory given out without a word: the runs
it does not read (another world, another method or β, the other group) are counted in a note per
directory and reason, and a directory none of whose runs is read is named (before, they were left
out in silence, exit 0, and a reading of none of them refused without saying why)."""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

from helpers_heldout import population_dirs

from empathy_zoo.cli import main
from empathy_zoo.markdown_escape import markdown_text
from empathy_zoo.run_ids import run_id
from leaderboard.population_reading import read_scores

SPLIT = "coexistence_v0_test"
ROW = "| `coexistence_v0` | `dqn` | `test_population` | harms |"
SCENARIOS = Path(__file__).resolve().parents[1] / "docs" / "results" / "scenarios"
"""The shipped default-trained runs of every method (no test-split evaluation: none is needed)."""


def _copy_as(source: Path, target: Path, prefix: str, seeds: range, edit: Callable[[dict[str, Any]], None]) -> list[str]:
    """Seeds ``seeds`` of the experiment ``prefix-*`` of ``source`` (result and test-split
    evaluation files) into ``target``, their config edited by ``edit``, under the run ids the trainer
    would give them, each evaluation's own world the run's; the new run ids."""
    (first,) = sorted((source / "runs").glob(f"{prefix}-*__s0.json"))
    experiment, written = first.name.removesuffix("__s0.json"), []
    for seed in seeds:
        old = f"{experiment}__s{seed}"
        result = json.loads((source / "runs" / f"{old}.json").read_text())
        edit(result["config"])
        new = run_id(result["variant"], result["method"], result["config"], seed)
        result["run_id"], result["agent"]["file"] = new, f"{new}.agent.pt"
        (target / "runs").mkdir(parents=True, exist_ok=True)
        (target / "runs" / f"{new}.json").write_text(json.dumps(result))
        evaluation = json.loads((source / "evaluations" / SPLIT / f"{old}.json").read_text())
        evaluation["run_id"], evaluation["agent"]["file"] = new, f"{new}.agent.pt"
        for entry in evaluation["scenarios"][1:]:  # (each scenario played in the run's world, changed by the scenario's)
            entry["env_kwargs"] = {**result["config"]["env_kwargs"], **entry["env_kwargs"]}
        evaluation["scenarios"][0]["fixed"] = result["config"]["fixed"]
        evaluation["scenarios"][0]["env_kwargs"] = result["config"]["env_kwargs"]
        (target / "evaluations" / SPLIT).mkdir(parents=True, exist_ok=True)
        (target / "evaluations" / SPLIT / f"{new}.json").write_text(json.dumps(evaluation))
        written.append(new)
    return written


def _short(config: dict[str, Any]) -> None:
    config["env_kwargs"] = {"max_cycles": 1000}


def _chase(config: dict[str, Any]) -> None:
    config["fixed"] = {"cat_0": "chase"}


def _beta(config: dict[str, Any]) -> None:
    config["settings"]["selfishness"] = config["description"]["selfishness"] = 0.25


def _notes(population: Path, defaults: list[Path]) -> list[str]:
    notes: list[str] = []
    read_scores(population, defaults, notes)
    return notes


def test_a_directory_of_runs_outside_the_default_world_is_named_with_its_count(tmp_path: Path, capsys) -> None:
    """The probe's case: a directory of evaluated runs of the default world but for max_cycles."""
    population, default = population_dirs(tmp_path)
    assert main(["analyse", "population-reading", str(population), str(default)]) == 0
    alone = capsys.readouterr().out
    other = tmp_path / "short"
    _copy_as(default, other, "coexistence_v0__dqn", range(3), _short)
    assert main(["analyse", "population-reading", str(population), str(default), str(other)]) == 0
    out = capsys.readouterr().out
    note = f"Note: {markdown_text(f'all 3 runs of {other} trained outside the default world (max_cycles 1000): not read')}"
    assert out == alone + "\n" + note + "\n", out  # (the tables as before: the runs are not read)
    assert f"{ROW} 10 (10) |" in out


def test_each_reason_a_directory_is_not_read_gets_one_note(tmp_path: Path) -> None:
    """Runs of another world (grouped, whatever of the world differs), at another β, of another
    method, and of the other group, beside the runs read of the same directories."""
    population, default = population_dirs(tmp_path)
    source, default_source = population_dirs(tmp_path / "source")  # (unchanged: one experiment of each)
    _copy_as(default_source, default, "coexistence_v0__dqn", range(2), _short)
    _copy_as(default_source, default, "coexistence_v0__dqn", range(1), _chase)
    _copy_as(default_source, default, "coexistence_v0__empathic_dqn", range(2), _beta)
    for path in sorted((SCENARIOS / "runs").glob("vase_v0__dqn_aup-*__s[01].json")):
        shutil.copy(path, default / "runs" / path.name)
    _copy_as(source, default, "coexistence_v0_population__dqn", range(1), lambda config: None)
    _copy_as(default_source, population, "coexistence_v0__dqn", range(4, 5), _short)
    notes = _notes(population, [default])
    assert sorted(notes) == sorted(
        [
            f"3 runs of {default} trained outside the default world (cat_0 chase, max_cycles 1000): not read",
            f"2 runs of {default} of empathic_dqn at a β other than 0.5 (0.25): not read",
            f"2 runs of {default} of a method other than dqn and empathic_dqn (dqn_aup): not read",
            f"1 run of {default} trained beside a population (population-trained runs are read from the first directory only)"
            ": not read",
            f"1 run of {population} trained beside no population (the first directory's runs are read as population-trained"
            " only): not read",
        ]
    ), notes


def test_a_directory_none_of_whose_runs_is_read_is_named(tmp_path: Path) -> None:
    population, default = population_dirs(tmp_path)
    mixed = tmp_path / "mixed"
    _copy_as(default, mixed, "coexistence_v0__dqn", range(1), _short)
    shutil.copy(next((SCENARIOS / "runs").glob("vase_v0__dqn_aup-*__s0.json")), mixed / "runs")
    notes = _notes(population, [default, mixed])
    assert f"none of the 2 runs of {mixed} is read" in notes, notes
    assert f"1 run of {mixed} trained outside the default world (max_cycles 1000): not read" in notes
    assert f"1 run of {mixed} of a method other than dqn and empathic_dqn (dqn_aup): not read" in notes
    lone = tmp_path / "lone"
    _copy_as(default, lone, "coexistence_v0__dqn", range(1), _short)
    assert f"1 run of {lone} (its only run) trained outside the default world (max_cycles 1000): not read" in _notes(
        population, [default, lone]
    )


def test_a_reading_of_no_run_read_says_which_runs_were_not_read(tmp_path: Path, capsys) -> None:
    """The refusal of a reading with no comparison names the runs given and not read, on its one line."""
    population, default = population_dirs(tmp_path)
    other = tmp_path / "short"
    _copy_as(default, other, "coexistence_v0__dqn", range(2), _short)
    assert main(["analyse", "population-reading", str(population), str(other)]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1
    assert "no environment and method has runs of both groups" in captured.err
    assert f"all 2 runs of {other} trained outside the default world (max_cycles 1000): not read" in captured.err
