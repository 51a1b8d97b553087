"""Live tracking (``--log``): every promised scalar is read back from TensorBoard's event files
(with TensorBoard's own reader), from the CSV files and from W&B's offline run; logging changes
no result file; bad or uninstalled backends are refused before anything trains; the sweep file's
``log`` reaches the runner and a resumed run's CSV drops what it logs again."""

from __future__ import annotations

import csv
import importlib.util
import json
from pathlib import Path
from typing import Any

import pytest
from helpers_cli_method import TINY

import empathy_zoo.training.tracking as tracking
from empathy_zoo.cli import main
from empathy_zoo.experiment.values import SweepConfigError
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.training.options import RunnerOptions
from empathy_zoo.training.tracking import EPISODE_SCALARS, SCALARS, CsvLogger, EnsembleTracker, log_dir, parse_log

TIME_STAMPS = ("created", "wall_time_s")
"""What differs between two result files of one run: when it was made, and how long it took."""
COMMANDS = (
    ["--selfishness", "0.5", "--seeds", "0", "1"],  # Q and Q_emp, two runs in one ensemble
    ["--method", "dqn_harm_penalty", "--seed", "0"],  # a reward transform: the shaping terms
)
"""The ``train`` commands each arm runs (beside :data:`TINY`)."""

BACKENDS = ",".join(name for name in ("tensorboard", "csv", "wandb") if name == "csv" or importlib.util.find_spec(name))
"""The arm that logs logs to every backend installed here (the tests of one that is not skip)."""


@pytest.fixture(scope="module")
def arms(tmp_path_factory) -> tuple[Path, Path]:
    """The same runs trained without logging and with ``--log tensorboard,csv,wandb`` (W&B offline;
    those of the three that are installed)."""
    plain, logged = tmp_path_factory.mktemp("plain"), tmp_path_factory.mktemp("logged")
    home = tmp_path_factory.mktemp("wandb_home")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("WANDB_MODE", "offline")
        patch.setenv("WANDB_ERROR_REPORTING", "false")
        for name in ("WANDB_CONFIG_DIR", "WANDB_CACHE_DIR", "WANDB_DATA_DIR", "WANDB_ARTIFACT_DIR"):
            patch.setenv(name, str(home / name.lower()))
        for command in COMMANDS:
            assert main(["train", "--out", str(plain), *TINY, *command]) == 0
            assert main(["train", "--out", str(logged), *TINY, *command, "--log", BACKENDS]) == 0
    return plain, logged


def _run_ids(out: Path) -> list[str]:
    return sorted(path.stem for path in (out / "runs").glob("*.json"))


def _expected(result: dict[str, Any]) -> set[str]:
    """The scalars a run of these commands logs (it ends episodes and has a gradient step)."""
    names = {*EPISODE_SCALARS.values(), *(f"eval/{m}" for m in METRIC_NAMES)}
    names |= {"charts/SPS", "charts/epsilon", "losses/td_loss", "losses/q_values"}
    if result["config"]["settings"]["selfishness"] < 1:
        names |= {"losses/td_loss_emp", "losses/q_values_emp"}
    if result["config"]["reward"] is not None:
        names |= {"charts/train_return", "charts/shaping_return"}
    return names


def _result(out: Path, run_id: str) -> dict[str, Any]:
    return json.loads((out / "runs" / f"{run_id}.json").read_text(encoding="utf-8"))


def test_logging_changes_no_result_file(arms) -> None:
    plain, logged = arms
    assert _run_ids(plain) == _run_ids(logged) and len(_run_ids(plain)) == 3
    for run_id in _run_ids(plain):
        a, b = _result(plain, run_id), _result(logged, run_id)
        assert {k: v for k, v in a.items() if k not in TIME_STAMPS} == {k: v for k, v in b.items() if k not in TIME_STAMPS}
        agent = a["agent"]["file"]
        assert (plain / "runs" / agent).read_bytes() == (logged / "runs" / agent).read_bytes()
    assert not (plain / "logs").exists()


def test_tensorboard_event_files_hold_every_promised_scalar(arms) -> None:
    pytest.importorskip("tensorboard")
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    _, logged = arms
    seen: set[str] = set()
    for run_id in _run_ids(logged):
        reader = EventAccumulator(str(log_dir(logged, "tensorboard", run_id)), size_guidance={"scalars": 0})
        reader.Reload()
        tags = set(reader.Tags()["scalars"])
        result = _result(logged, run_id)
        assert tags == _expected(result), run_id
        returns = [event.value for event in reader.Scalars("charts/episodic_return")]
        assert returns == pytest.approx(result["train"]["return"])  # every episode end, as the result file has it
        evaluations = [(event.step, event.value) for event in reader.Scalars("eval/harms")]
        assert evaluations == [(e["step"], sum(e["harms"]) / len(e["harms"])) for e in result["eval"]]  # (k/2: exact)
        seen |= tags
    assert seen == set(SCALARS) - {"learner/<name>"}  # (learner/<name>: a learner without tracked_scalars, below)


