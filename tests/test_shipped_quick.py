"""The main job's shipped output is what the main job computes today: one run of the quick
profile, trained here alone (solo and ensemble runs are bit-identical), gives exactly the columns
of its file in docs/results/quick/runs. A version that changes what the quick profile computes
fails here until the shipped directory is regenerated (docs/results/quick/NOTE.md says how)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from empathy_zoo.experiment.sweep_file import load_sweep, profile_path
from empathy_zoo.training import RunnerOptions, train_runs
from empathy_zoo.training.fingerprint import expected_update_kernel

SHIPPED = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick" / "runs"
RUN = "sharing_v0__empathic_dqn-24777995__s0"
"""The run trained again: Sharing, β = 1 (the cheapest of the profile: one network)."""
COMPUTED = ("run_id", "env", "variant", "method", "method_label", "seed", "config", "steps", "train", "eval", "update_kernel")
"""What a run computes (its wall time, date, version and commit say when and by what it was made)."""


def test_the_shipped_run_is_the_one_the_quick_profile_trains_today(tmp_path) -> None:
    shipped = json.loads((SHIPPED / f"{RUN}.json").read_text())
    (spec,) = [spec for spec in load_sweep(profile_path("quick")) if spec.run_id == RUN]
    here = expected_update_kernel(spec, "auto", "cpu")
    if shipped.get("update_kernel") == "numba" and here != "numba":
        pytest.skip(f"the shipped run was made by the compiled update, which does not build here (the {here} update would run)")
    (path,) = train_runs([spec], tmp_path, RunnerOptions(progress=False, checkpoint_interval=0))
    fresh = json.loads(Path(path).read_text())
    assert {key: fresh.get(key) for key in COMPUTED} == {key: shipped.get(key) for key in COMPUTED}
