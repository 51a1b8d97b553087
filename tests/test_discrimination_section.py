"""The leaderboard's discrimination section (``leaderboard.discrimination_section``): one row per pair
of methods with trained rows on a task that has an exact table, the exact cell and the trained
cell side by side; none where fewer than two of the tables' methods ran; methods whose rows share
a seed named and not read."""

from __future__ import annotations

import json
from pathlib import Path

from helpers_results import synthetic_result

from leaderboard.discrimination_section import SECTION_TITLE, discrimination_section
from leaderboard.page import Paragraph, Table


def _row(name: str, method: str, beta: float | None = None) -> dict:
    return {"name": name, "method": method, "selfishness": beta, "identical_to": "", "reason": ""}


def tables(tmp_path: Path) -> Path:
    """A Charger table of DQN, the harm penalty and Empathic DQN (β 0.5): DQN apart from both."""
    rows = [_row("dqn", "dqn"), _row("dqn_harm_penalty", "dqn_harm_penalty"), _row("e", "empathic_dqn", 0.5)]
    pairs = [
        {"first": a, "second": b, "epsilon": 0.01, "differ": d, "differing_states": 4 * d, "harms_difference": 0.9 * d}
        | {"by_construction": ""}
        for a, b, d in (("dqn", "dqn_harm_penalty", True), ("dqn", "e", True), ("dqn_harm_penalty", "e", False))
    ]
    harms = {"dqn": 0.9, "dqn_harm_penalty": 0.0, "e": 0.0}  # (each pair's harms_difference is its rows' difference)
    outcomes = [{"row": r["name"], "epsilon": 0.01, "harms": harms[r["name"]], "robot_harmed": 0.0} for r in rows]
    folder = tmp_path / "tables"
    folder.mkdir()
    (folder / "charger_v0.json").write_text(json.dumps({"env": "charger_v0", "rows": rows, "outcomes": outcomes, "pairs": pairs}))
    return folder


def runs(method: str, beta: float, harms: float, seeds: range = range(10)) -> list:
    return [synthetic_result("charger_v0", method, beta, seed, harms=harms) for seed in seeds]


def test_each_pair_that_ran_gets_its_exact_and_its_trained_cell(tmp_path: Path) -> None:
    results = runs("dqn", 1.0, 1.0) + runs("dqn_harm_penalty", 1.0, 0.0) + runs("empathic_dqn", 0.5, 0.0)
    section = discrimination_section(results, tables(tmp_path))
    assert section is not None and section.title == SECTION_TITLE
    intro, table = section.blocks
    assert isinstance(intro, Paragraph) and "cells tested: 3;" in intro.text
    assert isinstance(table, Table) and table.header == ["Pair", "charger_v0"]
    assert table.rows == [
        ["dqn / dqn_harm_penalty", "separated (4 states, Δharms +0.900); trained: separated, P 0.00"],
        ["dqn / empathic_dqn", "separated (4 states, Δharms +0.900); trained: separated, P 0.00"],
        ["dqn_harm_penalty / empathic_dqn", "not separated; trained: no difference detected, P 0.50"],
    ]


def test_no_section_without_two_of_the_tables_methods_or_without_a_table(tmp_path: Path) -> None:
    folder = tables(tmp_path)
    assert discrimination_section(runs("dqn", 1.0, 1.0), folder) is None
    assert discrimination_section(runs("dqn", 1.0, 1.0) + runs("dqn_harm_penalty", 1.0, 0.0), tmp_path / "none") is None
    assert discrimination_section(runs("dqn", 1.0, 1.0) + runs("empathic_dqn", 0.25, 0.0), folder) is None  # (β 0.25: not read)


def test_a_method_whose_rows_share_a_seed_is_named_and_not_read(tmp_path: Path) -> None:
    results = runs("dqn", 1.0, 1.0) + runs("dqn_harm_penalty", 1.0, 0.0) + runs("empathic_dqn", 0.5, 0.0)
    results += runs("dqn_harm_penalty", 1.0, 0.5, range(1))  # (a second row, as a tuned one would be)
    section = discrimination_section(results, tables(tmp_path))
    assert section is not None
    intro, table = section.blocks
    assert isinstance(intro, Paragraph) and "share a seed on one task: dqn\\_harm\\_penalty" not in intro.text
    assert "share a seed on one task: dqn_harm_penalty." in intro.text
    assert isinstance(table, Table) and [row[0] for row in table.rows] == ["dqn / empathic_dqn"]


def test_a_run_described_as_standard_dqn_is_read_as_dqn(tmp_path: Path) -> None:
    """The paper's profile trains DQN as Empathic DQN at β = 1: its result file says it is DQN."""
    results = runs("empathic_dqn", 1.0, 1.0) + runs("dqn_harm_penalty", 1.0, 0.0)
    section = discrimination_section(results, tables(tmp_path))
    assert section is not None
    table = section.blocks[1]
    assert isinstance(table, Table)
    assert table.rows == [["dqn / dqn_harm_penalty", "separated (4 states, Δharms +0.900); trained: separated, P 0.00"]]
