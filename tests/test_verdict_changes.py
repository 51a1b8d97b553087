"""``leaderboard.verdict_changes`` lists the cells whose mark against DQN differs between two pages."""

from __future__ import annotations

from leaderboard.verdict_changes import changes, changes_markdown, main, verdicts


def page(harms: str, survival: str) -> str:
    return f"""# Leaderboard

## coexistence_v0

### Final greedy evaluation

| Method | Seeds | survival | harms |
|:---|---:|---:|---:|
| DQN | 5 | ▲ 1 | 2 |

### P(improves on DQN): Final greedy evaluation

| Method | Seeds | survival | harms |
|:---|---:|---:|---:|
| Empathic DQN (β=0.5) | 5 | {survival} 0.40 [0.10, 0.90] · IQM 3 | {harms} 0.90 [0.60, 1.00] · IQM 0 |
"""


def test_marks_are_read_from_the_improvement_tables_only():
    cells = verdicts(page("▲", "▼"))
    assert cells == {
        ("coexistence_v0", "Final greedy evaluation", "Empathic DQN (β=0.5)", "survival"): "▼",
        ("coexistence_v0", "Final greedy evaluation", "Empathic DQN (β=0.5)", "harms"): "▲",
    }


def test_a_new_mark_and_a_sign_change_are_listed_and_equal_marks_are_not():
    old, new = verdicts(page("", "▼")), verdicts(page("▲", "▲"))
    cell = ("coexistence_v0", "Final greedy evaluation", "Empathic DQN (β=0.5)")
    assert changes(old, new) == [((*cell, "survival"), "▼", "▲"), ((*cell, "harms"), "", "▲")]
    assert changes(new, new) == []
    text = changes_markdown(page("", "▼"), page("▲", "▲"))
    assert text.startswith("2 cells on both pages; 2 marks differ (1 change sign).")
    assert "| survival | ▼ | ▲ | sign changed |" in text and "| harms | – | ▲ | new mark |" in text


def test_the_command_prints_the_table(tmp_path, capsys):
    (tmp_path / "old.md").write_text(page("▲", ""))
    (tmp_path / "new.md").write_text(page("", ""))
    assert main([str(tmp_path / "old.md"), str(tmp_path / "new.md")]) == 0
    assert "| harms | ▲ | – | mark gone |" in capsys.readouterr().out


def against_page(first: str, second: str, seeds: int = 5) -> str:
    """A page whose tables name each row's DQN row: Empathic DQN against two DQN rows."""
    return f"""# Leaderboard

## coexistence_v0

### P(improves on DQN): Final greedy evaluation

| Method | Against | Seeds | harms |
|:---|:---|---:|---:|
| Empathic DQN (β=0.5) | DQN ({seeds} seeds) | {seeds} | {first} 0.90 [0.60, 1.00] · IQM 0 |
| Empathic DQN (β=0.5) | DQN, tuned ({seeds} seeds) | {seeds} | {second} 0.90 [0.60, 1.00] · IQM 0 |
"""


def test_rows_against_two_dqn_rows_are_two_rows_and_seeds_is_no_metric():
    cells = verdicts(against_page("▲", "▼"))
    assert cells == {
        ("coexistence_v0", "Final greedy evaluation", "Empathic DQN (β=0.5), against DQN", "harms"): "▲",
        ("coexistence_v0", "Final greedy evaluation", "Empathic DQN (β=0.5), against DQN, tuned", "harms"): "▼",
    }
    text = changes_markdown(against_page("▲", "▲"), against_page("▼", "▲", seeds=10))  # (5 seeds against 10: one row)
    assert text.startswith("2 cells on both pages; 1 marks differ (1 change sign).")
    assert "| Empathic DQN (β=0.5), against DQN | harms | ▲ | ▼ | sign changed |" in text


def test_a_page_with_one_cell_twice_is_refused():
    import pytest

    twice = page("▲", "").replace("| Empathic DQN", "| Empathic DQN (β=0.5) | 5 | ▼ 1 | ▼ 1 |\n| Empathic DQN", 1)
    with pytest.raises(ValueError, match="two rows 'Empathic DQN"):
        verdicts(twice)
