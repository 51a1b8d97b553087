"""``analyse verdict-changes`` counts and names the cells found on one page only (a method row
gone, a metric column renamed), bounded; a header naming a metric column twice is refused naming
that column."""

from __future__ import annotations

from pathlib import Path

import pytest

from empathy_zoo.cli import main as cli_main
from leaderboard.verdict_changes import changes_markdown, verdicts

MAX_NAMED = 10
"""The most cells of one page only the summary names (:data:`leaderboard.verdict_changes.MAX_NAMED`)."""
HEAD = "## env\n### P(improves on DQN): Final greedy evaluation\n"


def page(rows: dict[str, str], metric: str = "harms") -> str:
    """A page of one table: a row per method, its one metric cell as given."""
    lines = [f"| Method | Seeds | {metric} |", "|---|---|---|", *(f"| {m} | 5 | {cell} |" for m, cell in rows.items())]
    return HEAD + "\n".join(lines) + "\n"


def test_a_row_on_the_old_page_only_is_counted_and_named(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    old, new = tmp_path / "old.md", tmp_path / "new.md"
    old.write_text(page({"A": "▲ 0.9", "B": "▼ 0.2"}), encoding="utf-8")
    new.write_text(page({"A": "▲ 0.9"}), encoding="utf-8")
    assert cli_main(["analyse", "verdict-changes", str(old), str(new)]) == 0
    assert capsys.readouterr().out.splitlines()[:4] == [
        "1 cells on both pages; 0 marks differ (0 change sign).",
        "1 cells on the old page only, not compared: B · harms (env, Final greedy evaluation) ▼.",
        "0 cells on the new page only.",
        "",
    ]
    same = changes_markdown(page({"A": "▲ 0.9", "B": "0.2"}), page({"A": "0.9", "B": "0.2"}))
    assert same == (  # (pages of the same cells: the output as it was, no line of one page's cells)
        "2 cells on both pages; 1 marks differ (0 change sign).\n\n"
        "| variant | phase | method | metric | old | new | change |\n"
        "|---|---|---|---|:-:|:-:|---|\n"
        "| env | Final greedy evaluation | A | harms | ▲ | – | mark gone |\n"
    )


def test_a_renamed_column_names_its_cells_on_each_page() -> None:
    text = changes_markdown(page({"A": "▲ 0.9"}), page({"A": "0.5"}, metric="harm\\|s"))
    assert text.splitlines()[:3] == [
        "0 cells on both pages; 0 marks differ (0 change sign).",
        "1 cells on the old page only, not compared: A · harms (env, Final greedy evaluation) ▲.",
        "1 cells on the new page only, not compared: A · harm\\|s (env, Final greedy evaluation) –.",
    ]


def test_past_the_bound_the_rest_are_counted() -> None:
    many = {f"M{i:02d}": "0.5" for i in range(MAX_NAMED + 3)}
    line = changes_markdown(page(many), page({})).splitlines()[1]
    assert line.startswith(f"{MAX_NAMED + 3} cells on the old page only, not compared: M00 · harms")
    assert f"M{MAX_NAMED - 1:02d} · harms" in line and f"M{MAX_NAMED:02d}" not in line
    assert line.endswith("; and 3 more.")


def test_a_metric_column_named_twice_is_refused_naming_the_column(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    twice = HEAD + "| Method | Seeds | harms | harms |\n|---|---|---|---|\n| A | 5 | ▲ 0.9 | 0.5 |\n"
    with pytest.raises(ValueError, match=r"^two columns 'harms' in 'env', 'Final greedy evaluation': ") as refused:
        verdicts(twice)
    assert "row" not in str(refused.value)
    (tmp_path / "twice.md").write_text(twice, encoding="utf-8")
    (tmp_path / "one.md").write_text(page({"A": "▲ 0.9"}), encoding="utf-8")
    assert cli_main(["analyse", "verdict-changes", str(tmp_path / "one.md"), str(tmp_path / "twice.md")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and ": error: leaderboard page " in err and "two columns 'harms'" in err