def test_csv_files_hold_the_same_scalars_as_rows(arms) -> None:
    _, logged = arms
    for run_id in _run_ids(logged):
        with (log_dir(logged, "csv", run_id) / "scalars.csv").open(newline="", encoding="utf-8") as file:
            rows = list(csv.reader(file))
        assert rows[0] == ["step", "name", "value"]
        result = _result(logged, run_id)
        assert {name for _, name, _ in rows[1:]} == _expected(result)
        survival = [(int(step), float(value)) for step, name, value in rows[1:] if name == "charts/survival"]
        assert survival == list(zip(result["train"]["episode_end_step"], map(float, result["train"]["survival"]), strict=True))
        steps = [int(step) for step, _, _ in rows[1:]]
        assert steps == sorted(steps) and steps[-1] == result["steps"]


def _wandb_records(path: Path) -> list[Any]:
    """The records of a W&B offline run file (``run-<id>.wandb``: a LevelDB-style log of
    ``wandb_internal_pb2.Record`` protobufs in 32 KiB blocks after a 7-byte header)."""
    from wandb.proto import wandb_internal_pb2

    data, records, pending, position, block = path.read_bytes(), [], b"", 7, 32768
    assert data[:4] == b":W&B"
    while position + 7 <= len(data):
        if block - position % block < 7:  # (a block's tail too short for a header is padding)
            position += block - position % block
            continue
        length, kind = int.from_bytes(data[position + 4 : position + 6], "little"), data[position + 6]
        pending += data[position + 7 : position + 7 + length]
        position += 7 + length
        if kind in (1, 4):  # a full record, or the last piece of one
            record = wandb_internal_pb2.Record()
            record.ParseFromString(pending)
            records.append(record)
            pending = b""
    return records


def test_wandb_offline_run_holds_config_scalars_and_the_result_artifact(arms) -> None:
    pytest.importorskip("wandb")
    _, logged = arms
    for run_id in _run_ids(logged):
        [run_file] = log_dir(logged, "wandb", run_id).glob("wandb/offline-run-*/run-*.wandb")
        records = _wandb_records(run_file)
        kinds = [record.WhichOneof("record_type") for record in records]
        [run] = [record.run for record, kind in zip(records, kinds, strict=True) if kind == "run"]
        result = _result(logged, run_id)
        assert run.display_name == run_id and run.run_group == run_id.rpartition("__s")[0]
        config = {item.key: json.loads(item.value_json) for item in run.config.update if item.key != "_wandb"}
        assert config["run_id"] == run_id and config["settings"] == result["config"]["settings"]
        history = [item for record, kind in zip(records, kinds, strict=True) if kind == "history" for item in record.history.item]
        logged_names = {item.key or "/".join(item.nested_key) for item in history}  # (W&B splits a name at its "/")
        assert _expected(result) <= logged_names
        [artifact] = [record.artifact for record, kind in zip(records, kinds, strict=True) if kind == "artifact"]
        assert artifact.type == "result" and [entry.path for entry in artifact.manifest.contents] == [f"{run_id}.json"]


def test_wandb_runs_offline_unless_the_user_logged_in_or_chose(tmp_path, monkeypatch) -> None:
    for name in ("WANDB_MODE", "WANDB_API_KEY", "WANDB_BASE_URL"):
        monkeypatch.delenv(name, raising=False)
    netrc_file = tmp_path / "netrc"
    netrc_file.write_text("machine example.org login me password secret\n", encoding="utf-8")
    monkeypatch.setenv("NETRC", str(netrc_file))
    assert tracking.wandb_mode() == "offline"
    netrc_file.write_text("machine api.wandb.ai login user password 0123456789abcdef\n", encoding="utf-8")
    assert tracking.wandb_mode() == "online"  # (wandb login writes this entry)
    monkeypatch.setenv("WANDB_MODE", "disabled")
    assert tracking.wandb_mode() == "disabled"


# ---------------------------------------------------------------------------- what is refused, and where
@pytest.mark.parametrize(
    ("value", "message"),
    [
        ("tensorbored", "unknown backend 'tensorbored'; choose from tensorboard, csv, wandb"),
        ("csv,csv", "csv given twice"),
        ("csv,", "an empty name"),
    ],
)
def test_a_bad_log_value_is_one_clear_error_before_anything_is_written(tmp_path, capsys, value, message) -> None:
    out = tmp_path / "out"
    assert main(["train", "--out", str(out), *TINY, "--log", value]) == 2
    err = capsys.readouterr().err
    assert err.startswith("empathy-zoo: error: ") and message in err and "Traceback" not in err
    assert not out.exists()


