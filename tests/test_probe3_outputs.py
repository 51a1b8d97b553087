"""What a hostile results or output directory may hold, met by the report, the cleanup of
temporary files and the output lock (probe 3): a forged result whose training window spans a
billion steps is counted in closed form, an episode longer than ``max_cycles`` is refused naming
its file; a temporary-file name with a pid no process can have is no name of the suite's; the lock
file's place holding a link, a hard link, a directory, a FIFO or a user's file is refused in one
line and left as it was, and nothing is created in an output directory before its lock is held."""

from __future__ import annotations

import dataclasses
import os
import re
import stat
from pathlib import Path

import numpy as np
import pytest
from helpers_results import SETTINGS, SYNTHETIC_STEPS, synthetic_document, synthetic_result
from helpers_sweeps import TINY_TRAIN

import empathy_zoo.schedules as schedules
import empathy_zoo.training.runner as runner
import leaderboard.report as report
from empathy_zoo.atomic import process_alive, remove_stale_temp_files, write_json_atomic
from empathy_zoo.cli import main
from empathy_zoo.experiment.records import RunResult, frozen_plain, read_only_series
from empathy_zoo.output_lock import LOCK_NAME, hold_output_dir
from empathy_zoo.result_file import RUNS_DIR
from empathy_zoo.schedules import epsilon_function
from leaderboard.reproduction import training_window_epsilons

DEAD = 2**22 + 12345
"""A process id above Linux's default pid_max: no such process."""
HUGE_PID = "9" * 20
"""A process id no system has (``os.kill`` of it overflows)."""
CALLS = 100_000
"""The most reads of the ε schedule a training window may take (its steps are up to a billion)."""


@pytest.fixture
def counted_schedule(monkeypatch):
    """Count every read of the ε schedule; more than :data:`CALLS` fails at once (a loop per step)."""
    calls = [0]
    real = schedules._linear

    def counted(*args):
        calls[0] += 1
        if calls[0] > CALLS:
            raise AssertionError("the ε schedule was read once per step")
        return real(*args)

    monkeypatch.setattr(schedules, "_linear", counted)
    return calls


def _window_run(low: int, high: int, schedule: dict | None = None) -> RunResult:
    """A run of 40 training episodes whose final 10 % (the last 4) span steps ``low`` … ``high - 1``,
    in an environment whose episodes may be that long (a record made in code: no file holds one)."""
    run = synthetic_result("coexistence_v0", "empathic_dqn", 0.5, 0)
    head = [round(low * (i + 1) / 36) for i in range(36)]
    tail = [low + round((high - low) * (i + 1) / 4) for i in range(4)]
    described = run.config.description
    if schedule is not None:
        described = frozen_plain({**described, "exploration": {"kind": "linear", **schedule}})
    config = dataclasses.replace(run.config, env_kwargs=frozen_plain({"max_cycles": 10**9}), description=described)
    return dataclasses.replace(
        run, config=config, train=dataclasses.replace(run.train, episode_end_step=read_only_series(head + tail))
    )


def _counted_by_hand(schedule: dict, low: int, high: int, digits: int) -> dict[float, int]:
    """The window's counts, reading the schedule at every step where it changes (warm-up and decay)
    and counting the constant stretches before and after in one go."""
    epsilon_at = epsilon_function({"kind": "linear", **schedule})
    changing_from = min(high, max(low, int(np.floor(schedule["warmup"])) - 1))
    changing_to = max(changing_from, min(high, int(np.ceil(schedule["warmup"] + schedule["decay_steps"])) + 2))
    counts: dict[float, int] = {}
    if changing_from > low:
        counts[round(epsilon_at(low), digits)] = changing_from - low
    for step in range(changing_from, changing_to):
        value = round(epsilon_at(step), digits)
        counts[value] = counts.get(value, 0) + 1
    if high > changing_to:
        value = round(epsilon_at(high - 1), digits)
        counts[value] = counts.get(value, 0) + high - changing_to
    return counts


# ---------------------------------------------------------------------------- the training window
def test_a_billion_step_training_window_is_counted_without_reading_every_step(counted_schedule) -> None:
    run = _window_run(3600, 10**9)
    counts = training_window_epsilons(run)
    schedule = {"start": 1.0, "end": 0.01, "warmup": SETTINGS["learning_starts"], "decay_steps": SETTINGS["epsilon_decay_steps"]}
    expected = _counted_by_hand(schedule, 3600, 10**9, 3)
    assert counts == expected and sum(counts.values()) == 10**9 - 3600 and counts[0.01] > 10**9 - SYNTHETIC_STEPS - 1000
    assert counted_schedule[0] < CALLS


