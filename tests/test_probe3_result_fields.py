"""Forged fields of result, evaluation and scenario files, refused when read, in one line naming the
file and the field (a hostile probe's findings; every file is data, checked before it is used).

* A count (harms, batteries, other_batteries) is at most what one episode holds: ``max_cycles``
  times what one step adds (:data:`empathy_zoo.metrics.COUNT_PER_STEP`), so no sum overflows;
  harms at most each other agent once (and Vase's vase), none and no battery where the environment
  table says its environment has none.
* A registered method's settings are of the types its settings class declares and within range;
  ``config.description`` (its exploration schedule within range) says what the method describes a
  run of those settings as: a β or a DQN reference that contradicts them is refused.
* A run id ends with ``__s<seed>`` of the file's seed, and a result file is named ``<run id>.json``.
* A scenario file's text is what an evaluation file of it may record (no U+2028), ``held_out`` of a
  scenario set is true or left out, and an evaluation's scenario is held out exactly when it is not
  the run's own world (one said not held out in another world is refused when read; one said held
  out in its run's own world when matched with its run).
"""

from __future__ import annotations

import copy
import json
import shutil
from pathlib import Path
from typing import Any

import pytest
from helpers_results import derive_run_id, synthetic_schema_1

from empathy_zoo.environments import ENVIRONMENT_TABLE
from empathy_zoo.evaluation_file import EvaluationFileError, check_evaluation, evaluation_mismatch, read_evaluation
from empathy_zoo.evaluation_record import EvaluationResult
from empathy_zoo.experiment.result_reader import MAX_SETTING, check_result, read_result
from empathy_zoo.experiment.values import SweepConfigError
from empathy_zoo.metrics import COUNT_PER_STEP, INTEGER_METRICS
from empathy_zoo.result_file import ResultFileError, episode_bounds
from empathy_zoo.scenarios import load_scenario_set
from empathy_zoo.schedules import ScheduleError, check_schedule

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick"
REFERENCE_RUN = RESULTS / "runs" / "coexistence_v0__empathic_dqn-b52b0d46__s0.json"
"""Empathic DQN at β = 1 on Coexistence: the DQN reference (``dqn_reference`` true)."""
EMPATHIC_RUN = RESULTS / "runs" / "coexistence_v0__empathic_dqn-ceb94979__s0.json"
"""Empathic DQN at β = 0.5 on Coexistence."""
SHARING_RUN = RESULTS / "runs" / "sharing_v0__empathic_dqn-24777995__s0.json"
"""Empathic DQN at β = 0.5 on Sharing."""
EVALUATION = RESULTS / "evaluations" / "coexistence_v0" / "coexistence_v0__empathic_dqn-b52b0d46__s0.json"
"""The reference run beside the shipped held-out partners."""
HUGE = 10**400
"""An int past a float's range."""


def short(value: Any) -> str | None:
    """A test id of :data:`HUGE` (else pytest's own)."""
    return "10**400" if value == HUGE else None


def genuine(path: Path) -> dict[str, Any]:
    document: dict[str, Any] = json.loads(path.read_text())
    return document


