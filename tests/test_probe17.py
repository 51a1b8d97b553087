"""The sixteenth probe's findings: the agent-file writer refuses networks its readers refuse
(a hidden width or an observation its header contradicts); ``watch --gif`` and ``analyse
discrimination --out`` write only files of their own kind, never an input they read."""

from __future__ import annotations

import re
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from empathy_zoo.cli import main

ROOT = Path(__file__).resolve().parents[1]
RUNS = ROOT / "docs" / "results" / "quick" / "runs"
EXPERIMENT = sorted(RUNS.glob("coexistence_v0__empathic_dqn-*__s0.json"))[0].name.removesuffix("__s0.json")
TABLES = ROOT / "docs" / "results" / "separation"


class _Net:
    """A learner whose run 0 keeps an all-zero Q network of ``inputs`` inputs and ``hidden`` units."""

    def __init__(self, inputs: int, hidden: int | None = None) -> None:
        self.inputs, self.hidden = inputs, hidden

    def agent_state(self, run: int) -> dict[str, Any]:
        if self.hidden is None:
            layers = [np.zeros((self.inputs, 5), np.float32), np.zeros(5, np.float32)]
        else:
            h = self.hidden
            layers = [np.zeros((self.inputs, h), np.float32), np.zeros(h, np.float32)]
            layers += [np.zeros((h, h), np.float32), np.zeros(h, np.float32)]
            layers += [np.zeros((h, 5), np.float32), np.zeros(5, np.float32)]
        return {"heads": {"q": layers}, "acting": "q"}


@pytest.mark.parametrize(
    ("learner", "settings", "field"),
    [
        (_Net(100), {}, "header.env_kwargs"),
        (_Net(25, hidden=8), {"hidden_size": 16}, "header.settings.hidden_size"),
    ],
    ids=["an observation coexistence_v0 does not give", "a hidden width its settings contradict"],
)
def test_the_writer_refuses_networks_its_readers_refuse(tmp_path: Path, learner: _Net, settings: dict, field: str) -> None:
    from empathy_zoo.agent_file import write_agent_file

    header = {"method": "empathic_dqn", "settings": settings, "env": "coexistence_v0", "env_kwargs": {}}
    with pytest.raises(ValueError, match=f"field {re.escape(field)}: expected"):
        write_agent_file(learner, 0, tmp_path / "a.agent.pt", header)
    assert list(tmp_path.iterdir()) == []


def test_the_writer_still_writes_networks_that_fit(tmp_path: Path) -> None:
    from empathy_zoo.agent_file import load_agent, write_agent_file

    header = {"method": "empathic_dqn", "settings": {"hidden_size": 8}, "env": "coexistence_v0", "env_kwargs": {}}
    assert write_agent_file(_Net(25, hidden=8), 0, tmp_path / "a.agent.pt", header) is not None
    assert load_agent(tmp_path / "a.agent.pt").describe()["method"] == "empathic_dqn"


@pytest.mark.parametrize("target", [".json", ".agent.pt", ".txt"])
def test_watch_gif_writes_only_a_gif_never_a_file_it_read(tmp_path: Path, capsys, target: str) -> None:
    for suffix in (".json", ".agent.pt"):
        shutil.copy(RUNS / f"{EXPERIMENT}__s0{suffix}", tmp_path / f"{EXPERIMENT}__s0{suffix}")
    agent = tmp_path / f"{EXPERIMENT}__s0.agent.pt"
    out = tmp_path / f"{EXPERIMENT}__s0{target}"
    before = out.read_bytes() if out.exists() else None
    capsys.readouterr()
    assert main(["watch", str(agent), "--episodes", "1", "--gif", str(out)]) == 2
    captured = capsys.readouterr()
    assert captured.err.count("\n") == 1 and "ending in .gif" in captured.err, captured.err
    assert "survival" not in captured.out, "no episode was played"
    assert (out.read_bytes() if out.exists() else None) == before


def test_discrimination_out_writes_only_a_page_never_a_table_it_read(tmp_path: Path, capsys) -> None:
    from baselines.discrimination import main as discrimination

    tables = tmp_path / "tables"
    tables.mkdir()
    for name in ("charger_v0.json", "coexistence_v0.json"):
        shutil.copy(TABLES / name, tables / name)
    before = (tables / "charger_v0.json").read_bytes()
    capsys.readouterr()
    assert discrimination([str(tables), "--out", str(tables / "charger_v0.json")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "ending in .md" in err, err
    assert (tables / "charger_v0.json").read_bytes() == before
    assert discrimination([str(tables), "--out", str(tmp_path / "page.md")]) == 0
    assert (tmp_path / "page.md").read_text().startswith("#")
