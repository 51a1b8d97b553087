"""Every size an input gives is bounded (issue 25, cause 2): threads and workers by the machine, a
learner's memory by what is available (computed before anything is allocated), steps, evaluations,
seeds, runs, notes and config files by the bounds of :mod:`empathy_zoo.limits`, each refused with
its bound in one line; result files are read within what the writer can produce; the Sharing
tables' documented size is an upper bound of what building them takes."""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import pytest
from helpers_results import synthetic_schema_1
from helpers_sweeps import TINY_TRAIN
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_grid_size import construction_peak

import empathy_zoo.cli.train as cli_train
from agents.empathic_dqn import EmpathicDQN
from agents.settings import EmpathicDQNSettings
from empathy_zoo import limits
from empathy_zoo.cli import main
from empathy_zoo.engine.arguments import table_bytes
from empathy_zoo.environments import ENGINES
from empathy_zoo.experiment.model import Budget, RunSpec
from empathy_zoo.experiment.result_reader import read_result
from empathy_zoo.experiment.sweep_file import load_sweep, parse_sweep
from empathy_zoo.experiment.values import SweepConfigError
from empathy_zoo.limits import (
    BOUNDS,
    MAX_CONFIG_BYTES,
    MAX_EVAL_EPISODES,
    MAX_EVALUATIONS,
    MAX_NOTE_BYTES,
    MAX_RUNS,
    MAX_SEED,
    MAX_SEEDS,
    MAX_STEPS,
)
from empathy_zoo.training import RunnerOptions

