"""``analyse`` tools refuse a directory argument that names a file as such (not as missing), in the
words of every other tool, and ``analyse discrimination`` refuses an ``--epsilon`` the separation
tables were not computed at, naming the option and the ε values they hold (not as a damaged table)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from empathy_zoo.cli import main

ROOT = Path(__file__).resolve().parents[1]
TABLES = ROOT / "docs" / "results" / "separation"
QUICK = ROOT / "docs" / "results" / "quick"


def one_error_line(capsys: pytest.CaptureFixture[str]) -> str:
    """The one line the command wrote to stderr."""
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1, lines
    return lines[0]


@pytest.mark.parametrize(
    "argv",
    [
        ["separation-reading", "{file}"],
        ["separation-reading", "{quick}", "--tables", "{file}"],
        ["discrimination", "{file}"],
        ["discrimination", "--results", "{file}"],
        ["tuning-summary", "{file}"],
        ["versus-dqn", "{file}"],
        ["heldout-verdicts", "{file}"],
        ["coexistence-sensitivity", "{file}"],
        ["compare-runs", "{file}", "{results}"],
        ["equivalence", "{file}", "{results}"],
        ["tuning-effect", "{file}", "{results}"],
        ["population-reading", "{file}", "{results}"],
    ],
)
def test_a_file_given_as_a_directory_is_named_a_file(argv: list[str], tmp_path: Path, capsys, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "afile").write_text("")
    (tmp_path / "results").mkdir()
    given = [arg.format(file="afile", results=tmp_path / "results", quick=QUICK) for arg in argv]
    assert main(["analyse", *given]) == 2
    line = one_error_line(capsys)
    assert line.startswith(f"empathy-zoo analyse {argv[0]}: error: ") and " afile is a file, not a directory: " in line


def test_a_missing_directory_is_said_missing(tmp_path: Path, capsys) -> None:
    for argv in (["tuning-summary", "nowhere"], ["discrimination", "nowhere"], ["separation-reading", "nowhere"]):
        assert main(["analyse", *(str(tmp_path / arg) if arg == "nowhere" else arg for arg in argv)]) == 2
        assert one_error_line(capsys).endswith(f" {tmp_path / 'nowhere'} does not exist")


def test_an_epsilon_no_table_was_computed_at_is_refused_naming_the_option(tmp_path: Path, capsys) -> None:
    from baselines.discrimination import held_epsilons
    from baselines.separation_file import read_separation_table

    held = sorted(set.intersection(*(set(held_epsilons(read_separation_table(path))) for path in TABLES.glob("*.json"))))
    assert len(held) >= 2
    between = (held[-2] + held[-1]) / 2
    assert main(["analyse", "discrimination", "--epsilon", f"{between:g}", "--out", str(tmp_path / "D.md")]) == 2
    line = one_error_line(capsys)
    assert line.startswith(f"empathy-zoo analyse discrimination: error: --epsilon {between:g}: the separation tables in ")
    assert f"ε = {', '.join(f'{value:g}' for value in held)}" in line and "empathy-zoo analyse separation" in line
    assert "no pair '" not in line and not (tmp_path / "D.md").exists()
    assert main(["analyse", "discrimination", "--epsilon", f"{held[-1]:g}", "--out", str(tmp_path / "D.md")]) == 0


def test_a_table_computed_at_fewer_epsilons_is_named(tmp_path: Path, capsys) -> None:
    from baselines.discrimination import held_epsilons

    tables = tmp_path / "tables"
    tables.mkdir()
    for task in ("charger_v0", "vase_v0"):
        shutil.copy(TABLES / f"{task}.json", tables / f"{task}.json")
    table = json.loads((tables / "vase_v0.json").read_text())
    dropped = held_epsilons(table)[-1]
    for key in ("outcomes", "pairs"):
        table[key] = [entry for entry in table[key] if entry["epsilon"] != dropped]
    (tables / "vase_v0.json").write_text(json.dumps(table))
    argv = ["analyse", "discrimination", str(tables), "--out", str(tmp_path / "D.md")]
    assert main([*argv, "--epsilon", f"{dropped:g}"]) == 2
    line = one_error_line(capsys)
    assert f"--epsilon {dropped:g}: the separation tables of vase_v0 in {tables} hold no pairs at that ε" in line
    assert f"every table holds ε = {', '.join(f'{value:g}' for value in held_epsilons(table))})" in line
    assert main([*argv, "--epsilon", f"{held_epsilons(table)[-1]:g}"]) == 0
