"""A run's description (``config.description``, result schema 3): what its method declares, what
an older file is given when it is read, and a plug-in method the leaderboard has never heard of
grouped, compared and given the reference by what it declares."""

from __future__ import annotations

import json
import re
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import pytest
from helpers_described_method import KIND_DQN, NAME, KindSettings, kind_document, kind_result
from helpers_results import synthetic_document, synthetic_result

from agents.base import Method
from agents.rewards import transform_config
from agents.settings import EmpathicDQNSettings
from baselines.registry import METHODS, get_method
from empathy_zoo.atomic import read_json, write_json_atomic
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.experiment.result_reader import check_result, read_result
from empathy_zoo.method_description import DESCRIPTION_FIELDS, check_description
from empathy_zoo.result_file import SCHEMA_2_METHODS, ResultFileError, schema_2_description
from empathy_zoo.schedules import epsilon_at, linear_epsilon
from leaderboard.improvement import improvements_over_dqn, is_dqn
from leaderboard.reference_curves import reference_curve
from leaderboard.reproduction import assess_claims, paper_runs
from leaderboard.sensitivity import sensitivity_rows

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results"


@dataclass(frozen=True)
class Plain:
    """Settings of a method that describes nothing."""

    width: int = 8
    """A setting."""


class Learner:
    """Stands in for a learner."""


# ------------------------------------------------------------------------------ what a method declares
def test_a_method_that_declares_nothing_gets_its_name_and_nothing_else() -> None:
    method = Method(name="mine", learner=Learner, settings=Plain)
    assert method.describe(Plain(), None) == {
        "family": "mine",
        "dqn_reference": False,
        "selfishness": None,
        "target": None,
        "in_view_only": False,
        "gamma": None,
        "exploration": None,
        "reward": None,
    }
    assert set(DESCRIPTION_FIELDS) == set(method.describe(Plain(), None))


def test_empathic_dqn_s_settings_give_beta_gamma_and_the_schedule_the_learner_explores_by() -> None:
    settings = EmpathicDQNSettings(selfishness=0.25, gamma=0.9, learning_starts=100, epsilon_decay_steps=1000, epsilon_end=0.05)
    described = get_method("empathic_dqn").describe(settings, None)
    assert described["family"] == "empathic_dqn" and described["target"] == "golden"
    assert (described["selfishness"], described["gamma"], described["dqn_reference"]) == (0.25, 0.9, False)
    assert described["exploration"] == {"kind": "linear", "start": 1.0, "end": 0.05, "warmup": 100, "decay_steps": 1000}
    for step in (0, 99, 100, 101, 600, 1099, 1100, 10**7):
        assert epsilon_at(described["exploration"], step) == linear_epsilon(settings, step)  # the same number, bit for bit
    assert json.loads(json.dumps(described)) == described  # plain JSON data


@pytest.mark.parametrize(
    ("name", "overrides", "family", "target", "in_view_only", "reference"),
    [
        ("empathic_dqn", {}, "empathic_dqn", "golden", False, True),  # β = 1 on the environment's reward
        ("empathic_dqn", {"selfishness": 0.5}, "empathic_dqn", "golden", False, False),
        ("dqn", {}, "dqn", "golden", False, True),
        ("empathic_dqn_in_view", {}, "empathic_dqn", "golden", True, False),
        ("empathic_dqn_silver", {"selfishness": 0.5}, "empathic_dqn", "silver", False, False),
        ("dqn_harm_penalty", {}, "dqn", "golden", False, False),  # a reward transform: never the reference
        ("sb3_dqn", {}, "sb3", None, False, False),
    ],
)
def test_the_built_in_methods_describe_themselves(name, overrides, family, target, in_view_only, reference) -> None:
    method = get_method(name)
    described = method.describe(method.make_settings(overrides), method.make_reward({}))
    assert (described["family"], described["target"], described["in_view_only"]) == (family, target, in_view_only)
    assert described["dqn_reference"] is reference
    if name == "dqn_harm_penalty":
        assert described["reward"] == {"name": "harm_penalty", "penalty": -100.0}
    if name == "sb3_dqn":
        assert described["selfishness"] is None and described["exploration"] is None