def test_the_closed_form_counts_exactly_what_reading_every_step_counts(counted_schedule) -> None:
    rng = np.random.default_rng(3)
    for case in range(40):
        warmup, decay = int(rng.integers(0, 3000)), int(rng.integers(1, 4000))
        schedule = {"start": float(rng.uniform()), "end": float(rng.uniform()), "warmup": warmup, "decay_steps": decay}
        low = int(rng.integers(36, 5000))
        high = low + int(rng.integers(10**6, 10**8))
        digits = 3 if case % 4 else 2
        counted_schedule[0] = 0
        counts = training_window_epsilons(_window_run(low, high, schedule), digits=digits)
        assert counts == _counted_by_hand(schedule, low, high, digits), (case, schedule, low, high)
        assert sum(counts.values()) == high - low


@pytest.mark.parametrize("field, value", [("start", float("nan")), ("end", 1.5), ("warmup", float("inf"))])
def test_a_schedule_outside_its_range_is_refused_naming_the_run(field, value) -> None:
    schedule = {"start": 1.0, "end": 0.01, "warmup": 100, "decay_steps": 3900, field: value}
    run = _window_run(3600, 4000, schedule)
    where = rf"{re.escape(run.run_id)}: field config\.description\.exploration\.{field}"
    with pytest.raises(ValueError, match=where):
        training_window_epsilons(run)


def _paper_runs(forged: int) -> list[dict]:
    """The paper's experiments (5 seeds); run number ``forged`` has one training episode of
    2,450 steps, longer than the environment's 500 (``max_cycles``); its others of 450 hold their survival."""
    runs = []
    for seed in range(2):
        for beta in (1.0, 0.75, 0.5, 0.25):
            runs.append(synthetic_document("coexistence_v0", "empathic_dqn", beta, seed, survival=400))
            runs.append(synthetic_document("sharing_v0", "empathic_dqn", beta, seed))
        runs.append(synthetic_document("coexistence_v0", "dqn_harm_penalty", 1.0, seed))
        runs.append(synthetic_document("sharing_v0", "dqn_equality", 1.0, seed))
    runs[forged]["train"]["episode_end_step"] = [*range(450, 17551, 450), SYNTHETIC_STEPS]
    return runs


