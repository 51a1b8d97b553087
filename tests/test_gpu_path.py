"""The GPU path's benchmark (benchmarks/gpu_path.py) runs on the CPU as on a GPU: the paper's
Coexistence ensemble trains end to end and the figures it prints describe that run; on a machine
with CUDA, the same ensemble trains on the device."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest
import torch

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "gpu_path.py"


def gpu_path():
    spec = importlib.util.spec_from_file_location("gpu_path", SCRIPT)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_ensemble_is_the_papers_coexistence_sweep_at_the_seeds_asked() -> None:
    runs = gpu_path().specs(seeds=3, steps=100)
    assert len(runs) == 12
    assert sorted({(run.entry.settings.selfishness, run.seed) for run in runs}) == sorted(
        (beta, seed) for beta in (1.0, 0.75, 0.5, 0.25) for seed in range(3)
    )


def _figures(tmp_path: Path, device: str, kernel: str, capsys) -> dict:
    out = tmp_path / device
    figures = gpu_path().main(["--device", device, "--kernel", kernel, "--seeds", "1", "--steps", "80", "--out", str(out)])
    assert json.loads(capsys.readouterr().out.strip().splitlines()[-1]) == figures
    results = sorted((out / "runs").glob("*.json"))
    assert len(results) == figures["runs"] == 4
    assert figures["steps_per_run"] == 80 and figures["env_steps_per_s"] > 0
    assert figures["env_steps_per_s"] == pytest.approx(4 * 80 / figures["wall_s"], rel=0.01)
    return figures


def test_it_trains_and_reports_on_the_cpu(tmp_path, capsys) -> None:
    figures = _figures(tmp_path, "cpu", "numba", capsys)
    assert figures["device"] == "cpu" and figures["kernel"] == "numba"


@pytest.mark.skipif(not torch.cuda.is_available(), reason="needs a CUDA device")
def test_it_trains_and_reports_on_a_gpu(tmp_path, capsys) -> None:
    figures = _figures(tmp_path, "cuda", "torch", capsys)
    assert figures["device_name"] == torch.cuda.get_device_name(0)


def test_a_budget_inside_the_warm_up_is_refused(capsys) -> None:
    with pytest.raises(SystemExit):
        gpu_path().main(["--steps", "10"])
    assert "--steps above" in capsys.readouterr().err