def test_a_settings_class_describes_only_what_it_may() -> None:
    @dataclass(frozen=True)
    class Boastful:
        def describe(self) -> dict:
            return {"selfishness": 0.5, "family": "not mine to say"}

    with pytest.raises(ValueError, match=r"method 'boast': its settings describe \['family'\]"):
        Method(name="boast", learner=Learner, settings=Boastful).describe(Boastful(), None)

    @dataclass(frozen=True)
    class Overcaring:
        def describe(self) -> dict:
            return {"selfishness": 1.5}

    with pytest.raises(ValueError, match="method 'over': description field selfishness: expected a number in"):
        Method(name="over", learner=Learner, settings=Overcaring).describe(Overcaring(), None)


def test_a_plug_in_declares_its_family_and_beta() -> None:
    described = KIND_DQN.describe(KindSettings(care=0.5), None)
    assert (described["family"], described["selfishness"], described["target"], described["dqn_reference"]) == (
        "kind_dqn",
        0.5,
        "golden",
        False,
    )
    assert KIND_DQN.describe(KindSettings(), None)["dqn_reference"] is True  # care 0: β = 1


# ------------------------------------------------------------------------------ older files
@pytest.mark.parametrize("name", sorted(SCHEMA_2_METHODS))
def test_the_schema_2_upgrade_gives_every_built_in_the_description_it_gives_a_run_now(name: str) -> None:
    method = METHODS[name]  # (every method of schema 2 is still registered)
    overrides = {"selfishness": 0.5} if "selfishness" not in method.preset and method.settings is EmpathicDQNSettings else {}
    settings, reward = method.make_settings(overrides), method.make_reward({})
    config = json.loads(json.dumps({"settings": asdict(settings), "reward": transform_config(reward)}))
    assert schema_2_description(name, config) == json.loads(json.dumps(method.describe(settings, reward)))


@pytest.mark.parametrize(("directory", "schema"), [("methods", 3), ("quick", 3)])
def test_a_file_reads_with_the_description_a_fresh_run_of_its_config_gets(directory: str, schema: int) -> None:
    """A shipped schema-3 file holds the description a fresh run of its config gets (the upgrades of
    schema-1 and -2 files are tested on hand-made ones above)."""
    paths = sorted((RESULTS / directory / "runs").glob("*__s0.json"))
    assert paths
    for path in paths:
        raw = read_json(path)
        assert raw["schema"] == schema and ("description" in raw["config"]) == (schema == 3)
        result = read_result(path)
        assert result.schema == 3 and result.run_id == raw["run_id"]
        config = raw["config"]
        method = get_method(config["method"])
        settings = method.make_settings(config["settings"])
        reward = method.make_reward({k: v for k, v in (config["reward"] or {}).items() if k != "name"})
        assert result.to_document()["config"]["description"] == json.loads(json.dumps(method.describe(settings, reward))), (
            path.name
        )


def test_the_description_is_no_part_of_a_run_s_id() -> None:
    from empathy_zoo.experiment.model import RunSpec

    for path in sorted((RESULTS / "quick" / "runs").glob("*.json"))[:6]:
        raw = read_json(path)
        c = raw["config"]
        spec = RunSpec.of(
            env=c["env"],
            method=c["method"],
            settings=c["settings"],
            reward={k: v for k, v in (c["reward"] or {}).items() if k != "name"},
            seed=c["seed"],
            steps=c["steps"],
            eval_interval=c["eval_interval"],
            eval_episodes=c["eval_episodes"],
            fixed=c["fixed"],
            env_kwargs=c["env_kwargs"],
        )
        assert spec.run_id == raw["run_id"]
        assert spec.config()["description"] == read_result(path).config.description


def test_an_unknown_method_of_an_older_file_is_described_as_declaring_nothing() -> None:
    described = schema_2_description("my_plugins:MINE", {"settings": {"selfishness": 0.5}, "reward": {"name": "mine"}})
    assert described == {**check_description(described), "family": "my_plugins:MINE", "selfishness": None}
    assert described["reward"] == {"name": "mine"} and described["exploration"] is None


def test_a_schema_3_file_needs_a_well_formed_description(tmp_path: Path) -> None:
    run = synthetic_document("coexistence_v0", "dqn", 1.0, 0)
    run["config"]["description"]["exploration"] = {"kind": "cosine"}
    with pytest.raises(ResultFileError, match=r"r\.json: field config\.description\.exploration: expected an exploration"):
        check_result(run, tmp_path / "r.json")
    del run["config"]["description"]
    with pytest.raises(ResultFileError, match=re.escape("field config.description: missing")):
        check_result(run, tmp_path / "r.json")


