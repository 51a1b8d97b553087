"""What is checked of a sweep's runs before the first one trains and before anything is written.

The sweep loader (:mod:`empathy_zoo.experiment.sweep_file`) and the experiment model
(:mod:`empathy_zoo.experiment.model`) check every value a run is built from: its label, its
environment variant (exactly one learning agent), its method's settings (an SB3 method's keyword
arguments against its class), its budget and seeds within :mod:`empathy_zoo.limits`.
:func:`check_before_training` adds what needs the environment built: once for each ensemble the
runs make (:func:`~empathy_zoo.experiment.model.group_specs`), it builds that ensemble's
environment (one copy), resets it and checks that

* every fixed policy's state can be checkpointed, its ``state()`` taken once as plain data (when
  checkpoints are on), so no run is refused at its first checkpoint;
* the learner's memory fits on the device (the learner's optional ``check_memory``, computed from
  its settings, before anything is allocated; on this machine's backend only: a Ray task's learner
  asks on the node it lands on).

Before those, no ensemble may evaluate more environments at once (``runs × eval_episodes``) than
:data:`~empathy_zoo.limits.MAX_VECTOR_ENVS`, and every run's budget is checked against the warm-up
and the ε schedule its method's settings declare
(:func:`empathy_zoo.experiment.budget_fit.check_budgets`): a budget that ends inside the warm-up is
refused; an ε decay that ends after the budget is said once, through ``note``.

:func:`~empathy_zoo.training.runner.train_runs` asks it for every run still to train, before it
writes anything.
"""

from __future__ import annotations

from collections.abc import Sequence

from empathy_zoo.experiment.budget_fit import check_budgets
from empathy_zoo.experiment.model import RunSpec, group_specs
from empathy_zoo.limits import MAX_VECTOR_ENVS
from empathy_zoo.training.options import RunnerOptions
from empathy_zoo.vector import VectorEnv

__all__ = ["check_before_training"]


def check_before_training(specs: Sequence[RunSpec], options: RunnerOptions) -> list[str]:
    """Raise ``ValueError`` naming a run of ``specs`` whose budget ends inside its warm-up, or a run
    of the first ensemble that could not train to its end with ``options`` (see the module
    documentation); nothing is written or trained. Returns the warnings to say once every check
    before training has passed (a budget the ε decay outlasts): a refused call says only why."""
    warnings = check_budgets(specs)
    largest: dict[tuple, list[RunSpec]] = {}
    for chunk in group_specs(specs, options.max_parallel_runs):
        _check_evaluation_size(chunk)
        key = chunk[0].ensemble_key()
        if len(chunk) > len(largest.get(key, ())):
            largest[key] = chunk
    for chunk in largest.values():
        first = chunk[0]
        where = f"run {first.run_id}" + (f" (and {len(chunk) - 1} more of its ensemble)" if len(chunk) > 1 else "")
        try:
            _check_ensemble(chunk, options)
        except ValueError as error:
            raise ValueError(f"{where}: {error}") from None
    return warnings


def largest_checkpoint_bytes(specs: Sequence[RunSpec], options: RunnerOptions) -> int:
    """An upper bound of the largest checkpoint ``specs`` will write with ``options``: the memory
    of its largest ensemble as its learner estimates it (``memory_needed``: replay, networks,
    optimiser), 0 for a learner without an estimate. :func:`empathy_zoo.atomic.check_output_dir`
    asks the disk for that much room before any training."""
    largest = 0
    biggest: dict[tuple, Sequence[RunSpec]] = {}
    for chunk in group_specs(specs, options.max_parallel_runs):
        key = chunk[0].ensemble_key()
        if len(chunk) > len(biggest.get(key, ())):
            biggest[key] = chunk
    for ensemble in biggest.values():
        first = ensemble[0]
        method = first.method_object()
        estimate = getattr(method.learner, "memory_needed", None)
        if not callable(estimate):
            continue
        venv = VectorEnv(first.env, 1, fixed=first.fixed_policies(), in_view_only=method.in_view_only, **first.env_kwargs)
        needed = estimate(
            [spec.method_settings() for spec in chunk], venv.obs_size, venv.num_actions, num_others=len(venv.others[0])
        )
        largest = max(largest, int(needed.per_run) * len(chunk))
    return largest


def _check_evaluation_size(chunk: Sequence[RunSpec]) -> None:
    """Refuse an ensemble whose greedy evaluation would step more environments at once
    (``runs × eval_episodes``) than :data:`~empathy_zoo.limits.MAX_VECTOR_ENVS`."""
    environments = len(chunk) * max(spec.eval_episodes for spec in chunk)
    if environments > MAX_VECTOR_ENVS:
        raise ValueError(
            f"run {chunk[0].run_id} (and {len(chunk) - 1} more of its ensemble): its greedy evaluation would step "
            f"{len(chunk):,} runs × {max(spec.eval_episodes for spec in chunk):,} episodes = {environments:,} environments "
            f"at once, more than {MAX_VECTOR_ENVS:,} (docs/limits.md); train fewer runs at once (--max-parallel-runs) "
            "or evaluate fewer episodes (eval_episodes)"
        )


def _check_ensemble(chunk: Sequence[RunSpec], options: RunnerOptions) -> None:
    first = chunk[0]
    method = first.method_object()
    venv = VectorEnv(first.env, 1, fixed=first.fixed_policies(), in_view_only=method.in_view_only, **first.env_kwargs)
    if options.checkpoint_interval > 0:
        venv.reset(seed=first.seed)
        venv.check_checkpointable()
    check_memory = getattr(method.learner, "check_memory", None)
    if options.backend == "local" and callable(check_memory):
        check_memory(
            [spec.method_settings() for spec in chunk],
            venv.obs_size,
            venv.num_actions,
            options.device,
            num_others=len(venv.others[0]),
        )
