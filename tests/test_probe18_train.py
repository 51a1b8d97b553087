"""The eighteenth probe's findings on training: the settings a run is built with are checked by
the result reader's own rule before anything is written; a run whose networks diverge is refused
naming it, and no checkpoint of non-finite weights is written; an agent file's head names are
whole lower-case identifiers (no trailing line break)."""

from __future__ import annotations

import io
import json
import shutil
import signal
import subprocess
import sys
import textwrap
import zipfile
from pathlib import Path

import pytest
import torch
from helpers_sweeps import TINY_DQN_TRAIN

from empathy_zoo.cli import main

ROOT = Path(__file__).resolve().parents[1]
RUNS = ROOT / "docs" / "results" / "quick" / "runs"
CRASH = Path(__file__).with_name("helpers_crash.py")
LIBRARY_RUNS = ROOT / "docs" / "results" / "sb3_transforms" / "runs"

TINY = TINY_DQN_TRAIN
"""A tiny run of DQN (a few hundred steps take a second or two)."""


TINY_SWEEP = """
[sweep]
seeds = [0, 1]
steps = 300
eval_interval = 300
eval_episodes = 1

[envs.coexistence_v0]
max_cycles = 40

[[methods]]
method = "dqn"
hidden_size = 8
learning_starts = 50
replay_capacity = 100
batch_size = 8
epsilon_decay_steps = 10
"""
"""A tuning study's experiment of tiny runs."""


