"""A fifth probe's leftovers (issue 33, "files from elsewhere are inert"): an evaluation file's
partners only for agents its scenario's world holds; a checkpoint's saved stream keys rederived
from the seeds of the runs it resumes."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from empathy_zoo.evaluation_file import EvaluationFileError, check_evaluation
from empathy_zoo.fixed_agents import policy_seed
from empathy_zoo.partner_policies import Population
from empathy_zoo.policies import batched, make_policy
from empathy_zoo.vector import VectorEnv

DOCS = Path(__file__).resolve().parents[1] / "docs" / "results"
THREE_CATS = DOCS / "methods" / "evaluations" / "coexistence_v0" / "coexistence_3cats__dqn-8e5a283c__s0.json"


# ---------------------------------------------------------------------------- evaluation partners (#13)
def three_cats_evaluation() -> dict[str, Any]:
    """A shipped evaluation of a run beside three cats: ``trained_with`` holds cat_0 … cat_2, and
    its scenarios (one cat unless they say otherwise) their own."""
    return json.loads(THREE_CATS.read_text())


def test_the_shipped_evaluation_passes() -> None:
    check_evaluation(three_cats_evaluation(), THREE_CATS)


@pytest.mark.parametrize(
    "where, agent",
    [
        (("scenarios", 0, "fixed"), "cat_3"),  # the run's world: three cats
        (("scenarios", 1, "fixed"), "cat_1"),  # cat_stays: one cat
        (("scenarios", 1, "fixed"), "human_0"),  # no human in Coexistence
        (("scenarios", 1, "fixed"), "robot_0"),  # the learner is no partner
        (("scenarios", 1, "fixed"), "cat_01"),
        (("scenario_set", "scenarios", 0, "fixed"), "cat_1"),  # the set's definition of cat_stays
        (("scenario_set", "scenarios", 4, "fixed"), "cat_2"),  # two_random_cats: cat_0, cat_1
    ],
)
def test_an_evaluation_partner_for_an_agent_its_world_lacks_is_refused(where: tuple[Any, ...], agent: str) -> None:
    document = copy.deepcopy(three_cats_evaluation())
    table = document
    for key in where:
        table = table[key]
    table[agent] = "random_walk"
    with pytest.raises(EvaluationFileError) as refused:
        check_evaluation(document, "forged.json")
    message = str(refused.value)
    assert message.startswith("forged.json: field ") and f"(the agent {agent!r})" in message and "\n" not in message


def test_an_evaluation_partner_numbered_within_a_huge_count_is_checked_without_listing_them() -> None:
    document = copy.deepcopy(three_cats_evaluation())
    definition = document["scenario_set"]["scenarios"][0]  # (a definition's grid is checked when played)
    definition["env_kwargs"]["num_cats"] = 10**9
    definition["fixed"]["cat_999999999"] = "stay"
    check_evaluation(copy.deepcopy(document), "forged.json")
    definition["fixed"]["cat_1000000000"] = "stay"
    with pytest.raises(EvaluationFileError, match=r"'cat_1000000000'"):
        check_evaluation(document, "forged.json")


# ---------------------------------------------------------------------------- saved stream keys (#6)
SEED = 2024
"""The seed of every policy's last seeded reset below."""


def _stepped(policy: Any, steps: int = 7) -> Any:
    """``policy`` reset with :data:`SEED` and acted ``steps`` times: its key is the seed's, its count moved."""
    policy.reset(SEED)
    for _ in range(steps):
        policy.act(np.zeros(25, dtype=np.float32), {"step": 0, "agent": "cat_0", "size": 7, "positions": {}})
    return policy


@pytest.mark.parametrize("name", ["random_walk", "slow_walk", "noisy"])
def test_a_streams_saved_key_is_rederived_from_its_seed(name: str) -> None:
    policy: Any = _stepped(make_policy(name))
    state = policy.state()
    assert policy.saved_key_problem(state, SEED) is None
    forged = {**state, "key": state["key"] ^ 1}  # (a 64-bit key still: load_state alone takes it)
    fresh: Any = make_policy(name)
    fresh.load_state(forged)
    assert policy.saved_key_problem(forged, SEED) == f"key is {forged['key']}, not {state['key']}, the key its seed gives"
    assert policy.saved_key_problem({**state, "key": None}, SEED) is not None  # (None would draw a fresh key)
    assert policy.saved_key_problem(state, SEED + 1) is not None


def test_a_populations_saved_keys_are_rederived_its_own_and_its_first_members() -> None:
    population = Population(["random_walk", "slow_walk"])
    _stepped(population)
    state = population.state()
    first = population.member
    assert population.saved_key_problem(state, SEED) is None
    forged = {**state, "key": state["key"] ^ 1}
    assert str(population.saved_key_problem(forged, SEED)).startswith("key is ")
    members = copy.deepcopy(state["members"])
    members[first]["key"] ^= 1
    assert str(population.saved_key_problem({**state, "members": members}, SEED)).startswith(f"members[{first}].key is ")


def test_a_batched_streams_saved_keys_are_rederived_per_environment() -> None:
    fast: Any = batched(make_policy("random_walk"), 3)
    seeds = [policy_seed(s, 1) for s in (5, 6, 7)]
    fast.reset(np.arange(3), seeds)
    fast.act(None, np.zeros(3, dtype=np.int64), np.ones(3, dtype=bool))
    state = fast.state()
    assert fast.saved_key_problem(state, seeds) is None
    keys = state["keys"].copy()
    keys[2] ^= np.uint64(1)
    assert fast.saved_key_problem({**state, "keys": keys}, seeds).startswith("keys[2] is ")
    assert fast.saved_key_problem({**state, "keys": keys}, [*seeds[:2], None]) is None  # (never seeded: not judged)
    copies: Any = batched(make_policy("noisy"), 2)  # (the generic path: one copy per environment)
    copies.reset(np.arange(2), seeds[:2])
    saved = copies.state()
    assert copies.saved_key_problem(saved, seeds[:2]) is None
    saved["copies"][1]["key"] ^= 1
    assert copies.saved_key_problem(saved, seeds[:2]).startswith("copies[1].key is ")


def test_a_vector_envs_saved_key_is_judged_against_the_seeds_it_was_reset_with() -> None:
    venv = VectorEnv("coexistence_v0", 2, fixed={"cat_0": "random_walk"})
    venv.reset(seed=[11, 12])
    venv.step(np.zeros((2, 1), dtype=np.int64))
    state = venv.state()
    fresh = VectorEnv("coexistence_v0", 2, fixed={"cat_0": "random_walk"})
    fresh.reset(seed=[11, 12])
    assert fresh.saved_key_problem(state) is None
    state["policies"]["cat_0"]["keys"][1] ^= np.uint64(1)
    assert str(fresh.saved_key_problem(state)).startswith("policies.cat_0.keys[1] is ")
    unseeded = VectorEnv("coexistence_v0", 2, fixed={"cat_0": "random_walk"})
    unseeded.reset()
    assert unseeded.saved_key_problem(state) is None  # (reset without seeds: no key to rederive)
