"""``tune --objective`` of a metric every episode of the environment gives one value (no battery in
Coexistence: ``batteries``, ``other_batteries`` 0 and ``equality`` 1; no one to harm in Sharing:
``harms`` 0) is refused in one line before anything is written: every trial would tie and the
study would choose nothing."""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers_sweeps import TUNE_SWEEP
from helpers_tune import run_tune

from empathy_zoo.environments import ENVIRONMENT_TABLE
from empathy_zoo.metrics import METRIC_NAMES

SHARING_SWEEP = TUNE_SWEEP.replace("[envs.coexistence_v0]", "[envs.sharing_v0]")


@pytest.mark.parametrize(
    "env, objective",
    [
        ("coexistence_v0", "batteries"),
        ("coexistence_v0", "other_batteries"),
        ("coexistence_v0", "equality"),
        ("sharing_v0", "harms"),
    ],
)
def test_an_objective_that_never_moves_is_refused_before_anything_is_written(tmp_path: Path, capsys, env, objective) -> None:
    sweep = tmp_path / "tiny.toml"
    sweep.write_text(TUNE_SWEEP if env == "coexistence_v0" else SHARING_SWEEP)
    out = tmp_path / "study"
    status = run_tune(sweep, out, 1, "--objective", objective)
    err = capsys.readouterr().err
    assert status == 2 and err.count("\n") == 1 and f"--objective {objective}" in err and env in err, err
    assert "name one that moves there: survival" in err, err
    assert not out.exists()


def test_an_objective_that_moves_still_tunes(tmp_path: Path) -> None:
    sweep = tmp_path / "tiny.toml"
    sweep.write_text(TUNE_SWEEP)
    assert run_tune(sweep, tmp_path / "study", 1, "--objective", "harms") == 0


def test_the_constant_metrics_follow_the_environment_table() -> None:
    from empathy_zoo.result_file import constant_metrics

    for env, entry in ENVIRONMENT_TABLE.items():
        constant = constant_metrics(env, {})
        assert set(constant) <= set(METRIC_NAMES)
        assert ("harms" in constant) == (entry.most_harms(1) == 0), env
        assert (
            ("batteries" in constant) == ("other_batteries" in constant) == ("equality" in constant) == (not entry.batteries)
        ), env
        assert all(value == (1.0 if name == "equality" else 0.0) for name, value in constant.items())
    assert constant_metrics("coexistence_v0", {}) == {"batteries": 0.0, "other_batteries": 0.0, "equality": 1.0}
    assert constant_metrics("sharing_v0", {}) == {"harms": 0.0}