def written(document: dict[str, Any], folder: Path, name: str | None = None) -> Path:
    """``document`` as a result file in ``folder`` (named ``<run id>.json`` unless ``name``)."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / (name or f"{document['run_id']}.json")
    path.write_text(json.dumps(document))  # (Infinity and NaN written as JSON's readers take them)
    return path


def refused(path: Path, field: str, error: type[ValueError] = ResultFileError) -> str:
    """Reading the result file ``path`` raises ``error`` in one line naming it and ``field``."""
    with pytest.raises(error) as caught:
        read_result(path)
    message = str(caught.value)
    assert "\n" not in message and message.startswith(f"{path}: field {field}:"), message
    return message


# ------------------------------------------------------------------------------ 1. counts per episode
def test_every_count_has_a_bound_of_one_episode() -> None:
    bounds = episode_bounds("coexistence_v0", {})
    assert set(COUNT_PER_STEP) == set(INTEGER_METRICS)
    # (one cat, harmed at most once; Coexistence has no batteries)
    assert (bounds["survival"], bounds["harms"], bounds["batteries"], bounds["other_batteries"]) == (500, 1, 0, 0)
    assert episode_bounds("coexistence_v0", {"num_cats": 3, "max_cycles": 10})["harms"] == 3
    assert episode_bounds("sharing_v0", {"num_humans": 2})["other_batteries"] == 1000
    assert episode_bounds("sharing_v0", {"num_humans": 2})["harms"] == 0


@pytest.mark.parametrize("env", sorted(ENVIRONMENT_TABLE))
def test_a_count_its_environment_cannot_give_is_bounded_by_the_table(env: str) -> None:
    entry = ENVIRONMENT_TABLE[env]
    bounds = episode_bounds(env, {})
    assert bounds["harms"] == (1 + entry.harms_besides_agents if entry.can_harm else 0)
    assert (bounds["batteries"] == 0) == (bounds["other_batteries"] == 0) == (not entry.batteries)
    assert episode_bounds(env, {"max_cycles": 1})["harms"] == min(2, entry.most_harms(1))  # (one step: 1 + 1 per other)


@pytest.mark.parametrize(
    ("env", "metric", "most"), [("sharing_v0", "harms", 0), ("coexistence_v0", "batteries", 0), ("vase_v0", "harms", 2)]
)
def test_a_count_past_what_its_environment_gives_is_refused_naming_it(env: str, metric: str, most: int) -> None:
    document = synthetic_schema_1(env, "dqn", 1.0, 0)
    document["eval"][0][metric][7] = most
    check_result(copy.deepcopy(document), "forged.json")
    document["eval"][0][metric][7] = most + 1
    with pytest.raises(ResultFileError, match=rf"^forged\.json: field eval\[0\]\.{metric}\[7\]: .*<= {most},"):
        check_result(document, "forged.json")


def test_a_count_at_its_bound_is_read_and_one_more_is_refused(tmp_path: Path) -> None:
    document = genuine(REFERENCE_RUN)
    document["eval"][0]["harms"][0] = 1  # (one cat: harmed at most once, as it leaves)
    assert read_result(written(document, tmp_path)).eval[0].metrics["harms"][0] == 1
    document["eval"][0]["harms"][0] = 2
    refused(written(document, tmp_path), "eval[0].harms[0]")


@pytest.mark.parametrize("metric", ["harms", "batteries", "other_batteries"])
@pytest.mark.parametrize("value", [1e308, 10**12, 1001])
def test_a_count_past_what_an_episode_holds_is_refused(metric: str, value: float, tmp_path: Path) -> None:
    document = genuine(REFERENCE_RUN)
    document["eval"][1][metric][3] = value
    refused(written(document, tmp_path), f"eval[1].{metric}[3]")
    document = genuine(SHARING_RUN)
    document["train"][metric][5] = value
    message = refused(written(document, tmp_path), f"train.{metric}[5]")
    assert f"{metric}, a count (a whole number) >= 0 and <= " in message


@pytest.mark.parametrize(("scenario", "metric", "value"), [(1, "harms", 1e308), (6, "harms", 4), (2, "batteries", 1)])
def test_an_evaluation_s_count_past_its_scenario_s_episode_is_refused(scenario: int, metric: str, value: float) -> None:
    evaluation = genuine(EVALUATION)
    assert evaluation["scenarios"][6]["env_kwargs"]["num_cats"] == 3  # (a bound of 3 harms: each cat once)
    evaluation["scenarios"][scenario]["metrics"][metric][4] = value
    with pytest.raises(EvaluationFileError, match=rf"^\S+: field scenarios\[{scenario}\]\.metrics\.{metric}\[4\]: expected"):
        check_evaluation(evaluation, EVALUATION)
    evaluation["scenarios"][scenario]["metrics"][metric][4] = int(value) - 1 if value < 1e6 else 0
    check_evaluation(evaluation, EVALUATION)


# ------------------------------------------------------------------------------ 2. settings and description
@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("learning_rate", float("inf")),
        ("learning_rate", 1e308),
        ("learning_rate", HUGE),
        ("learning_rate", True),
        ("replay_capacity", 1e308),
        ("replay_capacity", HUGE),
        ("replay_capacity", True),
        ("replay_capacity", 50000.5),
        ("batch_size", 1.5),
        ("target_update_interval", True),
        ("target_update_interval", MAX_SETTING + 1),
        ("others", "clo\u2028sest"),
        ("others", 3),
    ],
    ids=short,
)
def test_a_setting_of_the_wrong_type_or_out_of_range_is_refused_by_name(name: str, value: Any, tmp_path: Path) -> None:
    document = genuine(REFERENCE_RUN)
    document["config"]["settings"][name] = value
    path = written(document, tmp_path)
    with pytest.raises(ResultFileError) as caught:
        read_result(path)
    message = str(caught.value)  # (not plain data: named by its field; else by the settings of its method)
    assert "\n" not in message, message
    assert message.startswith((f"{path}: field config.settings.{name}: expected ", f"{path}: field config.settings: ")), message
    assert f"field config.settings.{name}: " in message or f"expected settings of empathic_dqn ({name}: " in message, message


def test_a_setting_its_class_refuses_is_named_too(tmp_path: Path) -> None:
    document = genuine(REFERENCE_RUN)
    document["config"]["settings"]["replay_capacity"] = 8  # (fewer than a batch)
    message = refused(written(document, tmp_path), "config.settings")
    assert "expected settings of empathic_dqn (replay_capacity must be >= batch_size (32), got 8)" in message


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("decay_steps", float("inf")),
        ("decay_steps", 1e308),
        ("decay_steps", HUGE),
        ("decay_steps", True),
        ("decay_steps", 20000.5),
        ("warmup", 1.5),
        ("warmup", -1),
        ("start", 1.5),
        ("start", float("nan")),
        ("end", -0.01),
    ],
    ids=short,
)
def test_an_exploration_schedule_out_of_range_is_refused_by_field(name: str, value: Any, tmp_path: Path) -> None:
    document = genuine(REFERENCE_RUN)
    document["config"]["description"]["exploration"][name] = value
    refused(written(document, tmp_path), f"config.description.exploration.{name}")
    with pytest.raises(ScheduleError) as caught:
        check_schedule(document["config"]["description"]["exploration"])
    assert caught.value.field == name


def test_a_schedule_the_settings_do_not_give_is_refused(tmp_path: Path) -> None:
    document = genuine(REFERENCE_RUN)
    document["config"]["description"]["exploration"]["decay_steps"] = 40000  # (within range; the settings say 20,000)
    refused(written(document, tmp_path), "config.description.exploration")


def test_a_beta_that_contradicts_the_settings_is_refused(tmp_path: Path) -> None:
    document = genuine(REFERENCE_RUN)
    document["config"]["description"] |= {"selfishness": 0.5, "dqn_reference": False}  # (settings: β = 1)
    refused(written(document, tmp_path), "config.description.selfishness")


def test_a_dqn_reference_that_contradicts_the_settings_is_refused(tmp_path: Path) -> None:
    document = genuine(EMPATHIC_RUN)
    document["config"]["description"]["dqn_reference"] = True  # (β = 0.5: no plain DQN)
    refused(written(document, tmp_path), "config.description.dqn_reference")
    document = genuine(REFERENCE_RUN)
    document["config"]["description"]["dqn_reference"] = False  # (β = 1 on the environment's reward: the reference)
    refused(written(document, tmp_path), "config.description.dqn_reference")
    document = genuine(EMPATHIC_RUN)
    document["config"]["settings"]["selfishness"] = 1.0
    document["config"]["description"] |= {"selfishness": 1.0, "dqn_reference": True, "reward": {"name": "harm_penalty"}}
    refused(written(document, tmp_path), "config.description.dqn_reference")


@pytest.mark.parametrize(
    ("name", "value"),
    [("epsilon_decay_steps", 1.5), ("learning_starts", True), ("epsilon_start", float("inf")), ("selfishness", HUGE)],
    ids=short,
)
def test_an_older_file_s_setting_is_named_as_the_setting(name: str, value: Any) -> None:
    document = synthetic_schema_1("coexistence_v0", "empathic_dqn", 0.5, 0)
    document["config"]["settings"][name] = value
    with pytest.raises(ResultFileError, match=rf"^old\.json: field config\.settings\.{name}: expected"):
        check_result(document, "old.json")


def test_an_older_file_s_huge_penalty_is_refused_in_one_line() -> None:
    document = synthetic_schema_1("coexistence_v0", "dqn_harm_penalty", 1.0, 0)
    document["config"]["settings"]["harm_penalty"] = 10**400
    with pytest.raises(ResultFileError, match=r"^old\.json: field config\.settings\.harm_penalty: a finite number, got an int"):
        check_result(document, "old.json")


def test_a_plug_in_s_settings_are_plain_data(tmp_path: Path) -> None:
    document = genuine(REFERENCE_RUN)
    document["method"] = document["config"]["method"] = "my_plugins.methods:MINE"
    document["config"]["description"]["family"] = "my_plugins.methods:MINE"
    derive_run_id(document)  # (the plug-in's run: the id its config gives, its agent file named so)
    document["agent"]["file"] = f"{document['run_id']}.agent.pt"
    assert read_result(written(document, tmp_path)).method == "my_plugins.methods:MINE"  # (never imported)
    document["config"]["settings"]["width"] = float("inf")
    refused(written(document, tmp_path), "config.settings.width")


# ------------------------------------------------------------------------------ 3. one run, one file
def test_a_run_id_of_another_seed_is_refused(tmp_path: Path) -> None:
    document = genuine(REFERENCE_RUN)
    document["run_id"] = document["run_id"].replace("__s0", "__s7")
    refused(written(document, tmp_path), "run_id")
    document["run_id"] = document["run_id"].removesuffix("__s7")
    refused(written(document, tmp_path), "run_id")


def test_a_result_file_under_another_name_is_refused(tmp_path: Path) -> None:
    runs = tmp_path / "runs"
    runs.mkdir()
    shutil.copy(REFERENCE_RUN, runs / REFERENCE_RUN.name)
    assert read_result(runs / REFERENCE_RUN.name).run_id == REFERENCE_RUN.stem
    copied = runs / "coexistence_v0__empathic_dqn-b52b0d46__s9.json"
    shutil.copy(REFERENCE_RUN, copied)
    message = refused(copied, "run_id")
    assert f"the file is named {copied.name}, but it holds run {REFERENCE_RUN.stem}" in message
    paths = sorted((RESULTS / "runs").glob("*.json"))
    assert len(paths) == 30
    for path in paths:  # (every genuine one still reads)
        assert read_result(path).run_id == path.stem


# ------------------------------------------------------------------------------ 4. scenario files
HEADER = '[scenario_set]\nenv = "coexistence_v0"\n'
SCENARIO = '[scenarios.still]\nreason = "A cat that stays."\nfixed = { cat_0 = "stay" }\n'


def scenario_file(text: str, tmp_path: Path) -> Path:
    path = tmp_path / "mine.toml"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize("character", ["\u2028", "\u2029", "\u0085", "\u200b", "\x1b"])
def test_a_description_the_evaluation_reader_would_refuse_is_refused_when_loaded(character: str, tmp_path: Path) -> None:
    path = scenario_file(HEADER + f'description = "one\\u{ord(character):04X}two"\n' + SCENARIO, tmp_path)  # (a TOML escape)
    with pytest.raises(SweepConfigError) as caught:
        load_scenario_set(path)
    message = str(caught.value)
    assert "\n" not in message and message.startswith(f"{path}: [scenario_set] description: expected one line of printable"), (
        message
    )


def test_a_scenario_set_may_say_it_is_held_out(tmp_path: Path) -> None:
    for line in ("held_out = true\n", ""):
        scenario_set = load_scenario_set(scenario_file(HEADER + line + SCENARIO, tmp_path))
        assert [scenario.name for scenario in scenario_set.scenarios] == ["still"]
        assert "held_out" not in scenario_set.definition()  # (nothing an evaluation file records)


def test_a_scenario_set_saying_it_is_not_held_out_is_refused(tmp_path: Path) -> None:
    path = scenario_file(HEADER + "held_out = false\n" + SCENARIO, tmp_path)
    with pytest.raises(SweepConfigError, match=r"mine\.toml: \[scenario_set\] held_out: a scenario set is always held out"):
        load_scenario_set(path)


def test_an_evaluation_s_scenario_is_held_out_unless_it_is_the_run_s_own_world(tmp_path: Path) -> None:
    evaluation, run = genuine(EVALUATION), read_result(REFERENCE_RUN)

    def mismatch_of(document: dict) -> str | None:
        return evaluation_mismatch(EvaluationResult.from_checked(check_evaluation(document, EVALUATION)), run)

    assert mismatch_of(evaluation) is None
    forged = copy.deepcopy(evaluation)
    forged["scenarios"][1]["held_out"] = False  # (the cat stays: another partner than the run's)
    with pytest.raises(EvaluationFileError, match=r"field scenarios\[1\]\.held_out: expected true: a scenario of a held-out"):
        check_evaluation(forged, EVALUATION)
    own = copy.deepcopy(evaluation)
    own["scenarios"][1] |= {"env_kwargs": dict(own["scenarios"][0]["env_kwargs"]), "fixed": dict(own["scenarios"][0]["fixed"])}
    own["scenario_set"]["scenarios"][0]["fixed"] = dict(own["scenarios"][0]["fixed"])  # (played as its set defines it)
    mismatch = mismatch_of(own)  # (held out in the run's own world)
    assert mismatch == "scenarios[1].held_out (cat_stays: the same world as its run's own): True, its run has False"
    own["scenarios"][1]["held_out"] = False
    assert mismatch_of(own) is None  # (the run's own world, played again)


@pytest.mark.parametrize(
    ("where", "field"),
    [
        (lambda e: e["scenario_set"], "scenario_set.held_out"),
        (lambda e: e["scenario_set"]["scenarios"][0], r"scenario_set\.scenarios\[0\]\.held_out"),
        (lambda e: e["scenarios"][2], r"scenarios\[2\]\.extra"),
        (lambda e: e, "extra"),
    ],
)
def test_an_evaluation_holds_no_field_of_its_own_making(where: Any, field: str, tmp_path: Path) -> None:
    evaluation = genuine(EVALUATION)
    where(evaluation)["held_out" if "held_out" in field else "extra"] = False
    path = tmp_path / "coexistence_v0" / EVALUATION.name
    path.parent.mkdir()
    path.write_text(json.dumps(evaluation))
    with pytest.raises(EvaluationFileError, match=rf"^{path}: field {field}: expected no such field"):
        read_evaluation(path)
