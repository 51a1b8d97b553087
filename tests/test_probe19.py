"""The eighteenth probe's findings: ``analyse coexistence-sensitivity --out`` writes only a
Markdown file; ``export --out`` finds a results folder through ``..`` and links too; a forged
agent file's ``acting`` and sizes of the wrong type are refused in one line, never a traceback."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from pathlib import Path
from typing import Any

import pytest
import torch

from empathy_zoo.cli import main

ROOT = Path(__file__).resolve().parents[1]
QUICK = ROOT / "docs" / "results" / "quick"
AGENT = sorted((QUICK / "runs").glob("coexistence_v0__empathic_dqn-*__s0.agent.pt"))[0]
RESULT = AGENT.with_name(AGENT.name.removesuffix(".agent.pt") + ".json")


def _refused(argv: list[str], capsys, words: str) -> str:
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err and "Traceback" not in err, err
    return err


@pytest.mark.parametrize("target", [".json", ".agent.pt"])
def test_coexistence_sensitivity_writes_only_a_markdown_file(tmp_path: Path, capsys, target: str) -> None:
    runs = tmp_path / "cs" / "runs"
    runs.mkdir(parents=True)
    for path in (RESULT, AGENT):
        shutil.copy(path, runs / path.name)
    victim = runs / f"{RESULT.stem}{target}"
    before = victim.read_bytes()
    _refused(["analyse", "coexistence-sensitivity", str(runs.parent), "--out", str(victim)], capsys, "ending in .md")
    assert victim.read_bytes() == before


def test_coexistence_sensitivity_refuses_an_empty_out(tmp_path: Path, capsys) -> None:
    capsys.readouterr()
    assert main(["analyse", "coexistence-sensitivity", str(QUICK), "--out", ""]) == 2
    captured = capsys.readouterr()
    assert "an empty path" in captured.err and captured.out == "", captured


def _other_results(tmp_path: Path) -> Path:
    runs = tmp_path / "A" / "runs"
    (tmp_path / "A" / "evaluations" / "coexistence_v0").mkdir(parents=True)
    runs.mkdir()
    shutil.copy(RESULT, runs / RESULT.name)
    return runs.parent


@pytest.mark.parametrize("how", ["dot-dot into runs", "a link to runs", "a link to an evaluation set"])
def test_export_finds_a_results_folder_behind_dot_dot_and_links(tmp_path: Path, capsys, how: str) -> None:
    other = _other_results(tmp_path)
    if how == "dot-dot into runs":
        (other / "runs" / "sub").mkdir()
        out, lands = other / "runs" / "sub" / ".." / "x.json", other / "runs" / "x.json"
    else:
        folder = other / ("runs" if how == "a link to runs" else "evaluations/coexistence_v0")
        os.symlink(folder, tmp_path / "L")
        out, lands = tmp_path / "L" / "y.json", folder / "y.json"
    _refused(["export", str(QUICK), "--format", "marl-eval", "--out", str(out)], capsys, "folder of a results directory")
    assert not lands.exists()


def _nested(depth: int) -> Any:
    value: Any = "q"
    for _ in range(depth):
        value = [value]
    return value


FORGERIES = {
    "acting a list": ("acting", ["q"]),
    "acting a dict": ("acting", {"q": 1}),
    "acting nested 70 deep": ("acting", _nested(70)),
    "obs_size a tensor": ("obs_size", torch.zeros(3)),
    "obs_size a 0-d tensor": ("obs_size", None),
    "obs_size a float": ("obs_size", 25.0),
    "num_actions a tensor": ("num_actions", torch.zeros(2)),
}


def _forged(tmp_path: Path, key: str, value: Any) -> Path:
    runs = tmp_path / "ev" / "runs"
    runs.mkdir(parents=True)
    shutil.copy(RESULT, runs / RESULT.name)
    agent = runs / AGENT.name
    document = torch.load(AGENT, weights_only=True)
    document[key] = torch.tensor(document[key]) if value is None else value
    torch.save(document, agent)
    recorded = json.loads((runs / RESULT.name).read_text())
    recorded["agent"]["sha256"] = hashlib.sha256(agent.read_bytes()).hexdigest()
    (runs / RESULT.name).write_text(json.dumps(recorded))
    return agent


@pytest.mark.parametrize(("key", "value"), list(FORGERIES.values()), ids=list(FORGERIES))
def test_a_forged_acting_or_size_is_refused_in_one_line(tmp_path: Path, capsys, key: str, value: Any) -> None:
    from empathy_zoo.agent_file import AgentFileError, load_agent

    agent = _forged(tmp_path, key, value)
    with pytest.raises(AgentFileError, match=agent.name):
        load_agent(agent)
    _refused(["watch", str(agent), "--episodes", "1"], capsys, agent.name)
    out = tmp_path / "out"
    _refused(["evaluate", str(agent.parent.parent), "--episodes", "1", "--out", str(out)], capsys, agent.name)
    assert not out.exists() or not any(out.rglob("*.json"))


def test_the_shipped_agent_still_loads() -> None:
    from empathy_zoo.agent_file import load_agent

    assert load_agent(AGENT).describe()["env"] == "coexistence_v0"
