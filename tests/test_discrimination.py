"""The discrimination matrix reads separation tables: a pair's cell on a task says whether the
task's exact optima separate it (and by how much), label it identical by construction, or cannot
tell it apart; a method's β rows are grouped by the optima they share."""

from __future__ import annotations

import json

import pytest

from baselines.discrimination import Cell, beta_groups, cell, discrimination_markdown, load_tables, main, method_rows


def row(name: str, method: str, beta: float | None = None) -> dict:
    return {"name": name, "method": method, "selfishness": beta, "identical_to": "", "reason": ""}


def pair(first: str, second: str, differ: bool, states: int = 0, harms: float = 0.0, why: str = "") -> dict:
    return {
        "first": first,
        "second": second,
        "epsilon": 0.01,
        "differ": differ,
        "differing_states": states,
        "reachable_states": 100,
        "harms_difference": harms,
        "survival_difference": 0.0,
        "by_construction": why,
    }


TABLE = {
    "rows": [
        row("dqn", "dqn"),
        row("twin", "twin"),
        row("e β=0.5", "e", 0.5),
        row("e β=0.25", "e", 0.25),
        row("e β=0", "e", 0.0),
    ],
    "pairs": [
        pair("dqn", "twin", False, why="twin is DQN here"),
        pair("dqn", "e β=0.5", True, 12, 0.75),
        pair("twin", "e β=0.5", True, 12, 0.75),
        pair("e β=0.5", "e β=0.25", False),
        pair("e β=0.5", "e β=0", True, 3, -0.5),
        pair("e β=0.25", "e β=0", True, 3, -0.5),
    ],
    "outcomes": [  # (every row at each ε, harms whose differences are the pairs')
        {"row": name, "epsilon": 0.01, "harms": harms, "robot_harmed": 0.0}
        for name, harms in (("dqn", 1.0), ("twin", 1.0), ("e β=0.5", 0.25), ("e β=0.25", 0.25), ("e β=0", 0.75))
    ],
    "omitted": [{"method": "far", "reason": "no exact model"}],
}


def test_a_method_enters_at_the_matrix_beta():
    assert method_rows(TABLE) == {"dqn": "dqn", "twin": "twin", "e": "e β=0.5"}


def test_each_kind_of_cell_and_the_sign_of_the_harms_difference():
    assert cell(TABLE, "dqn", "e", 0.01) == Cell("separated", 12, 0.75)
    assert cell(TABLE, "e", "dqn", 0.01) == Cell("separated", 12, -0.75)
    assert cell(TABLE, "dqn", "twin", 0.01).kind == "identical by construction"
    assert cell(TABLE, "dqn", "far", 0.01).text() == "–"
    with pytest.raises(ValueError, match=r"no pair 'dqn' / 'e β=0\.5' at ε = 0\.05"):
        cell(TABLE, "dqn", "e", 0.05)


def test_beta_rows_that_share_an_optimum_are_one_group():
    assert beta_groups(TABLE, "e", 0.01) == 2
    assert beta_groups(TABLE, "dqn", 0.01) is None


def test_the_page_counts_the_tasks_that_separate_each_pair():
    page = discrimination_markdown({"toy_v0": TABLE, "copy_v0": TABLE}, 0.01, "cmd")
    assert "| `dqn` / `e` | separated (12 states, Δharms +0.750) | separated (12 states, Δharms +0.750) | 2 of 2 |" in page
    assert "| `dqn` / `twin` | identical by construction | identical by construction | 0 of 2 |" in page
    assert "| `e` | 2 | 2 |" in page and "* `far` on `toy_v0`: no exact model" in page


def test_the_command_writes_the_page_and_refuses_a_directory_without_tables(tmp_path, capsys, monkeypatch):
    tables, here = tmp_path / "tables", tmp_path / "here"
    tables.mkdir()
    here.mkdir()
    (tables / "toy_v0.json").write_text(json.dumps(TABLE))
    monkeypatch.chdir(here)
    assert main([str(tables)]) == 0
    assert (here / "DISCRIMINATION.md").read_text().startswith("# Discrimination matrix")  # (the current folder)
    assert not (tables / "DISCRIMINATION.md").exists()  # (never beside the tables read)
    assert load_tables(tables).keys() == {"toy_v0"}
    (tmp_path / "empty").mkdir()
    assert main([str(tmp_path / "empty")]) == 2
    assert "no separation table" in capsys.readouterr().err
    assert main([str(tmp_path / "missing")]) == 2
    assert f"separation tables' folder {tmp_path / 'missing'} does not exist" in capsys.readouterr().err


def test_the_shipped_page_is_what_the_command_makes(tmp_path, monkeypatch):
    """The shipped page, trained cells included, is what its own command line makes today."""
    from pathlib import Path

    from leaderboard.trained_discrimination import main as trained_main

    root = Path(__file__).resolve().parents[1]
    shipped = root / "docs" / "results" / "separation" / "DISCRIMINATION.md"
    monkeypatch.chdir(root)
    command = next(line for line in shipped.read_text().splitlines() if "Made by `" in line)
    argv = command.split("Made by `empathy-zoo analyse discrimination")[1].split("`")[0].split()
    out = tmp_path / "page.md"
    assert trained_main([*argv, "--out", str(out)]) == 0
    assert out.read_text() == shipped.read_text()


def test_by_default_neither_command_writes_into_the_shipped_tables_folder(tmp_path, monkeypatch):
    """Run from the repository without ``--out``, the page and a table land in the current folder."""
    from pathlib import Path

    from baselines.separation_render import main as separation_main

    root = Path(__file__).resolve().parents[1]
    shipped = root / "docs" / "results" / "separation"
    before = {path.name: path.read_bytes() for path in shipped.iterdir()}
    monkeypatch.chdir(tmp_path)
    assert main([]) == 0
    separation_main(["coexistence_v0", "size=5", "view=3", "max_cycles=3"])
    assert sorted(path.name for path in tmp_path.iterdir()) == [
        "DISCRIMINATION.md",
        "coexistence_v0.json",
        "coexistence_v0.md",
    ]
    assert {path.name: path.read_bytes() for path in shipped.iterdir()} == before


def test_trained_runs_not_read_close_the_page_with_their_count_and_reason(tmp_path):
    """A results directory's runs the matrix cannot read (another variant, another β) are counted, never dropped silently."""
    from helpers_results import synthetic_document

    from leaderboard.trained_discrimination import cells_of_results

    runs = tmp_path / "results" / "runs"
    runs.mkdir(parents=True)
    for seed in range(3):
        for method, beta in (("dqn", 1.0), ("e", 0.5), ("e", 0.25)):
            document = synthetic_document("coexistence_v0", "empathic_dqn" if method == "e" else method, beta, seed)
            (runs / f"{document['run_id']}.json").write_text(json.dumps(document))
    rows = [{**r, "method": "empathic_dqn"} if r["method"] == "e" else r for r in TABLE["rows"]]  # (a registered method)
    table = {**TABLE, "rows": rows}
    cells, notes = cells_of_results({"coexistence_v0": table}, [tmp_path / "results"])
    assert notes == ["3 runs of a method with β at another β than 0.5: not read"]
    page = discrimination_markdown({"coexistence_v0": table}, 0.01, "cmd", cells, notes)
    assert page.endswith("## Trained runs not read\n\n* 3 runs of a method with β at another β than 0.5: not read\n")
    assert "## Trained runs not read" not in discrimination_markdown({"coexistence_v0": table}, 0.01, "cmd", cells)
