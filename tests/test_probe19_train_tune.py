"""Two refusals that must leave the output directory as it was.

* ``tune`` resumed with ``--trials N`` below the trials its journal already holds done (or a
  journal that holds more done trials than the plan's ``--trials``) is refused up front, naming
  ``--trials``, the count done and the journal, before the journal gains a line: it once went on
  ("10 of 5 trial(s) done") and wrote a ``study.json`` that ``analyse tuning-summary`` refuses.
* ``train`` refused because a run's file place (its agent file, its result file) holds a directory
  is refused before training and before any directory is made: it once trained, then refused at
  the write, leaving a new ``checkpoints/`` behind.
"""

from __future__ import annotations

import json
import re
import shutil
from dataclasses import replace
from pathlib import Path

import pytest
from helpers_sweeps import TINY_DQN_TRAIN, TUNE_PARAMS, TUNE_SWEEP
from helpers_tune import run_tune, snapshot, tiny_plan, tiny_study

from empathy_zoo.cli import main, parse_args
from empathy_zoo.experiment.model import RunSpec

SWEEP = TUNE_SWEEP

PARAMS = TUNE_PARAMS


_snapshot = snapshot


_tune = run_tune


@pytest.fixture(scope="module")
def study(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """``(sweep file, study directory)`` of a genuine study of two trials (one, then one more resumed)."""
    pytest.importorskip("optuna")
    return tiny_study(tmp_path_factory.mktemp("study"), 1, 2)


@pytest.mark.parametrize("extra", [(), ("--log", "csv")])
def test_tune_resumed_with_fewer_trials_than_done_is_refused_up_front(
    study: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: tuple[str, ...]
) -> None:
    sweep, genuine = study
    out = tmp_path / "study"
    shutil.copytree(genuine, out)
    document = json.loads((out / "study.json").read_text())
    assert document["trials_done"] == 2
    before = _snapshot(out)
    capsys.readouterr()
    assert _tune(sweep, out, 1, *extra) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("empathy-zoo: error: "), err
    assert "--trials 1" in err and "2 trial(s) done" in err and str(out / "study.journal") in err, err
    assert _snapshot(out) == before  # (no new journal line, no study.json of 2 trials under a plan of 1, no logs/)


def test_tune_resumed_with_as_many_trials_as_done_rewrites_a_study_the_checker_takes(
    study: tuple[Path, Path], tmp_path: Path
) -> None:
    from leaderboard.study_file import check_study

    sweep, genuine = study
    out = tmp_path / "study"
    shutil.copytree(genuine, out)
    assert _tune(sweep, out, 2) == 0
    path = out / "study.json"
    document = check_study(json.loads(path.read_text()), path)
    assert document["trials_done"] == 2 and document["plan"]["budget"]["trials"] == 2


def test_check_journal_refuses_more_done_trials_than_the_plan_naming_the_journal(
    study: tuple[Path, Path], tmp_path: Path
) -> None:
    """The journal's own check: a journal holding more trials done than the plan's ``--trials`` (a
    forged extra trial, or a study resumed with fewer) is refused naming the file, unchanged."""
    from empathy_zoo.training.tuning import JOURNAL_FILE, check_journal

    sweep, genuine = study
    journal = tmp_path / JOURNAL_FILE
    shutil.copy(genuine / JOURNAL_FILE, journal)
    before = journal.read_bytes()
    stored = json.loads(journal.read_text().splitlines()[1])["user_attr"]["plan"]
    plan = tiny_plan(sweep, 1)
    notes: list[str] = []
    with pytest.raises(ValueError, match=rf"^tuning journal {re.escape(str(journal))} holds 2 trial\(s\) done") as error:
        check_journal(journal, notes.append, plan, stored["update_kernel"])
    assert "\n" not in str(error.value) and "--trials 1" in str(error.value)
    assert not notes and journal.read_bytes() == before
    assert check_journal(journal, notes.append, replace(plan, trials=2), stored["update_kernel"])


TRAIN = [*TINY_DQN_TRAIN, "--steps", "300", "--eval-interval", "300"]


def _run(out: Path) -> RunSpec:
    """The run ``train TRAIN --out out`` trains (made as the command makes it)."""
    from empathy_zoo.cli.train import ENV_ARGUMENTS, train_values
    from empathy_zoo.environments import default_policies
    from empathy_zoo.experiment.model import Budget, EnvVariant, MethodEntry

    run, settings = train_values(parse_args([*TRAIN, "--out", str(out)]))
    env_kwargs = {key: run[key] for key in ENV_ARGUMENTS if run.get(key) is not None}
    fixed = None if run["fixed"] is None else {**default_policies(run["env"], env_kwargs), **run["fixed"]}
    entry = MethodEntry.resolve(run["method"], settings, run["reward"], run["label"])
    (seed,) = run["seeds"]
    return RunSpec(EnvVariant(run["env"], env_kwargs, fixed), entry, Budget(run["steps"], run["eval_interval"], 1), seed)


@pytest.mark.parametrize("place", ["agent", "result", "checkpoint", "list of runs"])
def test_train_refused_for_a_directory_in_a_file_place_leaves_the_output_directory_as_it_was(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], place: str
) -> None:
    from empathy_zoo.training.checkpoint import runs_list_path
    from empathy_zoo.training.resume import checkpoint_path

    out = tmp_path / "out"
    spec = _run(out)
    assert "77e06169" in spec.run_id or spec.run_id.startswith("coexistence_v0__dqn-")
    path = {
        "agent": out / "runs" / f"{spec.run_id}.agent.pt",
        "result": out / "runs" / f"{spec.run_id}.json",
        "checkpoint": checkpoint_path(out, [spec]),
        "list of runs": runs_list_path(checkpoint_path(out, [spec])),
    }[place]
    path.mkdir(parents=True)
    before = _snapshot(out)
    capsys.readouterr()
    assert main([*TRAIN, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    refusal = [line for line in err.splitlines() if line.startswith("empathy-zoo: error:")]
    assert len(refusal) == 1 and str(path) in refusal[0] and "a directory" in refusal[0], err
    assert "finished" not in err, err  # (refused before training, not after it)
    assert _snapshot(out) == before
