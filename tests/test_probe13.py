"""The thirteenth probe's findings: a result file's run id is the one its configuration gives, so a
configuration changed after the run cannot pool the run with another experiment."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import pytest
from helpers_heldout import population_dirs

from empathy_zoo.cli import main
from empathy_zoo.experiment.result_reader import read_result
from empathy_zoo.run_ids import config_hash, run_id

ROOT = Path(__file__).resolve().parents[1]
QUICK = ROOT / "docs" / "results" / "quick" / "runs"
SHIPPED = sorted(QUICK.glob("coexistence_v0__dqn_harm_penalty-*__s*.json"))


def _shipped() -> dict[str, Any]:
    return json.loads(SHIPPED[0].read_text())


def _written(folder: Path, document: dict[str, Any]) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{document['run_id']}.json"
    path.write_text(json.dumps(document))
    return path


def test_the_shipped_result_files_hold_the_ids_their_configs_give() -> None:
    assert len(SHIPPED) == 3
    for path in sorted(QUICK.glob("*.json")):
        document = json.loads(path.read_text())
        config = document["config"]
        assert document["run_id"] == run_id(config["variant"], document["method"], config, document["seed"])
        assert read_result(path).run_id == document["run_id"]


@pytest.mark.parametrize(
    ("where", "value"),
    [
        (("settings", "learning_rate"), 0.5),
        (("settings", "batch_size"), 64),
        (("fixed", "cat_0"), "stay"),
        (("settings", "target_update_interval"), 500),
        (("label",), None),
    ],
)
def test_a_config_changed_after_the_run_is_refused_by_its_run_id(tmp_path: Path, where: tuple[str, ...], value: Any) -> None:
    document = _shipped()
    table = document["config"]
    for key in where[:-1]:
        table = table[key]
    table[where[-1]] = value if value is not None else "another label"
    if where == ("label",):
        document["method_label"] = "another label"
    with pytest.raises(ValueError, match=r"field run_id: expected coexistence_v0__dqn_harm_penalty-[0-9a-f]{8}__s0 \(the id"):
        read_result(_written(tmp_path, document))


def test_a_run_id_of_another_hash_is_refused(tmp_path: Path) -> None:
    document = _shipped()
    document["run_id"] = document["run_id"].replace(config_hash(document["config"]), "0123abcd")
    document["agent"]["file"] = f"{document['run_id']}.agent.pt"
    with pytest.raises(ValueError, match=r"field run_id"):
        read_result(_written(tmp_path, document))


def test_a_changed_config_under_its_own_new_id_is_another_experiment(tmp_path: Path) -> None:
    document = _shipped()
    document["config"]["settings"]["learning_rate"] = 0.5
    document["run_id"] = run_id("coexistence_v0", document["method"], document["config"], 0)
    document["agent"]["file"] = f"{document['run_id']}.agent.pt"
    assert document["run_id"] != _shipped()["run_id"]
    assert read_result(_written(tmp_path, document)).run_id == document["run_id"]


def test_the_leaderboard_refuses_a_changed_run_pooled_with_its_seeds(tmp_path: Path, capsys) -> None:
    runs = tmp_path / "results" / "runs"
    runs.mkdir(parents=True)
    for path in SHIPPED[1:]:
        shutil.copy(path, runs / path.name)
        shutil.copy(path.with_suffix(".agent.pt"), runs / path.with_suffix(".agent.pt").name)
    document = _shipped()
    document["config"]["settings"]["learning_rate"] = 0.5
    forged = _written(runs, document)
    shutil.copy(SHIPPED[0].with_suffix(".agent.pt"), runs / SHIPPED[0].with_suffix(".agent.pt").name)
    assert main(["leaderboard", str(tmp_path / "results"), "--out", str(tmp_path / "board")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(forged) in err and "field run_id" in err
    assert not (tmp_path / "board").exists()


def test_population_reading_refuses_one_directory_twice(tmp_path: Path, capsys) -> None:
    population, default = population_dirs(tmp_path)
    for argv in ([default, default], [population, default, population], [population, tmp_path / "." / "default", default]):
        assert main(["analyse", "population-reading", *map(str, argv)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "is given twice" in err and "compared with themselves" in err
    assert main(["analyse", "population-reading", str(population), str(default)]) == 0


def test_population_reading_refuses_a_population_directory_of_default_trained_runs(tmp_path: Path, capsys) -> None:
    population, default = population_dirs(tmp_path)
    shutil.rmtree(population / "runs")
    shutil.rmtree(population / "evaluations")
    shutil.copytree(default, population, dirs_exist_ok=True)  # (default-trained runs under another name)
    assert main(["analyse", "population-reading", str(population), str(default)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{population} holds no population-trained run" in err


def test_population_readings_second_evaluation_of_a_seed_names_both_files(tmp_path: Path) -> None:
    from leaderboard.population_reading import read_scores

    population, default = population_dirs(tmp_path)
    again = shutil.copytree(default, tmp_path / "again")  # (one directory's copy: each seed twice)
    with pytest.raises(ValueError, match="two default-trained runs of dqn on coexistence_v0 with seed 0") as refused:
        read_scores(population, [default, again])
    first = next((default / "evaluations" / "coexistence_v0_test").glob("coexistence_v0__dqn-*__s0.json"))
    assert str(first) in str(refused.value) and str(again / first.relative_to(default)) in str(refused.value)


def test_population_reading_refuses_a_test_split_renamed_in_every_file(tmp_path: Path) -> None:
    """A consistent change of the test split (here its population's first member renamed in every
    file) is no longer the shipped split: refused, naming the file and the shipped definition."""
    from leaderboard.population_reading import read_scores

    population, default = population_dirs(tmp_path)
    for path in sorted((tmp_path).glob("*/evaluations/coexistence_v0_test/*.json")):
        document = json.loads(path.read_text())
        for scenario in document["scenario_set"]["scenarios"]:
            if scenario["name"] == "test_population":
                scenario["name"] = "renamed_population"
        for scenario in document["scenarios"]:
            if scenario["name"] == "test_population":
                scenario["name"] = "renamed_population"
        path.write_text(json.dumps(document))
    with pytest.raises(
        ValueError,
        match=r"another definition of scenario set 'coexistence_v0_test' than the shipped one \(.*coexistence_v0_test\.toml\)",
    ):
        read_scores(population, [default])


AGENT = SHIPPED[0].with_suffix(".agent.pt")
"""The agent file of the first shipped run (DQN with a harm penalty on Coexistence)."""


def _agent_with(tmp_path: Path, **header: Any) -> Path:
    import torch

    document = torch.load(AGENT, weights_only=True)
    document["header"] = {**document["header"], **header}
    path = tmp_path / AGENT.name
    torch.save(document, path)
    return path


@pytest.mark.parametrize(
    ("key", "value"),
    [("seed", 2), ("steps", 40_000), ("label", "another label"), ("run_id", "coexistence_v0__dqn_harm_penalty-0123abcd__s0")],
)
def test_an_agent_read_alone_holds_the_run_id_its_header_gives(tmp_path: Path, capsys, key: str, value: Any) -> None:
    from empathy_zoo.agent_file import AgentFileError, load_agent

    path = _agent_with(tmp_path, **{key: value})
    with pytest.raises(
        AgentFileError,
        match=r"field header\.run_id: expected coexistence_v0__dqn_harm_penalty-[0-9a-f]{8}__s[02] \(the id its header gives",
    ):
        load_agent(path)
    assert main(["watch", str(path), "--episodes", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(path) in err and "header.run_id" in err


def test_an_agent_whose_header_gives_its_own_id_is_read(tmp_path: Path) -> None:
    import torch

    from empathy_zoo.agent_file import load_agent

    header = dict(torch.load(AGENT, weights_only=True)["header"])
    header["seed"] = 2
    header["run_id"] = run_id(header["variant"], header["method"], {k: v for k, v in header.items() if k != "run_id"}, 2)
    assert header["run_id"] == SHIPPED[0].stem.replace("__s0", "__s2")  # (the seed is no part of the hash)
    assert load_agent(_agent_with(tmp_path, **header)).describe()["method"] == "dqn_harm_penalty"


def test_the_leaderboard_csv_shows_a_formula_label_as_text(tmp_path: Path) -> None:
    import csv

    from helpers_results import derive_run_id, synthetic_document

    runs = tmp_path / "results" / "runs"
    runs.mkdir(parents=True)
    for method, label in (("dqn", "DQN"), ("empathic_dqn", '=HYPERLINK("http://x.test","click")')):
        for seed in range(2):
            document = synthetic_document("coexistence_v0", method, 1.0 if method == "dqn" else 0.5, seed)
            document["method_label"] = label
            document["config"].pop("label", None)
            _written(runs, derive_run_id(document))
    assert main(["leaderboard", str(tmp_path / "results"), "--out", str(tmp_path / "board")]) == 0
    rows = list(csv.DictReader((tmp_path / "board" / "leaderboard.csv").open()))
    labels = {row["method_label"] for row in rows}
    assert any(label.startswith('\'=HYPERLINK("http://x.test","click")') for label in labels)
    assert not any(label.startswith("=") for label in labels)


@pytest.mark.parametrize(
    ("value", "cell"),
    [("=1+1", "'=1+1"), ("+x", "'+x"), ("-x", "'-x"), ("@SUM(A1)", "'@SUM(A1)"), ("\tx", "'\tx"), ("DQN", "DQN"), ("a=b", "a=b")],
)
def test_a_csv_text_cell_that_starts_a_formula_is_quoted(value: str, cell: str) -> None:
    from leaderboard.tables import csv_text_cell

    assert csv_text_cell(value) == cell


STUDY = ROOT / "docs" / "results" / "methods" / "tuning" / "coexistence_v0" / "dqn" / "study.json"


def _study_refused(tmp_path: Path, change: Any, field: str) -> None:
    from leaderboard.study_file import StudyFileError, check_study

    document = json.loads(STUDY.read_text())
    check_study(document, STUDY)  # (as shipped)
    change(document)
    with pytest.raises(StudyFileError, match=rf"field {field}: expected"):
        check_study(document, tmp_path / "study.json")


def _worse_best(document: dict[str, Any]) -> None:
    finished = [trial for trial in document["trials"] if trial["state"] == "COMPLETE"]
    worst = min(finished, key=lambda trial: trial["value"])
    document["best"] = {"number": worst["number"], "value": worst["value"], "params": worst["params"]}


def _one_trial_more(document: dict[str, Any]) -> None:
    document["trials"].append({**document["trials"][0], "number": len(document["trials"])})


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (_worse_best, "best.number"),
        (_one_trial_more, "trials"),
        (lambda d: d.__setitem__("env_steps_trained", d["plan"]["budget"]["env_steps_at_most"] + 1), "env_steps_trained"),
        (lambda d: d["plan"]["budget"].__setitem__("env_steps_at_most", 10**6 + 1), r"plan\.budget\.env_steps_at_most"),
        (lambda d: d["plan"]["objective"].__setitem__("direction", "sideways"), r"plan\.objective\.direction"),
    ],
    ids=[
        "best not the best",
        "more trials than the plan",
        "more steps than the budget",
        "a budget of no whole trials",
        "no direction",
    ],
)
def test_a_study_whose_fields_disagree_is_refused(tmp_path: Path, change: Any, field: str) -> None:
    _study_refused(tmp_path, change, field)
