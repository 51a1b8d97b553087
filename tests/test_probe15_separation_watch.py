"""The fifteenth probe's findings, each refused in one line naming the file and the field.

* A separation table's pair cross-checks its counts: ``differ`` is true exactly when
  ``differing_states`` is above 0, and ``differing_states`` is at most ``reachable_states``
  (an integer, where the pair holds it), as :mod:`baselines.separation` writes them.
* ``watch`` of an agent file whose header's ``env_kwargs`` give an observation its network does
  not read (another ``view``) is refused before any episode, naming the file and
  ``header.env_kwargs``.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import pytest
import torch

from baselines.separation_file import SeparationTableError, read_separation_table
from empathy_zoo.cli import main

ROOT = Path(__file__).resolve().parents[1]
SHIPPED_TABLES = sorted((ROOT / "docs" / "results" / "separation").glob("*.json"))
TABLE = ROOT / "docs" / "results" / "separation" / "vase_v0.json"
RUNS = ROOT / "docs" / "results" / "quick" / "runs"
AGENTS = {
    "coexistence_v0": RUNS / "coexistence_v0__dqn_harm_penalty-684a7c7f__s0.agent.pt",
    "sharing_v0": sorted(RUNS.glob("sharing_v0__*__s0.agent.pt"))[0],
}


def one_error_line(capsys: pytest.CaptureFixture[str]) -> str:
    """The one line the CLI wrote to stderr."""
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1, lines
    return lines[0]


# --------------------------------------------------------------------------- separation tables


def test_every_shipped_table_reads_and_its_pairs_are_consistent() -> None:
    assert len(SHIPPED_TABLES) >= 6
    for path in SHIPPED_TABLES:
        table = read_separation_table(path)
        for pair in table["pairs"]:
            assert pair["differ"] == (pair["differing_states"] > 0)
            assert pair["differing_states"] <= pair["reachable_states"]


def forged_table(tmp_path: Path, change: dict[str, Any], differ: bool = True) -> tuple[Path, int]:
    """A copy of the shipped vase table in ``tmp_path/tables`` with ``change`` made to its first pair
    whose ``differ`` is ``differ``; the file and the pair's index."""
    table = json.loads(TABLE.read_text())
    index = next(i for i, pair in enumerate(table["pairs"]) if pair["differ"] is differ)
    table["pairs"][index].update(change)
    folder = tmp_path / "tables"
    folder.mkdir()
    path = folder / TABLE.name
    path.write_text(json.dumps(table))
    return path, index


FORGERIES = {
    "differ without a differing state": (True, {"differing_states": 0}, "differ"),
    "no differ with differing states": (False, {"differing_states": 3}, "differ"),
    "more differing states than reachable": (True, {"differing_states": 10**6}, "differing_states"),
    "reachable states not a count": (True, {"reachable_states": 2.5}, "reachable_states"),
    "reachable states negative": (True, {"reachable_states": -1}, "reachable_states"),
}


@pytest.mark.parametrize("name", sorted(FORGERIES))
def test_a_pair_whose_counts_disagree_is_refused_naming_the_field(tmp_path, name) -> None:
    differ, change, field = FORGERIES[name]
    path, index = forged_table(tmp_path, change, differ)
    with pytest.raises(SeparationTableError) as error:
        read_separation_table(path)
    message = str(error.value)
    assert "\n" not in message
    assert str(path) in message and f"pairs[{index}].{field}" in message, message


def test_the_cli_refuses_such_a_table_in_one_line(tmp_path, capsys) -> None:
    path, index = forged_table(tmp_path, {"differing_states": 0}, True)
    assert main(["analyse", "discrimination", str(path.parent), "--out", str(tmp_path / "D.md")]) == 2
    line = one_error_line(capsys)
    assert str(path) in line and f"pairs[{index}].differ" in line, line
    assert not (tmp_path / "D.md").exists()


# --------------------------------------------------------------------------- watch


def forged_agent(tmp_path: Path, env: str, env_kwargs: dict[str, Any]) -> Path:
    """A copy of a shipped agent of ``env`` whose header says ``env_kwargs`` (no run id or seed:
    its run id is a hash of the configuration, and a header may hold none)."""
    document = torch.load(AGENTS[env], weights_only=True)
    header = document["header"]
    assert header["env"] == env
    header.pop("run_id")
    header.pop("seed")
    header["env_kwargs"] = env_kwargs
    path = tmp_path / f"forged_{env}.agent.pt"
    torch.save(document, path)
    return path


@pytest.mark.parametrize("env", sorted(AGENTS))
def test_watch_refuses_a_header_whose_view_the_network_does_not_read(tmp_path, capsys, env) -> None:
    path = forged_agent(tmp_path, env, {"view": 3})
    assert main(["watch", str(path), "--episodes", "1"]) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1, lines
    assert str(path) in lines[0] and "header.env_kwargs" in lines[0], lines[0]
    assert "25 values" in lines[0] and "'view': 3" in lines[0], lines[0]
    assert "episode 0" not in captured.out


def test_watch_plays_a_header_of_another_size_and_the_same_view(tmp_path, capsys) -> None:
    path = forged_agent(tmp_path, "coexistence_v0", {"size": 6, "max_cycles": 5})
    assert main(["watch", str(path), "--episodes", "1"]) == 0
    assert "episode 0 (seed 0)" in capsys.readouterr().out


def test_the_shipped_agent_copied_still_plays(tmp_path, capsys) -> None:
    path = tmp_path / "copy.agent.pt"
    shutil.copyfile(AGENTS["coexistence_v0"], path)
    assert main(["watch", str(path), "--episodes", "1"]) == 0
    assert "episode 0 (seed 0)" in capsys.readouterr().out
