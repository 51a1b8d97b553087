"""The Ray backend gives the local backend's result files, and survives a worker that dies."""

from __future__ import annotations

import hashlib
import json
import os
import sys
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import pytest

from empathy_zoo.experiment.model import RunSpec, group_specs
from empathy_zoo.training import RunnerOptions, train_runs
from empathy_zoo.training.ray_backend import train_with_ray

TINY = {"learning_starts": 64, "replay_capacity": 1_000, "epsilon_decay_steps": 200, "target_update_interval": 50}
SPECS = [
    RunSpec.of(
        env=env,
        method="empathic_dqn",
        settings={**TINY, "selfishness": 0.5},
        seed=seed,
        steps=300,
        eval_interval=150,
        eval_episodes=2,
    )
    for env in ("coexistence_v0", "sharing_v0")
    for seed in (0, 1)
]
OPTIONS = RunnerOptions(progress=False, threads=1)
RAY = replace(OPTIONS, backend="ray")


@pytest.fixture(scope="module")
def local_ray():
    """One single-node Ray for the module (``train_with_ray`` uses it instead of starting its own)."""
    ray = pytest.importorskip("ray")
    ray.init(num_cpus=2, include_dashboard=False, logging_level="ERROR")
    yield
    ray.shutdown()


@pytest.fixture(scope="module")
def local_results(tmp_path_factory) -> dict[str, dict]:
    """The same sweep through the local backend: the reference."""
    out = tmp_path_factory.mktemp("local")
    return {path.name: _scores(path) for path in train_runs(SPECS, out, OPTIONS)}


def _scores(path: Path) -> dict:
    result = json.loads(path.read_text())
    return {"run_id": result["run_id"], "train": result["train"], "eval": result["eval"], "config": result["config"]}


def test_ray_gives_the_local_backends_result_files(local_ray, local_results, tmp_path) -> None:
    seen: list[str] = []
    paths = train_runs(SPECS, tmp_path, RAY, on_result=lambda result: seen.append(result["run_id"]))
    assert sorted(seen) == sorted(spec.run_id for spec in SPECS)
    assert {path.name: _scores(path) for path in paths} == local_results
    agents = [f"{spec.run_id}.agent.pt" for spec in SPECS]
    assert sorted(p.name for p in (tmp_path / "runs").iterdir()) == sorted([*local_results, *agents])
    for path in paths:  # each agent file, written by the driver, is the one its result file names
        entry = json.loads(path.read_text())["agent"]
        assert hashlib.sha256(path.with_name(entry["file"]).read_bytes()).hexdigest() == entry["sha256"]
    assert not list((tmp_path / "checkpoints").glob("*.pt")), "finished ensembles leave no checkpoint"
    # a second call finds every run written and starts no task
    assert train_runs(SPECS, tmp_path, RAY, on_result=lambda result: seen.append(result["run_id"])) == paths
    assert len(seen) == len(SPECS)


def _kill_worker_once(marker: str):
    """A fault injection: the first task to run makes its worker process exit, once."""

    def inject(chunk: Sequence[RunSpec]) -> None:
        try:
            fd = os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            return
        os.write(fd, chunk[0].run_id.encode())
        os.close(fd)
        os._exit(1)

    return inject


def test_a_task_whose_worker_dies_is_retried_without_lost_or_duplicated_runs(local_ray, local_results, tmp_path) -> None:
    marker = tmp_path / "killed"
    seen: list[str] = []
    chunks = group_specs(SPECS, 32)
    train_with_ray(
        chunks,
        tmp_path / "out",
        RAY,
        lambda result: seen.append(result["run_id"]),
        fault_injection=_kill_worker_once(str(marker)),
    )
    killed = marker.read_text()
    assert killed in {spec.run_id for spec in SPECS}, "the fault was injected"
    assert sorted(seen) == sorted(spec.run_id for spec in SPECS), "each run written exactly once"
    files = sorted((tmp_path / "out" / "runs").glob("*.json"))
    assert {path.name: _scores(path) for path in files} == local_results


