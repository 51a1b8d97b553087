"""Many tuning studies at a glance: the table counts each study's trials and steps as its
``study.json`` says, and the figure draws studies of one parameter and refuses others."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest

from leaderboard.study_file import find_studies
from leaderboard.tuning_summary import main, render_studies_png, summarise, summary_table


def _curve(state: str, value: float | None) -> list[dict[str, Any]]:
    """What tune writes of a trial's curve (evaluated every 20 of 100 steps on one seed): a finished
    one's to the last step (``value`` at each point, so over the curve its value), a pruned one's
    to step 60, none for a refused one."""
    steps = {"COMPLETE": [20, 40, 60, 80, 100], "PRUNED": [20, 40, 60]}.get(state, [])
    point = 250.0 if value is None else value
    return [{"step": step, "value": point, "per_seed": [point]} for step in steps]


def _study(variant: str, label: str, rates: list[float], states: list[str], values: list[float | None]) -> dict[str, Any]:
    trials = [
        {"number": i, "state": s, "params": {"learning_rate": r}, "value": v, "wall_time_s": 30.0}
        for i, (r, s, v) in enumerate(zip(rates, states, values, strict=True))
    ]
    for trial in trials:  # (the fields tune writes of each trial: its curve, its value over it, its steps)
        curve = _curve(trial["state"], trial["value"])
        trial.update(
            curve=curve, last_value=curve[-1]["value"] if curve else None, steps_trained=curve[-1]["step"] if curve else 0
        )
    finished = [t for t in trials if t["state"] == "COMPLETE"]
    best = max(finished, key=lambda t: t["value"]) if finished else None
    interrupted = {"number": len(trials), "state": "INTERRUPTED", "params": {}, "value": None, "wall_time_s": 5.0}
    interrupted.update(curve=[], last_value=None, steps_trained=0)
    return {
        "plan": {
            "variant": variant,
            "label": label,
            "params": {"learning_rate": "log:0.0001:0.003"},
            "objective": {"metric": "survival", "direction": "maximize", "over": "curve"},
            "tuning_seeds": [10000],
            "budget": {"env_steps_at_most": 400, "steps": 100, "eval_interval": 20},
        },
        "trials": [*trials, interrupted],
        "env_steps_trained": sum(t["steps_trained"] for t in trials),  # (× 1 tuning seed)
        "best": best and {"number": best["number"], "value": best["value"], "params": best["params"]},
    }


STUDIES = [
    _study(
        "coexistence_v0",
        "DQN",
        [1e-4, 1e-3, 2e-3, 3e-4],
        ["COMPLETE", "COMPLETE", "PRUNED", "REFUSED"],
        [300.0, 420.0, None, None],
    ),
    _study("sharing_v0", "DQN", [2e-4, 5e-4], ["PRUNED", "PRUNED"], [None, None]),
]


def test_a_study_is_counted_as_its_file_says() -> None:
    first = summarise(STUDIES[0])
    assert (first.trials, first.finished, first.pruned, first.refused) == (4, 2, 1, 1)  # (the interrupted one not counted)
    assert first.best_value == 420.0 and first.best_params == {"learning_rate": 1e-3}
    assert first.wall_time_s == 120.0 and first.env_steps_trained == 260 and first.over == "curve"
    table = summary_table([summarise(s) for s in STUDIES])
    assert "| coexistence_v0 | DQN | 4: 2 / 1 / 1 | 260 (400) | 2.0 min | survival 420 (curve) | learning_rate = 0.001 |" in table
    assert "| sharing_v0 | DQN | 2: 0 / 2 / 0 |" in table and "none finished" in table


def test_the_figure_draws_studies_of_one_parameter_and_refuses_others() -> None:
    assert render_studies_png(STUDIES)[:8] == b"\x89PNG\r\n\x1a\n"
    other = json.loads(json.dumps(STUDIES[1]))
    other["plan"]["params"] = {"gamma": "float:0.9:0.99"}
    with pytest.raises(ValueError, match="one and the same parameter"):
        render_studies_png([STUDIES[0], other])
    other["plan"]["params"] = {"others": "choice:closest,min"}
    with pytest.raises(ValueError, match="numeric parameter"):
        render_studies_png([other])


def test_the_command_finds_studies_at_any_depth(tmp_path: Path, capsys) -> None:
    for study in STUDIES:
        where = tmp_path / study["plan"]["variant"] / "dqn"
        where.mkdir(parents=True)
        (where / "study.json").write_text(json.dumps(study))
    assert len(find_studies(tmp_path)) == 2
    assert main([str(tmp_path), "--figure", str(tmp_path / "studies.png")]) == 0
    assert "| sharing_v0 | DQN |" in capsys.readouterr().out
    assert (tmp_path / "studies.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    (tmp_path / "coexistence_v0" / "none").mkdir()
    with pytest.raises(ValueError, match=re.escape("no study.json")):
        find_studies(tmp_path / "coexistence_v0" / "none")
    with pytest.raises(ValueError, match=re.escape(f"tuning directory {tmp_path / 'coexistence_v0' / 'nowhere'} does not exist")):
        find_studies(tmp_path / "coexistence_v0" / "nowhere")


def test_two_studies_of_one_variant_and_label_are_told_apart_by_their_folders(tmp_path: Path, capsys, monkeypatch) -> None:
    from test_probe18_tuning import _texts_drawn

    from leaderboard import tuning_summary

    for folder in ("first", "second"):  # (two studies of coexistence_v0's DQN, copied apart)
        where = tmp_path / folder / "DQN"
        where.mkdir(parents=True)
        (where / "study.json").write_text(json.dumps(STUDIES[0]))
    (tmp_path / "third").mkdir()
    (tmp_path / "third" / "study.json").write_text(json.dumps(STUDIES[1]))
    figure = tmp_path / "studies.png"

    def draw() -> bytes:
        assert main([str(tmp_path), "--figure", str(figure)]) == 0
        return figure.read_bytes()

    drawn = _texts_drawn(monkeypatch, tuning_summary, draw)
    assert {"DQN (study first/DQN)", "DQN (study second/DQN)", "DQN"} <= drawn
    out = capsys.readouterr().out
    names = [line.split(" | ")[1] for line in out.splitlines() if line.startswith("| coexistence_v0")]
    assert names == ["DQN (study first/DQN)", "DQN (study second/DQN)"]
    assert "| sharing_v0 | DQN |" in out  # (a study alone with its variant and label keeps the label alone)
