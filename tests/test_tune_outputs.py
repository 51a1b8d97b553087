"""What ``tune`` writes beside its study: every trial's runs logged with ``--log``, the parameter
importance figure (or a one-line reason there is none), and a journal that Optuna's own
``JournalStorage`` (what optuna-dashboard reads) loads, trials and values, with the study's
sampling replayed exactly from it. Tiny studies only (300-step runs, one tuning seed)."""

from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

pytest.importorskip("optuna")

import optuna
from test_tune import SWEEP, TUNE

from baselines.registry import get_method
from empathy_zoo.cli import main
from empathy_zoo.experiment import load_sweep
from empathy_zoo.experiment.search_space import parse_params, point_runs
from empathy_zoo.training import tuning
from empathy_zoo.training.trials_figure import (
    IMPORTANCE_FIGURE,
    param_importances,
    render_importance_png,
)
from empathy_zoo.training.tuning import JOURNAL_FILE, STUDY_FILE
from empathy_zoo.training.tuning_journal import param_distribution

SHIPPED = Path(__file__).resolve().parents[1] / "docs" / "results" / "methods" / "tuning"
"""The methods profile's studies (docs/tuning.md), each a ``study.json`` and its ``study.journal``."""
ONE_SEED = [*TUNE, "--tuning-seeds", "1", "--no-prune"]
PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture
def sweep(tmp_path: Path) -> Path:
    path = tmp_path / "tiny.toml"
    path.write_text(SWEEP)
    return path


def _load(journal: Path, tmp_path: Path) -> Any:
    """The study in a copy of ``journal``, through Optuna's own journal storage (read-only here)."""
    from optuna.storages import JournalStorage

    try:
        from optuna.storages.journal import JournalFileBackend as Backend
    except ImportError:  # (Optuna before 4.0)
        from optuna.storages import JournalFileStorage as Backend
    copy = tmp_path / f"{journal.parent.parent.name}-{journal.parent.name}.journal"
    shutil.copy(journal, copy)
    optuna.logging.set_verbosity(optuna.logging.ERROR)
    return optuna.load_study(study_name="tune", storage=JournalStorage(Backend(str(copy))))


def test_every_trials_runs_log_under_out_logs_and_the_study_is_the_same_without(sweep: Path, tmp_path: Path) -> None:
    logged, plain = tmp_path / "logged", tmp_path / "plain"
    assert main(["tune", str(sweep), *ONE_SEED, "--trials", "2", "--log", "csv", "--out", str(logged)]) == 0
    assert main(["tune", str(sweep), *ONE_SEED, "--trials", "2", "--out", str(plain)]) == 0
    study = json.loads((logged / STUDY_FILE).read_text())
    base = load_sweep(sweep)[0]
    params = parse_params(["penalty=float:-200:-1", "learning_rate=log:1e-4:1e-2"], base.method_object())
    run_ids = {spec.run_id for t in study["trials"] for spec in point_runs(base, params, t["params"], [10_000])}
    assert len(run_ids) == 2
    assert {path.name for path in (logged / "logs" / "csv").iterdir()} == run_ids
    for run_id in run_ids:
        rows = (logged / "logs" / "csv" / run_id / "scalars.csv").read_text().splitlines()
        assert rows[0] == "step,name,value" and any(",eval/survival," in row for row in rows)
    values = [(t["params"], t["value"], t["curve"]) for t in study["trials"]]
    assert values == [(t["params"], t["value"], t["curve"]) for t in json.loads((plain / STUDY_FILE).read_text())["trials"]]
    assert not (plain / "logs").exists()


