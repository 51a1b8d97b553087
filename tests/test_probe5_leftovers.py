"""A fifth probe's leftovers (issue 33, "files from elsewhere are inert"): an evaluation file's
partners only for agents its scenario's world holds."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import pytest

from empathy_zoo.evaluation_file import EvaluationFileError, check_evaluation

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