def test_a_backend_whose_package_is_missing_names_the_extra(tmp_path, capsys, monkeypatch) -> None:
    monkeypatch.setitem(tracking.EXTRAS, "wandb", ("no_such_wandb_module", "wandb"))
    with pytest.raises(tracking.TrackingNotInstalledError, match=r'pip install -e "\.\[wandb\]"'):
        RunnerOptions(log="csv,wandb")
    out = tmp_path / "out"
    assert main(["train", "--out", str(out), *TINY, "--log", "wandb"]) == 2
    assert 'pip install -e ".[wandb]"' in capsys.readouterr().err and not out.exists()


def test_log_values_parse_in_order_and_none_logs_nothing() -> None:
    assert parse_log("csv, tensorboard") == ("csv", "tensorboard") == RunnerOptions(log=["csv", "tensorboard"]).log
    assert parse_log("none") == parse_log(None) == RunnerOptions().log == ()


SWEEP = """
[sweep]
seeds = 1
steps = 100
eval_interval = 100
eval_episodes = 1
{log}
[settings]
learning_starts = 32
[envs.coexistence_v0]
max_cycles = 20
[[methods]]
method = "dqn"
"""


def test_the_sweep_files_log_reaches_the_runner_and_reproduce_log_overrides_it(tmp_path, monkeypatch) -> None:
    import empathy_zoo.training.runner as runner
    from empathy_zoo.experiment.sweep_file import load_sweep

    class Stop(Exception):
        pass

    given: list[tuple[str, ...]] = []

    def capture(specs: Any, out: Any, options: RunnerOptions, **_: Any) -> list[Path]:
        given.append(options.log)
        raise Stop

    monkeypatch.setattr(runner, "train_runs", capture)
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(SWEEP.format(log='log = ["csv"]'), encoding="utf-8")
    plain = tmp_path / "plain.toml"
    plain.write_text(SWEEP.format(log=""), encoding="utf-8")
    assert [s.run_id for s in load_sweep(sweep)] == [s.run_id for s in load_sweep(plain)]  # (no part of a run id)
    for argv in ([], ["--log", "none"], ["--log", "tensorboard,csv"]):
        with pytest.raises(Stop):
            main(["reproduce", "--profile", str(sweep), "--out", str(tmp_path / "out"), "--no-progress", *argv])
    assert given == [("csv",), (), ("tensorboard", "csv")]
    sweep.write_text(SWEEP.format(log='log = "csv,mlflow"'), encoding="utf-8")
    with pytest.raises(SweepConfigError, match=r"\[sweep\] log: unknown backend 'mlflow'"):
        load_sweep(sweep)


def test_train_config_file_takes_log(tmp_path) -> None:
    from empathy_zoo.cli import parse_args
    from empathy_zoo.cli.train import train_values

    config = tmp_path / "run.toml"
    config.write_text('log = "tensorboard,csv"\n', encoding="utf-8")
    run, _ = train_values(parse_args(["train", "--config", str(config)]))
    assert run["log"] == "tensorboard,csv" and parse_log(run["log"]) == ("tensorboard", "csv")
    run, _ = train_values(parse_args(["train", "--config", str(config), "--log", "csv"]))
    assert run["log"] == "csv"  # the command line wins


# ---------------------------------------------------------------------------- the parts
def test_a_learner_without_tracked_scalars_logs_its_live_stats(tmp_path) -> None:
    class Learner:
        def live_stats(self) -> dict[str, float]:
            return {"eps": 0.25, "loss": 2.5}

    specs = [type("Spec", (), {"run_id": f"run_{i}"})() for i in range(2)]
    tracker = EnsembleTracker(("csv",), tmp_path, specs)
    tracker.start(0, [None, None])
    tracker.interval(500, Learner(), 1000.0)
    tracker.close()
    for spec in specs:
        rows = (log_dir(tmp_path, "csv", spec.run_id) / "scalars.csv").read_text(encoding="utf-8").splitlines()
        assert rows == ["step,name,value", "500,charts/SPS,1000.0", "500,charts/epsilon,0.25", "500,learner/loss,2.5"]