def test_a_bad_log_backend_is_refused_in_one_line(sweep: Path, tmp_path: Path, capsys) -> None:
    assert main(["tune", str(sweep), *ONE_SEED, "--log", "csv,paper", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--log: unknown backend 'paper'" in err
    assert not (tmp_path / "o").exists()


def test_the_importance_figure_is_drawn_the_same_twice_and_skipped_with_a_reason(sweep: Path, tmp_path: Path, capsys) -> None:
    out = tmp_path / "two_params"
    assert main(["tune", str(sweep), *TUNE, "--no-prune", "--out", str(out)]) == 0  # (two seeds: trials that differ)
    assert f"wrote {out / IMPORTANCE_FIGURE}" in capsys.readouterr().out
    figure = (out / IMPORTANCE_FIGURE).read_bytes()
    assert figure[:8] == PNG
    study = json.loads((out / STUDY_FILE).read_text())
    base = load_sweep(sweep)[0]
    specs = parse_params(["penalty=float:-200:-1", "learning_rate=log:1e-4:1e-2"], base.method_object())
    importances = param_importances(study, {spec.name: param_distribution(spec) for spec in specs})
    assert isinstance(importances, dict) and sorted(importances) == ["learning_rate", "penalty"]
    assert sum(importances.values()) == pytest.approx(1.0)
    assert render_importance_png(study, importances) == figure  # (PED-ANOVA draws no random number)

    one = tmp_path / "one_param"
    assert main(["tune", str(sweep), *ONE_SEED[:4], *ONE_SEED[6:], "--out", str(one)]) == 0
    printed = capsys.readouterr().out
    assert "no importance.png: the study tunes one parameter (penalty)" in printed
    assert not (one / IMPORTANCE_FIGURE).exists()

    tied = tmp_path / "tied"  # (one seed: every trial survives the 40 steps)
    assert main(["tune", str(sweep), *ONE_SEED, "--trials", "3", "--out", str(tied)]) == 0
    assert "no importance.png: the 3 finished trials cannot tell the parameters apart" in capsys.readouterr().out

    few = tmp_path / "one_trial"
    assert main(["tune", str(sweep), *ONE_SEED, "--trials", "1", "--out", str(few)]) == 0
    assert "no importance.png: it needs 2 finished trials, the study has 1" in capsys.readouterr().out


def test_the_figures_load_no_matplotlib_when_imported() -> None:
    import subprocess

    code = "import empathy_zoo.training.trials_figure, sys; print('matplotlib' in sys.modules, 'optuna' in sys.modules)"
    shown = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert shown == ["False", "False"]


@pytest.mark.parametrize(
    "study_json", sorted(SHIPPED.glob("*/*/" + STUDY_FILE)), ids=lambda p: f"{p.parent.parent.name}/{p.parent.name}"
)
def test_a_shipped_journal_loads_in_optunas_journal_storage_and_replays_its_sampling(study_json: Path, tmp_path: Path) -> None:
    document = json.loads(study_json.read_text())
    study = _load(study_json.parent / JOURNAL_FILE, tmp_path)
    states = optuna.trial.TrialState
    trials = [t for t in study.trials if tuning._counted(t, states)]
    assert [(t.number, t.state.name, t.value if t.state == states.COMPLETE else None, t.params) for t in trials] == [
        (t["number"], t["state"], t["value"], t["params"]) for t in document["trials"] if t["state"] != "INTERRUPTED"
    ]
    assert study.user_attrs["plan"]["experiment"] == document["plan"]["experiment"]
    assert study.best_trial.number == document["best"]["number"]
    # a batch of one proposes each trial's point from the trials before it, as the shipped study drew them
    if int(optuna.__version__.split(".")[0]) != int(document["optuna"].split(".")[0]):
        pytest.skip(f"TPE of Optuna {optuna.__version__} need not draw what Optuna {document['optuna']} drew")
    plan = document["plan"]
    proposer = SimpleNamespace(
        sampler_seed=plan["sampler"]["seed"],
        startup_trials=plan["sampler"]["n_startup_trials"],
        direction=plan["objective"]["direction"],
        params=parse_params([f"{name}={range_}" for name, range_ in plan["params"].items()], get_method(plan["method"])),
    )
    for i, trial in enumerate(trials):
        assert tuning._propose(optuna, proposer, trials[:i], 1) == [trial.params]