# ------------------------------------------------------------------------------ the leaderboard
def _kind_paper_sweep() -> list[RunResult]:
    """The paper's sweep with the plug-in in Empathic DQN's place (the same numbers)."""
    runs = []
    for seed in range(5):
        for beta, harms, survival in ((1.0, 0.9, 490), (0.75, 0.5, 480), (0.5, 0.0, 475), (0.25, 0.0, 470)):
            runs.append(kind_result("coexistence_v0", beta, seed, harms=harms, survival=survival))
        runs.append(synthetic_result("coexistence_v0", "dqn_harm_penalty", 1.0, seed, harms=0.2, survival=470))
        for beta, batteries, eq in ((1.0, 6, 0.5), (0.75, 5, 0.8), (0.5, 4.5, 0.95), (0.25, 3, 0.85)):
            runs.append(kind_result("sharing_v0", beta, seed, batteries=batteries, other_batteries=9 - batteries, equality=eq))
        runs.append(synthetic_result("sharing_v0", "dqn_equality", 1.0, seed, batteries=4.5, equality=0.97))
    return runs


def test_the_plug_in_is_judged_as_empathic_dqn_by_what_it_declares() -> None:
    from test_reproduction import _paper_like, fake_reference

    runs = _kind_paper_sweep()
    groups = paper_runs(runs)
    assert sorted(groups["coexistence_v0"]) == ["dqn_harm_penalty", "β=0.25", "β=0.5", "β=0.75", "β=1"]
    assert {run.method for run in groups["sharing_v0"]["β=0.5"]} == {NAME}
    claims = assess_claims(runs, reference=fake_reference)
    assert claims == assess_claims(_paper_like(), reference=fake_reference)  # as Empathic DQN with the same numbers
    rows = sensitivity_rows(runs)
    assert list(rows) == [("random", "count_plus_one", "patrol")] and sorted(
        rows[("random", "count_plus_one", "patrol")]["greedy"]["batteries"]
    ) == [
        0.25,
        0.5,
        0.75,
        1.0,
    ]


def test_the_plug_in_at_beta_1_is_the_dqn_every_other_method_is_compared_with() -> None:
    dqn = [kind_result("coexistence_v0", 1.0, seed, survival=100.0 + seed) for seed in range(5)]
    better = [synthetic_result("coexistence_v0", "empathic_dqn", 0.5, seed, survival=300.0 + seed) for seed in range(5)]
    assert all(is_dqn(run) for run in dqn) and not any(is_dqn(run) for run in better)
    cells = improvements_over_dqn(dqn + better, {"coexistence_v0": ["survival"]})
    assert {cell.method_label for cell in cells} == {"empathic_dqn 0.5"}
    assert all(cell.probability == 1.0 for cell in cells)


def test_the_plug_in_gets_the_reference_of_its_beta() -> None:
    steps = np.array([50.0, 2000.0, 10_000.0])
    kind = reference_curve([kind_result("coexistence_v0", 0.5, seed) for seed in range(2)], "harms", steps)
    empathic = reference_curve(
        [synthetic_result("coexistence_v0", "empathic_dqn", 0.5, seed) for seed in range(2)], "harms", steps
    )
    assert kind is not None and empathic is not None and kind.tolist() == empathic.tolist()


def test_the_leaderboard_shows_the_plug_in_s_rows(tmp_path: Path) -> None:
    from leaderboard.report import write_leaderboard

    runs = [
        kind_document("coexistence_v0", beta, seed, survival=400.0 if beta == 1.0 else 410.0)
        for beta in (1.0, 0.5)
        for seed in range(4)
    ]
    runs += [synthetic_document("coexistence_v0", "empathic_dqn", 0.25, seed, survival=450.0) for seed in range(4)]
    for run in runs:
        write_json_atomic(tmp_path / "runs" / f"{run['run_id']}.json", run)
    markdown = write_leaderboard(tmp_path)["markdown"].read_text(encoding="utf-8")
    tables, improvements = markdown.split("### P(improves on DQN): Final greedy evaluation")
    assert "| DQN | 4 |" in tables and "| Kind DQN (care=0.5) | 4 |" in tables  # (its DQN reference is shown as DQN)
    assert "Kind DQN (care=0)" in markdown  # (the reference note names the file's label)
    compared = improvements.split("### P(improves on DQN): Training")[0]  # every method but the DQN, the plug-in at β = 1
    assert "| empathic_dqn 0.25 | 4 | ▲ 1.00" in compared and "| Kind DQN (care=0.5) | 4 |" in compared
    assert "Kind DQN (care=0) |" not in compared
