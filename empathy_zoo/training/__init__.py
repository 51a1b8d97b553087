"""Training: run specifications, the lockstep ensemble runner, evaluation, checkpoints, results."""

from empathy_zoo.training.runner import train_ensemble, train_runs
from empathy_zoo.training.spec import RunSpec, group_specs

__all__ = ["RunSpec", "group_specs", "train_ensemble", "train_runs"]
