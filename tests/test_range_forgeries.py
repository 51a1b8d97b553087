"""Every value of a forged result or evaluation file is checked against its range, and every size a
command takes has a bound, checked before anything is played or written.

* A result file's ``wall_time_s`` is a finite number of seconds in ``[0, MAX_WALL_TIME_S]``; its
  ``steps`` equals its ``config.steps``; its metrics are only the suite's, each within its range
  (counts whole, survival at most ``max_cycles``).
* An evaluation file's ``method_label`` follows the label rule and its scenarios' reasons are one
  line of printable text; its metrics are only the suite's.
* ``watch`` and ``play`` refuse ``--episodes``, ``--seed`` and ``--gif-steps`` past their bounds
  in one line (exit status 2) before any episode is played; a GIF that cannot be written names
  its file.
* ``reproduce`` stops on SIGINT while it writes its leaderboard (exit status 130), as it does while
  it trains.
"""

from __future__ import annotations

import copy
import errno
import json
import os
import signal
from pathlib import Path
from typing import Any

import pytest
import test_check_then_write as check_then_write
from helpers_sweeps import TINY_SWEEP
from test_check_then_write import agent_file_of, one_line_refusal

from empathy_zoo.cli import main
from empathy_zoo.evaluation_file import EvaluationFileError, check_evaluation, evaluation_files
from empathy_zoo.experiment.result_reader import check_result
from empathy_zoo.limits import MAX_CYCLES, MAX_EVAL_EPISODES, MAX_SEED, MAX_WALL_TIME_S
from empathy_zoo.result_file import ResultFileError
from empathy_zoo.training.heldout import evaluate_results

trained = check_then_write.trained
"""Two tiny runs (DQN, Empathic DQN) that kept their agents (the fixture of tests/test_check_then_write.py)."""

ESC = "\x1b"


@pytest.fixture(scope="module")
def genuine_result(trained: Path) -> dict[str, Any]:
    """The Empathic DQN run's result file, as written."""
    run_file, _ = agent_file_of(trained, "empathic_dqn")
    document: dict[str, Any] = json.loads(run_file.read_text())
    return document


@pytest.fixture(scope="module")
def genuine_evaluation(trained: Path, tmp_path_factory) -> dict[str, Any]:
    """One evaluation file of the two runs beside the shipped held-out partners, as written."""
    out = tmp_path_factory.mktemp("evaluated")
    evaluate_results(trained, episodes=2, out_dir=out, progress=False)
    document: dict[str, Any] = json.loads(evaluation_files(out)[0].read_text())
    return document


def forged(document: dict[str, Any], *path: str | int, value: Any) -> dict[str, Any]:
    """A deep copy of ``document`` with the field at ``path`` set to ``value``."""
    copied = copy.deepcopy(document)
    where = copied
    for key in path[:-1]:
        where = where[key]
    where[path[-1]] = value
    return copied


def test_the_genuine_files_pass(genuine_result, genuine_evaluation):
    check_result(copy.deepcopy(genuine_result), "genuine.json")
    check_evaluation(copy.deepcopy(genuine_evaluation), "genuine.json")


# ---------------------------------------------------------------------------- result files
@pytest.mark.parametrize("seconds", [-1.0, float("inf"), float("nan"), MAX_WALL_TIME_S + 1, "12", True])
def test_a_wall_time_out_of_range_is_refused(genuine_result, seconds):
    with pytest.raises(ResultFileError, match="wall_time_s"):
        check_result(forged(genuine_result, "wall_time_s", value=seconds), "forged.json")


def test_a_wall_time_at_its_bound_passes(genuine_result):
    check_result(forged(genuine_result, "wall_time_s", value=MAX_WALL_TIME_S), "forged.json")


def test_steps_other_than_the_configs_are_refused(genuine_result):
    with pytest.raises(ResultFileError, match=r"forged\.json.*steps.*config\.steps"):
        check_result(forged(genuine_result, "steps", value=genuine_result["steps"] + 1), "forged.json")


@pytest.mark.parametrize("phase", ["train", "eval"])
def test_a_metric_the_suite_does_not_have_is_refused(genuine_result, phase):
    document = copy.deepcopy(genuine_result)
    entry = document["train"] if phase == "train" else document["eval"][0]
    metrics = entry.get("metrics", entry)
    metrics["happiness"] = copy.deepcopy(metrics["harms"])
    with pytest.raises(ResultFileError, match="happiness"):
        check_result(document, "forged.json")


@pytest.mark.parametrize(("metric", "value"), [("harms", 0.5), ("harms", -1.0), ("survival", 10**6), ("equality", 2.0)])
def test_an_impossible_greedy_episode_is_refused(genuine_result, metric, value):
    document = copy.deepcopy(genuine_result)
    metrics = document["eval"][0]
    metrics = metrics.get("metrics", metrics)
    metrics[metric] = [value, *metrics[metric][1:]]
    with pytest.raises(ResultFileError, match=metric):
        check_result(document, "forged.json")


