"""Training: sweep files, run specifications, the lockstep ensemble trainer, local/Ray dispatch,
checkpoints, results.

What a user drives: :class:`RunSpec` (one run), :func:`load_sweep` (the runs of a sweep file),
:func:`train_runs` (train them, skipping finished ones) with :class:`RunnerOptions` (how, never
what), and :func:`train_ensemble` (one ensemble, here).
"""

from empathy_zoo.experiment.model import RunSpec, group_specs
from empathy_zoo.experiment.sweep_file import load_sweep
from empathy_zoo.training.ensemble import train_ensemble
from empathy_zoo.training.options import RunnerOptions
from empathy_zoo.training.runner import train_runs

__all__ = ["RunSpec", "RunnerOptions", "group_specs", "load_sweep", "train_ensemble", "train_runs"]
