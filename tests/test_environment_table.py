"""One table of environments: every view the suite uses (engines, faces, default fixed agents,
Gymnasium ids) is read from ``empathy_zoo.environments.ENVIRONMENT_TABLE`` and agrees with it."""

from __future__ import annotations

import gymnasium
import pytest

import empathy_zoo
import empathy_zoo.gym_adapter  # noqa: F401 - registers the Gymnasium ids
from empathy_zoo.environments import DEFAULT_POLICIES, ENGINES, ENVIRONMENT_TABLE, GYM_IDS, face_module


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

    from empathy_zoo.environments import DEFAULT_ARGUMENTS

    parameters = inspect.signature(ENGINES[name]).parameters
    signature = {key: p.default for key, p in parameters.items() if key != "num_envs"}
    assert ENVIRONMENT_TABLE[name].arguments == DEFAULT_ARGUMENTS[name] == signature
