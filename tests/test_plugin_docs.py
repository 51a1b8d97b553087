"""The code of docs/plugins.md and docs/formats.md runs as printed: the plug-in page's modules
are written out, its sweep trains the user's fixed agent and methods beside the built-ins, and
the results say what the page says they say."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[1] / "docs"
BLOCK = re.compile(r"^```(python|toml)\n(.*?)^```", re.MULTILINE | re.DOTALL)


def blocks(page: str) -> list[tuple[str | None, str]]:
    """``(file name or None, code)`` of every python/toml block of ``page``, in order; a block
    whose first line is ``# file: NAME`` belongs to that file (several blocks add up)."""
    found = []
    for _, code in BLOCK.findall((DOCS / page).read_text(encoding="utf-8")):
        first, _, rest = code.partition("\n")
        name = first.removeprefix("# file:").strip() if first.startswith("# file:") else None
        found.append((name, rest if name else code))
    return found


def run_page(page: str, directory: Path, run: bool = True) -> None:
    """Write the page's files into ``directory`` and (with ``run``) run its other blocks there, in order."""
    files: dict[str, str] = {}
    for name, code in blocks(page):
        if name is not None:
            files[name] = files.get(name, "") + code + "\n"
            (directory / name).write_text(files[name], encoding="utf-8")
        elif run:
            exec(compile(code, f"{page} block", "exec"), {"__name__": "__doc_block__"})


def write_files(page: str, directory: Path) -> None:
    run_page(page, directory, run=False)


@pytest.fixture
def in_tmp(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))
    yield tmp_path
    sys.modules.pop("my_plugins", None)


def test_the_plugin_page_runs_and_its_runs_are_scored(in_tmp: Path) -> None:
    from empathy_zoo.experiment.result_reader import read_result
    from empathy_zoo.result_file import RUNS_DIR

    page = blocks("plugins.md")
    assert [name for name, _ in page if name] == ["my_plugins.py"] * 3 + ["my_sweep.toml"]
    run_page("plugins.md", in_tmp)
    results = [read_result(path) for path in sorted((in_tmp / "my_results" / RUNS_DIR).glob("*.json"))]
    rows = {(r.variant, r.method_label) for r in results}
    assert rows == {
        ("coexistence_chased", "Tabular Q (ε=0.1)"),
        ("coexistence_chased", "Tabular Q (ε=0.3)"),
        ("coexistence_chased", "DQN"),
        ("sharing_v0", "DQN"),
        ("sharing_v0", "DQN − envy (weight=0.5)"),
        ("sharing_v0", "DQN − envy (weight=1)"),  # a reward transform's field swept like a setting
    }
    chased = [r for r in results if r.variant == "coexistence_chased"]
    assert {r.config.fixed["cat_0"] for r in chased} == {"my_plugins:Chaser(eagerness=0.5)"}
    envious = next(r for r in results if r.method_label == "DQN − envy (weight=0.5)")
    assert envious.config.reward == {"name": "envy", "weight": 0.5}
    heavier = next(r for r in results if r.method_label == "DQN − envy (weight=1)")
    assert heavier.config.reward == {"name": "envy", "weight": 1.0} and heavier.run_id != envious.run_id
    assert set(envious.plugin_sha256 or {}) == {"my_plugins"}
    assert (in_tmp / "my_results" / "LEADERBOARD.md").read_text(encoding="utf-8").count("Tabular Q") >= 2


def test_the_chaser_of_the_page_chases_the_short_way_round_and_resumes_its_state(in_tmp: Path) -> None:
    write_files("plugins.md", in_tmp)
    from my_plugins import Chaser

    def context(robot: tuple[int, int]) -> dict:
        return {"positions": {"cat_0": (0, 0), "robot_0": robot}, "agent": "cat_0", "size": 7}

    eager = Chaser(eagerness=1.0)
    eager.reset(seed=0)
    moves = {robot: eager.act(None, context(robot)) for robot in ((3, 3), (5, 0), (0, 2), (0, 6), (0, 0))}
    assert moves == {(3, 3): 1, (5, 0): 0, (0, 2): 3, (0, 6): 2, (0, 0): 4}
    chaser = Chaser(eagerness=0.5)
    chaser.reset(seed=1)
    saved = chaser.state()
    first = [chaser.act(None, context((3, 3))) for _ in range(20)]
    chaser.load_state(saved)
    assert [chaser.act(None, context((3, 3))) for _ in range(20)] == first
    assert first.count(1) < 20 and set(first) - {1}, "some steps chase (down), some are random"


def test_the_formats_page_snippet_runs(in_tmp: Path, capsys) -> None:
    run_page("formats.md", in_tmp)
    printed = capsys.readouterr().out
    assert "'survival'" in printed and "'harms'" in printed
