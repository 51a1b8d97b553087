"""Files from elsewhere are inert, bounded, range-checked data.

A result, evaluation, agent, checkpoint or tuning-journal file may come from anyone: each is read
through one bounded reader (a regular file, at most the cap of its kind, JSON nested at most
``MAX_JSON_DEPTH`` deep), every value it holds is checked against its range and the settings of its
run, and every refusal is one ``ValueError`` line naming the file. The suite deletes only the
temporary files it made, and asks for room for its largest file before training.
"""

from __future__ import annotations

import contextlib
import copy
import json
import math
import os
import re
import shutil
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import torch
from helpers_heldout import scenario_set, synthetic_evaluation, synthetic_run
from helpers_results import synthetic_schema_1
from helpers_resume import TINY_SETTINGS

from empathy_zoo import atomic, bounded_read
from empathy_zoo.agent_file import agent_document, load_agent
from empathy_zoo.atomic import check_output_dir, read_json, remove_stale_temp_files, write_bytes_atomic, write_with_atomic
from empathy_zoo.bounded_read import json_depth
from empathy_zoo.evaluation_file import check_evaluation, read_evaluation
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.experiment.result_reader import check_result, read_result
from empathy_zoo.limits import MAX_JSON_DEPTH, read_bounded
from empathy_zoo.result_file import ResultFileError
from empathy_zoo.training import RunnerOptions, ensemble, train_runs
from empathy_zoo.training.checkpoint import load_checkpoint
from empathy_zoo.training.resume import CHECKPOINT_DIR, checkpoint_path, manifest_path
from empathy_zoo.training.tuning import check_journal

DEAD = 2**22 + 12345
"""A process id above Linux's default pid_max: no such process."""


# ---------------------------------------------------------------------------- temporary files
def test_only_the_suites_own_temporary_files_are_removed(tmp_path):
    own = [tmp_path / f".x.json.ezoo-{DEAD}-abcd1234.tmp", tmp_path / f".ezoo-write-probe-{DEAD}-0badc0de"]
    users = [
        tmp_path / ".notes.tmp",
        tmp_path / f".x.{DEAD}.abcdef12.tmp",
        tmp_path / ".write-probe-1",
        tmp_path / f".x.ezoo-{DEAD}-abcd1234.tmp.bak",
        tmp_path / f"x.json.ezoo-{DEAD}-abcd1234.tmp",
    ]
    for path in [*own, *users]:
        path.write_bytes(b"mine")
    assert sorted(remove_stale_temp_files(tmp_path)) == sorted(own)
    assert all(path.exists() for path in users) and not any(path.exists() for path in own)


def test_a_temporary_file_carries_the_suites_marker(tmp_path):
    seen: list[str] = []
    write_with_atomic(tmp_path / "a.json", lambda handle: seen.extend(p.name for p in tmp_path.iterdir()))
    assert len(seen) == 1 and re.fullmatch(rf"\.a\.json\.ezoo-{os.getpid()}-[0-9a-f]{{8}}\.tmp", seen[0]), seen


# ---------------------------------------------------------------------------- room for the largest file
def test_the_output_directory_must_have_room_for_the_largest_file(tmp_path, monkeypatch):
    usage = shutil.disk_usage(tmp_path)
    monkeypatch.setattr(atomic.shutil, "disk_usage", lambda path: usage._replace(free=1 << 20))
    check_output_dir(tmp_path / "small")  # (a result file and its agent file fit)
    with pytest.raises(ValueError, match=r"has 1\.0 MB free, less than the 1\.0 GB of the largest file"):
        check_output_dir(tmp_path / "out", ("checkpoints",), largest_file=1 << 30)


# ---------------------------------------------------------------------------- the bounded reader
def call_within(seconds: float, call: Callable[[], Any]) -> BaseException | None:
    """What ``call()`` raised, within ``seconds`` (a call still blocked then fails the test)."""
    caught: list[BaseException | None] = []

    def run() -> None:
        try:
            call()
            caught.append(None)
        except BaseException as error:  # handed back to the test
            caught.append(error)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(seconds)
    return caught[0] if caught else TimeoutError(f"still blocked after {seconds} s")


READERS: dict[str, Callable[[Path], Any]] = {
    "result file": read_result,
    "evaluation file": read_evaluation,
    "agent file": load_agent,
    "checkpoint": load_checkpoint,
    "runs list": lambda path: read_json(path, "list of runs"),
    "note": lambda path: read_bounded(path, 1 << 20, "--note"),
}


