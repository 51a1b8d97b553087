"""The fourteenth probe's minor findings: every value of a result file is checked (also a field no
check reads, and one a schema upgrade replaces); a study's counters agree; an evaluation names its
own agent file; an object holding one key twice is refused; the agent-file writer refuses the
header its readers refuse."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from helpers_results import derive_run_id, synthetic_schema_1

from empathy_zoo.agent_file import write_agent_file
from empathy_zoo.evaluation_file import EvaluationFileError, check_evaluation
from empathy_zoo.experiment.result_reader import check_result, read_result
from empathy_zoo.result_file import ResultFileError
from leaderboard.study_file import StudyFileError, check_study, read_study

ROOT = Path(__file__).resolve().parents[1]
RESULT = sorted((ROOT / "docs" / "results" / "quick" / "runs").glob("coexistence_v0__empathic_dqn-*__s0.json"))[0]
EVALUATION = sorted((ROOT / "docs" / "results" / "paper" / "evaluations" / "sharing_v0").glob("*.json"))[0]
STUDY = ROOT / "docs" / "results" / "methods" / "tuning" / "coexistence_v0" / "dqn" / "study.json"


def _result(change: Any) -> dict[str, Any]:
    """The shipped result file with ``change`` made to it, under the run id its config then gives
    (its agent file's name with it)."""
    document = json.loads(RESULT.read_text())
    change(document)
    derive_run_id(document)
    document["agent"]["file"] = document["run_id"] + ".agent.pt"
    return document


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (lambda d: d["config"].__setitem__("comment", math.nan), "config.comment"),
        (lambda d: d["config"].__setitem__("comment", 10**400), "config.comment"),
        (lambda d: d["config"].__setitem__("comment", "a\x1bb"), "config.comment"),
        (lambda d: d["config"].__setitem__("note\x07", 1), "config (the key 'note\\x07')"),
        (lambda d: d["config"].__setitem__("comment", {"deep": [1, math.inf]}), "config.comment.deep[1]"),
        (lambda d: d.__setitem__("remark", math.nan), "remark"),
        (lambda d: d.__setitem__("remark", ["fine", "\u202eevil"]), "remark[1]"),
    ],
    ids=["NaN", "10**400", "ESC", "a key with BEL", "inf deep down", "top-level NaN", "top-level RLO"],
)
def test_a_field_no_check_reads_is_plain_data(change: Any, field: str) -> None:
    with pytest.raises(ResultFileError, match=rf"x\.json: field {re.escape(field)}: expected"):
        check_result(_result(change), "x.json")


def test_a_plain_field_no_check_reads_is_kept() -> None:
    result = check_result(_result(lambda d: d["config"].__setitem__("comment", "a note")), "x.json")
    assert result["config"]["comment"] == "a note"


@pytest.mark.parametrize(
    ("field", "value"),
    [("reward", math.nan), ("reward", {"name": "x\x1b"}), ("description", 10**400)],
    ids=["reward NaN", "reward name with ESC", "description 10**400"],
)
def test_a_schema_1_field_its_upgrade_replaces_is_checked_too(field: str, value: Any) -> None:
    document = synthetic_schema_1("coexistence_v0", "empathic_dqn", 0.5, 0)
    document["config"][field] = value  # (hashed into the run id, then replaced by the upgrade)
    with pytest.raises(ResultFileError, match=rf"field config\.{field}"):
        check_result(derive_run_id(document), "x.json")


def test_a_schema_1_file_reads_as_before() -> None:
    document = derive_run_id(synthetic_schema_1("coexistence_v0", "empathic_dqn", 0.5, 0))
    assert check_result(document, "x.json")["config"]["description"]["selfishness"] == 0.5


def _study(change: Any) -> dict[str, Any]:
    document = json.loads(STUDY.read_text())
    change(document)
    return document


def _not_best(document: dict[str, Any]) -> dict[str, Any]:
    return next(trial for trial in document["trials"] if trial["number"] != document["best"]["number"])


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (lambda d: _not_best(d).__setitem__("steps_trained", -(10**30)), r"trials\[\d+\]\.steps_trained"),
        (lambda d: _not_best(d).__setitem__("steps_trained", 10_000), r"trials\[\d+\]\.steps_trained"),
        (lambda d: _not_best(d).__setitem__("number", 10**300), r"trials\[\d+\]\.number"),
        (lambda d: d["plan"]["params"].__setitem__("learning_rate", "log:-1:0.003"), r"plan\.params\.learning_rate"),
        (lambda d: d["plan"]["params"].__setitem__("learning_rate", "log:0:0.003"), r"plan\.params\.learning_rate"),
        (lambda d: d["plan"]["budget"].__setitem__("trials", 11), r"plan\.budget\.trials"),
        (lambda d: d.__setitem__("env_steps_trained", d["env_steps_trained"] + 100_000), r"env_steps_trained"),
    ],
    ids=[
        "steps_trained -10**30",
        "steps_trained not its curve's",
        "number 10**300",
        "log range below 0",
        "log range from 0",
        "trials not the budget's",
        "env steps not the trials'",
    ],
)
def test_a_study_s_counters_agree(tmp_path: Path, change: Any, field: str) -> None:
    with pytest.raises(StudyFileError, match=rf"field {field}: expected"):
        check_study(_study(change), tmp_path / "study.json")


