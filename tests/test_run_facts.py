"""What the leaderboard reads of a result file (leaderboard.run_facts): the paper's setting, an
environment argument at its default, and the ε schedule as data."""

from __future__ import annotations

import dataclasses
from types import MappingProxyType

import pytest
from helpers_results import derive_run_id, record, synthetic_document, synthetic_result

from empathy_zoo.experiment.records import RunResult
from empathy_zoo.schedules import check_schedule, epsilon_at
from leaderboard.run_facts import empathic_selfishness, env_argument, exploration_of, in_paper_setting


def _with(document: dict, **env_kwargs) -> RunResult:
    """The run of ``document`` had it been built with ``env_kwargs``."""
    document["config"]["env_kwargs"] = env_kwargs
    return record(derive_run_id(document))


def test_the_paper_s_setting_is_every_argument_at_its_default_and_the_default_fixed_agents() -> None:
    run = synthetic_result("coexistence_v0", "empathic_dqn", 0.5, 0)
    assert in_paper_setting(run)
    assert in_paper_setting(_with(synthetic_document("coexistence_v0", "empathic_dqn", 0.5, 0), max_cycles=500, num_cats=1))
    shorter = _with(synthetic_document("coexistence_v0", "empathic_dqn", 0.5, 0), max_cycles=400)
    assert not in_paper_setting(shorter) and in_paper_setting(shorter, varying=("max_cycles",))
    assert not in_paper_setting(
        _with(synthetic_document("coexistence_v0", "empathic_dqn", 0.5, 0), num_cats=3), varying=("max_cycles",)
    )
    assert not in_paper_setting(synthetic_result("coexistence_v0", "empathic_dqn", 0.5, 0, fixed={"cat_0": "stay"}))
    assert in_paper_setting(_with(synthetic_document("sharing_v0", "empathic_dqn", 0.5, 0), start="random"))
    assert not in_paper_setting(_with(synthetic_document("sharing_v0", "empathic_dqn", 0.5, 0), start="centre"))


def test_an_environment_argument_is_the_run_s_or_its_environment_s_default() -> None:
    run = _with(synthetic_document("sharing_v0", "empathic_dqn", 0.5, 0), max_cycles=40)
    assert env_argument(run, "max_cycles") == 40 and env_argument(run, "inventory_encoding") == "count_plus_one"
    with pytest.raises(ValueError, match="environment 'sharing_v0' has no argument 'num_cats'"):
        env_argument(run, "num_cats")


def test_empathic_dqn_s_runs_are_those_of_its_target_on_the_environment_s_reward() -> None:
    assert empathic_selfishness(synthetic_result("coexistence_v0", "empathic_dqn", 0.5, 0)) == 0.5
    assert empathic_selfishness(synthetic_result("coexistence_v0", "dqn", 1.0, 0)) == 1.0
    for method in ("empathic_dqn_in_view", "empathic_dqn_silver", "dqn_harm_penalty"):
        assert empathic_selfishness(synthetic_result("coexistence_v0", method, 1.0, 0)) is None, method
    run = synthetic_result("coexistence_v0", "empathic_dqn", 0.5, 0)  # (as a method that declares no schedule describes it)
    described = MappingProxyType({**run.config.description, "exploration": None})
    run = dataclasses.replace(run, config=dataclasses.replace(run.config, description=described))
    assert empathic_selfishness(run) is None
    with pytest.raises(ValueError, match="records no exploration schedule"):
        exploration_of(run)


def test_a_schedule_is_checked_and_followed() -> None:
    schedule = {"kind": "linear", "start": 1.0, "end": 0.1, "warmup": 10, "decay_steps": 90}
    assert [epsilon_at(schedule, step) for step in (0, 9, 10, 55, 100, 1000)] == pytest.approx([1.0, 1.0, 1.0, 0.55, 0.1, 0.1])
    for bad, message in (
        ({**schedule, "kind": "cosine"}, "kind one of"),
        ({k: v for k, v in schedule.items() if k != "warmup"}, "has the fields kind, start, end, warmup, decay_steps"),
        ({**schedule, "end": "low"}, "end must be a number"),
        ({**schedule, "decay_steps": 0}, "decay_steps must be at least 1"),
    ):
        with pytest.raises(ValueError, match=message):
            check_schedule(bad)
