"""Forged result, evaluation and agent files are refused by the readers in one line naming the
file and the field, however their values are forged: an integer past the range of a float, fields
that disagree with each other, a header ``watch`` prints, a broken zip or pickle, a tensor that
would take a terabyte once copied. Every file is forged from a genuine one (a tiny trained run)."""

from __future__ import annotations

import copy
import io
import json
import os
import re
import shutil
import zipfile
from pathlib import Path
from typing import Any

import pytest
import test_check_then_write as check_then_write
import torch
from test_check_then_write import agent_file_of, one_line_refusal

from empathy_zoo.agent_file import FORMAT, LIBRARY_MEMBER, VERSION, load_agent
from empathy_zoo.cli import main
from empathy_zoo.evaluation_file import EvaluationFileError, check_evaluation, evaluation_files, read_evaluation
from empathy_zoo.experiment.result_reader import check_result, read_result
from empathy_zoo.experiment.values import SweepConfigError
from empathy_zoo.limits import MAX_SCENARIOS
from empathy_zoo.result_file import ResultFileError
from empathy_zoo.run_ids import run_id
from empathy_zoo.scenarios import load_scenario_set
from empathy_zoo.training.heldout import evaluate_results
from leaderboard.evaluation_dirs import match_evaluations

trained = check_then_write.trained
"""Two tiny runs (DQN, Empathic DQN) that kept their agents (the fixture of tests/test_check_then_write.py)."""

HUGE = 10**400
"""An integer JSON holds and no float does: ``math.isfinite`` raises ``OverflowError`` on it."""
ESC = "\x1b"


@pytest.fixture(scope="module")
def genuine_result(trained: Path) -> dict[str, Any]:
    """The Empathic DQN run's result file, as written."""
    run_file, _ = agent_file_of(trained, "empathic_dqn")
    document: dict[str, Any] = json.loads(run_file.read_text())
    return document


@pytest.fixture(scope="module")
def evaluated(trained: Path, tmp_path_factory) -> Path:
    """Where ``evaluate --out`` wrote the evaluations of the two runs (2 episodes per scenario)."""
    out = tmp_path_factory.mktemp("evaluated")
    evaluate_results(trained, episodes=2, out_dir=out, progress=False)
    return out


@pytest.fixture(scope="module")
def genuine_evaluation(evaluated: Path) -> dict[str, Any]:
    """The Empathic DQN run's evaluation file, as written."""
    (path,) = [p for p in evaluation_files(evaluated) if "empathic_dqn" in p.name]
    document: dict[str, Any] = json.loads(path.read_text())
    return document


def forged(document: dict[str, Any], *path: str | int, value: Any) -> dict[str, Any]:
    """A deep copy of ``document`` with the field at ``path`` set to ``value``."""
    copied = copy.deepcopy(document)
    where = copied
    for key in path[:-1]:
        where = where[key]
    where[path[-1]] = value
    return copied


def results_with(trained: Path, tmp_path: Path, document: dict[str, Any]) -> Path:
    """A copy of the trained results directory with the Empathic DQN run's result file replaced by ``document``."""
    results = tmp_path / "results"
    shutil.copytree(trained, results)
    run_file, _ = agent_file_of(results, "empathic_dqn")
    run_file.write_text(json.dumps(document))
    return results


def test_the_genuine_files_pass(trained, genuine_result, genuine_evaluation, evaluated):
    check_result(copy.deepcopy(genuine_result), "genuine.json")
    check_evaluation(copy.deepcopy(genuine_evaluation), "genuine.json")
    runs = [read_result(path) for path in sorted((trained / "runs").glob("*.json"))]
    matched = match_evaluations([evaluated], runs, [trained])
    assert len(matched) == len(evaluation_files(evaluated)) == 2
    for _, agent in (agent_file_of(trained, method) for method in ("dqn", "empathic_dqn")):
        load_agent(agent)


# ---------------------------------------------------------------------------- 1: integers past a float
@pytest.mark.parametrize(
    "where",
    [
        ("wall_time_s",),
        ("eval", 0, "survival", 0),
        ("eval", 0, "return", 0),
        ("eval", 0, "equality", 0),
        ("train", "survival", 0),
        ("train", "other_return", 0),
    ],
)
def test_an_integer_past_the_range_of_a_float_is_refused_in_a_result_file(genuine_result, where):
    if where[0] == "train" and not genuine_result["train"]["survival"]:
        pytest.skip("the tiny run finished no training episode")
    with pytest.raises(ResultFileError, match=r"forged\.json: field .*an integer of about 401 digits") as refused:
        check_result(forged(genuine_result, *where, value=HUGE), "forged.json")
    assert "\n" not in str(refused.value)


