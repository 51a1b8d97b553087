"""``time_limit``: a time-limit end bootstraps (SPEC §6, the default) or counts as terminal (the
authors' code), and a run records the setting only where it is not the default, so that every
earlier run keeps its record and its id."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from helpers_batches import one_other

from agents.base import StepBatch
from agents.settings import EmpathicDQNSettings
from baselines.registry import get_method
from empathy_zoo.experiment.sweep_file import load_sweep, profile_path

TINY = {"learning_starts": 64, "replay_capacity": 100, "epsilon_decay_steps": 500, "target_update_interval": 50}


def cut_by_the_time_limit(k: int, truncated: bool | None = True) -> StepBatch:
    """One step of ``k`` runs: no run's episode ended for good, each was cut by the time limit."""
    return StepBatch(
        obs=np.zeros((k, 1, 25), np.float32),
        actions=np.zeros((k, 1), int),
        rewards=np.ones((k, 1), np.float32),
        terminated=np.zeros((k, 1), bool),
        next_obs=np.zeros((k, 1, 25), np.float32),
        harms=np.zeros((k, 1)),
        battery_return=np.zeros((k, 1)),
        truncated=None if truncated is None else np.full((k, 1), truncated),
        **one_other(np.zeros((k, 1, 25), np.float32), np.ones((k, 1), bool), np.zeros((k, 1))),
    )


def stored_end(time_limit: str, truncated: bool = True) -> bool:
    method = get_method("empathic_dqn")
    learner = method.learner([method.make_settings({**TINY, "time_limit": time_limit})], [0], 25)
    learner.observe(cut_by_the_time_limit(1, truncated))
    return bool(learner.replay.sample(torch.zeros((1, 1), dtype=torch.long))["terminated"][0, 0])


def test_a_time_limit_end_bootstraps_by_default_and_is_terminal_when_asked():
    assert EmpathicDQNSettings().time_limit == "bootstrap"
    assert stored_end("bootstrap") is False
    assert stored_end("terminal") is True
    assert stored_end("terminal", truncated=False) is False  # (only the time limit's end changes)


def test_terminal_time_limits_need_the_steps_truncations():
    method = get_method("empathic_dqn")
    learner = method.learner([method.make_settings({**TINY, "time_limit": "terminal"})], [0], 25)
    with pytest.raises(ValueError, match="truncations"):
        learner.observe(cut_by_the_time_limit(1, truncated=None))


def test_an_unknown_time_limit_rule_is_refused():
    with pytest.raises(ValueError, match=r"time_limit must be one of \('bootstrap', 'terminal'\)"):
        EmpathicDQNSettings(time_limit="truncate")


def test_the_setting_is_recorded_only_where_it_is_not_the_default():
    assert "time_limit" not in EmpathicDQNSettings().record()
    assert EmpathicDQNSettings(time_limit="terminal").record()["time_limit"] == "terminal"
    assert set(EmpathicDQNSettings().record()) | {"time_limit"} == set(vars(EmpathicDQNSettings()))


def test_runs_that_leave_it_at_its_default_keep_their_ids(tmp_path):
    # the quick profile's run ids are those of its shipped files, made before the setting existed
    shipped = {path.stem for path in (profile_path("quick").parents[2] / "docs/results/quick/runs").glob("*.json")}
    specs = load_sweep(profile_path("quick"))
    assert {spec.run_id for spec in specs} <= shipped and specs
    assert all("time_limit" not in spec.config()["settings"] for spec in specs)
    sweep = tmp_path / "terminal.toml"
    sweep.write_text(
        '[sweep]\nname = "t"\nseeds = 1\nsteps = 200\n[settings]\ntime_limit = "terminal"\n'
        '[envs.coexistence_v0]\n[[methods]]\nmethod = "dqn"\n'
    )
    (spec,) = load_sweep(sweep)
    assert spec.config()["settings"]["time_limit"] == "terminal"
