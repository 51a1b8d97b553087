"""Where standard error is no terminal, progress is plain lines, never carriage returns: one line
every :data:`~empathy_zoo.training.progress.PLAIN_INTERVAL_S` seconds with the count, the rate and
the time left, one at the end, and one per ensemble that finishes; ``--progress`` chooses."""

from __future__ import annotations

import io
import sys
from types import SimpleNamespace

import pytest
from helpers_sweeps import TINY_TRAIN

import empathy_zoo.training.progress as progress
from empathy_zoo.cli import main
from empathy_zoo.training import RunnerOptions
from empathy_zoo.training.progress import PlainBar, Report, SweepProgress, progress_bar, resolve_style


class Clock:
    """A clock the test moves by hand."""

    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_auto_is_bars_on_a_terminal_and_plain_lines_elsewhere(monkeypatch):
    monkeypatch.setattr(sys, "stderr", Terminal())
    assert resolve_style("auto") == "bars"
    monkeypatch.setattr(sys, "stderr", io.StringIO())
    assert resolve_style("auto") == "plain"
    assert resolve_style("bars") == "bars" and resolve_style("plain") == "plain"


def test_an_unknown_style_is_refused():
    with pytest.raises(ValueError, match="progress style must be one of auto, bars, plain, got 'fancy'"):
        resolve_style("fancy")
    with pytest.raises(ValueError, match="progress_style"):
        RunnerOptions(progress_style="fancy")


def test_a_plain_bar_writes_a_line_per_interval_and_one_at_the_end(capsys):
    clock = Clock()
    bar = PlainBar(1000, "sweep", "step", interval=30.0, clock=clock)
    clock.now += 10
    bar.update(100)
    assert capsys.readouterr().err == ""  # (10 s: too soon)
    clock.now += 20
    bar.update(200)
    assert capsys.readouterr().err == "sweep: 300 of 1,000 steps (30 %), 10 steps/s, about 1 min left\n"
    clock.now += 5
    bar.set_postfix({"harms": "0.5"})
    bar.update(700)
    bar.close()
    bar.close()
    assert capsys.readouterr().err == "sweep: 1,000 of 1,000 steps (100 %), 29 steps/s, harms=0.5\n"


def test_a_disabled_plain_bar_writes_nothing(capsys):
    clock = Clock()
    bar = PlainBar(10, "evaluate", "scenario", disable=True, clock=clock)
    clock.now += 100
    bar.update(10)
    bar.close()
    assert capsys.readouterr().err == ""


def test_progress_bar_gives_plain_lines_where_asked(capsys):
    with progress_bar("plain", total=3, desc="evaluate", unit="scenario") as bar:
        bar.update(3)
    assert capsys.readouterr().err.startswith("evaluate: 3 of 3 scenarios (100 %)")


def test_a_plain_sweep_says_each_ensembles_line_and_end_without_bars(capsys, monkeypatch):
    clock = Clock()
    monkeypatch.setattr(progress, "time", SimpleNamespace(monotonic=clock))
    display = SweepProgress([(2, 100), (2, 100)], style="plain")
    display.update(Report(0, 0, 100, 2, "coexistence_v0 ×2", line="2 run(s) in lockstep"))
    clock.now += 60
    display.update(Report(0, 100, 100, 2, "coexistence_v0 ×2", done=True))
    display.close()
    err = capsys.readouterr().err
    assert "\r" not in err
    assert err.splitlines() == [
        "2 run(s) in lockstep",
        "sweep: 200 of 400 steps (50 %), 3.3 steps/s, about 1 min left",
        "finished coexistence_v0 ×2 (2 run(s), 100 steps each)",
    ]


def test_train_with_progress_plain_writes_lines_not_bars(tmp_path, capsys):
    argv = ["train", "--out", str(tmp_path), *[a for a in TINY_TRAIN if a != "--no-progress"], "--progress", "plain"]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "\r" not in err and "finished" in err, err


def test_progress_refuses_an_unknown_style(tmp_path, capsys):
    assert main(["train", "--out", str(tmp_path), "--progress", "fancy"]) == 2
    assert "argument --progress: invalid choice: 'fancy'" in capsys.readouterr().err
    assert not tmp_path.joinpath("runs").exists()
