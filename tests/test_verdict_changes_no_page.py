"""``analyse verdict-changes`` refuses a page that holds no verdict table it reads (a README, an
empty file, a page of ``#### P(improves on DQN)`` headings as REPRODUCTION.md writes them): one line
naming the file and what to give, status 2, nothing on stdout. Before, each read as a page of zero
cells and printed "0 cells on both pages; 0 marks differ", which reads as "no verdict moved"."""

from __future__ import annotations

from pathlib import Path

import pytest

from empathy_zoo.cli import main as cli_main

ROOT = Path(__file__).resolve().parents[1]
QUICK = ROOT / "docs" / "results" / "quick" / "LEADERBOARD.md"
TABLE = "| Method | Seeds | harms |\n|---|---|---|\n| A | 5 | ▲ 0.9 |\n"
PAGES = {
    "readme": "# empathy-zoo\n\nA PettingZoo gridworld benchmark suite.\n\n| a | b |\n|---|---|\n| 1 | 2 |\n",
    "empty": "",
    "reproduction": "# Reproduction\n\n## coexistence_v0\n\n#### P(improves on DQN): harms\n\n" + TABLE,
    "heading only": "## env\n### P(improves on DQN): Final greedy evaluation\n\nNo table.\n",
}


@pytest.mark.parametrize("kind", sorted(PAGES))
@pytest.mark.parametrize("side", ["old", "new", "both"])
def test_a_page_of_no_verdict_table_is_refused_naming_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], kind: str, side: str
) -> None:
    page = tmp_path / "PAGE.md"
    page.write_text(PAGES[kind], encoding="utf-8")
    old, new = {"old": (page, QUICK), "new": (QUICK, page), "both": (page, page)}[side]
    before = sorted(tmp_path.iterdir())
    assert cli_main(["analyse", "verdict-changes", str(old), str(new)]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.count("\n") == 1 and err.startswith("empathy-zoo analyse verdict-changes: error: ")
    assert f"leaderboard page {page}: holds no verdict table" in err
    assert "### P(improves on DQN): " in err and "give a LEADERBOARD.md the leaderboard wrote" in err
    assert sorted(tmp_path.iterdir()) == before  # (nothing written)


def test_the_repositorys_readme_and_changelog_are_refused(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli_main(["analyse", "verdict-changes", str(ROOT / "README.md"), str(ROOT / "CHANGELOG.md")]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and f"leaderboard page {ROOT / 'README.md'}: holds no verdict table" in err


def test_every_shipped_page_with_verdict_tables_is_still_compared(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from leaderboard.verdict_changes import verdicts

    pages = sorted((ROOT / "docs" / "results").glob("**/LEADERBOARD.md"))
    with_tables = [page for page in pages if verdicts(page.read_text(encoding="utf-8"))]
    assert len(with_tables) >= 6
    for page in with_tables:
        copy_of_page = tmp_path / "copy.md"  # (a copy: one file given twice is refused, as are pages of no common cell)
        copy_of_page.write_bytes(page.read_bytes())
        assert cli_main(["analyse", "verdict-changes", str(page), str(copy_of_page)]) == 0
        assert capsys.readouterr().out.split("\n", 1)[0].endswith("change sign).")


def test_two_pages_that_share_no_cell_are_refused_naming_a_cell_of_each(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    old, new = tmp_path / "old.md", tmp_path / "new.md"
    old.write_text("## env\n### P(improves on DQN): Final greedy evaluation\n" + TABLE, encoding="utf-8")
    new.write_text("## other\n### P(improves on DQN): Final greedy evaluation\n" + TABLE, encoding="utf-8")
    capsys.readouterr()
    assert cli_main(["analyse", "verdict-changes", str(old), str(new)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1, (out, err)
    assert f"leaderboard pages {old} and {new} share no verdict cell" in err
    assert (
        "1 cells on the first only, e.g. A · harms (env, Final greedy evaluation); 1 on the second only, e.g. A · harms " in err
    )


def test_the_shipped_pages_of_two_tasks_are_refused_as_sharing_no_cell(capsys: pytest.CaptureFixture[str]) -> None:
    results = ROOT / "docs" / "results"
    first, second = results / "sharing_sensitivity" / "LEADERBOARD.md", results / "coexistence_sensitivity" / "LEADERBOARD.md"
    capsys.readouterr()
    assert cli_main(["analyse", "verdict-changes", str(first), str(second)]) == 2
    assert "share no verdict cell" in capsys.readouterr().err
