"""``tune --batch B --jobs N``: the sampler proposes B trials at once, they train side by side in up
to N processes and are told back in trial order, so any ``--jobs`` gives the same study; a batch of
one is the study of one trial at a time; a batch stopped mid-way (Ctrl-C or a kill) resumes into
the study an unstopped one gives; a bad ``--jobs`` or ``--batch`` is refused in one line. Tiny
studies only (300-step runs, one tuning seed where two are not needed)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("optuna")

from test_tune import SWEEP, TUNE, _same_study

from empathy_zoo.cli import main
from empathy_zoo.limits import cpu_count
from empathy_zoo.training import tuning
from empathy_zoo.training.tuning import JOURNAL_FILE, STUDY_FILE

BATCH = [*TUNE, "--batch", "2", "--tuning-seeds", "1"]
"""The 4-trial study of tests/test_tune.py, on one tuning seed, in batches of 2 (two batches)."""
CREATE_TRIAL, END_TRIAL = 4, 6
"""Optuna's journal operations: a trial created, a trial ended."""


@pytest.fixture
def sweep(tmp_path: Path) -> Path:
    path = tmp_path / "tiny.toml"
    path.write_text(SWEEP)
    return path


def _journal(path: Path) -> list[dict[str, Any]]:
    """The journal's lines without what differs between two runs of one study: worker ids, time
    stamps and wall times."""
    lines = []
    for text in path.read_text().splitlines():
        entry = json.loads(text)
        for key in ("worker_id", "datetime_start", "datetime_complete"):
            entry.pop(key, None)
        if entry["op_code"] == 8 and "wall_time_s" in entry["user_attr"]:
            entry["user_attr"] = {"wall_time_s": "(seconds)"}
        lines.append(entry)
    return lines


def _study(out: Path) -> dict[str, Any]:
    return json.loads((out / STUDY_FILE).read_text())


def test_a_batch_gives_the_same_journal_and_study_with_one_process_or_two(sweep: Path, tmp_path: Path) -> None:
    if cpu_count() < 2:
        pytest.skip("two processes need two CPUs (--jobs is at most the CPUs)")
    one, two = tmp_path / "one", tmp_path / "two"
    assert main(["tune", str(sweep), *BATCH, "--jobs", "1", "--out", str(one)]) == 0
    assert main(["tune", str(sweep), *BATCH, "--jobs", "2", "--out", str(two)]) == 0
    assert _journal(one / JOURNAL_FILE) == _journal(two / JOURNAL_FILE)
    assert _same_study(_study(one)) == _same_study(_study(two))
    study = _study(one)
    assert study["trials_done"] == 4 and study["plan"]["sampler"]["batch"] == 2
    assert [t["number"] for t in study["trials"]] == [0, 1, 2, 3]
    # a batch's trials are created together, then told back in trial order
    ops = [(e["op_code"], e.get("trial_id")) for e in _journal(one / JOURNAL_FILE) if e["op_code"] in (CREATE_TRIAL, END_TRIAL)]
    assert ops == [(4, None), (4, None), (6, 0), (6, 1), (4, None), (4, None), (6, 2), (6, 3)]


def test_a_batch_of_one_records_no_batch_and_runs_one_trial_at_a_time(sweep: Path, tmp_path: Path) -> None:
    out = tmp_path / "one_at_a_time"
    assert main(["tune", str(sweep), *TUNE, "--tuning-seeds", "1", "--trials", "2", "--jobs", "1", "--out", str(out)]) == 0
    study = _study(out)
    assert study["plan"]["sampler"] == {"name": "TPESampler", "seed": 0, "n_startup_trials": 2}  # (the plan before batches)
    ops = [e["op_code"] for e in _journal(out / JOURNAL_FILE) if e["op_code"] in (CREATE_TRIAL, END_TRIAL)]
    assert ops == [4, 6, 4, 6]


def test_a_batch_stopped_by_ctrl_c_keeps_its_told_trials_and_reruns_the_others(
    sweep: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    whole = tmp_path / "whole"
    assert main(["tune", str(sweep), *BATCH, "--out", str(whole)]) == 0
    real = tuning.train_trial
    calls: list[list[str]] = []
    stop_at = [2]

    def stopped_in_the_first_batchs_second_trial(specs, out_dir, options, on_evaluation=None):
        calls.append([spec.run_id for spec in specs])
        if len(calls) in stop_at:
            raise KeyboardInterrupt
        return real(specs, out_dir, options, on_evaluation)

    monkeypatch.setattr(tuning, "train_trial", stopped_in_the_first_batchs_second_trial)
    stopped = tmp_path / "stopped"
    assert main(["tune", str(sweep), *BATCH, "--out", str(stopped)]) == 130
    assert _study(stopped)["trials_done"] == 1  # (the batch's first trial was told back)
    interrupted = calls[1]
    calls.clear()
    stop_at.clear()
    assert main(["tune", str(sweep), *BATCH, "--out", str(stopped)]) == 0
    assert calls[0] == interrupted  # (the same point again, and the told trial not trained again)
    assert len(calls) == 3
    resumed = _study(stopped)
    assert [t["state"] for t in resumed["trials"]].count("INTERRUPTED") == 1
    assert _same_study(resumed) == _same_study(_study(whole))


def test_a_batch_cut_by_a_kill_resumes_into_the_study_an_unstopped_one_gives(sweep: Path, tmp_path: Path) -> None:
    whole = tmp_path / "whole"
    assert main(["tune", str(sweep), *BATCH, "--out", str(whole)]) == 0
    killed = tmp_path / "killed"
    killed.mkdir()
    lines = (whole / JOURNAL_FILE).read_text().splitlines(keepends=True)
    first_end = next(i for i, line in enumerate(lines) if json.loads(line)["op_code"] == END_TRIAL)
    (killed / JOURNAL_FILE).write_text("".join(lines[: first_end + 1]))  # (trial 0 told; trial 1 running, never told)
    shutil.copy(sweep, killed / "unrelated.toml")  # (the directory holds other files too)
    assert main(["tune", str(sweep), *BATCH, "--out", str(killed)]) == 0
    resumed = _study(killed)
    assert [t["state"] for t in resumed["trials"]].count("INTERRUPTED") == 1 and resumed["trials"][1]["state"] == "INTERRUPTED"
    assert resumed["trials"][2]["params"] == _study(whole)["trials"][1]["params"]  # (the running trial's point, rerun)
    assert _same_study(resumed) == _same_study(_study(whole))


@pytest.mark.parametrize(
    ("option", "says"),
    [
        (["--jobs", "0"], "--jobs must be positive, got 0"),
        (["--jobs", "-3"], "--jobs must be positive, got -3"),
        (["--jobs", "100000"], "--jobs must be at most"),
        (["--batch", "0"], "--batch must be positive, got 0"),
        (["--batch", "20000"], "batch must be at most 10,000"),
    ],
)
def test_a_bad_jobs_or_batch_is_refused_in_one_line(sweep: Path, tmp_path: Path, capsys, option: list[str], says: str) -> None:
    out = tmp_path / "o"
    assert main(["tune", str(sweep), *TUNE, *option, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err
    assert not out.exists()
