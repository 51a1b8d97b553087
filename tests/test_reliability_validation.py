"""A sweep is checked in full before the first ensemble trains (issue 25, cause 1): a label the
result-file reader would refuse, a fixed policy whose state a checkpoint cannot hold, SB3 keyword
arguments its class does not take and a variant without exactly one learning agent are refused
when the sweep or run is built, naming where; a full disk is found by the output check, and a
write that fails at the end of a run names its file and keeps what the run trained."""

from __future__ import annotations

import errno
import glob
import json
import unicodedata
from pathlib import Path

import numpy as np
import pytest
from helpers_policies import SavesItsGenerator
from helpers_results import synthetic_schema_1
from helpers_sweeps import TINY_SWEEP, TINY_TRAIN
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import empathy_zoo.training.runner as runner
from empathy_zoo import atomic
from empathy_zoo.cli import main
from empathy_zoo.experiment.model import EnvVariant, MethodEntry, RunSpec
from empathy_zoo.experiment.result_reader import check_result, read_result
from empathy_zoo.experiment.sweep_file import load_sweep, parse_sweep
from empathy_zoo.experiment.values import SweepConfigError
from empathy_zoo.limits import MAX_LABEL
from empathy_zoo.names import check_label
from empathy_zoo.result_file import ResultFileError
from empathy_zoo.training import RunnerOptions, train_runs
from empathy_zoo.training import results as results_module
from empathy_zoo.training.checkpoint import load_checkpoint
from empathy_zoo.training.ensemble import train_ensemble
from empathy_zoo.vector import VectorEnv

