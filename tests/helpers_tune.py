"""What the ``tune`` tests share: a genuine tiny study made through the command line, the plan
its journal was written with, and a snapshot of a directory to show a refusal changed nothing."""

from __future__ import annotations

from pathlib import Path

from helpers_sweeps import TUNE_PARAMS, TUNE_SWEEP

from empathy_zoo.cli import main


def run_tune(sweep: Path, out: Path, trials: int, *extra: str, params: list[str] = TUNE_PARAMS) -> int:
    """``empathy-zoo tune SWEEP`` of ``dqn_harm_penalty`` for ``trials`` trials on one tuning seed
    (two startup trials) into ``out``; its exit status."""
    tuning = ["--trials", str(trials), "--tuning-seeds", "1", "--startup-trials", "2", "--no-progress", "--out", str(out)]
    return main(["tune", str(sweep), "--method", "dqn_harm_penalty", *params, *tuning, *extra])


def tiny_study(root: Path, *trials: int) -> tuple[Path, Path]:
    """``(sweep file, study directory)`` under ``root``: :data:`TUNE_SWEEP` tuned once per count of
    ``trials`` (``1, 2``: one trial, then a second resumed), each call asserted to succeed."""
    sweep = root / "tiny.toml"
    sweep.write_text(TUNE_SWEEP)
    out = root / "study"
    for count in trials:
        assert run_tune(sweep, out, count) == 0
    return sweep, out


def tiny_plan(sweep: Path, trials: int):  # type: ignore[no-untyped-def]
    """The :class:`~empathy_zoo.training.study_plan.StudyPlan` :func:`run_tune` tunes ``sweep`` by,
    with ``trials`` trials (what ``check_journal`` compares a journal with)."""
    from empathy_zoo.cli.tune import default_objective
    from empathy_zoo.experiment import load_sweep
    from empathy_zoo.experiment.search_space import parse_params
    from empathy_zoo.training.study_plan import StudyPlan, select_experiment, tuning_seeds

    base = select_experiment(load_sweep(sweep), "dqn_harm_penalty")
    return StudyPlan(
        source=str(sweep),
        base=base,
        params=parse_params(TUNE_PARAMS[1::2], base.method_object()),
        metric="survival",
        direction=default_objective(base.env)[1],
        seeds=tuning_seeds(1, [0, 1]),
        reporting_seeds=(0, 1),
        reporting_budget=base.budget,
        trials=trials,
        startup_trials=2,
    )


def snapshot(directory: Path) -> dict[str, bytes | None]:
    """Every path under ``directory``: a file's bytes, ``None`` for a directory."""
    return {
        str(path.relative_to(directory)): None if path.is_dir() else path.read_bytes() for path in sorted(directory.rglob("*"))
    }
