"""The discrimination matrix's trained cells (``leaderboard.trained_discrimination``), on hand-made
per-seed harms whose verdicts are known: two methods apart, alike, too few seeds; a task whose
robot cannot harm and a method without runs left without a trained cell; the command end to end."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from helpers_results import synthetic_document

from baselines.discrimination import discrimination_markdown
from empathy_zoo.cli import main
from leaderboard.trained_discrimination import NO_DIFFERENCE, SEPARATED, UNDECIDABLE, trained_cell, trained_cells

APART = ([0.0] * 10, [1.0] * 10)
ALIKE = ([0.1 * (i % 2) for i in range(10)], [0.1 * ((i + 1) % 2) for i in range(10)])


def test_a_pair_whose_seeds_all_differ_is_separated_with_its_probability() -> None:
    cell = trained_cell(*APART)
    assert (cell.kind, cell.probability, cell.seeds) == (SEPARATED, 1.0, (10, 10))
    assert trained_cell(APART[1], APART[0]).probability == 0.0  # (the first harms more: P 0, still separated)
    assert trained_cell(APART[1], APART[0]).separated
    assert cell.text() == "trained: separated, P 1.00"


def test_a_pair_of_alike_seeds_is_no_difference_detected() -> None:
    cell = trained_cell(*ALIKE)
    assert (cell.kind, cell.probability) == (NO_DIFFERENCE, 0.5)
    assert not cell.separated and cell.text() == "trained: no difference detected, P 0.50"


def test_one_slightly_better_seed_set_is_not_separated_at_ten_seeds() -> None:
    better = [0.0] * 6 + [1.0] * 4  # (P(fewer) = (36 + 24/2 + 24/2) / 100 = 0.60: inside (0.24, 0.76))
    worse = [0.0] * 4 + [1.0] * 6
    cell = trained_cell(better, worse)
    assert (cell.kind, cell.probability) == (NO_DIFFERENCE, pytest.approx(0.6))


def test_too_few_seeds_is_undecidable() -> None:
    cell = trained_cell([0.0, 0.0], [1.0, 1.0])
    assert cell.kind == UNDECIDABLE and cell.text() == "trained: undecidable (2 vs 2 seeds)"


def test_cells_only_where_the_task_can_harm_and_both_methods_have_runs() -> None:
    harms = {("charger_v0", "dqn"): APART[1], ("charger_v0", "e"): APART[0], ("sharing_v0", "dqn"): [0.0] * 10}
    harms[("sharing_v0", "e")] = [0.0] * 10
    cells = trained_cells(["charger_v0", "sharing_v0"], ["dqn", "e", "none"], harms, {"charger_v0": True, "sharing_v0": False})
    assert list(cells) == [("charger_v0", "dqn", "e")]
    assert cells["charger_v0", "dqn", "e"].probability == 0.0


def _row(name: str, method: str, beta: float | None = None) -> dict:
    return {"name": name, "method": method, "selfishness": beta, "identical_to": "", "reason": ""}


TABLE = {
    "env": "charger_v0",
    "rows": [_row("dqn", "dqn"), _row("dqn_harm_penalty", "dqn_harm_penalty"), _row("empathic_dqn β=0.5", "empathic_dqn", 0.5)],
    "outcomes": [
        {"row": r, "epsilon": 0.01, "harms": h, "robot_harmed": 0.0}
        for r, h in (("dqn", 1.0), ("dqn_harm_penalty", 0.0), ("empathic_dqn β=0.5", 0.0))
    ],
    "pairs": [
        {"first": a, "second": b, "epsilon": 0.01, "differ": d, "differing_states": 5 * d, "harms_difference": h}
        | {"by_construction": ""}
        for a, b, d, h in (
            ("dqn", "dqn_harm_penalty", True, 1.0),
            ("dqn", "empathic_dqn β=0.5", True, 1.0),
            ("dqn_harm_penalty", "empathic_dqn β=0.5", False, 0.0),
        )
    ],
}


def test_the_page_shows_each_trained_part_and_counts_the_tasks_that_separate() -> None:
    cells = {("charger_v0", "dqn", "dqn_harm_penalty"): trained_cell(APART[1], APART[0])}
    page = discrimination_markdown({"charger_v0": TABLE}, 0.01, "cmd", cells)
    shown = "separated (5 states, Δharms +1.000); trained: separated, P 0.00"
    assert f"| `dqn` / `dqn_harm_penalty` | {shown} | 1 of 1 | 1 of 1 |" in page
    assert "| `dqn` / `empathic_dqn` | separated (5 states, Δharms +1.000) | 1 of 1 | 0 of 0 |" in page
    assert "(cells tested: 1), each cell at 5 %, unadjusted" in page
    assert "trained" not in discrimination_markdown({"charger_v0": TABLE}, 0.01, "cmd")


def _tables_and_runs(tmp_path: Path, methods: tuple[tuple[str, float, float], ...], env: str = "charger_v0") -> Path:
    tables = tmp_path / "tables"
    tables.mkdir()
    (tables / "charger_v0.json").write_text(json.dumps(TABLE))
    runs = tmp_path / "res" / "runs"
    runs.mkdir(parents=True)
    for seed in range(10):
        for method, beta, harms in methods:
            document = synthetic_document(env, method, beta, seed, harms=harms)
            (runs / f"{document['run_id']}.json").write_text(json.dumps(document))
    return tables


@pytest.mark.parametrize("results", [True, False])
def test_the_command_reads_results_directories(tmp_path: Path, capsys, results) -> None:
    tables = _tables_and_runs(tmp_path, (("dqn", 1.0, 1.0), ("dqn_harm_penalty", 1.0, 0.0), ("empathic_dqn", 0.5, 0.0)))
    out = tmp_path / "D.md"
    argv = ["analyse", "discrimination", str(tables), "--out", str(out)]
    argv += ["--results", str(tmp_path / "res")] if results else []
    assert main(argv) == 0
    page = out.read_text()
    if results:
        assert "separated (5 states, Δharms +1.000); trained: separated, P 0.00" in page
        assert "| `dqn_harm_penalty` / `empathic_dqn` | not separated; trained: no difference detected, P 0.50 |" in page
    else:
        assert "trained" not in page


def test_the_command_refuses_a_results_directory_it_cannot_read(tmp_path: Path, capsys) -> None:
    tables = tmp_path / "tables"
    tables.mkdir()
    (tables / "charger_v0.json").write_text(json.dumps(TABLE))
    bad = tmp_path / "bad" / "runs"
    bad.mkdir(parents=True)
    (bad / "x.json").write_text("{")
    argv = ["analyse", "discrimination", str(tables), "--results", str(tmp_path / "bad"), "--out", str(tmp_path / "D.md")]
    assert main(argv) == 2
    assert "x.json" in capsys.readouterr().err
    assert not (tmp_path / "D.md").exists()


def test_runs_that_make_no_cell_are_refused_not_read_as_zero_of_zero(tmp_path: Path, capsys) -> None:
    tables = _tables_and_runs(tmp_path, (("dqn_harm_penalty", 1.0, 0.0),))  # (one method alone: no pair)
    out = tmp_path / "D.md"
    argv = ["analyse", "discrimination", str(tables), "--results", str(tmp_path / "res"), "--out", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "make no cell" in err and "dqn_harm_penalty on charger_v0" in err, err
    assert not out.exists()


def test_a_method_whose_runs_fall_in_no_cell_is_named(tmp_path: Path, capsys) -> None:
    from leaderboard.trained_discrimination import cells_of_results

    tables = _tables_and_runs(tmp_path, (("dqn", 1.0, 1.0), ("dqn_harm_penalty", 1.0, 0.0)))
    runs = tmp_path / "res" / "runs"
    for seed in range(3):  # (a method of the tables on a task no other method of them has runs of)
        document = synthetic_document("vase_v0", "empathic_dqn", 0.5, seed, harms=0.0)
        (runs / f"{document['run_id']}.json").write_text(json.dumps(document))
    table = json.loads((tables / "charger_v0.json").read_text())
    cells, notes = cells_of_results({"charger_v0": table, "vase_v0": {**table, "env": "vase_v0"}}, [tmp_path / "res"])
    assert set(cells) == {("charger_v0", "dqn", "dqn_harm_penalty")}
    assert any(note.startswith("3 runs of empathic_dqn on vase_v0: in no cell") for note in notes), notes