ROOT = Path(__file__).resolve().parents[1]
HELPERS = SavesItsGenerator.__module__
QUIET = RunnerOptions(progress=False, checkpoint_interval=0)
FAST = settings(max_examples=200, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
TINY_SETTINGS = {"learning_starts": 32, "replay_capacity": 200, "hidden_size": 8}
UNSTAMPED = ("wall_time_s", "created")


def tiny_sweep(**methods_entry) -> dict:
    """One run of DQN on Coexistence, 200 steps, as parsed TOML; ``methods_entry`` adds to its entry."""
    return {
        "sweep": {"seeds": 1, "steps": 200, "eval_interval": 200, "eval_episodes": 1},
        "settings": TINY_SETTINGS,
        "envs": {"coexistence_v0": {"max_cycles": 50}},
        "methods": [{"method": "dqn", **methods_entry}],
    }


@pytest.fixture
def steps_taken(monkeypatch):
    """Counts the env steps any vector env takes (none may be taken before a refusal)."""
    taken = []
    real = VectorEnv.step

    def counted(self, actions):
        taken.append(1)
        return real(self, actions)

    monkeypatch.setattr(VectorEnv, "step", counted)
    return taken


# ---------------------------------------------------------------------------- 1. labels
BAD_LABELS = [
    "x\ny",
    "line1\nline2",
    "a\rb",
    "tab\there",
    "nul\x00",
    "esc\x1b[31m",
    "sep\u2028",
    "rtl\u202eabc",
    "",
    "x" * (MAX_LABEL + 1),
]


@pytest.mark.parametrize("label", BAD_LABELS)
def test_a_label_the_reader_would_refuse_is_refused_when_the_run_is_built(label):
    with pytest.raises(ValueError, match="label"):
        MethodEntry.resolve("dqn", label=label)
    with pytest.raises(ValueError, match="label"):
        RunSpec.of(method="dqn", label=label)


def test_train_with_a_newline_in_its_label_writes_nothing(tmp_path, capsys, steps_taken):
    out = tmp_path / "lblnl"
    assert main(["train", "--label", "x\ny", "--out", str(out), *TINY_TRAIN]) == 2
    err = capsys.readouterr().err
    assert err.startswith("empathy-zoo: error: ") and "label" in err and "Traceback" not in err, err
    assert not out.exists() and steps_taken == []


def test_a_sweep_file_label_with_a_newline_is_refused_naming_file_and_table(tmp_path):
    sweep = tmp_path / "lbl.toml"
    sweep.write_text(TINY_SWEEP + 'label = "line1\\nline2"\n')
    with pytest.raises(SweepConfigError, match=r"lbl\.toml: \[\[methods\]\] #1 \(dqn\).*label"):
        load_sweep(sweep)


def test_a_label_template_that_formats_to_a_bad_label_is_refused_naming_the_entry():
    with pytest.raises(SweepConfigError, match=r"\[\[methods\]\] #1 \(dqn\).*label"):
        parse_sweep(tiny_sweep(label="x" * MAX_LABEL + "{gamma}"), source="long.toml")


def written_label(label: str) -> bool:
    """The writer's verdict: a run may be built with ``label``."""
    try:
        MethodEntry.resolve("dqn", label=label)
    except ValueError:
        return False
    return True


def read_label(label: str) -> bool:
    """The reader's verdict: a result file with ``label`` is read."""
    document = synthetic_schema_1("coexistence_v0", "dqn", 1.0, 0)
    document["method_label"] = label
    try:
        check_result(document, "generated.json")
    except ResultFileError:
        return False
    return True


CONTROL = st.characters(whitelist_categories=("Cc", "Cf", "Zl", "Zp"))


@FAST
@given(st.text(min_size=0, max_size=12), CONTROL, st.text(min_size=0, max_size=12))
def test_labels_with_control_characters_are_refused_by_writer_and_reader_alike(before, control, after):
    label = before + control + after
    assert written_label(label) is False
    assert read_label(label) is False


@FAST
@given(st.text(min_size=1, max_size=MAX_LABEL + 20))
def test_the_writer_accepts_exactly_the_labels_the_reader_accepts(label):
    assert written_label(label) == read_label(label)
    accepted = all(unicodedata.category(c) not in ("Cc", "Cf", "Cs", "Zl", "Zp") for c in label) and len(label) <= MAX_LABEL
    assert written_label(label) is accepted


def test_check_label_is_the_one_rule():
    assert check_label("Empathic DQN (β=0.5)", "label") == "Empathic DQN (β=0.5)"
    with pytest.raises(ValueError, match=f"at most {MAX_LABEL} characters"):
        check_label("x" * (MAX_LABEL + 1), "label")


def test_every_shipped_result_file_still_reads():
    paths = sorted(glob.glob(str(ROOT / "docs" / "results" / "*" / "runs" / "*.json")))
    assert paths
    for path in paths:
        read_result(Path(path))


# ---------------------------------------------------------------------------- 2. a fixed policy's state
def unsaveable_sweep() -> list[RunSpec]:
    return parse_sweep(
        {
            "sweep": {"seeds": 1, "steps": 300, "eval_interval": 300, "eval_episodes": 1},
            "settings": TINY_SETTINGS,
            "envs": {"coexistence_v0": {"max_cycles": 40, "fixed": {"cat_0": f"{HELPERS}:SavesItsGenerator"}}},
            "methods": [{"method": "dqn"}],
        },
        source="unsaveable.toml",
    )


def test_a_policy_whose_state_is_not_plain_data_is_refused_before_training(tmp_path, steps_taken):
    out = tmp_path / "out"
    with pytest.raises(ValueError, match=f"state\\(\\) of fixed policy {HELPERS}:SavesItsGenerator is not plain data"):
        train_runs(unsaveable_sweep(), out, RunnerOptions(progress=False, checkpoint_interval=100))
    assert steps_taken == []
    assert list(out.rglob("*.runs.json")) == [] and list(out.rglob("*.pt")) == []


def test_train_ensemble_takes_a_state_before_its_first_step(tmp_path, steps_taken):
    with pytest.raises(ValueError, match="is not plain data"):
        train_ensemble(unsaveable_sweep(), tmp_path, RunnerOptions(progress=False, checkpoint_interval=100))
    assert steps_taken == [] and list(tmp_path.rglob("*.runs.json")) == []


def test_without_checkpoints_such_a_policy_trains(tmp_path):
    (path,) = train_runs(unsaveable_sweep(), tmp_path, QUIET)
    assert read_result(path).steps == 300


# ---------------------------------------------------------------------------- 3. SB3 keyword arguments
def test_sb3_keyword_arguments_its_class_does_not_take_are_refused_when_the_sweep_loads():
    pytest.importorskip("stable_baselines3")
    from baselines.sb3 import SB3Settings

    with pytest.raises(ValueError, match=r"algorithm_kwargs: .*'nosuch'.*DQN takes"):
        SB3Settings(algorithm="dqn", algorithm_kwargs={"nosuch": 1})
    with pytest.raises(ValueError, match=r"'n_steps_typo'.*PPO takes"):
        SB3Settings(algorithm="ppo", algorithm_kwargs={"n_steps_typo": 8})
    data = tiny_sweep()
    data["settings"] = {}
    data["methods"] = [{"method": "dqn"}, {"method": "sb3_dqn", "algorithm_kwargs": {"buffer_sise": 100}}]
    with pytest.raises(SweepConfigError, match=r"sb3\.toml: \[\[methods\]\] #2 \(sb3_dqn\).*'buffer_sise'"):
        parse_sweep(data, source="sb3.toml")
    SB3Settings(algorithm="dqn", algorithm_kwargs={"buffer_size": 100, "tau": 0.5})  # (what it takes is taken)


# ---------------------------------------------------------------------------- 4. one learning agent
def test_a_variant_whose_agents_are_all_fixed_is_refused_naming_file_and_table():
    with pytest.raises(ValueError, match="exactly one learning agent"):
        EnvVariant("coexistence_v0", {}, {"robot_0": "stay", "cat_0": "random_walk"})
    data = tiny_sweep()
    data["envs"]["coexistence_v0"]["fixed"] = {"robot_0": "stay"}
    with pytest.raises(SweepConfigError, match=r"allfixed\.toml: \[envs\.coexistence_v0\].*exactly one learning agent"):
        parse_sweep(data, source="allfixed.toml")


def test_a_variant_with_two_learning_agents_is_refused():
    with pytest.raises(ValueError, match=r"exactly one learning agent.*robot_0.*cat_1"):
        EnvVariant("coexistence_v0", {"num_cats": 2}, {"cat_0": "random_walk"})


# ---------------------------------------------------------------------------- 6. a full disk
class _FullDiskHandle:
    """A file on a full disk: it opens (an empty file fits), but no byte can be written."""

    def __init__(self, handle):
        self.handle = handle

    def write(self, data):
        if len(data):
            raise OSError(errno.ENOSPC, "No space left on device")
        return 0

    def __getattr__(self, name):
        return getattr(self.handle, name)


@pytest.fixture
def full_disk(monkeypatch):
    """Every atomic write behaves as on a full disk."""
    real = atomic.write_with_atomic

    def on_full_disk(path, write):
        return real(path, lambda handle: write(_FullDiskHandle(handle)))

    monkeypatch.setattr(atomic, "write_with_atomic", on_full_disk)


def test_the_output_check_writes_as_much_as_a_result_and_its_agent_file(tmp_path, full_disk):
    with pytest.raises(ValueError, match=r"not writable.*No space left on device"):
        atomic.check_output_dir(tmp_path / "out")
    assert atomic.PROBE_BYTES >= 200_000
    assert [p for p in (tmp_path / "out").rglob("*") if p.is_file()] == []


def test_train_on_a_full_disk_is_refused_before_training(tmp_path, capsys, full_disk, steps_taken):
    assert main(["train", "--out", str(tmp_path / "out"), *TINY_TRAIN]) == 2
    assert "No space left on device" in capsys.readouterr().err
    assert steps_taken == []


def stored_results(paths) -> dict[str, dict]:
    return {Path(p).name: {k: v for k, v in json.loads(Path(p).read_text()).items() if k not in UNSTAMPED} for p in paths}


@pytest.mark.parametrize("checkpoint_interval", [0, 100])
def test_a_result_write_that_fails_at_the_end_names_its_file_and_keeps_the_run(tmp_path, monkeypatch, checkpoint_interval):
    specs = parse_sweep(tiny_sweep(), source="tiny.toml")
    expected = stored_results(train_runs(specs, tmp_path / "whole", QUIET))
    options = RunnerOptions(progress=False, checkpoint_interval=checkpoint_interval)
    out = tmp_path / "out"

    def no_space(path, payload):
        raise OSError(errno.ENOSPC, "No space left on device")

    with monkeypatch.context() as patch:
        patch.setattr(results_module, "write_json_atomic", no_space)
        with pytest.raises(OSError, match="No space left on device") as error:
            train_runs(specs, out, options)
    message = str(error.value)
    result_file = out / "runs" / f"{specs[0].run_id}.json"
    assert str(result_file) in message, message
    (kept,) = (out / "checkpoints").glob("*.pt")
    assert str(kept) in message and "same command" in message
    assert load_checkpoint(kept)["step"] == specs[0].steps  # the finished training, not an earlier step
    assert not result_file.exists()

    with monkeypatch.context() as patch:
        patch.setattr(VectorEnv, "step", lambda *a: pytest.fail("trained again although the finished run was kept"))
        paths = train_runs(specs, out, options)
    assert stored_results(paths) == expected
    assert list((out / "checkpoints").glob("*")) == []


def test_a_checkpoint_that_cannot_be_written_is_one_line_naming_it_and_the_previous_one_resumes(tmp_path, monkeypatch, capsys):
    """A disk that fills between two checkpoints: torch's zip writer fails (a ``RuntimeError``
    whose context is the ``OSError``); the command says so in one line naming the checkpoint, keeps
    the previous one, and the same command resumes from it to the files of an uninterrupted run."""
    import empathy_zoo.training.checkpoint as checkpoint_module

    real, calls = checkpoint_module.write_with_atomic, []

    def second_fills_the_disk(path, write):
        calls.append(path)
        if len(calls) < 2:
            return real(path, write)
        return real(path, lambda handle: write(_FullDiskHandle(handle)))

    whole = tmp_path / "whole"
    assert main(["train", "--out", str(whole), *TINY_TRAIN]) == 0
    out = tmp_path / "out"
    command = ["train", "--out", str(out), "--checkpoint-interval", "50", *TINY_TRAIN]
    with monkeypatch.context() as patch:
        patch.setattr(checkpoint_module, "write_with_atomic", second_fills_the_disk)
        assert main(command) == 1
    err = capsys.readouterr().err
    (kept,) = (out / "checkpoints").glob("*.pt")
    assert "Traceback" not in err and "inline_container" not in err
    assert f"cannot write checkpoint {kept} (No space left on device)" in err, err
    assert "previous checkpoint" in err and "same command" in err
    assert load_checkpoint(kept)["step"] == 50
    assert main(command) == 0
    assert stored_results((out / "runs").glob("*.json")) == stored_results((whole / "runs").glob("*.json"))


def test_a_first_checkpoint_that_cannot_be_written_says_none_is_kept(tmp_path, monkeypatch):
    import empathy_zoo.training.checkpoint as checkpoint_module

    real = checkpoint_module.write_with_atomic
    monkeypatch.setattr(
        checkpoint_module, "write_with_atomic", lambda path, write: real(path, lambda h: write(_FullDiskHandle(h)))
    )
    ckpt = tmp_path / "x.pt"
    with pytest.raises(OSError, match=r"cannot write checkpoint .*x\.pt \(No space left on device\); no earlier") as error:
        checkpoint_module.save_checkpoint(ckpt, {"a": 1})
    assert error.value.errno == errno.ENOSPC and not ckpt.exists()


def test_a_failed_write_that_cannot_keep_anything_says_the_run_is_lost(tmp_path, monkeypatch):
    specs = parse_sweep(tiny_sweep(), source="tiny.toml")

    def no_space(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(results_module, "write_json_atomic", no_space)
    monkeypatch.setattr("empathy_zoo.training.ensemble.save_checkpoint", no_space)
    with pytest.raises(OSError, match="No space left on device") as error:
        train_runs(specs, tmp_path / "out", QUIET)
    assert f"{specs[0].run_id}.json" in str(error.value) and "retrain" in str(error.value)


def test_the_vector_env_state_taken_up_front_changes_nothing():
    """Taking a state before training (the check) leaves the environment as it was."""
    a = VectorEnv("coexistence_v0", 2, fixed={"cat_0": "random_walk"}, max_cycles=20)
    b = VectorEnv("coexistence_v0", 2, fixed={"cat_0": "random_walk"}, max_cycles=20)
    a.reset(seed=[1, 2])
    b.reset(seed=[1, 2])
    a.check_checkpointable()
    actions = np.random.default_rng(0).integers(5, size=(60, 2, 1))
    for step in actions:
        np.testing.assert_array_equal(a.step(step).observations, b.step(step).observations)


def test_train_runs_checks_before_the_output_directory_is_touched(tmp_path, monkeypatch):
    """The refusals above come before anything is written (the output directory is not created)."""
    monkeypatch.setattr(runner, "train_ensemble", lambda *a, **k: pytest.fail("an ensemble started"))
    out = tmp_path / "never"
    with pytest.raises(ValueError, match="is not plain data"):
        train_runs(unsaveable_sweep(), out, RunnerOptions(progress=False, checkpoint_interval=100))
    assert not out.exists()
