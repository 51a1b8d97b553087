"""Crash test: a tiny sweep is killed with SIGKILL at seeded moments (mid-training, in the middle
of an atomic write, between a checkpoint and the list of its runs, between two result files, …),
resumed each time with the same command, and every result file is compared with an uninterrupted
run of the sweep: nothing lost, nothing duplicated, no checkpoint or temporary file left behind.

The kill comes from inside the process (``tests/helpers_crash.py``) on the n-th pass through a
chosen place, so the moments are the same on every run of the test, with no sleeps and no timing.
``-m slow`` kills it at many more moments.
"""

from __future__ import annotations

import json
import random
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from helpers_sweeps import TWO_ENV_SWEEP as SWEEP

from empathy_zoo.cli import main

RUNS = 8
"""2 envs × 2 methods × 2 seeds, in 4 ensembles of 2 runs."""
HOOKS = {"step": 2600, "checkpoint": 16, "result": 8, "replace": 30, "fsync": 30, "manifest": 4}
"""Where a kill may come, and how many passes there are at most in one uninterrupted sweep."""
COMPARED = ("run_id", "env", "variant", "method", "method_label", "seed", "steps", "config", "train", "eval", "memory_bytes")
"""The fields of a result file that must not depend on kills (not its wall time or creation time)."""
HELPER = Path(__file__).with_name("helpers_crash.py")


def argv(sweep: Path, out: Path) -> list[str]:
    return [
        "reproduce",
        "--profile",
        str(sweep),
        "--out",
        str(out),
        "--no-progress",
        "--workers",
        "1",
        "--threads",
        "1",
        "--checkpoint-interval",
        "50",
        "--max-parallel-runs",
        "2",
    ]


def contents(out: Path) -> dict[str, dict]:
    results = {}
    for path in sorted((out / "runs").glob("*.json")):
        result = json.loads(path.read_text())
        results[path.name] = {key: result.get(key) for key in COMPARED}
    return results


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> dict[str, dict]:
    """The sweep, uninterrupted."""
    root = tmp_path_factory.mktemp("reference")
    (root / "sweep.toml").write_text(SWEEP)
    assert main(argv(root / "sweep.toml", root / "out")) == 0
    results = contents(root / "out")
    assert len(results) == RUNS
    return results


def kill_plan(rng: random.Random) -> dict:
    """Where the next attempt dies: early passes are likelier (a resumed sweep has less left to do)."""
    hook = rng.choice(sorted(HOOKS))
    return {"hook": hook, "count": 1 + int(rng.random() ** 2 * HOOKS[hook]), "when": rng.choice(["before", "after"])}


def crash_and_resume(tmp_path: Path, seed: int, kills: int) -> dict:
    """Run the sweep under ``kills`` seeded kill plans, one per attempt, then once more without;
    returns what happened."""
    (tmp_path / "sweep.toml").write_text(SWEEP)
    out, rng = tmp_path / "out", random.Random(seed)
    plans = [kill_plan(rng) for _ in range(kills)] + [{}]
    killed = []
    for plan in plans:
        done = subprocess.run(
            [sys.executable, str(HELPER), json.dumps(plan), *argv(tmp_path / "sweep.toml", out)],
            capture_output=True,
            text=True,
            cwd=tmp_path,
            timeout=600,
        )
        if done.returncode == -signal.SIGKILL:
            killed.append(plan)
            continue
        assert done.returncode == 0, (plan, done.stderr)
        assert "Traceback" not in done.stderr, done.stderr
    return {"out": out, "killed": killed, "attempts": len(plans)}


def check_nothing_lost(out: Path, reference: dict[str, dict]) -> None:
    results = contents(out)
    assert sorted(results) == sorted(reference)  # nothing lost, nothing extra
    assert len({result["run_id"] for result in results.values()}) == RUNS  # nothing duplicated
    for name, result in results.items():
        assert result == reference[name], name
    leftovers = [p for p in out.rglob("*") if p.is_file() and (p.name.startswith(".") or "checkpoints" in p.parts)]
    assert leftovers == []
    assert (out / "LEADERBOARD.md").is_file() and (out / "leaderboard.html").is_file()


@pytest.mark.parametrize("seed", [0, 1])
def test_a_sweep_killed_at_seeded_moments_resumes_to_the_uninterrupted_results(tmp_path, reference, seed):
    outcome = crash_and_resume(tmp_path, seed, kills=4)
    assert outcome["killed"], "no kill fired: the plans miss the sweep"
    check_nothing_lost(outcome["out"], reference)
    print(
        f"\ncrash test, seed {seed}: {len(outcome['killed'])} kill(s) {outcome['killed']}, "
        f"{outcome['attempts']} attempts, {RUNS} result files compared"
    )


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(2, 12))
def test_a_sweep_killed_at_many_seeded_moments_resumes_to_the_uninterrupted_results(tmp_path, reference, seed):
    outcome = crash_and_resume(tmp_path, seed, kills=8)
    check_nothing_lost(outcome["out"], reference)
    print(
        f"\ncrash test, seed {seed}: {len(outcome['killed'])} kill(s) {outcome['killed']}, "
        f"{outcome['attempts']} attempts, {RUNS} result files compared"
    )