def test_an_integer_past_the_range_of_a_float_in_a_price_column_is_refused(genuine_result):
    episodes = len(genuine_result["train"]["episode_end_step"])
    document = forged(genuine_result, "train", "lambda", value=[HUGE] * episodes)
    if not episodes:
        document["train"]["lambda"] = [HUGE]
    with pytest.raises(ResultFileError, match=r"train\.lambda"):
        check_result(document, "forged.json")


def test_an_integer_past_the_range_of_a_float_in_an_evaluation_file_is_refused(genuine_evaluation):
    with pytest.raises(EvaluationFileError, match=r"scenarios\[0\]\.metrics\.survival\[0\]"):
        check_evaluation(forged(genuine_evaluation, "scenarios", 0, "metrics", "survival", 0, value=HUGE), "forged.json")


def test_the_leaderboard_refuses_a_huge_integer_in_one_line(trained, tmp_path, capsys, genuine_result):
    results = results_with(trained, tmp_path, forged(genuine_result, "wall_time_s", value=HUGE))
    out = tmp_path / "page"
    assert main(["leaderboard", str(results), "--out", str(out)]) == 2
    assert "wall_time_s" in one_line_refusal(capsys)
    assert not out.exists()


# ---------------------------------------------------------------------------- 15: fields that disagree
@pytest.mark.parametrize(
    ("where", "value", "named"),
    [
        (("config", "env_kwargs", "num_cats"), 48, r"config\.env_kwargs\.num_cats: expected at most 44"),
        (("config", "env"), "sharing_v0", r"config\.env: expected the run's env"),
        (("config", "seed"), 7, r"config\.seed: expected the run's seed"),
        (("config", "variant"), "elsewhere", r"config\.variant: expected the run's variant"),
        (("config", "method"), "dqn", r"config\.method: expected the run's method"),
        (("config", "label"), "another label", r"config\.label: expected the run's method_label"),
        (("config", "reward"), {"name": "harm_penalty", "penalty": float("nan")}, r"config\.reward\.penalty"),
        (("config", "description", "family"), f"dqn{ESC}[2J", r"config\.description\.family"),
        (("config", "description", "target"), "golden\x07", r"config\.description\.target"),
        (("eval",), [], r"eval: expected the run's 1 evaluation"),
        (("eval", 0, "return", 0), 1.7e308, r"eval\[0\]\.return\[0\]"),
        (("eval", 0, "other_return", 0), 1e300, r"eval\[0\]\.other_return\[0\]"),
    ],
)
def test_a_result_file_whose_fields_disagree_is_refused(genuine_result, where, value, named):
    with pytest.raises(ResultFileError, match=rf"forged\.json: field {named}") as refused:
        check_result(forged(genuine_result, *where, value=value), "forged.json")
    assert "\n" not in str(refused.value)


def test_evaluations_at_other_steps_than_the_runs_are_refused(genuine_result):
    (evaluation,) = genuine_result["eval"]
    early = {**copy.deepcopy(evaluation), "step": evaluation["step"] - 1}
    with pytest.raises(ResultFileError, match=r"field eval: expected the run's 1 evaluation"):
        check_result(forged(genuine_result, "eval", value=[early, evaluation]), "forged.json")


def test_a_grid_of_more_others_than_it_starts_names_the_file_in_the_leaderboard(trained, tmp_path, capsys, genuine_result):
    results = results_with(trained, tmp_path, forged(genuine_result, "config", "env_kwargs", "num_cats", value=48))
    out = tmp_path / "page"
    assert main(["leaderboard", str(results), "--out", str(out)]) == 2
    refusal = one_line_refusal(capsys)
    assert "config.env_kwargs.num_cats" in refusal and agent_file_of(results, "empathic_dqn")[0].name in refusal
    assert not out.exists()


@pytest.mark.parametrize(
    ("where", "value", "named"),
    [
        pytest.param(("seed",), 7, r"field seed: expected the seed its run id", id="seed"),
        pytest.param(("stream",), HUGE, r"field stream: expected 31", id="stream-huge"),
        pytest.param(("stream",), 5, r"field stream: expected 31", id="stream-other"),
    ],
)
def test_an_evaluation_file_whose_fields_disagree_is_refused(genuine_evaluation, where, value, named):
    with pytest.raises(EvaluationFileError, match=rf"forged\.json: {named}"):
        check_evaluation(forged(genuine_evaluation, *where, value=value), "forged.json")


def test_an_evaluation_file_named_for_another_run_is_refused(evaluated, tmp_path, capsys, trained):
    """A run's evaluation copied over another run's file (the probe's ``run_id`` forgery)."""
    results = tmp_path / "results"
    shutil.copytree(trained, results)
    shutil.copytree(evaluated / "evaluations", results / "evaluations")
    empathic, dqn = (
        next(p for p in evaluation_files(results) if method in p.name.split("-")[0]) for method in ("empathic_dqn", "__dqn")
    )
    shutil.copyfile(empathic, dqn)
    with pytest.raises(EvaluationFileError, match=rf"{dqn}: field run_id: its file is named"):
        read_evaluation(dqn)
    out = tmp_path / "page"
    assert main(["leaderboard", str(results), "--out", str(out)]) == 2
    assert dqn.name in one_line_refusal(capsys)
    assert not out.exists()


