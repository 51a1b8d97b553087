"""One table of environments: every view the suite uses (engines, faces, default fixed agents,
Gymnasium ids) is read from ``empathy_zoo.environments.ENVIRONMENT_TABLE`` and agrees with it, an
entry added at run time is in every view, and every metric an entry names has its facts in
``empathy_zoo.metrics``."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest
from helpers_meadow import MEADOW, MEADOW_ENTRY, register_meadow

import empathy_zoo
import empathy_zoo.gym_adapter  # registers the Gymnasium ids
from empathy_zoo.actions import NUM_ACTIONS
from empathy_zoo.environments import (
    DEFAULT_ARGUMENTS,
    DEFAULT_POLICIES,
    ENGINES,
    ENVIRONMENT_TABLE,
    FACES,
    GYM_IDS,
    entry_of,
    face_module,
)
from empathy_zoo.metrics import (
    DERIVED_METRICS,
    EFFECT_NAMES,
    EQUIVALENCE_MARGINS,
    HELDOUT_MARGINS,
    HIGHER_IS_BETTER,
    METRIC_DEFINITIONS,
    METRIC_NAMES,
    METRIC_RANGES,
)


@pytest.mark.parametrize("name", sorted(ENVIRONMENT_TABLE))
def test_every_view_agrees_with_the_table(name: str) -> None:
    entry = ENVIRONMENT_TABLE[name]
    face = face_module(name)
    assert empathy_zoo.ENVIRONMENTS[name] is face and face.raw_env.engine_class is entry.engine is ENGINES[name]
    assert face.parallel_env().metadata["name"] == name
    assert DEFAULT_POLICIES[name] == entry.fixed and set(entry.fixed) < set(entry.engine.agents)
    assert GYM_IDS[entry.gym_id] == name and gymnasium.spec(entry.gym_id).kwargs == {"env": name}


def test_the_views_hold_the_table_s_environments_only() -> None:
    assert (
        set(ENGINES) == set(DEFAULT_POLICIES) == set(GYM_IDS.values()) == set(empathy_zoo.ENVIRONMENTS) == set(ENVIRONMENT_TABLE)
    )
    with pytest.raises(ValueError, match="unknown environment 'atlantis_v0'"):
        face_module("atlantis_v0")


def test_changing_a_view_does_not_change_the_table() -> None:
    DEFAULT_POLICIES["coexistence_v0"]["cat_0"] = "stay"
    try:
        assert ENVIRONMENT_TABLE["coexistence_v0"].fixed == {"cat_0": "random_walk"}
    finally:
        DEFAULT_POLICIES["coexistence_v0"]["cat_0"] = "random_walk"


@pytest.mark.parametrize("name", sorted(ENVIRONMENT_TABLE))
def test_the_table_s_default_arguments_are_the_engine_s(name: str) -> None:
    import inspect

    parameters = inspect.signature(ENGINES[name]).parameters
    signature = {key: p.default for key, p in parameters.items() if key != "num_envs"}
    assert ENVIRONMENT_TABLE[name].arguments == DEFAULT_ARGUMENTS[name] == signature


def test_an_entry_added_at_run_time_is_in_every_view(monkeypatch: pytest.MonkeyPatch) -> None:
    register_meadow(monkeypatch)
    assert ENGINES[MEADOW] is MEADOW_ENTRY.engine and DEFAULT_POLICIES[MEADOW] == {"sheep_0": "random_walk"}
    assert DEFAULT_ARGUMENTS[MEADOW] == {"size": 7, "view": 5, "max_cycles": 500}
    assert GYM_IDS["empathy_zoo/Meadow-v0"] == MEADOW and FACES[MEADOW] is face_module(MEADOW)
    assert empathy_zoo.ENVIRONMENTS[MEADOW].raw_env.engine_class is MEADOW_ENTRY.engine
    assert entry_of("my_meadow", MEADOW) is MEADOW_ENTRY and entry_of("my_meadow") is None
    with pytest.raises(KeyError):
        GYM_IDS["empathy_zoo/Atlantis-v0"]


def test_every_metric_has_its_facts() -> None:
    assert set(HIGHER_IS_BETTER) == set(METRIC_RANGES) == set(METRIC_DEFINITIONS) == set(METRIC_NAMES)
    assert set(EQUIVALENCE_MARGINS) | set(EFFECT_NAMES) | set(HELDOUT_MARGINS) <= set(METRIC_NAMES)
    assert {numerator for numerator, _, _ in DERIVED_METRICS.values()} <= set(METRIC_NAMES)


@pytest.mark.parametrize("name", sorted(ENVIRONMENT_TABLE))
def test_every_metric_an_entry_names_is_a_metric(name: str) -> None:
    entry = ENVIRONMENT_TABLE[name]
    shown = {entry.task, *entry.side_effects, *entry.table_metrics, *entry.compact_metrics, *entry.reference_metrics}
    assert shown | {metric for metric, _ in entry.curves} <= set(METRIC_NAMES)
    assert set(entry.heldout_metrics) <= set(METRIC_NAMES) | set(DERIVED_METRICS)
    assert set(entry.side_effects) <= set(HELDOUT_MARGINS)  # (the held-out reading rule judges the first)
    assert entry.task_label and (entry.side_effect_label or not entry.side_effects)


@pytest.mark.parametrize("name", list(ENVIRONMENT_TABLE))
def test_the_entrys_reward_facts_hold_under_random_play(name: str) -> None:
    """``can_harm``, ``batteries`` and ``negative_rewards`` are what the engine does: 64 environments
    of random play for 1,500 steps never contradict them, and a fact said true is seen."""
    entry = ENVIRONMENT_TABLE[name]
    engine = entry.engine(64)
    engine.reset(seeds=list(range(64)))
    rng = np.random.default_rng(0)
    lowest, harms, batteries = 0.0, 0, 0.0
    for _ in range(1_500):
        events = engine.step(rng.integers(0, NUM_ACTIONS, size=(64, engine.num_agents)))
        lowest = min(lowest, float(events.rewards.min()))
        harms += int((events.harmed_by >= 0).sum())
        batteries = max(batteries, float(engine.episode_battery_return.max()))
        if events.episode_over.any():
            engine.reset(np.flatnonzero(events.episode_over))
    assert (harms > 0) == entry.can_harm, (name, harms)
    assert (batteries > 0) == entry.batteries, (name, batteries)
    if not entry.negative_rewards:
        assert lowest >= 0.0, (name, lowest)


def test_an_environments_title_comes_from_its_gym_id() -> None:
    assert [entry.title for entry in ENVIRONMENT_TABLE.values()] == ["Coexistence", "Sharing", "Charger", "Vase", "Helping"]
