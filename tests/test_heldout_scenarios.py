"""Scenario sets (empathy_zoo.scenarios): the shipped ones parse and cover what they promise, each
scenario with its reason; a file that sets the window or anything unknown is refused naming file,
table and key; a run's own partners read back from its result file; a scenario lives in the run's world."""

from __future__ import annotations

import pytest
from helpers_results import derive_run_id, record, synthetic_document

from empathy_zoo.environments import ENVIRONMENT_TABLE
from empathy_zoo.experiment.values import SweepConfigError
from empathy_zoo.policies import entry_label
from empathy_zoo.scenarios import (
    TRAINED_WITH,
    default_set_name,
    load_scenario_set,
    parse_entry_label,
    parse_scenario_set,
    scenario_set_path,
    shipped_sets,
    trained_with,
)

COEXISTENCE_PARTNERS = {
    "cat_stays": {"cat_0": "stay"},
    "cat_rarely_moves": {"cat_0": "slow_walk(move_probability=0.1)"},
    "cat_chases": {"cat_0": "chase"},
    "cat_keeps_away": {"cat_0": "keep_away"},
    "two_random_cats": {"cat_0": "random_walk", "cat_1": "random_walk"},
    "three_random_cats": {f"cat_{i}": "random_walk" for i in range(3)},
    "larger_grid": {"cat_0": "random_walk"},
}
SHARING_PARTNERS = {
    "human_walks_randomly": {"human_0": "random_walk"},
    "human_seeks_batteries": {"human_0": "nearest_battery"},
    "patrol_every_third_step": {"human_0": "patrol(period=3)"},
    "patrol_reversed": {"human_0": "patrol(first=1, then=2)"},
    "human_stays": {"human_0": "stay"},
    "two_humans": {"human_0": "patrol", "human_1": "patrol"},
}


SPLITS = tuple(f"{env}_{split}" for env in sorted(ENVIRONMENT_TABLE) for split in ("test", "validation"))
SHIPPED = sorted(["charger_v0", "coexistence_v0", "coexistence_v0_noisy", "helping_v0", "sharing_v0", "vase_v0", *SPLITS])
"""Every shipped set: the defaults, the noisy set and each environment's validation and test splits."""


def test_one_default_set_ships_per_environment_and_coexistence_has_its_noisy_set() -> None:
    assert shipped_sets() == SHIPPED
    assert [default_set_name(env) for env in ENVIRONMENT_TABLE] == list(ENVIRONMENT_TABLE)


def test_the_noisy_set_holds_the_noisy_chaser_and_fleer() -> None:
    noisy = load_scenario_set("coexistence_v0_noisy")
    assert noisy.env == "coexistence_v0" and noisy.name == "coexistence_v0_noisy"
    assert {s.name: s.definition()["fixed"] for s in noisy.scenarios} == {
        "cat_chases_noisily": {"cat_0": 'noisy(noise=0.2, partner="chase")'},
        "cat_keeps_away_noisily": {"cat_0": 'noisy(noise=0.2, partner="keep_away")'},
    }


@pytest.mark.parametrize("name, partners", [("coexistence_v0", COEXISTENCE_PARTNERS), ("sharing_v0", SHARING_PARTNERS)])
def test_the_shipped_sets_hold_their_partners_each_with_a_reason(name, partners) -> None:
    scenario_set = load_scenario_set(name)
    assert scenario_set.env == name and scenario_set.name == name
    assert {s.name: s.definition()["fixed"] for s in scenario_set.scenarios} == partners
    for scenario in scenario_set.scenarios:
        assert len(scenario.reason) > 20 and "\n" not in scenario.reason
    assert load_scenario_set(scenario_set_path(name)).definition() == scenario_set.definition()


def test_the_larger_grid_is_larger() -> None:
    (larger,) = [s for s in load_scenario_set("coexistence_v0").scenarios if s.name == "larger_grid"]
    assert larger.variant.kwargs == {"size": 11}


def parse(text: str, tmp_path):
    path = tmp_path / "mine.toml"
    path.write_text(text)
    return load_scenario_set(path)


HEADER = '[scenario_set]\nenv = "coexistence_v0"\n'


@pytest.mark.parametrize(
    "body, message",
    [
        (
            '[scenarios.small]\nreason = "r"\nview = 3\n',
            r"mine.toml: \[scenarios.small\] view: a scenario cannot set view: it changes the size",
        ),
        ('[scenarios.s]\nreason = "r"\nspeed = 3\n', r"\[scenarios.s\]: unknown key 'speed'"),
        ('[scenarios.s]\nfixed = { cat_0 = "stay" }\n', r"\[scenarios.s\] reason: every scenario needs a one-line reason"),
        (
            '[scenarios.s]\nreason = "r"\nfixed = { cat_0 = "teleport" }\n',
            r"\[scenarios.s\] fixed.cat_0: .*unknown fixed policy 'teleport'",
        ),
        ('[scenarios.s]\nreason = "r"\nfixed = { cat_1 = "stay" }\n', r"\[scenarios.s\] fixed: unknown agent"),
        ('[scenarios.s]\nreason = "r"\nsize = "big"\n', r"\[scenarios.s\] size: expected int"),
        ('[scenarios.trained_with]\nreason = "r"\n', "is the name of every run's own partners"),
        ("", r"declare at least one \[scenarios.<name>\]"),
    ],
)
def test_a_bad_scenario_is_refused_naming_file_table_and_key(body, message, tmp_path) -> None:
    with pytest.raises(SweepConfigError, match=message):
        parse(HEADER + body, tmp_path)


