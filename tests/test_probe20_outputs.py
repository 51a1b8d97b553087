"""Outputs never land where a results directory reads its own JSON files: ``tune --out`` into a
``runs`` folder or an evaluation set's folder is refused before anything is written."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
from helpers_sweeps import TUNE_SWEEP
from helpers_tune import run_tune, snapshot

from empathy_zoo.cli import main

ROOT = Path(__file__).resolve().parents[1]
QUICK = ROOT / "docs" / "results" / "quick"
AGENT = sorted((QUICK / "runs").glob("coexistence_v0__empathic_dqn-*__s0.agent.pt"))[0]


@pytest.mark.parametrize("how", ["a runs folder", "an evaluation set", "a link to a runs folder", "dot-dot into runs"])
def test_tune_out_is_never_a_folder_a_results_directory_reads(tmp_path: Path, capsys, how: str) -> None:
    results = tmp_path / "results"
    (results / "runs" / "sub").mkdir(parents=True)
    (results / "evaluations" / "swap").mkdir(parents=True)
    out = {
        "a runs folder": results / "runs",
        "an evaluation set": results / "evaluations" / "swap",
        "a link to a runs folder": tmp_path / "link",
        "dot-dot into runs": results / "runs" / "sub" / "..",
    }[how]
    if how == "a link to a runs folder":
        os.symlink(results / "runs", out)
    sweep = tmp_path / "tiny.toml"
    sweep.write_text(TUNE_SWEEP)
    before = snapshot(results)
    capsys.readouterr()
    assert run_tune(sweep, out, 1) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "lies in a folder of a results directory" in err and "--out" in err, err
    assert snapshot(results) == before


@pytest.mark.parametrize("below", ["", "deeper"])
def test_an_out_through_a_link_to_nothing_says_so(tmp_path: Path, capsys, below: str) -> None:
    os.symlink(tmp_path / "nowhere", tmp_path / "out")
    capsys.readouterr()
    out = tmp_path / "out" / below if below else tmp_path / "out"
    assert main(["leaderboard", str(QUICK), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    link = f"{tmp_path / 'out'} is a symbolic link to {tmp_path / 'nowhere'}, which does not exist"
    assert err.count("\n") == 1 and link in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


EXPERIMENT = "coexistence_v0__dqn_harm_penalty-684a7c7f"


def _small_results(directory: Path) -> Path:
    """The quick profile's three runs of one experiment (without their agents) in ``directory/runs``."""
    (directory / "runs").mkdir(parents=True)
    for source in sorted((QUICK / "runs").glob(f"{EXPERIMENT}__s*.json")):
        document = json.loads(source.read_text(encoding="utf-8"))
        document["agent"] = None
        (directory / "runs" / source.name).write_text(json.dumps(document), encoding="utf-8")
    return directory


@pytest.mark.parametrize("name", ["LEADERBOARD.md", "leaderboard.csv", "leaderboard.html", "figures/coexistence_v0_survival.png"])
def test_the_leaderboard_never_replaces_a_users_file_of_its_names(tmp_path: Path, capsys, name: str) -> None:
    results = _small_results(tmp_path / "results")
    out = tmp_path / "out"
    assert main(["leaderboard", str(results), "--out", str(out)]) == 0
    assert main(["leaderboard", str(results), "--out", str(out)]) == 0, "its own files are replaced"
    (out / name).write_text("my own notes\n", encoding="utf-8")
    before = snapshot(out)
    capsys.readouterr()
    assert main(["leaderboard", str(results), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{out / name} exists and is no leaderboard file this suite writes" in err, err
    assert snapshot(out) == before


def test_a_one_directory_leaderboard_replaces_a_several_directories_one_and_back(tmp_path: Path) -> None:
    from leaderboard.tables import CSV_COLUMNS

    results, copy, out = _small_results(tmp_path / "a"), _small_results(tmp_path / "b"), tmp_path / "out"
    assert main(["leaderboard", str(results), str(copy), "--label", f"{copy}=B", "--out", str(out)]) == 0
    several = (out / "leaderboard.csv").read_text(encoding="utf-8").splitlines()[0]
    assert several.startswith(",".join(CSV_COLUMNS)) and several != ",".join(CSV_COLUMNS)  # (its header has more columns)
    assert main(["leaderboard", str(results), "--out", str(out)]) == 0
    assert (out / "leaderboard.csv").read_text(encoding="utf-8").splitlines()[0] == ",".join(CSV_COLUMNS)
    (out / "leaderboard.csv").write_text("env,grade\nme,A\n", encoding="utf-8")  # (a user's CSV is still no leaderboard's)
    assert main(["leaderboard", str(results), "--out", str(out)]) == 2
    assert (out / "leaderboard.csv").read_text(encoding="utf-8") == "env,grade\nme,A\n"


def _page_commands(tmp_path: Path, notes: Path) -> dict[str, list[str]]:
    studies = tmp_path / "studies"
    studies.mkdir()
    return {
        "discrimination": ["analyse", "discrimination", str(ROOT / "docs" / "results" / "separation"), "--out", str(notes)],
        "coexistence-sensitivity": ["analyse", "coexistence-sensitivity", str(QUICK), "--out", str(notes)],
        "reproduction": ["reproduction", str(QUICK), "--out", str(notes)],
        "sensitivity": ["sensitivity", str(QUICK), "--out", str(notes)],
        "tuning-summary": ["analyse", "tuning-summary", str(studies), "--figure", str(notes.with_suffix(".png"))],
        "watch --gif": ["watch", str(AGENT), "--episodes", "1", "--gif", str(notes.with_suffix(".gif"))],
    }


@pytest.mark.parametrize(
    "command", ["discrimination", "coexistence-sensitivity", "reproduction", "sensitivity", "tuning-summary", "watch --gif"]
)
def test_a_page_or_figure_output_never_replaces_a_users_file(tmp_path: Path, capsys, command: str) -> None:
    argv = _page_commands(tmp_path, tmp_path / "notes.md")[command]
    target = Path(argv[-1])
    target.write_text("# my thesis chapter\n", encoding="utf-8")
    capsys.readouterr()
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.err.count("\n") == 1 and f"{target} exists and is no" in captured.err, captured.err
    assert "survival" not in captured.out, "nothing was played or read"
    assert target.read_text(encoding="utf-8") == "# my thesis chapter\n"


def test_discrimination_replaces_its_own_page(tmp_path: Path) -> None:
    page = tmp_path / "DISCRIMINATION.md"
    argv = ["analyse", "discrimination", str(ROOT / "docs" / "results" / "separation"), "--out", str(page)]
    assert main(argv) == 0
    first = page.read_bytes()
    assert main(argv) == 0 and page.read_bytes() == first


def test_separation_tables_never_land_in_a_results_folder_nor_replace_a_users_file(tmp_path: Path) -> None:
    from baselines.separation_render import module_main

    runs = tmp_path / "results" / "runs"
    runs.mkdir(parents=True)
    assert module_main(["coexistence_v0", "size=5", "view=3", "--out", str(runs)]) == 2
    assert list(runs.iterdir()) == []
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "coexistence_v0.md").write_text("# my notes\n", encoding="utf-8")
    before = snapshot(mine)
    assert module_main(["coexistence_v0", "size=5", "view=3", "--out", str(mine)]) == 2
    assert snapshot(mine) == before