@pytest.mark.parametrize(
    ("where", "value", "named"),
    [
        (("method",), "dqn", "method"),
        (("variant",), "elsewhere", "variant"),
        (("scenarios", 0, "fixed", "cat_0"), "stay", r"scenarios\[0\]\.fixed"),
        (("scenarios", "*", "env_kwargs", "max_cycles"), 41, r"scenarios\[0\]\.env_kwargs"),
    ],
)
def test_the_leaderboard_refuses_an_evaluation_that_is_not_its_runs(
    trained, evaluated, genuine_evaluation, tmp_path, capsys, where, value, named
):
    """As ``evaluate`` writes it: what it records of the run must be the run's."""
    apart = tmp_path / "apart"
    shutil.copytree(evaluated, apart)
    (path,) = [p for p in evaluation_files(apart) if "empathic_dqn" in p.name]
    if where[1:2] == ("*",):  # (the run's argument in every scenario played: each plays the run's world but its own)
        document = copy.deepcopy(genuine_evaluation)
        for scenario in document["scenarios"]:
            scenario[where[2]][where[3]] = value
    else:
        document = forged(genuine_evaluation, *where, value=value)
    path.write_text(json.dumps(document))
    out = tmp_path / "page"
    assert main(["leaderboard", str(trained), "--out", str(out), "--evaluations", str(apart)]) == 2
    refusal = one_line_refusal(capsys)
    assert path.name in refusal and "not the evaluation of run" in refusal
    assert re.search(named, refusal), refusal
    assert not out.exists()


# ---------------------------------------------------------------------------- 12: watch and the agent file's header
def agent_copy(trained: Path, tmp_path: Path, change: Any) -> Path:
    """The Empathic DQN run's agent file alone in ``tmp_path`` (no result file beside it), its
    document changed by ``change(document)``."""
    _, agent = agent_file_of(trained, "empathic_dqn")
    document = torch.load(agent, weights_only=True)
    change(document)
    path = tmp_path / agent.name
    torch.save(document, path)
    return path


@pytest.mark.parametrize(
    ("key", "value", "named"),
    [
        ("fixed", 5, "header.fixed"),
        ("env_kwargs", 5, "header.env_kwargs"),
        ("env_kwargs", [1, 2], "header.env_kwargs"),
        ("env_kwargs", {"num_cats": 48}, "header.env_kwargs.num_cats"),
        ("env", "elsewhere_v0", "header.env"),
        ("method", f"evil{ESC}[2J{ESC}]0;pwned\x07", "header.method"),
        ("run_id", f"run{ESC}]0;pwned\x07", "header.run_id"),
        ("label", f"label{ESC}[31m", "header.label"),
        ("fixed", {"cat_0": f"stay{ESC}[2J"}, "header.fixed.cat_0"),
    ],
)
def test_watch_checks_the_agent_files_header_before_printing(trained, tmp_path, capsys, key, value, named):
    path = agent_copy(trained, tmp_path, lambda document: document["header"].__setitem__(key, value))
    assert main(["watch", str(path)]) == 2
    captured = capsys.readouterr()
    assert ESC not in captured.out and "\x07" not in captured.out and captured.out == ""
    err = captured.err
    assert err.startswith("empathy-zoo: error: ") and err.count("\n") == 1 and "Traceback" not in err, err
    assert named in err and str(path) in err


# ---------------------------------------------------------------------------- 13: agent files that do not load
class Unpicklable:
    """What ``torch.load(weights_only=True)`` refuses to unpickle (its message spans lines)."""


def test_an_agent_file_torch_refuses_is_one_line(trained, tmp_path, capsys):
    path = tmp_path / "x.agent.pt"
    torch.save({"format": FORMAT, "version": VERSION, "x": Unpicklable()}, path)
    with pytest.raises(ValueError, match=rf"{path} is not an empathy-zoo agent file") as refused:
        load_agent(path)
    assert "\n" not in str(refused.value)
    assert main(["watch", str(path)]) == 2
    assert str(path) in one_line_refusal(capsys)


