"""The update kernel is chosen by ``RunnerOptions.update_kernel`` / ``--update-kernel``, recorded in
every result file, compared like the code version when a finished run is asked for again, and a
checkpoint resumes only with the kernel that wrote it."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

from agents import fused_update
from empathy_zoo.cli import main
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.training import RunnerOptions, ensemble, runner, train_runs
from empathy_zoo.training.checkpoint import CheckpointError
from empathy_zoo.training.fingerprint import CodeFingerprint

TINY = {"learning_starts": 32, "replay_capacity": 300, "hidden_size": 8, "target_update_interval": 50, "epsilon_decay_steps": 200}
OPTIONS = RunnerOptions(progress=False, threads=1, checkpoint_interval=0)

needs_numba = pytest.mark.skipif(not fused_update.numba_available(), reason="numba does not build here")


def spec(method: str = "empathic_dqn", **settings: object) -> RunSpec:
    return RunSpec.of(
        env="coexistence_v0",
        method=method,
        settings={**(TINY if method != "sb3_dqn" else {}), **settings},
        steps=200,
        eval_interval=100,
        eval_episodes=1,
        env_kwargs={"max_cycles": 30},
    )


def trained(out: Path, options: RunnerOptions, run: RunSpec | None = None) -> dict:
    return json.loads(train_runs([run or spec(selfishness=0.5)], out, options)[0].read_text())


@needs_numba
def test_each_result_file_records_the_kernel_that_made_it(tmp_path: Path) -> None:
    by_torch = trained(tmp_path / "torch", replace(OPTIONS, update_kernel="torch"))
    by_numba = trained(tmp_path / "numba", replace(OPTIONS, update_kernel="numba"))
    by_auto = trained(tmp_path / "auto", replace(OPTIONS, update_kernel="auto"))
    assert (by_torch["update_kernel"], by_numba["update_kernel"], by_auto["update_kernel"]) == ("torch", "numba", "numba")
    assert by_auto["train"] == by_numba["train"] and by_auto["eval"] == by_numba["eval"]
    assert by_torch["steps"] == by_numba["steps"] == 200


def test_a_learner_without_a_choice_records_none(tmp_path: Path) -> None:
    pytest.importorskip("stable_baselines3")
    result = trained(
        tmp_path / "sb3",
        replace(OPTIONS, update_kernel="numba"),
        spec("sb3_dqn", algorithm_kwargs={"learning_starts": 32, "buffer_size": 300}),
    )
    assert result["update_kernel"] is None


@needs_numba
def test_a_run_made_by_the_other_kernel_counts_as_made_by_other_code(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    out = tmp_path / "out"
    trained(out, replace(OPTIONS, update_kernel="torch"))
    monkeypatch.setattr(runner, "train_ensemble", lambda *a, **k: pytest.fail("a run of the kernel asked for was retrained"))
    trained(out, replace(OPTIONS, update_kernel="torch"))  # (the same kernel: reused)
    with pytest.raises(ValueError, match=r"made with the torch update kernel, this would use numba \(--update-kernel torch"):
        train_runs([spec(selfishness=0.5)], out, replace(OPTIONS, update_kernel="numba"))


def test_the_fingerprint_compares_kernels_only_where_both_are_known() -> None:
    now = CodeFingerprint("1.0", None, {}, "numba")
    assert now.changes_since(CodeFingerprint("1.0", None, {}, "torch"))[0] == [
        "made with the torch update kernel, this would use numba (--update-kernel torch goes on with it)"
    ]
    assert now.changes_since(CodeFingerprint("1.0", None, {}, None)) == ([], [])  # (a file older than the field)
    assert CodeFingerprint("1.0", None, {}, None).changes_since(CodeFingerprint("1.0", None, {}, "numba")) == ([], [])
    assert now.fields()["update_kernel"] == "numba"


@needs_numba
def test_a_checkpoint_resumes_only_with_the_kernel_that_wrote_it(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    out = tmp_path / "out"
    real = ensemble.save_checkpoint

    def save_then_die(path, payload):  # type: ignore[no-untyped-def]
        real(path, payload)
        raise KeyboardInterrupt

    monkeypatch.setattr(ensemble, "save_checkpoint", save_then_die)
    with_checkpoints = replace(OPTIONS, checkpoint_interval=100, update_kernel="numba")
    with pytest.raises(KeyboardInterrupt):
        trained(out, with_checkpoints)
    monkeypatch.setattr(ensemble, "save_checkpoint", real)
    with pytest.raises(
        CheckpointError, match=r"made with the numba update kernel .* would go on with torch.*--update-kernel numba"
    ):
        trained(out, replace(with_checkpoints, update_kernel="torch"))
    resumed = trained(out, with_checkpoints)
    whole = trained(tmp_path / "whole", replace(OPTIONS, update_kernel="numba"))
    assert (resumed["train"], resumed["eval"]) == (whole["train"], whole["eval"])


def test_a_bad_kernel_name_is_refused_by_the_options_and_the_command_line(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(ValueError, match="update_kernel must be one of auto, numba, torch, got 'fast'"):
        RunnerOptions(update_kernel="fast")
    assert main(["train", "--update-kernel", "fast", "--steps", "10"]) == 2
    assert "--update-kernel: invalid choice: 'fast'" in capsys.readouterr().err


@needs_numba
def test_the_command_line_option_reaches_the_result_file(tmp_path: Path) -> None:
    args = ["train", "--steps", "200", "--eval-interval", "100", "--eval-episodes", "1", "--max-cycles", "30", "--no-progress"]
    args += ["--learning-starts", "32", "--replay-capacity", "300", "--hidden-size", "8", "--epsilon-decay-steps", "150"]
    assert main([*args, "--update-kernel", "numba", "--out", str(tmp_path / "a")]) == 0
    (result,) = (tmp_path / "a" / "runs").glob("*.json")
    assert json.loads(result.read_text())["update_kernel"] == "numba"