def test_a_resumed_csv_drops_the_rows_after_its_checkpoint_and_a_cut_row(tmp_path) -> None:
    logger = CsvLogger(tmp_path, 0)
    logger.scalars({"a": 1.0}, 100)
    logger.scalars({"a": 2.0, "b": 3.0}, 200)
    logger.scalars({"a": 4.0}, 300)
    logger.close()
    with (tmp_path / "scalars.csv").open("a", encoding="utf-8") as file:
        file.write("400,a,5")  # (a row cut by a crash)
    logger = CsvLogger(tmp_path, 200)  # (resumed from the checkpoint of step 200)
    logger.scalars({"a": 6.0}, 300)
    logger.close()
    rows = (tmp_path / "scalars.csv").read_text(encoding="utf-8").splitlines()
    assert rows == ["step,name,value", "100,a,1.0", "200,a,2.0", "200,b,3.0", "300,a,6.0"]


def test_empathic_dqn_tracks_each_heads_figures_per_run_as_the_run_alone_and_changes_nothing() -> None:
    """In a mixed ensemble (β = 1 runs: ``Q`` only; β < 1: ``Q`` and ``Q_emp``) each run's tracked
    figures are those of the run trained alone, and asking for them changes no network."""
    import torch
    from test_empathic_dqn import TINY as SETTINGS
    from test_empathic_dqn import _random_batches

    from agents.base import StepBatch
    from baselines.registry import get_method

    betas = [1.0, 0.5, 1.0, 0.25]
    method = get_method("empathic_dqn")
    batches = _random_batches(120, len(betas), seed=4, swapped_noise=True)
    mixed = method.learner([method.make_settings({**SETTINGS, "selfishness": b}) for b in betas], list(range(4)), 25)
    assert mixed.tracked_scalars() == [{}] * 4  # (no gradient step yet)
    for batch in batches:
        mixed.observe(batch)
    before = [p.clone() for p in mixed.online] + [p.clone() for p in mixed.target]
    tracked = mixed.tracked_scalars()
    assert all(torch.equal(a, b) for a, b in zip(before, [*mixed.online, *mixed.target], strict=True))
    for run, beta in enumerate(betas):
        solo = method.learner([method.make_settings({**SETTINGS, "selfishness": beta})], [run], 25)
        for batch in batches:
            solo.observe(StepBatch(**{name: None if v is None else v[run : run + 1] for name, v in vars(batch).items()}))
        [alone] = solo.tracked_scalars()
        heads = ["losses/td_loss", "losses/q_values"] + (["losses/td_loss_emp", "losses/q_values_emp"] if beta < 1 else [])
        assert sorted(tracked[run]) == sorted(alone) == sorted(heads)
        assert tracked[run] == pytest.approx(alone, rel=1e-5)


def _scalars_of(out: Path, run_id: str) -> tuple[dict[str, list[tuple[int, float]]], dict[str, list[tuple[int, float]]]]:
    """``{name: [(step, value), …]}`` of a run's TensorBoard files and of its CSV file, less ``charts/SPS``."""
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    reader = EventAccumulator(str(log_dir(out, "tensorboard", run_id)), size_guidance={"scalars": 0})
    reader.Reload()
    board = {tag: [(e.step, e.value) for e in reader.Scalars(tag)] for tag in reader.Tags()["scalars"] if tag != "charts/SPS"}
    table: dict[str, list[tuple[int, float]]] = {}
    with (log_dir(out, "csv", run_id) / "scalars.csv").open(newline="", encoding="utf-8") as file:
        for step, name, value in list(csv.reader(file))[1:]:
            if name != "charts/SPS":
                table.setdefault(name, []).append((int(step), float(value)))
    return board, table


def test_a_run_killed_and_resumed_logs_each_step_once_as_an_uninterrupted_run(tmp_path) -> None:
    import signal
    import subprocess
    import sys

    pytest.importorskip("tensorboard")
    helper = Path(__file__).with_name("helpers_crash.py")
    argv = [*TINY, "--checkpoint-interval", "100", "--log", "tensorboard,csv"]
    killed, whole = tmp_path / "killed", tmp_path / "whole"
    plan = {"hook": "step", "count": 280, "when": "before"}  # (env steps, evaluations' too: past the checkpoint at 200)
    done = subprocess.run([sys.executable, str(helper), json.dumps(plan), "train", "--out", str(killed), *argv], cwd=tmp_path)
    assert done.returncode == -signal.SIGKILL
    assert main(["train", "--out", str(killed), *argv]) == 0  # (resumes from its checkpoint at step 200)
    assert main(["train", "--out", str(whole), *argv]) == 0
    [run_id] = _run_ids(whole)
    board, table = _scalars_of(killed, run_id)
    assert (board, table) == _scalars_of(whole, run_id)
    assert set(board) == _expected(_result(whole, run_id)) - {"charts/SPS"}
