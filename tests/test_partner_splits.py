"""Every environment ships a train / validation / test split of partners (docs/heldout.md):
the training population in the populations profile, the other two as scenario sets; their
members are disjoint, and the test set holds nothing a robot trained or was selected with."""

from __future__ import annotations

import pytest

from empathy_zoo.environments import ENVIRONMENT_TABLE
from empathy_zoo.experiment.sweep_file import load_sweep, profile_path
from empathy_zoo.scenarios import load_scenario_set

NOISY_DEFAULT_PARTNER = "chase"
"""The partner a ``noisy`` member wraps with its defaults (empathy_zoo.partner_policies.Noisy)."""


def _training_members() -> dict[str, set[str]]:
    """``{env: members}`` of the populations profile's training populations."""
    found: dict[str, set[str]] = {}
    for spec in load_sweep(profile_path("populations")):
        (entry,) = spec.variant.fixed.values()
        found[spec.env] = set(entry["members"])
    return found


def _members(name: str) -> tuple[set[str], set[str]]:
    """The population scenario's members and the single-member scenarios' partners of a set."""
    scenario_set = load_scenario_set(name)
    population: set[str] = set()
    alone: set[str] = set()
    for scenario in scenario_set.scenarios:
        (entry,) = scenario.variant.fixed.values()
        if isinstance(entry, str):
            alone.add(entry)
        else:
            assert entry["policy"] == "population"
            population |= set(entry["members"])
    return population, alone


@pytest.mark.parametrize("env", sorted(ENVIRONMENT_TABLE))
def test_the_three_splits_are_disjoint(env: str) -> None:
    train = _training_members()[env]
    validation, validation_alone = _members(f"{env}_validation")
    test, test_alone = _members(f"{env}_test")
    assert validation and test and train
    assert validation == validation_alone and test == test_alone  # each member also played alone
    assert not train & validation and not train & test and not validation & test
    near = train | validation | ({NOISY_DEFAULT_PARTNER} if "noisy" in validation | train else set())
    assert not test & near  # nothing in the test set is a partner met or a noisy copy of one


@pytest.mark.parametrize("env", sorted(ENVIRONMENT_TABLE))
def test_the_training_population_holds_the_default_partner(env: str) -> None:
    (default,) = ENVIRONMENT_TABLE[env].fixed.values()
    assert default in _training_members()[env]
