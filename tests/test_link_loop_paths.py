"""A path that is a loop of symbolic links (a link to itself, or a folder on the way that is one)
is refused in one line naming it, exit status 2, by every command that takes a path: read or
written, a results directory, a file, an output folder. Nothing is written, and no traceback.

One generator: each command line below names ``LOOP`` where the loop goes; a new command that
takes a path joins the list and is attacked the same way.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest
import test_check_then_write as check_then_write
from test_reader_forgeries import listing

from empathy_zoo.cli import main
from empathy_zoo.names import check_own_file, check_replaceable, resolved

trained = check_then_write.trained
"""Two tiny runs (DQN, Empathic DQN) that kept their agents (the fixture of tests/test_check_then_write.py)."""

COMMANDS: dict[str, list[str]] = {
    "leaderboard of a loop": ["leaderboard", "LOOP", "--out", "OUT/board"],
    "leaderboard of a directory and a loop": ["leaderboard", "RESULTS", "LOOP", "--out", "OUT/board"],
    "leaderboard --out through a loop": ["leaderboard", "RESULTS", "--out", "LOOP/board"],
    "export of a loop": ["export", "RESULTS", "LOOP", "--format", "marl-eval", "--out", "OUT/e.json"],
    "export --out through a loop": ["export", "RESULTS", "--format", "marl-eval", "--out", "LOOP/x.json"],
    "evaluate of a loop": ["evaluate", "LOOP"],
    "evaluate --scenarios of a loop": ["evaluate", "RESULTS", "--scenarios", "LOOP"],
    "watch --gif through a loop": ["watch", "AGENT", "--gif", "LOOP/a.gif"],
    "analyse separation --out a loop": ["analyse", "separation", "coexistence_v0", "max_cycles=5", "--out", "LOOP"],
    "analyse equivalence of a loop": ["analyse", "equivalence", "RESULTS", "LOOP"],
    "analyse population-reading of a loop": ["analyse", "population-reading", "RESULTS", "LOOP"],
    "analyse discrimination of a loop": ["analyse", "discrimination", "LOOP", "--out", "OUT/d.md"],
    "analyse discrimination --out through a loop": ["analyse", "discrimination", "--out", "LOOP/a.md"],
    "analyse verdict-changes of a loop": ["analyse", "verdict-changes", "LOOP", "LOOP"],
    "analyse tuning-summary of a loop": ["analyse", "tuning-summary", "LOOP"],
    "analyse tuning-summary --figure through a loop": ["analyse", "tuning-summary", "STUDIES", "--figure", "LOOP/x.png"],
    "leaderboard --evaluations of a loop": ["leaderboard", "RESULTS", "--out", "OUT/board", "--evaluations", "LOOP"],
    "reproduction --out through a loop": ["reproduction", "QUICK", "--out", "LOOP/x.md"],
    "sensitivity --out through a loop": ["sensitivity", "QUICK", "--out", "LOOP/x.md"],
    "analyse coexistence-sensitivity --out through a loop": ["analyse", "coexistence-sensitivity", "QUICK", "--out", "LOOP/x.md"],
}
ROOT = Path(__file__).resolve().parents[1]


def _filled(args: list[str], loop: Path, out: Path, results: Path) -> list[str]:
    (agent,) = sorted((results / "runs").glob("coexistence_v0__dqn-*.agent.pt"))
    shipped = {"QUICK": ROOT / "docs" / "results" / "quick", "STUDIES": ROOT / "docs" / "results" / "methods" / "tuning"}
    places = {"LOOP": loop, "OUT": out, "RESULTS": results, "AGENT": agent, **shipped}
    filled = []
    for arg in args:
        head, _, tail = arg.partition("/")
        filled.append(os.fspath(places[head] / tail if tail else places[head]) if head in places else arg)
    return filled


@pytest.mark.parametrize("args", list(COMMANDS.values()), ids=list(COMMANDS))
def test_a_loop_of_links_is_refused_in_one_line_by_every_command(trained, tmp_path, capsys, monkeypatch, args):
    monkeypatch.chdir(tmp_path)  # (a default output lands here, never in the checkout)
    loop = tmp_path / "loop"
    loop.symlink_to(loop.name)  # (a link to itself)
    out = tmp_path / "out"
    before, results_before = listing(tmp_path), listing(trained)
    status = main(_filled(args, loop, out, trained))
    err = capsys.readouterr().err
    assert re.match(r"empathy-zoo( analyse [a-z-]+)?: error: ", err) and err.count("\n") == 1 and "Traceback" not in err, err
    assert status == 2, err
    assert str(loop) in err and ("loop of symbolic links" in err or "Too many levels of symbolic links" in err), err
    assert listing(tmp_path) == before and listing(trained) == results_before, "nothing may be written"


def test_the_path_checks_name_a_loop_on_the_way(tmp_path):
    loop = tmp_path / "loop"
    loop.symlink_to(loop.name)
    for check in (resolved, check_replaceable, lambda path: check_own_file(path, "page", b"# ")):
        with pytest.raises(ValueError, match="loop of symbolic links") as caught:
            check(loop / "a.md")
        assert str(loop / "a.md") in str(caught.value) and "\n" not in str(caught.value)
    assert resolved(tmp_path) == tmp_path.resolve() and check_replaceable(tmp_path / "a.md") == tmp_path / "a.md"