def _fail_on(env: str):
    """A fault injection: every attempt at the ensemble of ``env`` raises."""

    def inject(chunk: Sequence[RunSpec]) -> None:
        if chunk[0].env == env:
            raise OSError(f"injected failure on {env}")

    return inject


def test_a_task_failing_every_retry_is_reported_after_the_others_are_written(local_ray, local_results, tmp_path) -> None:
    with pytest.raises(RuntimeError, match=r"1 ensemble task\(s\) failed after 3 retries.*sharing_v0") as caught:
        train_with_ray(group_specs(SPECS, 32), tmp_path, RAY, fault_injection=_fail_on("sharing_v0"))
    assert "injected failure on sharing_v0" in str(caught.value.__cause__)
    written = {path.name: _scores(path) for path in (tmp_path / "runs").glob("*.json")}
    assert written == {name: scores for name, scores in local_results.items() if name.startswith("coexistence_v0")}


def test_a_result_whose_file_exists_is_not_written_again(local_ray, local_results, tmp_path) -> None:
    chunks = group_specs(SPECS[:2], 32)
    first = SPECS[0].run_id
    existing = tmp_path / "runs" / f"{first}.json"
    existing.parent.mkdir(parents=True)
    existing.write_text("written by someone else")
    seen: list[str] = []
    train_with_ray(chunks, tmp_path, RAY, lambda result: seen.append(result["run_id"]))
    assert seen == [SPECS[1].run_id]
    assert existing.read_text() == "written by someone else"


def test_without_ray_the_error_says_how_to_install_it(monkeypatch, tmp_path) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)  # makes ``import ray`` fail, installed or not
    with pytest.raises(ImportError, match=r'pip install -e "\.\[ray\]"'):
        train_runs(SPECS, tmp_path, RAY)
    assert not (tmp_path / "runs").exists()


@pytest.mark.parametrize(
    "address, expected",
    [
        ("ray://127.0.0.1:1", "cannot reach the Ray cluster at ray://127.0.0.1:1"),
        ("127.0.0.1:1", "cannot reach the Ray cluster at 127.0.0.1:1"),
        ("ray://192.0.2.1:10001", "cannot reach the Ray cluster at ray://192.0.2.1:10001"),  # TEST-NET: never answers
        ("ray://no-port", "expected auto, ray://HOST:PORT"),
    ],
)
def test_an_unreachable_cluster_fails_at_once_naming_the_address(tmp_path, monkeypatch, address, expected) -> None:
    ray = pytest.importorskip("ray")
    if ray.is_initialized():
        pytest.skip("a Ray is already running in this process")
    import empathy_zoo.training.ray_backend as backend

    monkeypatch.setattr(backend, "CONNECT_TIMEOUT_S", 0.5)
    with pytest.raises(ValueError, match=expected):
        train_runs(SPECS, tmp_path / "out", replace(RAY, address=address))
    assert not (tmp_path / "out").exists()


def test_address_auto_without_a_cluster_is_refused_before_anything_is_written(tmp_path, monkeypatch) -> None:
    ray = pytest.importorskip("ray")
    if ray.is_initialized():
        pytest.skip("a Ray is already running in this process")
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    monkeypatch.setenv("RAY_TMPDIR", str(tmp_path / "ray-tmp"))  # (no cluster was started from here)
    with pytest.raises(ValueError, match=r"--address auto found no running Ray cluster .*ray start --head"):
        train_runs(SPECS, tmp_path / "out", replace(RAY, address="auto"))
    assert not (tmp_path / "out").exists()


def test_address_auto_follows_ray_address_and_checks_it(tmp_path, monkeypatch) -> None:
    ray = pytest.importorskip("ray")
    if ray.is_initialized():
        pytest.skip("a Ray is already running in this process")
    import empathy_zoo.training.ray_backend as backend

    monkeypatch.setattr(backend, "CONNECT_TIMEOUT_S", 0.5)
    monkeypatch.setenv("RAY_ADDRESS", "127.0.0.1:1")
    with pytest.raises(ValueError, match=r"cannot reach the Ray cluster at [^ ]+:1 "):  # (Ray names the host by its address)
        train_runs(SPECS, tmp_path / "out", replace(RAY, address="auto"))
    assert not (tmp_path / "out").exists()
