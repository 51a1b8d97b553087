"""The twelfth probe's findings: a separation table's every field in range and its names plain
text of bounded length; the discrimination matrix bounded in tables and cells; an error line shows
the names it quotes as text; an agent file's header consistent with itself and its world."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import pytest
import torch

from baselines.separation_file import MAX_ROW_NAME, SeparationTableError, read_separation_table
from empathy_zoo.cli import main
from empathy_zoo.names import terminal_line

ROOT = Path(__file__).resolve().parents[1]
TABLES = ROOT / "docs" / "results" / "separation"
SHIPPED_AGENT = ROOT / "docs" / "results" / "quick" / "runs"
ESC, BEL = "\x1b", "\x07"


def _vase() -> dict[str, Any]:
    return json.loads((TABLES / "vase_v0.json").read_text())


def _written(tmp_path: Path, document: dict[str, Any], name: str = "vase_v0.json") -> Path:
    path = tmp_path / name
    path.write_text(json.dumps(document))
    return path


@pytest.mark.parametrize("value", [[1], "abc", "1e999", 1e300, -50, "nan", 1.5])
def test_an_outcomes_changed_world_is_a_probability(tmp_path, value) -> None:
    document = _vase()
    document["outcomes"][0]["changed"] = value
    with pytest.raises(SeparationTableError, match=r"field outcomes\[0\]\.changed"):
        read_separation_table(_written(tmp_path, document))


def test_an_integer_too_large_for_a_float_is_refused_as_changed(tmp_path) -> None:
    text = json.dumps(_vase()).replace('"changed": 1.0000000000000044', '"changed": ' + "9" * 400, 1)
    (tmp_path / "vase_v0.json").write_text(text)
    with pytest.raises(SeparationTableError, match=r"changed"):
        read_separation_table(tmp_path / "vase_v0.json")


@pytest.mark.parametrize(("where", "value"), [(("outcomes", 0, "row"), ["dqn"]), (("pairs", 0, "first"), {"a": 1})])
def test_a_row_name_that_is_no_string_is_refused_naming_its_field(tmp_path, where, value) -> None:
    document = _vase()
    document[where[0]][where[1]][where[2]] = value
    with pytest.raises(SeparationTableError, match=rf"field {where[0]}\[0\]\.{where[2]}"):
        read_separation_table(_written(tmp_path, document))


@pytest.mark.parametrize(
    ("field", "value"),
    [("harms", 1e300), ("survival", 1e300), ("harms", -50.0)],
)
def test_an_outcomes_numbers_are_bounded(tmp_path, field, value) -> None:
    document = _vase()
    document["outcomes"][0][field] = value
    with pytest.raises(SeparationTableError, match=rf"field outcomes\[0\]\.{field}"):
        read_separation_table(_written(tmp_path, document))


def test_a_row_name_longer_than_the_bound_is_refused(tmp_path) -> None:
    document = _vase()
    long = "x" * (MAX_ROW_NAME + 1)
    for outcome in document["outcomes"]:
        if outcome["row"] == document["rows"][0]["name"]:
            outcome["row"] = long
    document["rows"][0]["name"] = long
    with pytest.raises(SeparationTableError, match=r"field rows\[0\]\.name"):
        read_separation_table(_written(tmp_path, document))


@pytest.mark.parametrize("value", ["[click](http://e.x)", "a b", "*em*"])
def test_a_tables_argument_value_is_an_options_word(tmp_path, value) -> None:
    document = _vase()
    document["arguments"] = [["start", value]]
    with pytest.raises(SeparationTableError, match=r"field arguments\[0\]\[1\]"):
        read_separation_table(_written(tmp_path, document))


def test_the_matrix_reads_a_bounded_number_of_tables(tmp_path, capsys) -> None:
    from baselines.discrimination import MAX_TABLES
    from baselines.discrimination import main as discrimination_main

    source = (TABLES / "vase_v0.json").read_text()
    for i in range(MAX_TABLES + 1):
        (tmp_path / f"task{i}.json").write_text(source)
    assert discrimination_main([str(tmp_path), "--out", str(tmp_path / "page.md")]) == 2
    assert f"at most {MAX_TABLES}" in capsys.readouterr().err
    assert not (tmp_path / "page.md").exists()


def test_a_table_file_name_that_is_no_task_name_is_refused_as_text(tmp_path, capsys) -> None:
    from baselines.discrimination import main as discrimination_main

    shutil.copy(TABLES / "vase_v0.json", tmp_path / f"x{ESC}]0;pwned{BEL}_v0.json")
    assert discrimination_main([str(tmp_path), "--out", str(tmp_path / "page.md")]) == 2
    err = capsys.readouterr().err
    assert "no task name" in err and ESC not in err and BEL not in err
    assert not (tmp_path / "page.md").exists()


def test_an_error_line_shows_control_characters_as_codes(tmp_path, capsys) -> None:
    runs = tmp_path / "results" / "runs"
    runs.mkdir(parents=True)
    (runs / f"a{ESC}]0;pwned{BEL}__s0.json").write_text("{}")
    assert main(["leaderboard", str(tmp_path / "results")]) == 2
    err = capsys.readouterr().err
    assert ESC not in err and BEL not in err and "\\x1b" in err and err.count("\n") == 1
    assert terminal_line(f"a{ESC}b\u2028c\udc85") == "a\\x1bb\\u2028c\\udc85"


def _forged_agent(tmp_path: Path, **header: Any) -> Path:
    source = sorted(SHIPPED_AGENT.glob("*.agent.pt"))[0]
    document = torch.load(source, weights_only=True)
    document["header"] = {**document["header"], **header}
    forged = tmp_path / source.name
    torch.save(document, forged)
    return forged


def test_an_agent_headers_fixed_agents_are_its_worlds(tmp_path, capsys) -> None:
    forged = _forged_agent(tmp_path, fixed={"cat_5": "stay"})
    capsys.readouterr()
    assert main(["watch", str(forged), "--episodes", "1"]) == 2
    err = capsys.readouterr().err
    assert "field header.fixed" in err and "cat_5" in err and str(forged) in err


def test_population_reading_refuses_two_definitions_of_one_test_split(tmp_path) -> None:
    from leaderboard.population_reading import read_scores

    shipped = ROOT / "docs" / "results" / "populations"
    population, default = tmp_path / "population", tmp_path / "default"
    for source, target in ((shipped, population), (shipped / "default_trained", default)):
        (target / "evaluations").mkdir(parents=True)
        shutil.copytree(source / "runs", target / "runs", ignore=shutil.ignore_patterns("*.agent.*"))
        shutil.copytree(source / "evaluations" / "coexistence_v0_test", target / "evaluations" / "coexistence_v0_test")
    read_scores(population, [default])  # (as shipped: one definition)
    for path in sorted((default / "evaluations" / "coexistence_v0_test").glob("*.json")):
        document = json.loads(path.read_text())
        for scenarios in (document["scenario_set"]["scenarios"], document["scenarios"]):
            for scenario in scenarios:
                if scenario["name"] == "test_population":
                    scenario.get("fixed", scenario.get("scenario", {}).get("fixed", {}))["cat_0"] = "stay"
        path.write_text(json.dumps(document))
    with pytest.raises(ValueError, match="another definition of scenario set 'coexistence_v0_test' than the shipped one"):
        read_scores(population, [default])
