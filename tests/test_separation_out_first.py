"""``analyse separation --out`` where no folder can be (a file there, or a file on its way) is
refused in one line, exit 2, before any model is built: the table takes about a minute, and the
arguments alone made the refusal certain."""

from __future__ import annotations

from pathlib import Path

import pytest

from empathy_zoo.cli import main
from empathy_zoo.names import check_output_folder
from tests.test_separation_bounds_first import _no_model  # noqa: F401  (the fixture: no model may be built)


@pytest.mark.usefixtures("_no_model")
@pytest.mark.parametrize("where", ["a file", "under a file"])
def test_an_out_that_cannot_be_a_folder_is_refused_before_any_model(tmp_path: Path, capsys, where: str) -> None:
    (tmp_path / "afile").write_text("kept\n")
    out = tmp_path / "afile" if where == "a file" else tmp_path / "afile" / "sub"
    assert main(["analyse", "separation", "coexistence_v0", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(out) in err and "not a folder" in err, err
    assert (tmp_path / "afile").read_text() == "kept\n" and sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


def test_a_folder_or_a_place_for_one_passes(tmp_path: Path) -> None:
    assert check_output_folder(tmp_path) == tmp_path
    assert check_output_folder(tmp_path / "new" / "deeper") == tmp_path / "new" / "deeper"
    assert not (tmp_path / "new").exists()  # (nothing is made)


def test_discrimination_refuses_an_out_under_a_file_before_reading_a_table(tmp_path: Path, capsys) -> None:
    (tmp_path / "nd").write_text("kept\n")
    assert main(["analyse", "discrimination", "--out", str(tmp_path / "nd" / "x.md")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "not a folder" in err and str(tmp_path / "nd") in err, err
    assert (tmp_path / "nd").read_text() == "kept\n"