# ---------------------------------------------------------------------------- 1: settings the reader refuses
@pytest.mark.parametrize(
    ("option", "value", "setting", "bound"),
    [
        ("--target-update-interval", "3000000000", "target_update_interval", "1,000,000,000"),
        ("--learning-rate", "5e9", "learning_rate", "1,000,000,000"),
    ],
    ids=["an interval beyond the reader's bound", "a learning rate beyond the reader's bound"],
)
def test_train_refuses_settings_its_reader_refuses_before_writing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], option: str, value: str, setting: str, bound: str
) -> None:
    out = tmp_path / "out"
    args = [*TINY, "--steps", "100", "--eval-interval", "100", "--checkpoint-interval", "0", option, value]
    assert main([*args, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and setting in err and bound in err, err
    assert "damaged" not in err and "Traceback" not in err, err
    assert not out.exists(), sorted(out.rglob("*"))


def test_a_config_file_setting_the_reader_refuses_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    config = tmp_path / "run.toml"
    config.write_text("[settings]\ntarget_update_interval = 3000000000\n", encoding="utf-8")
    out = tmp_path / "out"
    args = [*TINY, "--steps", "100", "--eval-interval", "100", "--checkpoint-interval", "0", "--config", str(config)]
    assert main([*args, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "target_update_interval" in err and "1,000,000,000" in err, err
    assert not out.exists()


@pytest.mark.parametrize(
    ("setting", "value"),
    [("learning_rate", 5e9), ("learning_rate", -5e9), ("target_update_interval", 3_000_000_000), ("gamma", True)],
)
def test_make_settings_applies_the_readers_rule(setting: str, value: object) -> None:
    from baselines.registry import get_method

    with pytest.raises(ValueError, match=setting) as caught:
        get_method("dqn").make_settings({setting: value})
    assert "\n" not in str(caught.value)


def test_make_settings_still_takes_the_readers_extremes() -> None:
    from baselines.registry import get_method

    settings = get_method("dqn").make_settings({"learning_rate": 1e9, "target_update_interval": 1_000_000_000})
    assert (settings.learning_rate, settings.target_update_interval) == (1e9, 1_000_000_000)


def test_a_sweep_file_setting_the_reader_refuses_is_refused(tmp_path: Path) -> None:
    from empathy_zoo.experiment.sweep_file import load_sweep
    from empathy_zoo.experiment.values import SweepConfigError

    path = tmp_path / "sweep.toml"
    text = """
    [sweep]
    seeds = 1
    steps = 1000
    eval_interval = 500
    eval_episodes = 1

    [envs.coexistence_v0]

    [[methods]]
    method = "dqn"
    learning_rate = 5e9
    """
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    with pytest.raises(SweepConfigError) as caught:
        load_sweep(path)
    message = str(caught.value)
    assert str(path) in message and "learning_rate" in message and "1,000,000,000" in message, message


# ---------------------------------------------------------------------------- 2: a run that diverges
def _checkpoints(out: Path) -> list[Path]:
    return sorted((out / "checkpoints").glob("*.pt")) if (out / "checkpoints").exists() else []


def test_a_diverged_run_is_refused_naming_it_and_leaves_no_unreadable_checkpoint(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from empathy_zoo.training.checkpoint import load_checkpoint

    out = tmp_path / "out"
    args = [*TINY, "--learning-rate", "1e9", "--steps", "300", "--eval-interval", "300", "--checkpoint-interval", "10"]
    for attempt in range(2):  # (the second resumes from what the first kept, and meets the same refusal)
        assert main([*args, "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1, err
        assert "coexistence_v0__dqn-" in err and "diverged" in err and "learning rate" in err, (attempt, err)
        assert "corrupted" not in err and "damaged" not in err, (attempt, err)
        assert not list((out / "runs").glob("*.json")) if (out / "runs").exists() else True
        for checkpoint in _checkpoints(out):
            load_checkpoint(checkpoint)  # (every checkpoint kept is one a rerun resumes from)


def test_the_checkpoint_writer_refuses_weights_that_are_no_finite_numbers(tmp_path: Path) -> None:
    from empathy_zoo.training.checkpoint import load_checkpoint, save_checkpoint

    path = tmp_path / "c.pt"
    finite = {"run_ids": ["r"], "learner": {"online": [torch.zeros(2)]}}
    save_checkpoint(path, finite)
    before = path.read_bytes()
    diverged = {"run_ids": ["r"], "learner": {"online": [torch.tensor([0.0, float("nan")])]}}
    with pytest.raises(ValueError, match=r"run r diverged") as caught:
        save_checkpoint(path, diverged)
    assert "corrupted" not in str(caught.value)
    assert path.read_bytes() == before
    assert load_checkpoint(path)["learner"]["online"][0].tolist() == [0.0, 0.0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.pt"]


def test_a_refused_checkpoint_leaves_no_list_of_runs_behind(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    args = [*TINY, "--learning-rate", "1e9", "--steps", "300", "--eval-interval", "300", "--checkpoint-interval", "100"]
    assert main([*args, "--out", str(out)]) == 2
    assert "diverged" in capsys.readouterr().err
    assert not (out / "checkpoints").exists() or list((out / "checkpoints").iterdir()) == []


def test_adams_overflowed_squares_are_kept_and_read_back(tmp_path: Path) -> None:
    """A gradient past ≈ 1.8e19 makes Adam's mean of its square +inf (the weight stays finite; Adam
    steps it no more): a state the trainer reaches (DQN at a learning rate of 1e4 on a tiny run), so
    its checkpoint is written and read back; NaN or -inf there is refused."""
    from empathy_zoo.training.checkpoint import load_checkpoint, save_checkpoint

    path = tmp_path / "c.pt"
    squares = torch.tensor([1.0, float("inf")])
    save_checkpoint(path, {"run_ids": ["r"], "learner": {"optimizer": {"exp_avg_sq": [squares]}}})
    assert load_checkpoint(path)["learner"]["optimizer"]["exp_avg_sq"][0].tolist() == [1.0, float("inf")]
    for bad in (float("nan"), -float("inf")):
        payload = {"run_ids": ["r"], "learner": {"optimizer": {"exp_avg_sq": [torch.tensor([1.0, bad])]}}}
        with pytest.raises(ValueError, match="run r diverged"):
            save_checkpoint(tmp_path / "d.pt", payload)
    with pytest.raises(ValueError, match="run r diverged"):  # (+inf anywhere else is refused)
        save_checkpoint(tmp_path / "d.pt", {"run_ids": ["r"], "learner": {"optimizer": {"exp_avg": [squares]}}})
    assert not (tmp_path / "d.pt").exists()


def test_a_run_whose_adam_squares_overflow_resumes_from_its_checkpoint_alike(tmp_path: Path) -> None:
    """Killed after its checkpoint of step 250 (whose Adam squares hold +inf), the run resumes from
    it and ends as the run trained at one go."""
    from empathy_zoo.experiment.result_reader import read_result

    args = [*TINY, "--learning-rate", "1e4", "--steps", "400", "--eval-interval", "200", "--checkpoint-interval", "50"]
    assert main([*args, "--out", str(tmp_path / "a")]) == 0
    plans = [{"hook": "checkpoint", "count": 5, "when": "after"}, {}]
    for plan in plans:
        done = subprocess.run(
            [sys.executable, str(CRASH), json.dumps(plan), *args, "--out", str(tmp_path / "b")],
            capture_output=True,
            text=True,
            cwd=tmp_path,
            timeout=600,
        )
        assert done.returncode == (-signal.SIGKILL if plan else 0), done.stderr
        if plan:
            (checkpoint,) = (tmp_path / "b" / "checkpoints").glob("*.pt")
            squares = torch.load(checkpoint, weights_only=True)["learner"]["optimizer"]["exp_avg_sq"]
            assert any(bool(torch.isinf(square).any()) for square in squares)  # (what the probe's reader refused)
    (first,), (second,) = ((tmp_path / name / "runs").glob("*.json") for name in ("a", "b"))
    assert (read_result(first).eval, read_result(first).train) == (read_result(second).eval, read_result(second).train)


def test_a_tuning_trial_that_diverges_is_refused_with_the_reason_and_the_study_goes_on(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("optuna")
    sweep = tmp_path / "tiny.toml"
    sweep.write_text(TINY_SWEEP, encoding="utf-8")
    args = ["tune", str(sweep), "--method", "dqn", "--param", "learning_rate=log:1e8:1e9", "--trials", "2"]
    args += ["--startup-trials", "2", "--no-progress", "--out", str(tmp_path / "o")]
    for attempt in range(2):  # (the second reads the study back: its refused trials count, nothing is trained)
        assert main(args) == 0, capsys.readouterr().err
        trials = json.loads((tmp_path / "o" / "study.json").read_text(encoding="utf-8"))["trials"]
        assert [trial["state"] for trial in trials] == ["REFUSED", "REFUSED"], (attempt, trials)
        assert all("diverged" in trial["refused"] and "coexistence_v0__dqn-" in trial["refused"] for trial in trials)


# ---------------------------------------------------------------------------- 3: head names
def _forged_agent(tmp_path: Path, field: str) -> Path:
    """A shipped agent file with its head ``q`` renamed ``"q\\n"`` (``heads``) or acting on ``"q\\n"``."""
    source = sorted(RUNS.glob("coexistence_v0__dqn_harm_penalty-*__s0.agent.pt"))[0]
    document = torch.load(source, map_location="cpu", weights_only=True)
    if field == "heads":
        document["heads"] = {f"{name}\n": layers for name, layers in document["heads"].items()}
        document["acting"] = f"{document['acting']}\n"
    else:
        document["acting"] = f"{document['acting']}\n"
    forged = tmp_path / source.name
    torch.save(document, forged)
    return forged


@pytest.mark.parametrize("field", ["heads", "acting"])
def test_watch_refuses_a_head_name_with_a_line_break(tmp_path: Path, capsys: pytest.CaptureFixture[str], field: str) -> None:
    forged = _forged_agent(tmp_path, field)
    assert main(["watch", str(forged), "--episodes", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and forged.name in err, err
    assert ("head name 'q\\n'" in err) if field == "heads" else ("'acting'" in err), err


@pytest.mark.parametrize("field", ["heads", "acting"])
def test_a_library_agent_files_head_names_are_whole_identifiers(tmp_path: Path, field: str) -> None:
    from empathy_zoo.agent_file import LIBRARY_MEMBER, load_agent

    source = sorted(LIBRARY_RUNS.glob("*.agent.zip"))[0]
    forged = tmp_path / source.name
    buffer = io.BytesIO()
    with zipfile.ZipFile(source) as original, zipfile.ZipFile(buffer, "w") as copy:
        for info in original.infolist():
            data = original.read(info.filename)
            if info.filename == LIBRARY_MEMBER:
                member = json.loads(data)
                if field == "heads":
                    member["heads"], member["acting"] = ["q\n"], "q\n"
                else:
                    member["acting"] = f"{member['acting']}\n"  # (a policy's name: no heads)
                data = json.dumps(member).encode()
            copy.writestr(info, data)
    forged.write_bytes(buffer.getvalue())
    with pytest.raises(ValueError, match=f"field {LIBRARY_MEMBER}.{field}") as caught:
        load_agent(forged)
    assert forged.name in str(caught.value)


def test_the_agent_writer_refuses_a_head_name_with_a_line_break() -> None:
    from empathy_zoo.agent_file import agent_document

    layers = [torch.zeros(25, 5), torch.zeros(5)]
    with pytest.raises(ValueError, match="head name"):
        agent_document({"heads": {"q\n": layers}, "acting": "q\n"}, {})


def test_shipped_agent_files_still_load(tmp_path: Path) -> None:
    from empathy_zoo.agent_file import load_run_agent

    source = sorted(RUNS.glob("coexistence_v0__dqn_harm_penalty-*__s0.json"))[0]
    for path in (source, source.with_name(source.stem + ".agent.pt")):
        shutil.copy(path, tmp_path / path.name)
    assert load_run_agent(tmp_path / source.name) is not None
