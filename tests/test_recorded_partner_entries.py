"""A recorded partner is checked in full when its file is read, by the rule a policy is built by.

A result file's ``config.fixed`` (and an agent file's ``header.fixed``, an evaluation file's
``fixed``) records each partner as a label. Read back, the label must name a partner that can
exist: a registered policy, every argument one it declares, of its type and range, and every
partner it names (``partner``, ``members``) registered; a ``package.module:Name`` nested anywhere
is refused. Nothing is imported or built to tell. Building (``make_policy``) follows the same
declarations, so reading and building never disagree.
"""

from __future__ import annotations

import inspect
import json
import re
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from helpers_results import derive_run_id

from empathy_zoo.cli import main
from empathy_zoo.experiment.result_reader import read_result
from empathy_zoo.policies import POLICIES, entry_label, make_policy

ROOT = Path(__file__).resolve().parents[1]
SOURCE = ROOT / "docs/results/quick/runs/coexistence_v0__empathic_dqn-10853fdf__s0.json"
"""A shipped result file whose cat's recorded partner the tests replace."""
FIELD = "config.fixed.cat_0"

HOSTILE = [
    "slow_walk(move_probability=2)",
    "patrol(period=-1)",
    "slow_walk(__class__=1)",
    'noisy(noise=0.5, partner="evilmod:X")',
    'population(members=["stay", "evilmod:X"])',
    'noisy(partner="evilmod:X")',
    'population(members=["noisy", "evilmod.deep:Y"])',
    "teleport",
]
"""Labels no partner can have: out of range, an argument the policy does not take, a nested
``package.module:Name``, an unregistered name."""


def out_of_range_labels() -> Iterator[tuple[str, str]]:
    """``(policy, label)`` for every argument of every registered policy that declares its
    arguments: the label of that policy with that argument just outside its declared range (the
    declarations' own :meth:`~empathy_zoo.policy_parameters.Parameter.outside`)."""
    for name, policy in sorted(POLICIES.items()):
        defaults = {p.name: p.default for p in inspect.signature(policy).parameters.values()}
        for key, parameter in vars(policy).get("parameters", {}).items():  # (none before they were declared)
            yield name, entry_label({"policy": name, key: parameter.outside(defaults)})


def forged(tmp_path: Path, label: Any) -> Path:
    """A copy of :data:`SOURCE` whose cat trained beside ``label``, under the run id its changed
    config gives, without its agent file."""
    document = json.loads(SOURCE.read_text())
    document["config"]["fixed"] = {"cat_0": label}
    document.pop("agent", None)
    derive_run_id(document)
    runs = tmp_path / "runs"
    runs.mkdir(parents=True, exist_ok=True)
    path = runs / f"{document['run_id']}.json"
    path.write_text(json.dumps(document))
    return path


@pytest.mark.parametrize("label", HOSTILE + [label for _, label in out_of_range_labels()])
def test_a_partner_that_cannot_exist_is_refused_naming_the_file_and_field(tmp_path: Path, label: str) -> None:
    modules = set(sys.modules)
    path = forged(tmp_path, label)
    with pytest.raises(ValueError, match=re.escape(FIELD)) as refused:
        read_result(path)
    message = str(refused.value)
    assert "\n" not in message and str(path) in message
    assert not [module for module in set(sys.modules) - modules if module.startswith("evilmod")]


def test_every_registered_policy_with_arguments_has_an_out_of_range_label() -> None:
    named = {name for name, _ in out_of_range_labels()}
    assert named == {name for name, policy in POLICIES.items() if vars(policy)["parameters"]}
    assert {"patrol", "slow_walk", "chase", "keep_away", "nearest_battery", "noisy", "population"} <= named


@pytest.mark.parametrize("name", sorted(POLICIES))
def test_every_registered_policy_declares_exactly_its_signature(name: str) -> None:
    policy = POLICIES[name]
    signature = [p.name for p in inspect.signature(policy).parameters.values()]
    assert list(vars(policy)["parameters"]) == signature