@pytest.mark.parametrize("kind", list(READERS))
def test_a_fifo_is_refused_at_once_naming_it(tmp_path, kind):
    fifo = tmp_path / "x.json"
    os.mkfifo(fifo)
    try:
        error = call_within(10, lambda: READERS[kind](fifo))
    finally:
        with contextlib.suppress(OSError):  # (unblock a reader that waits on the FIFO)
            os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
    assert isinstance(error, ValueError), error
    assert str(fifo) in str(error) and "FIFO" in str(error) and "\n" not in str(error)


@pytest.mark.parametrize("kind", list(READERS))
def test_a_device_or_a_directory_is_refused_naming_it(tmp_path, kind):
    for path in (Path("/dev/zero"), tmp_path):
        error = call_within(10, lambda path=path: READERS[kind](path))
        assert isinstance(error, ValueError), error
        assert str(path) in str(error) and "not a regular file" in str(error)


def test_a_file_past_its_cap_is_refused_naming_it(tmp_path, monkeypatch):
    path = tmp_path / "runs" / "big.json"
    path.parent.mkdir()
    path.write_text(json.dumps(synthetic_schema_1("coexistence_v0", "dqn", 1.0, 0)))
    monkeypatch.setitem(bounded_read.CAPS, "result file", 1000)
    with pytest.raises(ValueError, match=re.escape(f"result file {path} is larger than 1,000 bytes")):
        read_result(path)


def test_json_nested_past_the_cap_is_refused_before_it_is_parsed(tmp_path):
    path = tmp_path / "deep.json"
    path.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(ValueError, match=rf"{re.escape(str(path))} nests arrays and objects more than {MAX_JSON_DEPTH} deep"):
        read_result(path)
    assert json_depth(b'{"a": "[[[[[[", "b": [[1], {"c": "]]"}]}') == 3
    assert json_depth(b'["\\"[[["]') == 1


# ---------------------------------------------------------------------------- forged result files
def at(document: dict[str, Any], field: str, value: Any) -> dict[str, Any]:
    """``document`` with ``field`` (``eval.0.harms.1``) set to ``value``."""
    forged = copy.deepcopy(document)
    *parents, last = field.split(".")
    table: Any = forged
    for key in parents:
        table = table[int(key)] if isinstance(table, list) else table[key]
    table[int(last) if isinstance(table, list) else last] = value
    return forged


RESULT_FORGERIES = {
    "eval harms NaN": ("eval.0.harms.1", math.nan, "eval[0].harms[1]"),
    "eval harms inf": ("eval.0.harms.0", math.inf, "eval[0].harms[0]"),
    "eval harms -5": ("eval.0.harms.0", -5, "eval[0].harms[0]"),
    "train harms -5": ("train.harms.3", -5, "train.harms[3]"),
    "fractional eval harms": ("eval.0.harms.0", 0.5, "eval[0].harms[0]"),
    "fractional train survival": ("train.survival.2", 99.5, "train.survival[2]"),
    "fractional batteries": ("train.batteries.0", 1.25, "train.batteries[0]"),
    "train return NaN": ("train.return.0", math.nan, "train.return[0]"),
    "equality 2": ("eval.0.equality.2", 2, "eval[0].equality[2]"),
    "survival past max_cycles": ("eval.0.survival.0", 501, "eval[0].survival[0]"),
    "train survival past its episode": ("train.episode_end_step.0", 100, "train.survival[0]"),  # (it survived 400)
    "ragged evaluation": ("eval.0.harms", [0.0, 0.0], "eval[0].harms"),
    "unknown environment": ("env", "foo_v0", "env"),
    "malformed policy label": ("config.fixed.cat_0", "random_walk(", "config.fixed.cat_0"),
    "policy label with a bad argument": ("config.fixed.cat_0", "patrol(period=)", "config.fixed.cat_0"),
}


@pytest.mark.parametrize("field, value, named", list(RESULT_FORGERIES.values()), ids=list(RESULT_FORGERIES))
def test_a_forged_result_value_is_refused_naming_file_and_field(field, value, named):
    document = synthetic_schema_1("coexistence_v0", "dqn", 1.0, 0, survival=400.0)
    check_result(document, "good.json")
    with pytest.raises(ResultFileError, match=rf"^forged\.json: field {re.escape(named)}: expected") as caught:
        check_result(at(document, field, value), "forged.json")
    assert "\n" not in str(caught.value)


