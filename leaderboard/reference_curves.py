"""The exact optimum beside the learners: per Coexistence curve of a run that learns an empathic
target the reference models (Empathic DQN's, or the silver rule's; with the in-view swap or the
omniscient one), on the environment's reward, what the fully observing optimum of the same β
(:mod:`empathy_zoo.reference`) would score at the ε the run explored with at each point of
training. Which target, β, γ and ε schedule a run has, its result file's description says
(:mod:`leaderboard.run_facts`). Drawn dashed in the curve's colour."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from empathy_zoo.environments import DEFAULT_ARGUMENTS, ENVIRONMENT_TABLE
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.limits import MAX_REFERENCE_CYCLES, MAX_REFERENCE_SIZE, MAX_REFERENCE_WORK, format_bytes
from leaderboard.run_facts import description_of, exploration_of, in_paper_setting

__all__ = ["MODELLED_ARGUMENTS", "reference_curve", "reference_refusal", "reference_refusals"]

MODELLED_ARGUMENTS = ("size", "view", "max_cycles")
"""Environment arguments the reference takes; every other must be at its default."""


def reference_curve(runs: Sequence[RunResult], metric: str, steps: np.ndarray) -> np.ndarray | None:
    """The reference's ``metric`` at each of ``steps`` for a group of runs, or ``None`` when the
    reference does not apply (another env, fixed agent or target, a reward transform, a
    description without β, γ or ε schedule; runs of different descriptions) or when their grid or
    episodes are beyond what it is computed for (:func:`reference_refusal`)."""
    from empathy_zoo.reference import coexistence_optimum

    if not _applies(runs) or metric not in ENVIRONMENT_TABLE[runs[0].env].reference_metrics or reference_refusal(runs):
        return None
    first = runs[0]
    described = description_of(first)
    epsilon_at = exploration_of(first)
    arguments = {
        "gamma": described["gamma"],
        "rule": described["target"],
        "in_view_only": bool(described["in_view_only"]),
        **_modelled(first),
    }
    values = []
    for step in steps:
        epsilon = round(epsilon_at(int(step)), 3)
        outcome = coexistence_optimum(described["selfishness"], epsilon, **arguments)
        values.append(getattr(outcome, metric))
    return np.asarray(values, dtype=np.float64)


def reference_refusal(runs: Sequence[RunResult]) -> str | None:
    """Why a group of runs the reference applies to gets none, in one line: a γ of 1 (the
    discounted optimum exists only below it), a ``size`` beyond
    :data:`~empathy_zoo.limits.MAX_REFERENCE_SIZE` (its step matrix alone takes ``8·(size² + 2)²``
    bytes) or a ``max_cycles`` beyond :data:`~empathy_zoo.limits.MAX_REFERENCE_CYCLES` (a matrix
    product per step of an episode, at every point of the curve); ``None`` otherwise, and for
    runs the reference does not apply to."""
    if not _applies(runs):
        return None
    gamma = float(description_of(runs[0])["gamma"])
    if not 0.0 <= gamma < 1.0:
        return f"its γ {gamma!r} is outside [0, 1), where the discounted optimum is defined"
    size, cycles = _grid(runs[0])
    if size > MAX_REFERENCE_SIZE:
        return (
            f"its size {size:,} is beyond {MAX_REFERENCE_SIZE} (MAX_REFERENCE_SIZE), for which the exact optimum "
            f"is computed (its step matrix would take {format_bytes(8 * (size * size + 2) ** 2)}; docs/limits.md)"
        )
    if cycles > MAX_REFERENCE_CYCLES:
        return (
            f"its max_cycles {cycles:,} is beyond {MAX_REFERENCE_CYCLES:,} (MAX_REFERENCE_CYCLES), for which the exact "
            "optimum is computed (a matrix product per step of an episode; docs/limits.md)"
        )
    return None


def reference_refusals(groups: Mapping[tuple[str, str], Sequence[RunResult]], n_points: int) -> dict[tuple[str, str], str]:
    """Why each group of ``groups`` (``(env, label)`` to runs) gets no reference curve, for the groups
    that get none: :func:`reference_refusal`'s reason, or the page's bound on the work of all
    reference curves together (:data:`~empathy_zoo.limits.MAX_REFERENCE_WORK`, counted as
    ``n_points × max_cycles × (size² + 2)²`` per group), which the groups spend in their order."""
    refused: dict[tuple[str, str], str] = {}
    spent = 0
    for key, runs in groups.items():
        refusal = reference_refusal(runs)
        if refusal is None and _applies(runs):
            size, cycles = _grid(runs[0])
            work = n_points * cycles * (size * size + 2) ** 2
            if spent + work > MAX_REFERENCE_WORK:
                refusal = (
                    f"its curve's {work:.2g} units of work ({n_points} points × max_cycles × (size² + 2)²) would take "
                    f"this page's reference curves past {MAX_REFERENCE_WORK:.0e} (MAX_REFERENCE_WORK; docs/limits.md)"
                )
            else:
                spent += work
        if refusal is not None:
            refused[key] = refusal
    return refused


def _grid(run: RunResult) -> tuple[int, int]:
    """``(size, max_cycles)`` of ``run``'s environment, the defaults where it left them out."""
    modelled = {**DEFAULT_ARGUMENTS[run.env], **_modelled(run)}
    return int(modelled["size"]), int(modelled["max_cycles"])


def _applies(runs: Sequence[RunResult]) -> bool:
    """Whether the reference models ``runs`` (see :func:`reference_curve`)."""
    from empathy_zoo.reference import RULES

    if not runs:
        return False
    first = runs[0]
    described = description_of(first)
    return not (
        first.env not in ENVIRONMENT_TABLE
        or not ENVIRONMENT_TABLE[first.env].reference_metrics
        or not in_paper_setting(first, varying=MODELLED_ARGUMENTS)
        or described["target"] not in RULES
        or described["reward"] is not None
        or any(described[name] is None for name in ("selfishness", "gamma", "exploration"))
        or any(description_of(run) != described for run in runs)
    )


def _modelled(run: RunResult) -> dict[str, int]:
    """The environment arguments of ``run`` the reference takes (:data:`MODELLED_ARGUMENTS`)."""
    return {k: int(v) for k, v in run.config.env_kwargs.items() if k in MODELLED_ARGUMENTS}
