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
