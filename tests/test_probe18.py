"""The seventeenth probe's findings on outputs: a report's ``--out`` (``reproduction``,
``sensitivity``) is a Markdown file and never the note it reads; ``export --out`` never
replaces a file of another kind nor writes where results are read; a separation-table row is
never identical to itself."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from empathy_zoo.cli import main

ROOT = Path(__file__).resolve().parents[1]
QUICK = ROOT / "docs" / "results" / "quick"
RESULT = sorted((QUICK / "runs").glob("*.json"))[0]
TABLES = ROOT / "docs" / "results" / "separation"


def _results(tmp_path: Path) -> Path:
    """A copy of two shipped result files (what the refusals are asked about; they read nothing)."""
    runs = tmp_path / "q" / "runs"
    runs.mkdir(parents=True)
    for path in sorted((QUICK / "runs").glob("*.json"))[:2]:
        shutil.copy(path, runs / path.name)
    return runs.parent


def _refused(argv: list[str], capsys, words: str) -> None:
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err and "Traceback" not in err, err


@pytest.mark.parametrize("command", ["reproduction", "sensitivity"])
@pytest.mark.parametrize("suffix", [".json", ".agent.pt", ".txt"])
def test_a_report_is_written_only_to_a_markdown_file(tmp_path: Path, capsys, command: str, suffix: str) -> None:
    results = _results(tmp_path)
    target = results / "runs" / f"{RESULT.stem}{suffix}"
    if suffix == ".json":
        shutil.copy(RESULT, target)
    before = target.read_bytes() if target.exists() else None
    _refused([command, str(results), "--out", str(target)], capsys, "ending in .md")
    assert (target.read_bytes() if target.exists() else None) == before


@pytest.mark.parametrize("command", ["reproduction", "sensitivity"])
def test_a_report_never_replaces_the_note_it_reads(tmp_path: Path, capsys, command: str) -> None:
    results = _results(tmp_path)
    note = tmp_path / "note.md"
    note.write_text("How the run was made.\n")
    _refused([command, str(results), "--note", str(note), "--out", str(note)], capsys, "--note file")
    assert note.read_text() == "How the run was made.\n"


def test_a_report_under_a_file_is_refused_naming_out(tmp_path: Path, capsys) -> None:
    results = _results(tmp_path)
    blocker = tmp_path / "file.md"
    blocker.write_text("")
    _refused(["reproduction", str(results), "--out", str(blocker / "x.md")], capsys, "--out")
    assert blocker.read_text() == ""


def test_export_never_replaces_a_file_of_another_kind(tmp_path: Path, capsys) -> None:
    for victim in (tmp_path / "mine.json", tmp_path / "study.json"):  # (a result file's name: a folder of results)
        shutil.copy(RESULT, victim)
        before = victim.read_bytes()
        _refused(["export", str(QUICK), "--format", "marl-eval", "--out", str(victim)], capsys, "no marl-eval export")
        assert victim.read_bytes() == before


@pytest.mark.parametrize("folder", ["runs", "evaluations/coexistence_v0_test"])
def test_export_never_writes_where_results_or_evaluations_are_read(tmp_path: Path, capsys, folder: str) -> None:
    other = _results(tmp_path / "other")
    (other / folder).mkdir(parents=True, exist_ok=True)
    out = other / folder / "new.json"
    _refused(["export", str(QUICK), "--format", "marl-eval", "--out", str(out)], capsys, "folder of a results directory")
    assert not out.exists()


def test_export_still_replaces_its_own_earlier_export(tmp_path: Path, capsys) -> None:
    out = tmp_path / "quick.json"
    assert main(["export", str(QUICK), "--format", "marl-eval", "--out", str(out)]) == 0
    first = out.read_bytes()
    out.write_bytes(first.replace(b"seed_0", b"seed_9", 1))
    assert main(["export", str(QUICK), "--format", "marl-eval", "--out", str(out)]) == 0
    assert out.read_bytes() == first


def test_a_row_identical_to_itself_is_refused_naming_the_field(tmp_path: Path, capsys) -> None:
    from baselines.discrimination import main as discrimination

    table = json.loads((TABLES / "coexistence_v0.json").read_text())
    first = table["rows"][0]["name"]
    table["rows"][0]["identical_to"] = first
    tables = tmp_path / "tables"
    tables.mkdir()
    (tables / "coexistence_v0.json").write_text(json.dumps(table))
    capsys.readouterr()
    assert discrimination([str(tables)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "rows[0].identical_to" in err and "before it" in err, err


def test_export_still_refuses_the_folder_a_flat_results_directory_is_read_from(tmp_path: Path, capsys) -> None:
    flat = tmp_path / "flat"
    flat.mkdir()
    shutil.copy(RESULT, flat / RESULT.name)
    _refused(["export", str(flat), "--format", "marl-eval", "--out", str(flat / "x.json")], capsys, "folder of result files")
    assert not (flat / "x.json").exists()


def test_the_separation_module_refuses_in_one_line(capsys) -> None:
    from baselines.separation_render import module_main

    assert module_main(["bogus"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "unknown environment 'bogus'" in err, err