@pytest.mark.parametrize("name", sorted(POLICIES))
def test_every_registered_policys_default_label_still_reads(tmp_path: Path, name: str) -> None:
    result = read_result(forged(tmp_path, name))
    assert result.config.fixed == {"cat_0": name}


@pytest.mark.parametrize("name, label", list(out_of_range_labels()))
def test_building_refuses_what_reading_refuses(name: str, label: str) -> None:
    from empathy_zoo.policies import parse_entry_label

    with pytest.raises(ValueError, match=f"cannot build fixed policy '{name}'"):
        make_policy(parse_entry_label(label))


def test_a_top_level_plugin_partner_is_still_read_as_text_and_never_imported(tmp_path: Path) -> None:
    label = "evilmod:X(speed=2)"
    result = read_result(forged(tmp_path, label))
    assert result.config.fixed == {"cat_0": label}
    assert "evilmod" not in sys.modules


def test_the_leaderboard_refuses_a_forged_partner_in_one_line_and_writes_nothing(tmp_path: Path, capsys) -> None:
    forged(tmp_path / "results", "slow_walk(move_probability=2)")
    out = tmp_path / "board"
    assert main(["leaderboard", str(tmp_path / "results"), "--out", str(out)]) == 2
    error = capsys.readouterr().err.strip()
    assert error.startswith("empathy-zoo: error:") and FIELD in error and "\n" not in error
    assert not out.exists()


def test_a_scenario_file_may_name_a_plugin_but_never_a_nested_one() -> None:
    from empathy_zoo.scenarios import parse_scenario_set

    def scenario_set(partner: Any) -> dict:
        return {
            "scenario_set": {"env": "coexistence_v0", "description": "d"},
            "scenarios": {"s": {"reason": "r", "fixed": {"cat_0": partner}}},
        }

    plugin = "helpers_policies:AlwaysLeft"
    assert parse_scenario_set(scenario_set(plugin), source="t", default_name="t").scenarios
    for nested in ({"policy": "noisy", "partner": plugin}, {"policy": "population", "members": ["stay", plugin]}):
        with pytest.raises(ValueError, match="is not registered"):
            parse_scenario_set(scenario_set(nested), source="t", default_name="t")
    with pytest.raises(ValueError, match="move_probability"):
        parse_scenario_set(scenario_set({"policy": "slow_walk", "move_probability": 2}), source="t", default_name="t")


def test_every_partner_a_shipped_result_file_records_still_reads(tmp_path: Path) -> None:
    """Each distinct ``config.fixed`` label of docs/results (the full read of every file is slow:
    the report of this change ran it), read in a file of its own."""
    labels = set()
    for path in (ROOT / "docs/results").glob("**/runs/*.json"):
        labels.update(json.loads(path.read_text())["config"]["fixed"].values())
    assert any("population(" in label for label in labels)
    for i, label in enumerate(sorted(labels)):
        assert read_result(forged(tmp_path / str(i), label)).config.fixed == {"cat_0": label}


@pytest.mark.parametrize("label", ["slow_walk(move_probability=2)", 'population(members=["stay", "evilmod:X"])'])
def test_an_agent_files_recorded_partner_is_checked_by_the_same_rule(tmp_path: Path, label: str) -> None:
    import torch

    from empathy_zoo import load_agent
    from empathy_zoo.run_ids import run_id

    document = torch.load(SOURCE.with_name(SOURCE.stem + ".agent.pt"), weights_only=True)
    header = document["header"]
    header["fixed"] = {"cat_0": label}
    config = {key: value for key, value in header.items() if key != "run_id"}
    header["run_id"] = run_id(header.get("variant") or header["env"], header["method"], config, header["seed"])
    path = tmp_path / "forged.agent.pt"
    torch.save(document, path)
    with pytest.raises(ValueError, match=re.escape("header.fixed.cat_0")) as refused:
        load_agent(path)
    assert "\n" not in str(refused.value) and "evilmod" not in sys.modules
