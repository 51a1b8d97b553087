"""``empathy-zoo reproduce`` refuses, before it trains or writes anything, what its leaderboard
would refuse once the sweep is trained: an agent file changed since its run wrote it (the run
whose agent the "Greedy episodes" section loads) and a forged or malformed evaluation file."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from helpers_heldout import scenario_set, synthetic_evaluation
from helpers_sweeps import TINY_SWEEP, TINY_TRAIN

import empathy_zoo.training.runner as runner
from empathy_zoo.atomic import write_json_atomic
from empathy_zoo.cli import main
from empathy_zoo.evaluation_file import evaluation_path
from empathy_zoo.experiment.result_reader import read_result

TWO_SEEDS = TINY_SWEEP.replace("seeds = 1", "seeds = 2")
"""The tiny sweep with seeds 0 and 1: seed 0 is the run ``train`` made, seed 1 is trained."""
assert TWO_SEEDS != TINY_SWEEP


@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One tiny DQN run (seed 0, the tiny sweep's) with its agent file, trained once for the module."""
    out = tmp_path_factory.mktemp("trained") / "out"
    assert main(["train", "--method", "dqn", "--out", str(out), *TINY_TRAIN]) == 0
    return out


@pytest.fixture
def out(trained: Path, tmp_path: Path) -> Path:
    copy = tmp_path / "out"
    shutil.copytree(trained, copy)
    return copy


@pytest.fixture
def no_training(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(runner, "train_ensemble", lambda *a, **k: pytest.fail("training started"))


def everything_below(path: Path) -> list[tuple[str, bytes | None]]:
    return sorted((str(p), p.read_bytes() if p.is_file() else None) for p in path.rglob("*"))


def reproduce(sweep_text: str, out: Path, tmp_path: Path) -> int:
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(sweep_text)
    return main(["reproduce", "--profile", str(sweep), "--out", str(out), "--no-progress", "--workers", "1"])


def the_run(out: Path) -> Path:
    [result_file] = (out / "runs").glob("*.json")
    return result_file


def refused(capsys: pytest.CaptureFixture[str]) -> str:
    captured = capsys.readouterr()
    assert captured.out == "", captured.out  # (not even the sweep's plan: nothing was started)
    err = captured.err
    assert err.startswith("empathy-zoo: error: ") and err.count("\n") == 1 and "Traceback" not in err, err
    return err


def test_a_changed_agent_file_is_refused_before_anything_trains_or_is_written(
    out: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], no_training: None
) -> None:
    [agent_file] = (out / "runs").glob("*.agent.pt")
    data = bytearray(agent_file.read_bytes())
    data[100] ^= 0xFF
    agent_file.write_bytes(bytes(data))
    capsys.readouterr()
    before = everything_below(tmp_path)
    sweep = tmp_path / "sweep.toml"
    assert reproduce(TWO_SEEDS, out, tmp_path) == 2
    err = refused(capsys)
    assert str(agent_file) in err and str(the_run(out)) in err and "changed or replaced" in err, err
    assert everything_below(tmp_path) == sorted([*before, (str(sweep), TWO_SEEDS.encode())])


def forged_evaluation(out: Path, case: str) -> Path:
    """An evaluation file of the run in ``out`` (of its own agent) that the leaderboard refuses."""
    run = read_result(the_run(out))
    definition = scenario_set("coexistence_v0", {"still": {"cat_0": "stay"}})
    path = evaluation_path(out, definition["name"], run.run_id)
    if case == "other partners":  # (well-formed, of the run's agent, but not of the world it trained in)
        assert dict(run.config.fixed) != {"cat_0": "stay"}
        write_json_atomic(path, synthetic_evaluation(run, definition, {}, {"cat_0": "stay"}))
        return path
    document = synthetic_evaluation(run, definition, {}, dict(run.config.fixed))
    if case == "another seed":  # (well-formed, of the run's agent, but not of the run)
        document["seed"] = run.seed + 1
        write_json_atomic(path, document)
    else:
        path.parent.mkdir(parents=True)
        path.write_text(json.dumps({**document, "format": "something else"}))
    return path


@pytest.mark.parametrize(
    "case, expected",
    [("other partners", "not an evaluation of run"), ("another seed", "field seed"), ("malformed", "field format")],
)
def test_a_forged_evaluation_file_is_refused_before_anything_trains_or_is_written(
    out: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], no_training: None, case: str, expected: str
) -> None:
    path = forged_evaluation(out, case)
    assert main(["leaderboard", str(out), "--out", str(tmp_path / "board")]) == 2  # (what the end would refuse)
    assert str(path) in capsys.readouterr().err
    before = everything_below(tmp_path)
    sweep = tmp_path / "sweep.toml"
    assert reproduce(TWO_SEEDS, out, tmp_path) == 2
    err = refused(capsys)
    assert str(path) in err and expected in err, err
    assert everything_below(tmp_path) == sorted([*before, (str(sweep), TWO_SEEDS.encode())])


def test_a_changed_agent_file_the_leaderboard_will_not_load_does_not_stop_the_sweep(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Seed 1 was trained, and its agent file changed; the sweep trains seed 0, whose agent (the
    row's lowest seed) is the one the leaderboard's episode loads: nothing it loads was changed,
    so the sweep is not refused and runs to its end."""
    out = tmp_path / "out"
    assert main(["train", "--method", "dqn", "--out", str(out), *TINY_TRAIN, "--seeds", "1"]) == 0
    [agent_file] = (out / "runs").glob("*.agent.pt")
    data = bytearray(agent_file.read_bytes())
    data[100] ^= 0xFF
    agent_file.write_bytes(bytes(data))
    capsys.readouterr()
    assert reproduce(TWO_SEEDS, out, tmp_path) == 0, capsys.readouterr().err
    printed = capsys.readouterr().out
    assert "(1 experiments × 2 seeds)" in printed and "1 already finished" in printed, printed  # (seed 0 trained now)
    assert (out / "LEADERBOARD.md").is_file() and len(list((out / "runs").glob("*.json"))) == 2
