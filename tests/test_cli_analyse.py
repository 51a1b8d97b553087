"""``empathy-zoo analyse TOOL``: each analysis tool runs as ``python -m MODULE`` runs it."""

from __future__ import annotations

import importlib
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from empathy_zoo.cli import main
from empathy_zoo.cli.analyse import TOOLS

ROOT = Path(__file__).resolve().parents[1]
QUICK = ROOT / "docs" / "results" / "quick"


@pytest.mark.parametrize("name", list(TOOLS))
def test_every_tool_has_a_main(name: str) -> None:
    assert callable(importlib.import_module(TOOLS[name].module).main)


def test_compare_runs_prints_what_python_m_prints(capsys: pytest.CaptureFixture[str], tmp_path) -> None:
    copy = tmp_path / "quick"  # (a copy: one directory given twice is refused)
    shutil.copytree(QUICK / "runs", copy / "runs")
    assert main(["analyse", "compare-runs", str(QUICK), str(copy)]) == 0
    ours = capsys.readouterr().out
    theirs = subprocess.run(
        [sys.executable, "-m", "leaderboard.compare_runs", str(QUICK), str(copy)], capture_output=True, text=True, check=True
    ).stdout
    assert ours == theirs
    assert ours.splitlines()[-1] == "same: 30, different: 0, only_old: 0, only_new: 0"


def test_a_usage_error_names_the_subcommand(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["analyse", "compare-runs", str(QUICK)]) == 2
    assert capsys.readouterr().err.splitlines() == [
        "usage: empathy-zoo analyse compare-runs OLD_DIR NEW_DIR",
        f"empathy-zoo analyse compare-runs: error: takes 2 paths, got 1: {QUICK}",
    ]


@pytest.mark.parametrize(
    ("args", "problem"),
    [
        (["q", "q"], "takes 1 path, got 2: q, q"),
        (["q", "--foo"], "unrecognized arguments: --foo"),
        ([], "takes 1 path, got 0"),
    ],
)
def test_a_usage_error_says_what_is_wrong(capsys: pytest.CaptureFixture[str], args: list[str], problem: str) -> None:
    capsys.readouterr()
    assert main(["analyse", "heldout-verdicts", *args]) == 2
    assert capsys.readouterr().err.splitlines() == [
        "usage: empathy-zoo analyse heldout-verdicts RESULTS_DIR",
        f"empathy-zoo analyse heldout-verdicts: error: {problem}",
    ]


def test_a_tool_help_exits_zero(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["analyse", "verdict-changes", "--help"]) == 0
    assert "old" in capsys.readouterr().out


def test_an_unknown_tool_is_a_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["analyse", "no-such-tool"]) == 2
    err = capsys.readouterr().err
    assert "invalid choice: 'no-such-tool'" in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("tool", list(TOOLS))
def test_every_tool_answers_help_with_status_zero(capsys: pytest.CaptureFixture[str], tool: str) -> None:
    assert main(["analyse", tool, "--help"]) == 0
    assert capsys.readouterr().out.strip()


def test_exact_prints_a_small_tasks_table_and_refuses_what_it_cannot_model(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["analyse", "exact", "coexistence_v0", "size=5", "view=3"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "| β | ε | harms | survival |" and "| 1 | 0 | 1.0000 | 500.0 |" in lines
    assert main(["analyse", "exact", "nope_v0"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "unknown environment 'nope_v0'" in err


@pytest.mark.parametrize("tool", list(TOOLS))
def test_every_tools_usage_error_names_the_command_typed(capsys: pytest.CaptureFixture[str], tool: str) -> None:
    assert main(["analyse", tool, "--no-such-option"]) == 2
    err = capsys.readouterr().err
    assert f"empathy-zoo analyse {tool}" in err and "python -m" not in err


@pytest.mark.parametrize(
    ("tool", "args"),
    [
        ("tuning-summary", ["{missing}"]),
        ("population-reading", ["{missing}", "{missing}"]),
        ("verdict-changes", ["{missing}", "{missing}"]),
        ("separation-reading", ["{missing}"]),
        ("discrimination", ["{missing}"]),
    ],
)
def test_a_tools_refusal_names_the_command_typed(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, tool: str, args: list[str]
) -> None:
    missing = str(tmp_path / "missing")
    assert main(["analyse", tool, *(a.format(missing=missing) for a in args)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"empathy-zoo analyse {tool}: error: ") and err.count("\n") == 1, err


@pytest.mark.parametrize(
    ("module", "count"),
    [("compare_runs", 2), ("versus_dqn", 1), ("heldout_verdicts", 1), ("equivalence", 2), ("reproduction", 1)],
)
def test_a_positional_tool_refuses_a_missing_or_forged_directory_in_one_line(tmp_path: Path, module: str, count: int) -> None:
    forged = tmp_path / "forged"
    (forged / "runs").mkdir(parents=True)
    (forged / "runs" / "x.json").write_text('{"schema": 1, "run_id": 5}', encoding="utf-8")
    for directory in (tmp_path / "missing", forged):
        done = subprocess.run(
            [sys.executable, "-m", f"leaderboard.{module}", *[str(directory)] * count],
            capture_output=True,
            text=True,
            cwd=ROOT,
        )
        assert done.returncode == 2 and done.stderr.startswith(f"python -m leaderboard.{module}: error: "), done.stderr
        assert done.stderr.count("\n") == 1 and str(directory) in done.stderr


@pytest.mark.parametrize("module", ["compare_runs", "versus_dqn", "heldout_verdicts", "equivalence", "reproduction"])
def test_a_positional_tool_takes_no_unknown_option_for_a_path(module: str) -> None:
    done = subprocess.run(
        [sys.executable, "-m", f"leaderboard.{module}", "--bogus", str(QUICK)], capture_output=True, text=True, cwd=ROOT
    )
    assert done.returncode == 2 and done.stderr.startswith(f"usage: python -m leaderboard.{module} "), done.stderr


@pytest.mark.parametrize(("tool", "what", "count"), [("compare-runs", "run", 15), ("equivalence", "experiment", 5)])
def test_two_directories_of_no_common_experiment_are_refused(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, tool: str, what: str, count: int
) -> None:
    coexistence, sharing = tmp_path / "c", tmp_path / "s"
    for folder, env in ((coexistence, "coexistence_v0"), (sharing, "sharing_v0")):
        (folder / "runs").mkdir(parents=True)
        for source in (QUICK / "runs").glob(f"{env}__*.json"):
            shutil.copy(source, folder / "runs" / source.name)
    capsys.readouterr()
    assert main(["analyse", tool, str(coexistence), str(sharing)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1, (out, err)
    assert f"hold no {what} in common ({count} only in {coexistence}" in err and f"{count} only in {sharing}" in err, err


@pytest.mark.parametrize("name", list(TOOLS))
def test_a_tools_help_names_the_command_typed(capsys: pytest.CaptureFixture[str], name: str) -> None:
    capsys.readouterr()
    assert main(["analyse", name, "--help"]) == 0
    out = capsys.readouterr().out
    assert f"empathy-zoo analyse {name}" in out and f"python -m {TOOLS[name].module}" not in out, out[:300]