def test_a_forged_wall_time_stops_the_leaderboard_before_it_writes(trained, tmp_path, capsys, genuine_result):
    results = tmp_path / "results"
    (results / "runs").mkdir(parents=True)
    run_file, _ = agent_file_of(trained, "empathic_dqn")
    (results / "runs" / run_file.name).write_text(json.dumps(forged(genuine_result, "wall_time_s", value=-5)))
    out = tmp_path / "page"
    assert main(["leaderboard", str(results), "--out", str(out)]) == 2
    assert "wall_time_s" in one_line_refusal(capsys)
    assert not out.exists()


# ---------------------------------------------------------------------------- evaluation files
@pytest.mark.parametrize("label", [f"DQN{ESC}[31m", "DQN\u202e", "DQN\x07", "x" * 5_000])
def test_an_evaluation_files_method_label_follows_the_label_rule(genuine_evaluation, label):
    with pytest.raises(EvaluationFileError, match="method_label"):
        check_evaluation(forged(genuine_evaluation, "method_label", value=label), "forged.json")


@pytest.mark.parametrize("reason", [f"keeps away{ESC}[2J", "keeps\raway", ""])
def test_a_played_scenarios_reason_is_one_line_of_text(genuine_evaluation, reason):
    with pytest.raises(EvaluationFileError, match=r"scenarios\[1\]\.reason"):
        check_evaluation(forged(genuine_evaluation, "scenarios", 1, "reason", value=reason), "forged.json")


def test_an_evaluation_metric_the_suite_does_not_have_is_refused(genuine_evaluation):
    metrics = genuine_evaluation["scenarios"][1]["metrics"]
    document = forged(genuine_evaluation, "scenarios", 1, "metrics", value={**metrics, "happiness": metrics["harms"]})
    with pytest.raises(EvaluationFileError, match="happiness"):
        check_evaluation(document, "forged.json")


# ---------------------------------------------------------------------------- watch and play
def bound_refusals(run_id: str) -> list[tuple[list[str], str]]:
    """Each size flag of ``watch`` and ``play`` one past its bound, and the flag its refusal names."""
    return [
        (["watch", run_id, "--episodes", str(MAX_EVAL_EPISODES + 1)], "--episodes"),
        (["watch", run_id, "--episodes", "0"], "--episodes"),
        (["watch", run_id, "--seed", "-1"], "--seed"),
        (["watch", run_id, "--episodes", "2", "--seed", str(MAX_SEED)], "--seed"),
        (["watch", run_id, "--gif-steps", str(MAX_CYCLES + 1)], "--gif-steps"),
        (["play", "--episodes", str(MAX_EVAL_EPISODES + 1)], "--episodes"),
        (["play", "--seed", str(MAX_SEED)], None),  # (one episode at the largest seed: allowed)
        (["play", "--episodes", "3", "--seed", str(MAX_SEED - 1)], "--seed"),
    ]


@pytest.mark.parametrize("case", range(8))
def test_watch_and_play_refuse_a_size_past_its_bound_before_playing(trained, tmp_path, capsys, monkeypatch, case):
    import empathy_zoo.greedy_episode as greedy_episode

    run_file, _ = agent_file_of(trained, "empathic_dqn")
    argv, flag = bound_refusals(run_file.stem)[case]
    if argv[0] == "watch":
        argv = [*argv, "--dir", str(trained)]
    played: list[int] = []
    original = greedy_episode.play_greedy
    monkeypatch.setattr(greedy_episode, "play_greedy", lambda *a, **k: played.append(1) or original(*a, **k))
    if flag is None:
        assert main(argv) == 0
        return
    assert main(argv) == 2
    assert flag in one_line_refusal(capsys)
    assert played == []


def test_a_gif_that_cannot_be_written_names_its_file(tmp_path, monkeypatch):
    import empathy_zoo.atomic as atomic
    from empathy_zoo.cli.watch import write_gif

    def full_disk(path: Any, data: bytes) -> Path:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(atomic, "write_bytes_atomic", full_disk)
    target = tmp_path / "episode.gif"
    with pytest.raises(OSError, match=str(target)) as raised:
        write_gif(str(target), b"GIF89a")
    assert raised.value.errno == errno.ENOSPC
    assert not target.exists()


# ---------------------------------------------------------------------------- reproduce's leaderboard stage
def test_sigint_while_reproduce_writes_its_leaderboard_stops_it(tmp_path, capsys, monkeypatch):
    """Even in a process started with SIGINT ignored (a command put in the background by a shell)."""
    import leaderboard.report as report

    sweep = tmp_path / "tiny.toml"
    sweep.write_text(TINY_SWEEP)
    out = tmp_path / "results"
    reached: list[str] = []

    def interrupted(*args: Any, **kwargs: Any) -> Any:
        reached.append("leaderboard")
        os.kill(os.getpid(), signal.SIGINT)
        reached.append("went on after SIGINT")
        raise AssertionError("the leaderboard went on after SIGINT")

    monkeypatch.setattr(report, "write_leaderboard", interrupted)
    inherited = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        status = main(["reproduce", "--profile", str(sweep), "--out", str(out), "--no-progress", "--workers", "1"])
    finally:
        signal.signal(signal.SIGINT, inherited)
    assert status == 128 + signal.SIGINT
    assert reached == ["leaderboard"]
    assert list((out / "runs").glob("*.json")), "the trained run is kept for the same command to resume"
    assert "REPRODUCTION.md" not in capsys.readouterr().out
