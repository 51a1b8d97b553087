"""The fourteenth probe's findings: an agent header with a run id holds its seed, so the id is
always checked; a study's objective has a direction and every finished trial a value, so its best
is always compared."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import torch

from empathy_zoo.cli import main

ROOT = Path(__file__).resolve().parents[1]
AGENT = sorted((ROOT / "docs" / "results" / "quick" / "runs").glob("coexistence_v0__empathic_dqn-*__s0.agent.pt"))[0]
STUDY = ROOT / "docs" / "results" / "methods" / "tuning" / "coexistence_v0" / "dqn" / "study.json"


def _agent(tmp_path: Path, change: Any) -> Path:
    document = torch.load(AGENT, weights_only=True)
    change(document["header"])
    path = tmp_path / AGENT.name
    torch.save(document, path)
    return path


def _without_seed(header: dict[str, Any]) -> None:
    del header["seed"]
    header["settings"] = {**header["settings"], "learning_rate": 0.5}


def _only_required(header: dict[str, Any]) -> None:
    for key in [key for key in header if key not in ("method", "settings", "env", "env_kwargs", "run_id")]:
        del header[key]


@pytest.mark.parametrize(
    ("change", "field"),
    [(_without_seed, "header.seed"), (lambda h: h.__setitem__("seed", None), "header.seed"), (_only_required, "header.seed")],
    ids=["no seed, settings changed", "a null seed", "only the required keys and the run id"],
)
def test_an_agent_header_with_a_run_id_holds_its_seed(tmp_path: Path, capsys, change: Any, field: str) -> None:
    from empathy_zoo.agent_file import AgentFileError, load_agent

    path = _agent(tmp_path, change)
    with pytest.raises(AgentFileError, match=rf"{path.name}: field {field}: expected"):
        load_agent(path)
    assert main(["watch", str(path), "--episodes", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and field in err


def test_an_agent_header_without_a_run_id_has_none_to_check(tmp_path: Path) -> None:
    from empathy_zoo.agent_file import load_agent

    path = _agent(tmp_path, lambda h: (h.pop("run_id"), h.pop("seed")))
    assert load_agent(path).describe()["method"] == "empathic_dqn"


def _study_refused(tmp_path: Path, change: Any, field: str) -> None:
    from leaderboard.study_file import StudyFileError, check_study

    document = json.loads(STUDY.read_text())
    change(document)
    with pytest.raises(StudyFileError, match=rf"field {field}"):
        check_study(document, tmp_path / "study.json")


def _worst_best(document: dict[str, Any]) -> dict[str, Any]:
    finished = [trial for trial in document["trials"] if trial["state"] == "COMPLETE"]
    worst = min(finished, key=lambda trial: trial["value"])
    document["best"] = {"number": worst["number"], "value": worst["value"], "params": worst["params"]}
    return worst


def _no_direction(document: dict[str, Any]) -> None:
    _worst_best(document)
    del document["plan"]["objective"]["direction"]


def _values_removed(document: dict[str, Any]) -> None:
    worst = _worst_best(document)
    for trial in document["trials"]:
        if trial["state"] == "COMPLETE" and trial is not worst:
            del trial["value"]


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (_no_direction, r"plan\.objective\.direction: missing"),
        (_values_removed, r"trials\[\d+\]\.value: expected the value of a finished trial"),
    ],
    ids=["no direction", "other finished trials without values"],
)
def test_a_study_cannot_hide_a_better_trial(tmp_path: Path, change: Any, field: str) -> None:
    _study_refused(tmp_path, change, field)
