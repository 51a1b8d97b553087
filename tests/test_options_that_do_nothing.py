"""An option that would change nothing is refused in one line, never silently ignored:
``watch --gif-steps`` without ``--gif``."""

from __future__ import annotations

from pathlib import Path

from empathy_zoo.cli import main

ROOT = Path(__file__).resolve().parents[1]
QUICK = ROOT / "docs" / "results" / "quick"


def test_gif_steps_without_a_gif_is_refused(tmp_path: Path, capsys) -> None:
    (agent,) = sorted((QUICK / "runs").glob("coexistence_v0__dqn_harm_penalty-*__s0.agent.pt"))
    assert main(["watch", str(agent), "--gif-steps", "10", "--episodes", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--gif-steps" in err and "--gif PATH" in err, err
