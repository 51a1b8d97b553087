"""Progress on one terminal: worker processes only report, the sweep's process draws one bar per
running ensemble and a sweep bar in env steps (whose ETA covers every run still to train)."""

from __future__ import annotations

from typing import ClassVar

import pytest

import empathy_zoo.training.runner as runner
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.training import RunnerOptions, train_runs

SETTINGS = {"learning_starts": 32, "replay_capacity": 300, "hidden_size": 8}


def specs():
    return [
        RunSpec.of(
            env=env, settings=SETTINGS, seed=seed, steps=1000, eval_interval=1000, eval_episodes=1, env_kwargs={"max_cycles": 40}
        )
        for env in ("coexistence_v0", "sharing_v0")
        for seed in (0, 1)
    ]


class Recorder:
    """Stands in for the display: records what reaches the sweep's process."""

    made: ClassVar[list[Recorder]] = []

    def __init__(self, ensembles, enabled=True, style="auto"):
        self.ensembles, self.reports, self.closed = list(ensembles), [], False
        Recorder.made.append(self)

    def update(self, report):
        self.reports.append(report)

    def close(self):
        self.closed = True


@pytest.mark.parametrize("workers", [1, 2])
def test_ensembles_report_to_the_sweeps_process_and_workers_draw_nothing(tmp_path, monkeypatch, capfd, workers):
    Recorder.made.clear()
    monkeypatch.setattr(runner, "SweepProgress", Recorder)
    train_runs(specs(), tmp_path, RunnerOptions(progress=True, workers=workers, checkpoint_interval=0))
    [display] = Recorder.made
    assert display.closed and display.ensembles == [(2, 1000), (2, 1000)]
    for ensemble in (0, 1):
        steps = [r.step for r in display.reports if r.ensemble == ensemble]
        assert steps == [0, 500, 1000] and [r.done for r in display.reports if r.ensemble == ensemble][-1]
        [line] = [r.line for r in display.reports if r.ensemble == ensemble and r.line]
        assert "2 run(s) in lockstep" in line and "memory per run" in line
    err = capfd.readouterr().err
    assert "\r" not in err and "step/s" not in err and "lockstep" not in err, err  # nobody else drew


def test_the_sweep_bar_counts_env_steps_of_the_runs_to_train(tmp_path, capfd):
    train_runs(specs(), tmp_path, RunnerOptions(progress=True, progress_style="bars", workers=1, checkpoint_interval=0))
    err = capfd.readouterr().err
    assert "sweep: 100%" in err and "4.00k/4.00k" in err, err  # 4 runs × 1,000 steps