@pytest.mark.parametrize("steps", [[4000, 4000], [3000, 2000]], ids=["duplicate", "decreasing"])
def test_evaluation_steps_must_increase(steps):
    document = synthetic_schema_1("coexistence_v0", "dqn", 1.0, 0)
    document["eval"] = [{**document["eval"][0], "step": step} for step in steps]
    with pytest.raises(ResultFileError, match=r"field eval\[1\]\.step: expected a step after"):
        check_result(document, "forged.json")


def test_a_nan_in_a_result_file_is_one_line_on_the_command_line(tmp_path, capsys):
    from empathy_zoo.cli import main

    path = tmp_path / "runs" / "a.json"
    path.parent.mkdir()
    path.write_text(json.dumps(at(synthetic_schema_1("coexistence_v0", "dqn", 1.0, 0), "eval.0.return.0", math.nan)))
    assert main(["leaderboard", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"empathy-zoo: error: {path}: field eval[0].return[0]") and err.count("\n") == 1


def test_the_marl_eval_export_writes_strict_json(tmp_path, monkeypatch):
    from leaderboard import export_marl_eval

    monkeypatch.setattr(export_marl_eval, "load_results_dirs", lambda dirs, labels: type("R", (), {"results": []})())
    monkeypatch.setattr(export_marl_eval, "marl_eval_layout", lambda results: {"env": {"task": {"x": math.nan}}})
    monkeypatch.setattr(export_marl_eval, "check_export_path", lambda out, dirs: None)
    with pytest.raises(ValueError, match="no finite number"):
        export_marl_eval.write_marl_eval([tmp_path / "in"], tmp_path / "out.json")
    assert not (tmp_path / "out.json").exists()


# ---------------------------------------------------------------------------- forged evaluation files
def evaluation() -> dict[str, Any]:
    run = synthetic_run("coexistence_v0", "dqn", 1.0, 0)
    definition = scenario_set("coexistence_v0", {"lazy": {"cat_0": "stay"}})
    return synthetic_evaluation(run, definition, {}, {"cat_0": "random_walk"})


EVALUATION_FORGERIES = {
    "harms -5": ("scenarios.1.metrics.harms.0", -5, "scenarios[1].metrics.harms[0]"),
    "fractional harms": ("scenarios.1.metrics.harms.0", 0.5, "scenarios[1].metrics.harms[0]"),
    "fractional survival": ("scenarios.0.metrics.survival.1", 12.5, "scenarios[0].metrics.survival[1]"),
    "equality NaN": ("scenarios.0.metrics.equality.1", math.nan, "scenarios[0].metrics.equality[1]"),
    "survival past max_cycles": ("scenarios.0.metrics.survival.0", 10**6, "scenarios[0].metrics.survival[0]"),
    "unknown environment": ("env", "foo_v0", "env"),
    "malformed policy label": ("scenarios.1.fixed.cat_0", "stay)", "scenarios[1].fixed.cat_0"),
}


@pytest.mark.parametrize("field, value, named", list(EVALUATION_FORGERIES.values()), ids=list(EVALUATION_FORGERIES))
def test_a_forged_evaluation_value_is_refused_naming_file_and_field(field, value, named):
    with pytest.raises(ValueError, match=rf"^forged\.json: field {re.escape(named)}: expected"):
        check_evaluation(at(evaluation(), field, value), "forged.json")


# ---------------------------------------------------------------------------- forged agent files
HEADER = {"method": "dqn", "settings": {}, "env": "coexistence_v0", "env_kwargs": {}}


def agent_file(tmp_path: Path, change: Callable[[dict[str, Any]], None] | None = None) -> Path:
    document = agent_document({"heads": {"q": [torch.ones(25, 5), torch.zeros(5)]}, "acting": "q"}, HEADER)
    if change is not None:
        change(document)
    path = tmp_path / "x.agent.pt"
    torch.save(document, path)
    return path


def _layer(index: int, tensor: torch.Tensor) -> Callable[[dict[str, Any]], None]:
    return lambda document: document["heads"]["q"].__setitem__(index, tensor)


AGENT_FORGERIES = {
    "sparse weight": _layer(0, torch.ones(25, 5).to_sparse()),
    "NaN weight": _layer(0, torch.full((25, 5), math.nan)),
    "inf bias": _layer(1, torch.full((5,), math.inf)),
    "float64 weight": _layer(0, torch.ones(25, 5, dtype=torch.float64)),
    "int weight": _layer(0, torch.ones(25, 5, dtype=torch.int64)),
}


@pytest.mark.parametrize("change", list(AGENT_FORGERIES.values()), ids=list(AGENT_FORGERIES))
def test_a_forged_agent_file_is_refused_naming_it(tmp_path, change):
    load_agent(agent_file(tmp_path))
    path = agent_file(tmp_path, change)
    error = call_within(30, lambda: load_agent(path))
    assert isinstance(error, ValueError) and str(path) in str(error) and "\n" not in str(error), error


# ---------------------------------------------------------------------------- forged checkpoints
def run_spec() -> RunSpec:
    return RunSpec.of(
        env="coexistence_v0",
        method="dqn",
        steps=300,
        eval_interval=100,
        eval_episodes=2,
        settings=TINY_SETTINGS,
        env_kwargs={"max_cycles": 40},
    )


OPTIONS = RunnerOptions(progress=False, checkpoint_interval=200)


@pytest.fixture(scope="module")
def checkpointed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """An output directory whose run was killed just after its checkpoint at step 200."""
    out = tmp_path_factory.mktemp("checkpointed") / "out"
    real = ensemble.save_checkpoint

    def save_then_die(path: Path, payload: dict[str, Any]) -> None:
        real(path, payload)
        raise KeyboardInterrupt

    ensemble.save_checkpoint = save_then_die
    try:
        with pytest.raises(KeyboardInterrupt):
            train_runs([run_spec()], out, OPTIONS)
    finally:
        ensemble.save_checkpoint = real
    return out


def _set(path: str, value: Callable[[Any], Any]) -> Callable[[dict[str, Any]], None]:
    def change(payload: dict[str, Any]) -> None:
        *parents, last = path.split(".")
        table: Any = payload
        for key in parents:
            table = table[int(key)] if isinstance(table, list) else table[key]
        key_of: Any = int(last) if isinstance(table, list) else last
        table[key_of] = value(table[key_of])

    return change


def _nan_first(tensor: torch.Tensor) -> torch.Tensor:
    tensor = tensor.clone()
    tensor.view(-1)[0] = math.nan
    return tensor


def _survival_past_its_episode(payload: dict[str, Any]) -> None:
    """The first logged episode ends one step before its survival (the episode after it longer)."""
    log = payload["logs"][0]
    assert log["survival"][0] >= 2, "an episode the robot survived 2 steps or more"
    log["episode_end_step"][0] = log["survival"][0] - 1


CHECKPOINT_FORGERIES = {
    "step -5": _set("step", lambda _: -5),
    "step 1e9": _set("step", lambda _: 10**9),
    "step not the learner's": _set("step", lambda _: 150),
    "replay position 1e9": _set("learner.replay.position", lambda _: 10**9),
    "replay size past the steps": _set("learner.replay.size", lambda _: 10**6),
    "NaN weights": _set("learner.online.0", _nan_first),
    "sparse weights": _set("learner.online.0", lambda t: t.to_sparse()),
    "cells off the grid": _set("vector.engine.cells.__ndarray__", lambda t: t + 10_000),
    "clock past max_cycles": _set("vector.engine.t.__ndarray__", lambda t: t + 10_000),
    "cells of an object dtype": _set("vector.engine.cells.dtype", lambda _: "object"),
    "engine array of another shape": _set("vector.engine.cells.__ndarray__", lambda t: t[:0]),
    "NaN observations": _set("obs.__ndarray__", _nan_first),
    "log entry a string": _set("logs.0.harms.0", lambda _: "many"),
    "log entry negative": _set("logs.0.batteries.0", lambda _: -5),
    "log survival past max_cycles": _set("logs.0.survival.0", lambda _: 10**6),
    "log survival past its episode": _survival_past_its_episode,
    "log not a table": _set("logs.0", lambda _: [1, 2]),
    "evaluation NaN": _set("evaluations.0.0.harms.0", lambda _: math.nan),
    "evaluation at another step": _set("evaluations.0.0.step", lambda _: 50),
    "evaluation of other episodes": _set("evaluations.0.0.harms", lambda v: v * 2),
    "elapsed NaN": _set("elapsed", lambda _: math.nan),
}


@pytest.mark.parametrize("change", list(CHECKPOINT_FORGERIES.values()), ids=list(CHECKPOINT_FORGERIES))
def test_a_forged_checkpoint_is_refused_as_corrupted_naming_it(tmp_path, checkpointed, change):
    out = tmp_path / "out"
    shutil.copytree(checkpointed, out)
    checkpoint = checkpoint_path(out, [run_spec()])
    assert checkpoint.exists() and manifest_path(checkpoint).exists()
    payload = torch.load(checkpoint, weights_only=True)
    change(payload)
    torch.save(payload, checkpoint)
    error = call_within(120, lambda: train_runs([run_spec()], out, OPTIONS))
    assert isinstance(error, ValueError), error
    assert str(checkpoint) in str(error) and ("corrupted" in str(error) or "cannot be resumed" in str(error)), error
    assert not list((out / "runs").glob("*.json")) and checkpoint.exists()


def test_the_checkpoint_the_suite_wrote_resumes(tmp_path, checkpointed):
    out = tmp_path / "out"
    shutil.copytree(checkpointed, out)
    assert not list((out / CHECKPOINT_DIR).glob("*.pt.*"))
    [path] = train_runs([run_spec()], out, OPTIONS)
    assert read_result(path).steps == 300


# ---------------------------------------------------------------------------- the tuning journal
LINES = [json.dumps({"op_code": 0, "worker_id": "w", "study_name": "tune"}), json.dumps({"op_code": 4, "trial_id": 0})]


def test_a_torn_last_journal_line_is_dropped_with_a_note(tmp_path):
    path = tmp_path / "study.journal"
    whole = "\n".join(LINES) + "\n"
    path.write_text(whole + '{"op_code": 5, "trial_id"')
    notes: list[str] = []
    check_journal(path, notes.append)
    assert path.read_text() == whole
    assert len(notes) == 1 and str(path) in notes[0] and "cut it short" in notes[0]
    check_journal(path, notes.append)  # (a whole journal is left as it is)
    assert path.read_text() == whole and len(notes) == 1


@pytest.mark.parametrize(
    "bad, why",
    [('{"op_code": 5, "trial_id"', "is no JSON"), ("[1, 2]", "is no JSON object"), ("[" * 1000 + "]" * 1000, "nests")],
    ids=["cut mid-file", "no object", "nested too deep"],
)
def test_a_bad_journal_line_is_refused_naming_file_and_line(tmp_path, bad, why):
    path = tmp_path / "study.journal"
    path.write_text("\n".join([LINES[0], bad, LINES[1]]) + "\n")
    with pytest.raises(ValueError, match=rf"tuning journal {re.escape(str(path))}, line 2 {why}"):
        check_journal(path, print)


def test_a_fifo_in_the_journals_place_is_refused(tmp_path):
    path = tmp_path / "study.journal"
    os.mkfifo(path)
    error = call_within(10, lambda: check_journal(path, print))
    assert isinstance(error, ValueError) and str(path) in str(error) and "FIFO" in str(error), error


def test_write_bytes_atomic_still_writes(tmp_path):
    write_bytes_atomic(tmp_path / "a.bin", b"x")
    assert (tmp_path / "a.bin").read_bytes() == b"x" and [p.name for p in tmp_path.iterdir()] == ["a.bin"]


def test_training_asks_for_room_for_its_largest_checkpoint_before_it_starts(tmp_path, monkeypatch):
    from empathy_zoo.experiment.model import RunSpec
    from empathy_zoo.training import RunnerOptions, train_runs
    from empathy_zoo.training.preflight import largest_checkpoint_bytes

    specs = [
        RunSpec.of(
            steps=200,
            eval_interval=100,
            eval_episodes=1,
            env_kwargs={"max_cycles": 40},
            seed=seed,
            settings={"learning_starts": 64},
        )
        for seed in (0, 1)
    ]
    options = RunnerOptions(progress=False, checkpoint_interval=100)
    needed = largest_checkpoint_bytes(specs, options)
    assert needed > 2 * 20_000_000  # (two runs' default replay of 500,000 steps)
    usage = shutil.disk_usage(tmp_path)
    monkeypatch.setattr(atomic.shutil, "disk_usage", lambda path: usage._replace(free=needed // 2))
    with pytest.raises(ValueError, match=r"less than the .* of the largest file"):
        train_runs(specs, tmp_path / "out", options)
    assert not list((tmp_path / "out").rglob("*.json"))
    train_runs(specs, tmp_path / "without", RunnerOptions(progress=False, checkpoint_interval=0))  # (no checkpoint: no such room)
