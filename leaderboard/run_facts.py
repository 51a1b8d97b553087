"""What a result file says a run was, read the same way by every table, figure and verdict: its
method's own description (``config.description``, :mod:`empathy_zoo.method_description`), its
environment's arguments, and whether it ran in the paper's setting.

Nothing here knows a method: a plug-in method is grouped, compared and given a reference by what
its description declares. Every reader takes runs as records
(:class:`~empathy_zoo.experiment.records.RunResult`, as :func:`empathy_zoo.experiment.result_reader.read_result`
gives them: files of every schema get a description there).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

from empathy_zoo.environments import DEFAULT_ARGUMENTS, DEFAULT_POLICIES
from empathy_zoo.experiment.records import PlainTable, RunResult
from empathy_zoo.schedules import epsilon_function

__all__ = [
    "description_of",
    "is_dqn_reference",
    "empathic_selfishness",
    "exploration_of",
    "env_argument",
    "in_paper_setting",
    "check_one_experiment",
]


def description_of(run: RunResult) -> PlainTable:
    """The run's ``config.description`` (files of schemas 1 and 2 get theirs when read:
    :func:`empathy_zoo.result_file.upgrade_schema_2`)."""
    return run.config.description


def is_dqn_reference(run: RunResult) -> bool:
    """The run is plain DQN on the environment's reward, as its description says: the reference
    every other method is compared with."""
    return bool(description_of(run)["dqn_reference"])


def empathic_selfishness(run: RunResult) -> float | None:
    """β of a run that learns Empathic DQN's target (``target`` ``"golden"``: DQN at β = 1) with the
    paper's omniscient swap, on the environment's reward, and declares its γ and ε schedule: the
    runs the paper's claims are about, keyed by β. ``None`` for any other run."""
    described = description_of(run)
    if (
        described["target"] != "golden"
        or described["in_view_only"]
        or described["reward"] is not None
        or described["selfishness"] is None
        or described["gamma"] is None
        or described["exploration"] is None
    ):
        return None
    return float(described["selfishness"])


def exploration_of(run: RunResult) -> Callable[[int], float]:
    """ε as a function of the env step, by the schedule the run's description records;
    ``ValueError`` where it records none."""
    schedule = description_of(run)["exploration"]
    if schedule is None:
        raise ValueError(f"{run.run_id}: its method's description records no exploration schedule")
    return epsilon_function(schedule)


def env_argument(run: RunResult, name: str) -> Any:
    """The run's environment argument ``name``: as its config sets it, else its environment's
    default (:data:`empathy_zoo.environments.DEFAULT_ARGUMENTS`); ``ValueError`` for an environment
    or an argument the suite does not have."""
    defaults = DEFAULT_ARGUMENTS.get(run.env)
    if defaults is None or name not in defaults:
        known = ", ".join(sorted(DEFAULT_ARGUMENTS)) if defaults is None else ", ".join(defaults)
        raise ValueError(f"{run.run_id}: environment {run.env!r} has no argument {name!r} (known: {known})")
    return run.config.env_kwargs.get(name, defaults[name])


def in_paper_setting(run: RunResult, varying: Sequence[str] = ()) -> bool:
    """The run's environment is one of the suite's with every argument at its default (but those
    named in ``varying``, which may take any value) and its default fixed agents: the paper's
    setting, as the result file records it."""
    defaults = DEFAULT_ARGUMENTS.get(run.env)
    if defaults is None:
        return False
    return (
        all(name in defaults and (name in varying or defaults[name] == value) for name, value in run.config.env_kwargs.items())
        and dict(run.config.fixed) == DEFAULT_POLICIES[run.env]
    )


def check_one_experiment(cells: Mapping[str, Sequence[RunResult]]) -> None:
    """Refuse (``ValueError`` naming two runs) a cell of ``cells`` (``{what the cell is: runs}``)
    whose runs are of two experiments (their run ids differ beyond the seed: another label,
    setting, world or budget), or that holds a seed twice: a claim judges one experiment's seeds,
    never a pool of two."""
    for cell, runs in cells.items():
        seen: dict[int, RunResult] = {}
        for run in runs:
            first = runs[0]
            if run.experiment != first.experiment:
                raise ValueError(
                    f"runs {first.run_id} and {run.run_id} are both {cell} but of two experiments (another label, setting, "
                    "world or budget): a claim judges one experiment's seeds; keep one experiment of them in the directory"
                )
            other = seen.setdefault(run.seed, run)
            if other is not run:
                raise ValueError(f"runs {other.run_id} and {run.run_id} are both seed {run.seed} of {cell}: keep one")
