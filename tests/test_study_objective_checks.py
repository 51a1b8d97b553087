"""``analyse tuning-summary`` reads a study's plan as ``tune`` makes it: the objective's metric one
``tune`` takes for the study's environment, its direction the metric's, the experiment, variant,
method and environment one experiment's, and every trial value within what an episode of that
world holds. A real study from a tiny ``tune`` is read; each forged plan is refused in one line
naming the file and the field."""

from __future__ import annotations

import copy
import json
import re
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from helpers_sweeps import TUNE_SWEEP
from helpers_tune import snapshot, tiny_study

from empathy_zoo.cli import PROG, main

pytest.importorskip("optuna")

Change = Callable[[dict[str, Any]], None]

SHIPPED = sorted(Path(__file__).resolve().parents[1].joinpath("docs/results").rglob("study.json"))


@pytest.fixture(scope="module")
def real_study(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The ``study.json`` of a two-trial study of :data:`TUNE_SWEEP` (Coexistence, ``max_cycles = 40``)."""
    _, out = tiny_study(tmp_path_factory.mktemp("tune"), 2)
    return json.loads((out / "study.json").read_text())


def _max_cycles() -> int:
    """The episode length :data:`TUNE_SWEEP` builds its environment with."""
    found = re.search(r"max_cycles = (\d+)", TUNE_SWEEP)
    assert found is not None
    return int(found.group(1))


def _every_value(document: dict[str, Any], value: float) -> None:
    """Every trial value of ``document`` (its value, last value, curve points and their seeds' parts) and the best ``value``."""
    for trial in document["trials"]:
        for point in trial["curve"]:
            point["value"] = value
            point["per_seed"] = [value] * len(point["per_seed"])
        trial["last_value"] = value if trial["curve"] else None
        if trial["state"] == "COMPLETE":
            trial["value"] = value
    if document["best"] is not None:
        document["best"]["value"] = value


def _objective(metric: str, direction: str) -> Change:
    def change(document: dict[str, Any]) -> None:
        document["plan"]["objective"].update(metric=metric, direction=direction)

    return change


def _plan(**fields: Any) -> Change:
    def change(document: dict[str, Any]) -> None:
        document["plan"].update(fields)

    return change


def _then(*changes: Change) -> Change:
    def change(document: dict[str, Any]) -> None:
        for each in changes:
            each(document)

    return change


def _first_value(document: dict[str, Any]) -> str:
    """The field of the first trial value a reader meets: trial 0's value where it finished, else its last value."""
    return "trials[0].value" if document["trials"][0]["state"] == "COMPLETE" else "trials[0].last_value"


def hostile_plans() -> Iterator[tuple[str, Change, Callable[[dict[str, Any]], str]]]:
    """``(case, change, field)``: a change of a real study's plan or values ``tune`` never writes,
    and the field (of the changed document) a refusal must name."""
    cycles = _max_cycles()
    yield "batteries, which no Coexistence episode moves", _objective("batteries", "maximize"), lambda d: "plan.objective.metric"
    yield "equality, 1 in every Coexistence episode", _objective("equality", "maximize"), lambda d: "plan.objective.metric"
    yield "harms maximised", _objective("harms", "maximize"), lambda d: "plan.objective.direction"
    yield "survival minimised", _objective("survival", "minimize"), lambda d: "plan.objective.direction"
    yield "harms past one cat's one harm", _then(_objective("harms", "minimize"), lambda d: _every_value(d, 1.25)), _first_value
    yield "survival past max_cycles", _then(lambda d: _every_value(d, cycles + 0.5)), _first_value
    other = "sharing_v0__dqn_harm_penalty-0123abcd"
    yield "the experiment of another environment", _plan(experiment=other), lambda d: "plan.experiment"
    yield "an experiment id without its hash", _plan(experiment="coexistence_v0__dqn_harm_penalty"), lambda d: "plan.experiment"
    yield "another method than the experiment's", _plan(method="dqn"), lambda d: "plan.method"
    yield "the experiment without its method", lambda d: d["plan"].pop("method"), lambda d: "plan.method"
    yield "another environment than the variant", _plan(env="sharing_v0"), lambda d: "plan.env"
    yield "an environment not registered", _plan(env="nowhere_v0"), lambda d: "plan.env"
    yield "an environment without its arguments", lambda d: d["plan"].pop("env_kwargs"), lambda d: "plan.env_kwargs"
    yield "an episode of no step", _plan(env_kwargs={"max_cycles": 0}), lambda d: "plan.env_kwargs.max_cycles"
    yield "an argument the environment has not", _plan(env_kwargs={"batteries": 3}), lambda d: "plan.env_kwargs.batteries"


HOSTILE = list(hostile_plans())


@pytest.mark.parametrize(("case", "change", "field"), HOSTILE, ids=[case for case, _, _ in HOSTILE])
def test_a_plan_tune_cannot_write_is_refused_naming_its_field(
    real_study: dict[str, Any], tmp_path: Path, capsys: pytest.CaptureFixture[str], case: str, change: Change, field: Any
) -> None:
    document = copy.deepcopy(real_study)
    change(document)
    path = tmp_path / "forged" / "study.json"
    path.parent.mkdir()
    path.write_text(json.dumps(document))
    figure = tmp_path / "studies.png"
    before = snapshot(tmp_path)
    assert main(["analyse", "tuning-summary", str(tmp_path / "forged"), "--figure", str(figure)]) == 2, case
    err = capsys.readouterr().err
    assert err.startswith(f"{PROG}") and ": error: " in err and err.count("\n") == 1, err
    assert str(path) in err and f"field {field(document)}:" in err, err
    assert snapshot(tmp_path) == before  # (nothing written: the figure neither)


def test_the_real_study_of_a_tiny_tune_is_read(real_study: dict[str, Any], tmp_path: Path) -> None:
    from leaderboard.study_file import check_study

    assert real_study["plan"]["env"] == "coexistence_v0" and real_study["plan"]["env_kwargs"] == {"max_cycles": _max_cycles()}
    assert check_study(copy.deepcopy(real_study), tmp_path / "study.json") == real_study


def test_values_at_the_world_bound_are_read(real_study: dict[str, Any], tmp_path: Path) -> None:
    from leaderboard.study_file import check_study

    harms = copy.deepcopy(real_study)
    _objective("harms", "minimize")(harms)
    _every_value(harms, 1.0)  # (one cat, harmed once)
    assert check_study(harms, tmp_path / "study.json")["best"]["value"] == 1.0
    survival = copy.deepcopy(real_study)
    _every_value(survival, float(_max_cycles()))
    assert check_study(survival, tmp_path / "study.json")["best"]["value"] == _max_cycles()


@pytest.mark.parametrize("path", SHIPPED, ids=[str(path.parent.relative_to(path.parents[2])) for path in SHIPPED])
def test_every_shipped_study_is_read(path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["analyse", "tuning-summary", str(path.parent)]) == 0
    assert path.parent.parent.name in capsys.readouterr().out