ROOT = Path(__file__).resolve().parents[1]
FAST = settings(max_examples=60, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
OBS = 25


def without(argv: list[str], option: str) -> list[str]:
    """``argv`` without ``option`` and its value."""
    at = argv.index(option)
    return argv[:at] + argv[at + 2 :]


def one_line_refusal(capsys) -> str:
    err = capsys.readouterr().err
    assert err.startswith("empathy-zoo: error: ") and err.count("\n") == 1 and "Traceback" not in err, err
    return err


# ---------------------------------------------------------------------------- 7. threads and workers
@pytest.mark.parametrize("name", ["threads", "workers"])
def test_threads_and_workers_are_bounded_by_the_machine(name):
    cpus = os.cpu_count() or 1
    RunnerOptions(**{name: cpus})
    with pytest.raises(ValueError, match=rf"{name} must be at most {cpus}.*CPUs"):
        RunnerOptions(**{name: cpus + 1})
    with pytest.raises(ValueError, match=f"{name} must be"):
        RunnerOptions(**{name: 0})


@pytest.mark.parametrize("count", ["100000", "5000"])
def test_train_refuses_too_many_threads_in_one_line_writing_nothing(tmp_path, capsys, count):
    out = tmp_path / "out"
    assert main(["train", "--threads", count, "--out", str(out), *TINY_TRAIN]) == 2
    assert "threads" in one_line_refusal(capsys)
    assert not out.exists()


def test_runner_options_check_every_field():
    for bad in ({"max_parallel_runs": 0}, {"checkpoint_interval": -1}, {"checkpoint_interval": MAX_STEPS + 1}, {"backend": "x"}):
        with pytest.raises(ValueError):
            RunnerOptions(**bad)


# ---------------------------------------------------------------------------- 8. memory
@pytest.fixture
def small_machine(monkeypatch):
    """A machine with 1 MB of memory available."""
    monkeypatch.setattr(limits, "available_memory", lambda device="cpu": (2**20, "available on this machine (MemAvailable)"))


def test_a_learner_that_cannot_fit_is_refused_before_allocating_with_the_figure(small_machine):
    settings_ = EmpathicDQNSettings(replay_capacity=100_000, learning_starts=32)
    with pytest.raises(ValueError, match=r"need about [\d.]+ MB of memory, more than the 1\.0 MB available.*replay_capacity"):
        EmpathicDQN([settings_], [0], OBS)
    EmpathicDQN([EmpathicDQNSettings(replay_capacity=1_000, learning_starts=32, hidden_size=8)], [0], OBS)


@pytest.mark.parametrize(
    "settings_",
    [
        {"selfishness": 1.0},
        {"selfishness": 0.5},
        {"selfishness": 0.5, "others": "mean"},
        {"hidden_size": 16, "replay_capacity": 500},
    ],
)
def test_the_estimate_from_settings_is_what_the_built_learner_reports(settings_):
    config = EmpathicDQNSettings(**{"replay_capacity": 2_000, "learning_starts": 32, **settings_})
    for others in (1, 3):
        learner = EmpathicDQN([config, config], [0, 1], OBS, num_others=others)
        estimate = EmpathicDQN.memory_needed([config, config], OBS, 5, num_others=others)
        assert estimate.per_run == learner.memory_bytes_per_run()
        assert estimate.replay_per_run == learner.replay_bytes_per_run()
        assert estimate.total >= 2 * learner.memory_bytes_per_run()


@pytest.mark.parametrize("option, value", [("--hidden-size", "100000000"), ("--replay-capacity", "1000000000")])
def test_train_refuses_a_run_that_cannot_fit_in_one_line_at_once(tmp_path, capsys, option, value):
    out = tmp_path / "out"
    assert main(["train", option, value, "--out", str(out), *without(TINY_TRAIN, option)]) == 2
    err = one_line_refusal(capsys)
    assert re.search(r"need about [\d,.]+ [KMGTPE]B of memory", err), err
    assert not out.exists()


@pytest.mark.parametrize(
    "error",
    [MemoryError(), RuntimeError("[enforce fail at alloc_cpu.cpp:83] DefaultCPUAllocator: can't allocate memory: you tried")],
)
def test_the_command_line_turns_an_allocation_failure_into_one_line(monkeypatch, capsys, error):
    def fails(args, command):
        raise error

    monkeypatch.setattr(cli_train, "cmd_train", fails)
    assert main(["train", *TINY_TRAIN]) == 1
    assert "memory" in one_line_refusal(capsys)


def test_another_runtime_error_keeps_its_traceback(monkeypatch):
    def fails(args, command):
        raise RuntimeError("a bug")

    monkeypatch.setattr(cli_train, "cmd_train", fails)
    with pytest.raises(RuntimeError, match="a bug"):
        main(["train", *TINY_TRAIN])


# ---------------------------------------------------------------------------- 10. budgets, seeds, runs
def test_steps_and_evaluations_are_bounded():
    Budget(MAX_STEPS, MAX_STEPS, MAX_EVAL_EPISODES)
    with pytest.raises(ValueError, match=f"steps must be at most {MAX_STEPS:,}"):
        Budget(10**23)
    with pytest.raises(ValueError, match=f"eval_episodes must be at most {MAX_EVAL_EPISODES:,}"):
        Budget(100, 100, MAX_EVAL_EPISODES + 1)
    with pytest.raises(ValueError, match=f"at most {MAX_EVALUATIONS:,} evaluations"):
        Budget(MAX_EVALUATIONS + 1, 1, 1)
    with pytest.raises(ValueError, match="seed must be at most"):
        RunSpec.of(seed=MAX_SEED + 1)


def test_train_refuses_too_many_steps_in_one_line(tmp_path, capsys):
    assert main(["train", "--steps", str(10**23), "--out", str(tmp_path / "out"), *without(TINY_TRAIN, "--steps")]) == 2
    assert f"at most {MAX_STEPS:,}" in one_line_refusal(capsys)


def sweep(seeds, **entry) -> dict:
    return {
        "sweep": {"seeds": seeds, "steps": 100, "eval_interval": 100},
        "envs": {"coexistence_v0": {}},
        "methods": [{"method": "dqn", **entry}],
    }


def test_too_many_seeds_are_refused_before_any_run_is_built():
    with pytest.raises(SweepConfigError, match=rf"seeds\.toml: \[sweep\] seeds: .*at most {MAX_SEEDS:,}"):
        parse_sweep(sweep(MAX_SEEDS + 1), source="seeds.toml")
    with pytest.raises(SweepConfigError, match=f"at most {MAX_SEEDS:,}"):
        parse_sweep(sweep(100_000_000), source="seeds.toml")
    with pytest.raises(SweepConfigError, match=f"at most {MAX_SEEDS:,}"):
        parse_sweep(sweep(1), source="seeds.toml", seeds=MAX_SEEDS + 1)


def test_a_sweep_of_too_many_runs_is_refused_before_they_are_built():
    grid = [0.9 + i / 100_000 for i in range(MAX_RUNS // 1_000 + 1)]
    with pytest.raises(SweepConfigError, match=f"runs.toml: .*runs, more than {MAX_RUNS:,}"):
        parse_sweep(sweep(1_000, gamma=grid, learning_rate=[1e-3, 1e-4], label="DQN {gamma} {learning_rate}"), source="runs.toml")


def test_a_note_file_is_read_within_its_bound(tmp_path, capsys):
    big = tmp_path / "note.md"
    with big.open("wb") as handle:
        handle.truncate(MAX_NOTE_BYTES + 1)
    assert main(["reproduction", str(tmp_path), "--note", str(big), "--out", str(tmp_path / "R.md")]) == 2
    assert f"larger than {limits.format_bytes(MAX_NOTE_BYTES)}" in one_line_refusal(capsys)
    if Path("/dev/zero").exists():  # (a device is refused before a byte of it is read)
        assert main(["reproduction", str(tmp_path), "--note", "/dev/zero", "--out", str(tmp_path / "R.md")]) == 2
        assert "is a character device, not a regular file" in one_line_refusal(capsys)
    assert not (tmp_path / "R.md").exists()


def test_a_sweep_file_is_read_within_its_bound(tmp_path):
    big = tmp_path / "big.toml"
    big.write_text("# " + "x" * MAX_CONFIG_BYTES + "\n")
    with pytest.raises(SweepConfigError, match="larger than"):
        load_sweep(big)


# ---------------------------------------------------------------------------- 9. result files within the writer's bounds
def result_file(tmp_path: Path, change) -> Path:
    document = synthetic_schema_1("coexistence_v0", "dqn", 1.0, 0)
    change(document)
    path = tmp_path / "runs" / "x.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(document))
    return path


@pytest.mark.parametrize(
    "change",
    [
        lambda d: d.update(method_label="x" * 2_000_000),
        lambda d: d["config"]["env_kwargs"].update(size=2000),
        lambda d: d["config"]["env_kwargs"].update(size=10**9),
        lambda d: d["config"]["env_kwargs"].update(view=4),
        lambda d: d["config"]["env_kwargs"].update(num_cats=10**6),
        lambda d: d.update(steps=10**23),
        lambda d: d.update(seed=MAX_SEED + 1),
    ],
    ids=["2MB label", "size 2000", "size 1e9", "even view", "a million cats", "steps 1e23", "seed 2**63"],
)
def test_a_result_file_beyond_what_the_writer_produces_is_refused_naming_it(tmp_path, change):
    path = result_file(tmp_path, change)
    with pytest.raises(ValueError, match=re.escape(str(path))):
        read_result(path)


@pytest.mark.parametrize("text", ["[" * 200_000, '{"schema": ' + "9" * 5_000 + "}"], ids=["deeply nested", "5,000-digit integer"])
def test_unparseable_json_is_refused_naming_the_file(tmp_path, text):
    path = tmp_path / "runs" / "x.json"
    path.parent.mkdir()
    path.write_text(text)
    with pytest.raises(ValueError, match=re.escape(str(path))):
        read_result(path)


@FAST
@given(st.sampled_from(["size", "view", "max_cycles", "num_cats"]), st.integers(min_value=256, max_value=10**40))
def test_huge_environment_arguments_in_a_result_file_are_refused(name, value):
    document = synthetic_schema_1("coexistence_v0", "dqn", 1.0, 0)
    document["config"]["env_kwargs"][name] = value if name != "max_cycles" else value * 10**9
    from empathy_zoo.experiment.result_reader import check_result
    from empathy_zoo.result_file import ResultFileError

    with pytest.raises(ResultFileError, match=re.escape("config.env_kwargs")):
        check_result(document, "huge.json")


# ---------------------------------------------------------------------------- the Sharing tables
@pytest.mark.parametrize("size, view", [(61, 31), (101, 31)])
def test_building_an_engine_with_a_wide_view_stays_under_its_documented_bound(size, view):
    for name in ENGINES:
        peak = construction_peak(ENGINES[name], size, view)
        assert peak <= table_bytes(size, view), (name, size, view, peak, table_bytes(size, view))


# ---------------------------------------------------------------------------- docs/limits.md
def test_docs_state_every_bound():
    text = (ROOT / "docs" / "limits.md").read_text()
    rows = {line.split("|")[1]: line for line in text.splitlines() if line.startswith("| ")}
    for name, bound in BOUNDS.items():
        named = [row for first, row in rows.items() if f"`{name}`" in first]
        row = (named or [row for first, row in rows.items() if first.strip().startswith(name + " ")] or [None])[0]
        assert row is not None, f"docs/limits.md has no row for {name}"
        assert any(shown in row for shown in (f"{bound:,}", limits.format_bytes(bound), "2⁶³ − 1")), (name, row)
    for machine in ("threads", "workers", "memory"):
        assert any(machine in first for first in rows), machine