def test_the_inventory_encoding_is_refused_too(tmp_path) -> None:
    text = '[scenario_set]\nenv = "sharing_v0"\n[scenarios.s]\nreason = "r"\ninventory_encoding = "authors"\n'
    with pytest.raises(SweepConfigError, match="cannot set inventory_encoding: it changes what the values"):
        parse(text, tmp_path)


@pytest.mark.parametrize(
    "text, message",
    [
        ('[scenarios.s]\nreason = "r"\n', r"declare a \[scenario_set\] table"),
        ('[scenario_set]\nenv = "maze_v0"\n[scenarios.s]\nreason = "r"\n', "unknown environment 'maze_v0'"),
        ('[scenario_set]\n[scenarios.s]\nreason = "r"\n', "missing key 'env'"),
        (
            '[scenario_set]\nenv = "coexistence_v0"\nname = "../up"\n[scenarios.s]\nreason = "r"\n',
            "cannot be part of a file name",
        ),
    ],
)
def test_a_bad_set_header_is_refused(text, message, tmp_path) -> None:
    with pytest.raises(SweepConfigError, match=message):
        parse(text, tmp_path)


def test_an_unknown_set_name_lists_the_shipped_ones() -> None:
    shipped = ", ".join(SHIPPED)
    with pytest.raises(SweepConfigError, match=f"unknown scenario set 'mine'; shipped: {shipped}"):
        load_scenario_set("mine")


def test_a_users_set_takes_its_name_from_the_file_and_its_agents_the_defaults(tmp_path) -> None:
    scenario_set = parse(
        HEADER + '[scenarios.pair]\nreason = "Two cats, one still."\nnum_cats = 2\nfixed = { cat_1 = "stay" }\n', tmp_path
    )
    assert scenario_set.name == "mine"
    (pair,) = scenario_set.scenarios
    assert pair.definition() == {
        "name": "pair",
        "reason": "Two cats, one still.",
        "env_kwargs": {"num_cats": 2},
        "fixed": {"cat_0": "random_walk", "cat_1": "stay"},
    }


def test_a_scenario_lives_in_the_runs_world_with_its_own_partners() -> None:
    scenario_set = parse_scenario_set(
        {"scenario_set": {"env": "coexistence_v0"}, "scenarios": {"alone": {"reason": "r", "fixed": {"cat_0": "stay"}}}},
        "x.toml",
        "x",
    )
    (alone,) = scenario_set.scenarios
    variant = alone.for_run({"size": 9, "max_cycles": 60, "num_cats": 3})
    assert variant.kwargs == {"size": 9, "max_cycles": 60}  # the run's world, the scenario's one cat
    assert variant.fixed_policies() == {"cat_0": "stay"}


@pytest.mark.parametrize(
    "entry",
    [
        "random_walk",
        {"policy": "patrol", "period": 3},
        {"policy": "patrol", "first": 1, "then": 2},
        {"policy": "x.y:Z", "k": [1, {"a": "b, c"}]},
    ],
)
def test_a_policy_label_reads_back_as_its_entry(entry) -> None:
    assert parse_entry_label(entry_label(entry)) == entry


@pytest.mark.parametrize(
    "label", ["", "patrol(", "patrol(period=)", "patrol(period=3,period=4)", "(period=3)", "patrol(period=3)x)"]
)
def test_a_malformed_label_is_refused(label) -> None:
    with pytest.raises(ValueError):
        parse_entry_label(label)


def test_the_runs_own_partners_come_from_its_result_file() -> None:
    result = synthetic_document("sharing_v0", "dqn", 1.0, 0, fixed={"human_0": "patrol(period=3)"})
    result["config"]["env_kwargs"] = {"max_cycles": 50}
    own = trained_with(record(derive_run_id(result)))
    assert own.name == TRAINED_WITH
    assert own.variant.fixed_policies() == {"human_0": {"policy": "patrol", "period": 3}}
    assert own.for_run(result["config"]["env_kwargs"]).kwargs == {"max_cycles": 50}


def test_the_docs_example_set_parses(tmp_path) -> None:
    import re
    from pathlib import Path

    page = (Path(__file__).resolve().parents[1] / "docs" / "heldout.md").read_text(encoding="utf-8")
    (block,) = re.findall(r"^```toml\n# file: my_partners.toml\n(.*?)^```", page, re.MULTILINE | re.DOTALL)
    scenario_set = parse(block, tmp_path)
    assert scenario_set.name == "my_partners"
    assert {s.name: s.definition()["fixed"] for s in scenario_set.scenarios} == {
        "sleepy_cat": {"cat_0": "slow_walk(move_probability=0.02)"},
        "cat_and_chaser": {"cat_0": "random_walk", "cat_1": "chase(every=2)"},
    }


def test_an_empty_set_name_is_refused() -> None:
    with pytest.raises(SweepConfigError, match="got an empty name"):
        load_scenario_set("")