@pytest.mark.parametrize("forged", [0, 4])
def test_an_episode_longer_than_max_cycles_is_refused_in_one_line_naming_its_file(tmp_path, capsys, forged) -> None:
    runs = _paper_runs(forged)
    for run in runs:
        write_json_atomic(tmp_path / RUNS_DIR / f"{run['run_id']}.json", run)
    path = tmp_path / RUNS_DIR / f"{runs[forged]['run_id']}.json"
    assert main(["reproduction", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("empathy-zoo: error: ") and "Traceback" not in err, err
    assert f"{path}: field train.episode_end_step[39]" in err and "max_cycles (500)" in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == [RUNS_DIR], "nothing may be written"


# ---------------------------------------------------------------------------- temporary files
def test_a_temporary_file_name_with_a_pid_no_process_can_have_is_not_the_suites(tmp_path) -> None:
    users = [
        tmp_path / f".x.json.ezoo-{HUGE_PID}-abcd1234.tmp",
        tmp_path / f".ezoo-write-probe-{HUGE_PID}-0badc0de",
        tmp_path / f".x.json.ezoo-0{DEAD}-abcd1234.tmp",  # (the suite writes no leading zero)
    ]
    own = tmp_path / f".x.json.ezoo-{DEAD}-abcd1234.tmp"
    for path in [*users, own]:
        path.write_bytes(b"mine")
    assert remove_stale_temp_files(tmp_path) == [own]
    assert all(path.read_bytes() == b"mine" for path in users)


def test_a_pid_out_of_range_is_never_given_to_kill(monkeypatch) -> None:
    def kill(pid: int, signal: int) -> None:
        raise AssertionError(f"os.kill({pid}, {signal})")

    monkeypatch.setattr(os, "kill", kill)
    assert process_alive(int(HUGE_PID)) and process_alive(2**31) and process_alive(-1)


def test_the_leaderboard_keeps_names_with_impossible_pids_and_writes(tmp_path) -> None:
    results = tmp_path / "results"
    run = synthetic_document("coexistence_v0", "dqn", 1.0, 0)
    write_json_atomic(results / RUNS_DIR / f"{run['run_id']}.json", run)
    strange = [results / f".x.ezoo-{HUGE_PID}-abcdef12.tmp", results / f".leaderboard.ezoo-{HUGE_PID}-abcdef12.tmp"]
    strange[0].write_text("a user's")
    strange[1].mkdir()
    written = report.write_leaderboard(results, n_resamples=50, on_note=lambda _: None)
    assert written["markdown"].is_file()
    assert strange[0].read_text() == "a user's" and strange[1].is_dir()


def test_a_refused_leaderboard_leaves_no_figures_directory(tmp_path, monkeypatch) -> None:
    results = tmp_path / "results"
    run = synthetic_document("coexistence_v0", "dqn", 1.0, 0)
    write_json_atomic(results / RUNS_DIR / f"{run['run_id']}.json", run)

    def refuse(directory):
        raise ValueError(f"{directory}: refused")

    monkeypatch.setattr(report, "remove_stale_temp_files", refuse)
    with pytest.raises(ValueError, match="refused"):
        report.write_leaderboard(results, n_resamples=50, on_note=lambda _: None)
    assert sorted(p.name for p in results.iterdir()) == [RUNS_DIR]


# ---------------------------------------------------------------------------- the lock file's place
def _user_file(tmp_path: Path) -> Path:
    user = tmp_path / "notes.txt"
    user.write_text("a user's notes\n")
    return user


def _hard_link(out: Path, tmp_path: Path) -> None:
    os.link(_user_file(tmp_path), out / LOCK_NAME)


def _symbolic_link(out: Path, tmp_path: Path) -> None:
    (out / LOCK_NAME).symlink_to(_user_file(tmp_path))


def _directory(out: Path, tmp_path: Path) -> None:
    (out / LOCK_NAME).mkdir()
    (out / LOCK_NAME / "inside").write_text("kept")


def _fifo(out: Path, tmp_path: Path) -> None:
    os.mkfifo(out / LOCK_NAME)


def _foreign_file(out: Path, tmp_path: Path) -> None:
    (out / LOCK_NAME).write_text("a user's file that happens to have this name\n")


def _snapshot(tmp_path: Path) -> dict[str, tuple[int, int, bytes | None]]:
    """Every path below ``tmp_path``: its type, link count and contents (regular files)."""
    seen = {}
    for path in sorted(tmp_path.rglob("*")):
        status = os.lstat(path)
        body = path.read_bytes() if stat.S_ISREG(status.st_mode) else None
        seen[str(path.relative_to(tmp_path))] = (stat.S_IFMT(status.st_mode), status.st_nlink, body)
    return seen


PLACES = {
    _hard_link: "hard links",
    _symbolic_link: "a symbolic link",
    _directory: "a directory",
    _fifo: "a FIFO",
    _foreign_file: "holds no holder's record",
}


@pytest.mark.parametrize("place", list(PLACES), ids=lambda place: place.__name__.strip("_"))
def test_what_is_not_the_suites_lock_file_is_refused_in_one_line_and_left_as_it_was(tmp_path, place) -> None:
    out = tmp_path / "out"
    out.mkdir()
    place(out, tmp_path)
    before = _snapshot(tmp_path)
    with pytest.raises(ValueError) as error, hold_output_dir(out, "x"):
        pass
    message = str(error.value)
    assert message.startswith(f"{out / LOCK_NAME} is ") and PLACES[place] in message, message
    assert "\n" not in message and "Errno" not in message
    assert _snapshot(tmp_path) == before


def test_train_refuses_a_hard_link_in_the_lock_files_place_and_trains_nothing(tmp_path, capsys, monkeypatch) -> None:
    def refuse(*args, **kwargs):
        raise AssertionError("training started although the lock file's place is a user's file")

    monkeypatch.setattr(runner, "train_ensemble", refuse)
    out = tmp_path / "out"
    out.mkdir()
    _hard_link(out, tmp_path)
    before = _snapshot(tmp_path)
    assert main(["train", "--out", str(out), *TINY_TRAIN]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{out / LOCK_NAME} is a file with 2 hard links" in err and "Traceback" not in err, err
    assert _snapshot(tmp_path) == before


def test_nothing_is_created_in_an_output_directory_before_its_lock_is_held(tmp_path) -> None:
    from helpers_resume import small_run

    from empathy_zoo.output_lock import DirectoryInUse
    from empathy_zoo.training import RunnerOptions, train_runs

    out = tmp_path / "out"
    out.mkdir()
    with hold_output_dir(out, "the holder"):
        with pytest.raises(DirectoryInUse, match="the holder"):
            train_runs([small_run("dqn", seed=0)], out, RunnerOptions(progress=False))
        assert sorted(p.name for p in out.iterdir()) == [LOCK_NAME], "no runs/ before the lock is held"
    assert list(out.iterdir()) == []
    missing = tmp_path / "new" / "out"
    with hold_output_dir(missing, "first"):  # (the directory to lock is made, as the lock needs it) ...
        assert sorted(p.name for p in missing.iterdir()) == [LOCK_NAME]
    assert list(tmp_path.iterdir()) == [out], "... and removed again on leaving while empty"
    # a lock file a killed holder left is the suite's: taken over, and removed on leaving
    (out / LOCK_NAME).write_text('{"pid": 12345, "host": "h", "command": "c", "since": 0}')
    with hold_output_dir(out, "again"):
        assert '"command": "again"' in (out / LOCK_NAME).read_text()
    assert list(out.iterdir()) == []
