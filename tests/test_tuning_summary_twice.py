"""``analyse tuning-summary`` reads a study file once where it is reached twice (a symbolic link
to it, a second hard link), with a note naming both paths; a copy of a study in another folder
is listed on its own line, with a note naming both files."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest
from test_tuning_summary import STUDIES

from empathy_zoo.cli import main as cli_main
from leaderboard.study_file import find_studies

PROG = "empathy-zoo analyse tuning-summary"
NOTED = 10
"""The most paths a note names (:data:`leaderboard.tuning_summary.NOTED`)."""


def _write(where: Path, study: dict) -> Path:
    where.mkdir(parents=True, exist_ok=True)
    path = where / "study.json"
    path.write_text(json.dumps(study), encoding="utf-8")
    return path


def _lines(out: str) -> list[str]:
    return [line for line in out.splitlines() if line.startswith("| coexistence_v0") or line.startswith("| sharing_v0")]


def test_a_study_reached_by_a_symbolic_and_a_hard_link_is_read_once(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    root = tmp_path / "ts2"
    real = _write(root / "a", STUDIES[0])
    (root / "study.json").symlink_to(Path("a") / "study.json")
    (root / "c").mkdir()
    os.link(real, root / "c" / "study.json")
    assert find_studies(root) == [real]
    from leaderboard.study_file import study_files

    assert study_files(root) == ([real], [(root / "c" / "study.json", real), (root / "study.json", real)])
    assert cli_main(["analyse", "tuning-summary", str(root)]) == 0
    captured = capsys.readouterr()
    assert [line.split(" | ")[1] for line in _lines(captured.out)] == ["DQN"]  # (one study: its label alone)
    assert captured.err == (
        f"{PROG}: note: 2 path(s) lead to a study file read already (a symbolic or hard link), not read again: "
        f"{root}/c/study.json is {real}; {root}/study.json is {real}\n"
    )


def test_a_study_only_links_reach_is_read_once_by_its_first(tmp_path: Path) -> None:
    elsewhere = _write(tmp_path / "elsewhere", STUDIES[1])
    from leaderboard.study_file import study_files

    root = tmp_path / "root"
    for folder in ("x", "y"):
        (root / folder).mkdir(parents=True)
        (root / folder / "study.json").symlink_to(elsewhere)
    assert study_files(root) == ([root / "x" / "study.json"], [(root / "y" / "study.json", root / "x" / "study.json")])


def test_a_copy_in_another_folder_is_listed_with_a_note_naming_both(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    first = _write(tmp_path / "a", STUDIES[0])
    _write(tmp_path / "e", STUDIES[1])
    assert cli_main(["analyse", "tuning-summary", str(tmp_path)]) == 0
    assert capsys.readouterr().err == ""  # (studies of their own: no note)
    (tmp_path / "d").mkdir()
    shutil.copyfile(first, tmp_path / "d" / "study.json")
    assert cli_main(["analyse", "tuning-summary", str(tmp_path)]) == 0
    captured = capsys.readouterr()
    assert [line.split(" | ")[1] for line in _lines(captured.out)] == ["DQN (study a)", "DQN (study d)", "DQN"]
    assert captured.err == (
        f"{PROG}: note: 1 study file(s) hold the same study as another (one document, copied), each on a line of its "
        f"own: {tmp_path}/d/study.json is a copy of {first}; move a copy away\n"
    )


def test_many_links_are_named_up_to_the_bound_then_counted(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from leaderboard.tuning_summary import MAX_NOTED

    assert MAX_NOTED == NOTED
    real = _write(tmp_path / "a", STUDIES[0])
    for i in range(NOTED + 2):
        (tmp_path / f"l{i:02d}").mkdir()
        (tmp_path / f"l{i:02d}" / "study.json").symlink_to(real)
    assert cli_main(["analyse", "tuning-summary", str(tmp_path)]) == 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"{PROG}: note: {NOTED + 2} path(s) lead to a study file")
    assert f"l{NOTED - 1:02d}/study.json is" in err and f"l{NOTED:02d}/" not in err and err.endswith("; and 2 more\n")


@pytest.mark.parametrize("place", ["dangling", "loop"])
def test_a_study_json_that_leads_nowhere_is_refused_not_left_out(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], place
) -> None:
    """``Path.rglob`` skips a name whose target does not exist: such a study would vanish from the
    table without a word. It is found and refused in one line naming it."""
    _write(tmp_path / "a", STUDIES[0])
    (tmp_path / "x").mkdir()
    broken = tmp_path / "x" / "study.json"
    broken.symlink_to("nowhere" if place == "dangling" else "study.json")
    from leaderboard.study_file import study_files

    assert broken in study_files(tmp_path)[0]
    assert cli_main(["analyse", "tuning-summary", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"{PROG}: error: ") and err.count("\n") == 1 and str(broken) in err, err
