"""The twenty-first probe's findings: the claim reports never pool two experiments into one claim's
cell. A run of another label, setting, budget or world beside the paper's runs of one β is refused
in one line (``reproduction``, ``sensitivity``, ``analyse coexistence-sensitivity``), never judged."""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from pathlib import Path

import pytest

from empathy_zoo.cli import main
from empathy_zoo.run_ids import run_id

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "docs" / "results"


def _forged(source: Path, target: Path, change: Callable[[dict], None]) -> str:
    """``source`` (a shipped result file) changed by ``change``, its run id recomputed, written into
    the folder ``target`` without its agent; returns the new run id."""
    document = json.loads(source.read_text(encoding="utf-8"))
    change(document)
    document["agent"] = None
    document["run_id"] = run_id(document["variant"], document["method"], document["config"], document["seed"])
    (target / f"{document['run_id']}.json").write_text(json.dumps(document), encoding="utf-8")
    return document["run_id"]


def _relabelled(document: dict) -> None:
    document["config"]["label"] = document["method_label"] = "Mine, the same β"


def _copy_results(source: Path, target: Path) -> Path:
    (target / "runs").mkdir(parents=True)
    for path in (source / "runs").glob("*.json"):
        shutil.copy(path, target / "runs" / path.name)
    return target


def test_reproduction_refuses_two_experiments_in_one_claims_cell(tmp_path: Path) -> None:
    from leaderboard.aggregate import load_results
    from leaderboard.reproduction import paper_runs

    runs = tmp_path / "runs"
    runs.mkdir()
    shipped = sorted((RESULTS / "paper" / "runs").glob("coexistence_v0__empathic_dqn-*__s0.json"))
    for path in shipped:
        shutil.copy(path, runs / path.name)
    assert paper_runs(load_results(tmp_path))["coexistence_v0"]  # (the shipped runs alone: one experiment a cell)
    forged = _forged(shipped[0], runs, _relabelled)
    with pytest.raises(ValueError, match=r"are both the paper's β=[0-9.]+ in coexistence_v0 but of two experiments") as refused:
        paper_runs(load_results(tmp_path))
    assert forged in str(refused.value)


def test_coexistence_sensitivity_refuses_two_experiments_in_one_cell(tmp_path: Path, capsys) -> None:
    results = _copy_results(RESULTS / "coexistence_sensitivity", tmp_path / "results")
    source = sorted((results / "runs").glob("coexistence_authors__empathic_dqn-*__s0.json"))[0]
    _forged(source, results / "runs", _relabelled)
    capsys.readouterr()
    assert main(["analyse", "coexistence-sensitivity", str(results), "--out", str(tmp_path / "page.md")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "but of two experiments" in err, err
    assert not (tmp_path / "page.md").exists()


def test_coexistence_sensitivity_refuses_two_worlds_in_one_condition(tmp_path: Path) -> None:
    from leaderboard.aggregate import load_results
    from leaderboard.coexistence_sensitivity import condition_runs

    results = _copy_results(RESULTS / "coexistence_sensitivity", tmp_path / "results")
    penalty = sorted((results / "runs").glob("coexistence_authors__dqn_harm_penalty-*.json"))
    for path in penalty:  # (the condition's harm-penalty runs, now in a world of longer episodes)
        path.unlink()
        shipped = RESULTS / "coexistence_sensitivity" / "runs" / path.name
        _forged(shipped, results / "runs", lambda d: d["config"]["env_kwargs"].update(max_cycles=1000))
    with pytest.raises(ValueError, match="but of two worlds"):
        condition_runs(load_results(results))


def test_sensitivity_refuses_a_run_of_a_world_no_condition_varies(tmp_path: Path, capsys) -> None:
    results = _copy_results(RESULTS / "sharing_sensitivity", tmp_path / "results")
    source = sorted((results / "runs").glob("*__empathic_dqn-*__s0.json"))[0]

    def longer(document: dict) -> None:
        _relabelled(document)
        document["config"]["env_kwargs"]["max_cycles"] = 1000

    forged = _forged(source, results / "runs", longer)
    capsys.readouterr()
    assert main(["sensitivity", str(results), "--out", str(tmp_path / "page.md")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"run {forged} sets what no condition varies" in err, err


def test_sensitivity_refuses_two_experiments_in_one_cell(tmp_path: Path, capsys) -> None:
    results = _copy_results(RESULTS / "sharing_sensitivity", tmp_path / "results")
    source = sorted((results / "runs").glob("*__empathic_dqn-*__s0.json"))[0]
    _forged(source, results / "runs", _relabelled)
    capsys.readouterr()
    assert main(["sensitivity", str(results), "--out", str(tmp_path / "page.md")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "but of two experiments" in err, err


@pytest.mark.parametrize("module", ["compare_runs", "equivalence"])
def test_runs_of_two_worlds_or_partners_are_never_paired(tmp_path: Path, module: str) -> None:
    import subprocess
    import sys

    one, two = tmp_path / "one" / "runs", tmp_path / "two" / "runs"
    one.mkdir(parents=True)
    two.mkdir(parents=True)
    for source in sorted((RESULTS / "quick" / "runs").glob("coexistence_v0__dqn_harm_penalty-*.json")):
        shutil.copy(source, one / source.name)
        _forged(source, two, lambda d: d["config"]["fixed"].update(cat_0="stay"))
    done = subprocess.run(
        [sys.executable, "-m", f"leaderboard.{module}", str(one.parent), str(two.parent)],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    what = "run" if module == "compare_runs" else "experiment"  # (none paired: nothing to compare, refused)
    assert done.returncode == 2 and done.stdout == "", done.stdout
    assert f"hold no {what} in common" in done.stderr and "cat_0=stay" in done.stderr, done.stderr


@pytest.mark.parametrize(("text", "words"), [("hello\x00 world\n", "U+0000"), ("a\u202eb\n", "U+202E RIGHT-TO-LEFT OVERRIDE")])
def test_a_note_is_lines_of_printable_text(tmp_path: Path, capsys, text: str, words: str) -> None:
    note = tmp_path / "note.md"
    note.write_text(text, encoding="utf-8")
    capsys.readouterr()
    assert main(["sensitivity", str(RESULTS / "sharing_sensitivity"), "--note", str(note), "--out", str(tmp_path / "s.md")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"--note {note}, line 1: holds {words}" in err, err
    assert not (tmp_path / "s.md").exists()


def test_a_note_with_windows_line_ends_reads_as_its_lines(tmp_path: Path) -> None:
    from empathy_zoo.cli.sweep import _read_note

    note = tmp_path / "note.md"
    note.write_bytes(b"first\r\nsecond\tcolumn\r\n")
    assert _read_note(str(note)) == "first\nsecond\tcolumn\n"
