"""The fifteenth probe's findings: an agent's networks fit the environment its header names (its
actions, its observation) before anything is played or written; every field of an agent record
is plain data; the agent-file writer refuses any header its readers refuse; a list of runs holds
only its own keys; an evaluation is its run's by agent file name too."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import re
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from empathy_zoo.cli import main

ROOT = Path(__file__).resolve().parents[1]
RUNS = ROOT / "docs" / "results" / "quick" / "runs"
EXPERIMENT = sorted(RUNS.glob("coexistence_v0__empathic_dqn-*__s0.json"))[0].name.removesuffix("__s0.json")
EVALUATION = sorted((ROOT / "docs" / "results" / "paper" / "evaluations" / "sharing_v0").glob("*.json"))[0]


def _widened(document: dict[str, Any], actions: int) -> None:
    """Every head's last layer given ``actions`` outputs (the last one preferred by far)."""
    for layers in document["heads"].values():
        layers[-2] = torch.zeros(layers[-2].shape[0], actions)
        layers[-1] = torch.zeros(actions)
        layers[-1][-1] = 100.0
    document["num_actions"] = actions


def _runs_with_a_forged_agent(tmp_path: Path, actions: int) -> tuple[Path, Path]:
    """Seeds 0 and 1 of a shipped experiment; seed 1's agent forged to ``actions`` outputs and its
    result file given the forged file's SHA-256 (as a forger would)."""
    runs = tmp_path / "ev" / "runs"
    runs.mkdir(parents=True)
    for seed in (0, 1):
        for suffix in (".json", ".agent.pt"):
            shutil.copy(RUNS / f"{EXPERIMENT}__s{seed}{suffix}", runs / f"{EXPERIMENT}__s{seed}{suffix}")
    agent = runs / f"{EXPERIMENT}__s1.agent.pt"
    document = torch.load(agent, weights_only=True)
    _widened(document, actions)
    torch.save(document, agent)
    result = runs / f"{EXPERIMENT}__s1.json"
    recorded = json.loads(result.read_text())
    recorded["agent"]["sha256"] = hashlib.sha256(agent.read_bytes()).hexdigest()
    result.write_text(json.dumps(recorded))
    return runs.parent, agent


@pytest.mark.parametrize("actions", [7, 3])
def test_an_agent_with_other_actions_than_its_environment_is_refused_naming_the_field(tmp_path: Path, actions: int) -> None:
    from empathy_zoo.agent_file import AgentFileError, load_agent

    _, agent = _runs_with_a_forged_agent(tmp_path, actions)
    with pytest.raises(AgentFileError, match=rf"{agent.name}: field num_actions: expected 5, the actions of coexistence_v0"):
        load_agent(agent)


def test_evaluate_refuses_such_an_agent_before_it_writes(tmp_path: Path, capsys) -> None:
    directory, agent = _runs_with_a_forged_agent(tmp_path, 7)
    capsys.readouterr()
    assert main(["evaluate", str(directory), "--episodes", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and agent.name in err and "num_actions" in err, err
    assert not (directory / "evaluations").exists() or not any((directory / "evaluations").rglob("*.json"))


def test_watch_refuses_such_an_agent_before_it_plays(tmp_path: Path, capsys) -> None:
    _, agent = _runs_with_a_forged_agent(tmp_path, 7)
    capsys.readouterr()
    assert main(["watch", str(agent), "--episodes", "1"]) == 2
    captured = capsys.readouterr()
    assert captured.err.count("\n") == 1 and "num_actions" in captured.err, captured.err
    assert "survival" not in captured.out, "no episode was played"


def test_an_agent_record_holds_plain_data_only(tmp_path: Path) -> None:
    from empathy_zoo.evaluation_file import EvaluationFileError, check_evaluation
    from empathy_zoo.experiment.result_reader import check_result
    from empathy_zoo.result_file import ResultFileError

    result = json.loads((RUNS / f"{EXPERIMENT}__s0.json").read_text())
    evaluation = json.loads(EVALUATION.read_text())
    assert check_result({**result, "agent": {**result["agent"], "note": "kept"}}, "x.json")["agent"]["note"] == "kept"
    for value in (math.nan, "a\x1bb", 10**400):
        with pytest.raises(ResultFileError, match=r"field agent\.zzz: expected plain data|field agent\.zzz: expected one line"):
            check_result({**result, "agent": {**result["agent"], "zzz": value}}, "x.json")
        with pytest.raises(EvaluationFileError, match=r"field agent\.zzz: expected"):
            check_evaluation({**evaluation, "agent": {**evaluation["agent"], "zzz": value}}, tmp_path / EVALUATION.name)


class _Plain:
    """A learner whose run 0 keeps an all-zero Q network."""

    def agent_state(self, run: int) -> dict[str, Any]:
        return {"heads": {"q": [np.zeros((25, 5), np.float32), np.zeros(5, np.float32)]}, "acting": "q"}


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (lambda h: h.__setitem__("zzz", 1), "header (the key 'zzz')"),
        (lambda h: h.__setitem__("env", "nope"), "header.env"),
        (lambda h: h.__setitem__("seed", -1), "header.seed"),
        (lambda h: h.__setitem__("env_kwargs", {"view": 4}), "header.env_kwargs"),
        (lambda h: h.__setitem__("label", "two\nlines"), "header.label"),
    ],
    ids=["an unknown key", "an unknown environment", "seed -1", "an even view", "a label of two lines"],
)
def test_the_writer_refuses_every_header_its_readers_refuse(tmp_path: Path, change: Any, field: str) -> None:
    from empathy_zoo.agent_file import write_agent_file

    header = {"method": "empathic_dqn", "settings": {}, "env": "coexistence_v0", "env_kwargs": {}}
    change(header)
    with pytest.raises(ValueError, match=f"field {re.escape(field)}: expected"):
        write_agent_file(_Plain(), 0, tmp_path / "a.agent.pt", header)
    assert list(tmp_path.iterdir()) == []


def test_a_list_of_runs_holds_only_its_own_keys(tmp_path: Path) -> None:
    from empathy_zoo.training.resume import read_manifest

    manifest = tmp_path / "x.runs.json"
    manifest.write_text(json.dumps({"format": 2, "runs": [{"run_id": "a__s0"}], "zzz": 1}))
    with pytest.raises(ValueError, match=r"unknown key\(s\) \['zzz'\]"):
        read_manifest(manifest, tmp_path / "x.pt")


def test_an_evaluation_is_its_run_s_by_agent_file_too() -> None:
    from empathy_zoo.evaluation_file import evaluation_mismatch, read_evaluation
    from empathy_zoo.experiment.result_reader import read_result
    from empathy_zoo.record_parts import AgentRef

    evaluation = read_evaluation(EVALUATION)
    run = read_result(EVALUATION.parents[2] / "runs" / f"{evaluation.run_id}.json")
    assert evaluation_mismatch(evaluation, run) is None
    relabelled = dataclasses.replace(evaluation, method_label="Totally different")
    assert evaluation_mismatch(relabelled, run) is None, "a reading may relabel runs (the paper's β = 1 is DQN)"
    renamed = dataclasses.replace(evaluation, agent=AgentRef(file=run.run_id + ".agent.zip", sha256=evaluation.agent.sha256))
    assert str(evaluation_mismatch(renamed, run)).startswith("agent.file: ")


def test_an_empty_out_is_refused_not_taken_for_the_working_directory(tmp_path: Path, monkeypatch, capsys) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["analyse", "separation", "coexistence_v0", "--out", ""]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--out: an empty path" in err, err
    assert list(tmp_path.iterdir()) == []
