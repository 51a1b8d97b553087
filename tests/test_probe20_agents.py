"""Agent files read from elsewhere: a head's name starts with a letter (never ``__class__``),
and an agent whose values overflow float32 is refused when it must act, never acting at random."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from empathy_zoo.cli import main

ROOT = Path(__file__).resolve().parents[1]
AGENT = sorted((ROOT / "docs" / "results" / "quick" / "runs").glob("coexistence_v0__empathic_dqn-*__s0.agent.pt"))[0]


def _forged(tmp_path: Path, change: Any) -> Path:
    document = torch.load(AGENT, weights_only=True)
    change(document)
    path = tmp_path / "forged.agent.pt"
    torch.save(document, path)
    return path


@pytest.mark.parametrize("name", ["__class__", "_emp", "__init__"])
def test_a_head_name_that_does_not_start_with_a_letter_is_refused(tmp_path: Path, name: str) -> None:
    from empathy_zoo.agent_file import AgentFileError, load_agent

    def rename(document: dict) -> None:
        document["heads"] = {name: document["heads"][document["acting"]]}
        document["acting"] = name

    with pytest.raises(AgentFileError, match=r"forged\.agent\.pt"):
        load_agent(_forged(tmp_path, rename))


def _overflowing(document: dict) -> None:
    layers = document["heads"][document["acting"]]
    layers[-2] = torch.full_like(layers[-2], 3e38)
    layers[-4] = torch.full_like(layers[-4], 3e38)


def test_an_agent_whose_values_overflow_refuses_to_act(tmp_path: Path) -> None:
    from empathy_zoo.agent_file import load_agent

    agent = load_agent(_forged(tmp_path, _overflowing))
    observation = np.ones(agent.obs_size, np.float32)
    assert not np.isfinite(agent.q_values(observation)[agent.acting]).all(), "the forgery overflows"
    with pytest.raises(ValueError, match=r"forged\.agent\.pt: its head 'q_emp' gives values that are no finite"):
        agent.act(observation)
    with pytest.raises(ValueError, match="no finite numbers"):
        agent.act_batch(observation[None])


def test_watch_refuses_an_overflowing_agent_in_one_line(tmp_path: Path, capsys) -> None:
    forged = _forged(tmp_path, _overflowing)
    capsys.readouterr()
    assert main(["watch", str(forged), "--episodes", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no finite numbers" in err and "Traceback" not in err, err


def test_the_shipped_agent_still_acts(tmp_path: Path) -> None:
    from empathy_zoo.agent_file import load_agent

    shutil.copy(AGENT, tmp_path / AGENT.name)
    agent = load_agent(tmp_path / AGENT.name)
    assert 0 <= agent.act(np.zeros(agent.obs_size, np.float32)) < agent.num_actions