def test_the_shipped_studies_read() -> None:
    studies = sorted((ROOT / "docs" / "results").rglob("study.json"))
    assert studies
    for path in studies:
        assert check_study(read_study(path), path)["trials"]


def test_an_evaluation_names_its_own_run_s_agent_file(tmp_path: Path) -> None:
    document = json.loads(EVALUATION.read_text())
    assert check_evaluation(document, EVALUATION)["agent"]["file"] == document["run_id"] + ".agent.pt"
    for name in ("other.agent.pt", document["run_id"] + ".json", "../" + document["run_id"] + ".agent.pt"):
        document["agent"]["file"] = name
        with pytest.raises(EvaluationFileError, match=r"field agent\.file: expected"):
            check_evaluation(document, tmp_path / EVALUATION.name)


def test_an_object_holding_a_key_twice_is_refused(tmp_path: Path) -> None:
    from empathy_zoo.bounded_read import DuplicateKeyError, parse_json

    assert parse_json('{"a": 1, "b": {"a": 2}}') == {"a": 1, "b": {"a": 2}}
    with pytest.raises(DuplicateKeyError, match="the key 'a' twice"):
        parse_json('{"b": {"a": 1, "a": 2}}')
    text = RESULT.read_text()
    forged = tmp_path / RESULT.name
    forged.write_text(text.replace('"seed": 0,', '"seed": 0, "seed": 0,', 1))
    assert forged.read_text() != text
    with pytest.raises(ValueError, match=rf"{re.escape(str(forged))} is corrupted .*'seed' twice"):
        read_result(forged)
    study = tmp_path / "study.json"
    study.write_text(STUDY.read_text().replace('"plan": {', '"plan": {"label": "x", ', 1))
    with pytest.raises(ValueError, match=rf"{re.escape(str(study))} is not JSON .*'label' twice"):
        read_study(study)


class _Plain:
    """A learner whose run 0 keeps an all-zero Q network."""

    def agent_state(self, run: int) -> dict[str, Any]:
        return {"heads": {"q": [np.zeros((25, 5), np.float32), np.zeros(5, np.float32)]}, "acting": "q"}


def test_the_writer_refuses_a_header_the_readers_refuse(tmp_path: Path) -> None:
    from empathy_zoo.agent_file import load_agent
    from empathy_zoo.run_ids import run_id

    fields = {"method": "empathic_dqn", "settings": {}, "env": "coexistence_v0", "env_kwargs": {}, "seed": 3}
    good = {"run_id": run_id("coexistence_v0", "empathic_dqn", fields, 3), **fields}
    assert write_agent_file(_Plain(), 0, tmp_path / "good.agent.pt", good) is not None
    assert load_agent(tmp_path / "good.agent.pt").describe()["method"] == "empathic_dqn"
    no_seed = {key: value for key, value in good.items() if key != "seed"}
    for name, header, message in (
        ("demo", {**good, "run_id": "demo"}, r"field header\.run_id: expected coexistence_v0__empathic_dqn-"),
        ("changed", {**good, "settings": {"learning_rate": 0.5}}, r"field header\.run_id: expected"),
        ("no-seed", no_seed, r"field header\.seed: expected"),
    ):
        with pytest.raises(ValueError, match=message):
            write_agent_file(_Plain(), 0, tmp_path / f"{name}.agent.pt", header)
        assert not (tmp_path / f"{name}.agent.pt").exists()
    assert write_agent_file(_Plain(), 0, tmp_path / "alone.agent.pt", {k: v for k, v in no_seed.items() if k != "run_id"})


@pytest.mark.parametrize("env", ["charger_v0", "coexistence_v0", "helping_v0", "sharing_v0", "vase_v0"])
def test_an_agent_still_present_has_left_at_0_on_every_engine(env: str) -> None:
    """The rule a checkpoint's ``left_at`` is held to (a present agent has not left) holds on random play."""
    from empathy_zoo.environments import ENGINES

    engine = ENGINES[env](32, max_cycles=40)
    rng = np.random.default_rng(1)
    engine.reset(seeds=list(range(32)))
    left = 0
    for _ in range(300):
        events = engine.step(rng.integers(0, engine.num_actions, size=(engine.num_envs, engine.num_agents)))
        assert not np.any(engine.present & (engine.left_at != 0))
        left += int(np.count_nonzero(engine.left_at))
        over = np.flatnonzero(events.episode_over)
        if over.size:
            engine.reset(over)
    assert sorted(ENGINES) == ["charger_v0", "coexistence_v0", "helping_v0", "sharing_v0", "vase_v0"]
    assert (left > 0) == (env != "sharing_v0"), "agents leave an episode (left_at set) but in Sharing, where none does"
