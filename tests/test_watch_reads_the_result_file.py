"""``watch RESULT.json`` reads the result file through the result-file reader before it loads the
agent the file names: a file that is no result file (junk beside a copied ``agent`` entry, an
evaluation file) is refused in one line naming it, never played."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import pytest

from empathy_zoo.cli import main

QUICK = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick"
RESULT = sorted((QUICK / "runs").glob("coexistence_v0__dqn_harm_penalty-*__s0.json"))[0]


@pytest.fixture
def beside(tmp_path: Path) -> Path:
    """A folder holding the run's agent file, where a file of another kind names it."""
    agent = json.loads(RESULT.read_text())["agent"]["file"]
    shutil.copyfile(RESULT.with_name(agent), tmp_path / agent)
    return tmp_path


def test_junk_beside_an_agent_entry_is_refused(beside: Path, capsys) -> None:
    document = json.loads(RESULT.read_text())
    fake = beside / "fake.json"
    fake.write_text(json.dumps({"agent": document["agent"], "wall_time_s": math.nan, "eval": "bogus"}))
    assert main(["watch", str(fake), "--episodes", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(fake) in err and "Traceback" not in err, err


def test_the_genuine_result_file_is_watched(beside: Path, capsys) -> None:
    shutil.copyfile(RESULT, beside / RESULT.name)
    assert main(["watch", str(beside / RESULT.name), "--episodes", "1"]) == 0
    assert "harms" in capsys.readouterr().out