def library_zip(members: dict[str, bytes]) -> bytes:
    """A zip of ``members`` stored uncompressed."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_STORED) as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    return buffer.getvalue()


def library_member(trained: Path) -> dict[str, Any]:
    """An :data:`LIBRARY_MEMBER` of a Stable-Baselines3 DQN agent, its header the trained run's."""
    _, agent = agent_file_of(trained, "empathic_dqn")
    header = {**torch.load(agent, weights_only=True)["header"], "method": "sb3_dqn"}
    config = {key: value for key, value in header.items() if key != "run_id"}
    header["run_id"] = run_id(header["variant"], "sb3_dqn", config, header["seed"])  # (the id its header gives)
    return {
        "format": FORMAT,
        "version": VERSION,
        "header": header,
        "library": "stable_baselines3",
        "algorithm": "DQN",
        "policy": "MlpPolicy",
        "obs_size": 25,
        "num_actions": 5,
        "heads": ["q"],
        "acting": "q",
    }


def test_an_agent_zip_with_a_bad_crc_is_one_line(trained, tmp_path, capsys):
    text = json.dumps(library_member(trained)).encode()
    data = bytearray(library_zip({LIBRARY_MEMBER: text}))
    at = bytes(data).index(text) + 2
    data[at] ^= 0x01  # (one byte of the stored member changed: its CRC-32 no longer matches)
    path = tmp_path / "x.agent.zip"
    path.write_bytes(bytes(data))
    with pytest.raises(ValueError, match=rf"agent file {path} is a damaged zip \(BadZipFile"):
        load_agent(path)
    assert main(["watch", str(path)]) == 2
    assert str(path) in one_line_refusal(capsys)


def test_an_sb3_agent_zip_without_its_data_is_one_line(trained, tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    path = tmp_path / "x.agent.zip"
    path.write_bytes(library_zip({LIBRARY_MEMBER: json.dumps(library_member(trained)).encode()}))
    with pytest.raises(ValueError, match=rf"agent file {path} has no member 'data'"):
        load_agent(path)
    assert main(["watch", str(path)]) == 2
    assert str(path) in one_line_refusal(capsys)


# ---------------------------------------------------------------------------- 14: a tensor huge once copied
def test_an_expanded_tensor_is_refused_before_it_is_copied(trained, tmp_path, capsys, monkeypatch):
    def expand(document: dict[str, Any]) -> None:
        document["heads"]["q"][0] = torch.zeros(1).expand(25, 10**10)  # (1 TB once copied; 4 bytes stored)

    path = agent_copy(trained, tmp_path, expand)
    assert path.stat().st_size < 1 << 20
    cloned: list[tuple[int, ...]] = []
    original = torch.Tensor.clone
    monkeypatch.setattr(torch.Tensor, "clone", lambda self, *a, **k: cloned.append(tuple(self.shape)) or original(self, *a, **k))
    with pytest.raises(ValueError, match=r"head 'q' weight 1 of shape \(25, 10000000000\) takes 1,000,000,000,000 bytes"):
        load_agent(path)
    assert (25, 10**10) not in cloned
    assert main(["watch", str(path)]) == 2
    assert "weight 1" in one_line_refusal(capsys)


# ---------------------------------------------------------------------------- 17: scenario files
@pytest.mark.parametrize("kind", ["fifo", "device"])
def test_a_scenario_file_that_is_no_regular_file_says_what_it_is(tmp_path, capsys, trained, kind):
    path = tmp_path / "held_out.toml"
    if kind == "fifo":
        os.mkfifo(path)
    else:
        path.symlink_to("/dev/zero")
    said = "a FIFO (named pipe)" if kind == "fifo" else "a character device"
    with pytest.raises(SweepConfigError, match=rf"scenario file {path} is {re.escape(said)}"):
        load_scenario_set(path)
    assert main(["evaluate", str(trained), "--scenarios", str(path), "--out", str(tmp_path / "out"), "--no-progress"]) == 2
    assert said in one_line_refusal(capsys)
    assert not (tmp_path / "out").exists()


def test_a_scenario_file_of_too_many_scenarios_is_refused(tmp_path):
    tables = "".join(f'[scenarios.s{i}]\nreason = "one of many"\n' for i in range(MAX_SCENARIOS + 1))
    path = tmp_path / "many.toml"
    path.write_text(f'[scenario_set]\nenv = "coexistence_v0"\n{tables}')
    with pytest.raises(SweepConfigError, match=rf"{MAX_SCENARIOS + 1:,} \[scenarios\.\*\] tables; .* at most {MAX_SCENARIOS:,}"):
        load_scenario_set(path)


def test_an_evaluation_file_of_too_many_scenarios_is_refused(genuine_evaluation):
    definitions = genuine_evaluation["scenario_set"]["scenarios"]
    many = [copy.deepcopy(definitions[0]) for _ in range(MAX_SCENARIOS + 1)]
    with pytest.raises(EvaluationFileError, match=r"scenario_set\.scenarios: expected an array of at most 1,000"):
        check_evaluation(forged(genuine_evaluation, "scenario_set", "scenarios", value=many), "forged.json")
