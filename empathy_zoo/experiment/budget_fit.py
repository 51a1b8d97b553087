"""Whether a run's budget leaves room for its warm-up and its ε decay, checked before anything trains.

Read from what a method's settings declare (:func:`agents.phases.training_phases`; a settings
class that declares nothing is not checked):

* a budget of no more steps than the warm-up (``steps <= learning_starts``) is **refused**: no
  gradient step would be taken, and a result file of a run that learnt nothing would be scored
  beside the others as if it meant something. The message names the setting to lower and a value
  for it (a tenth of the budget).
* an ε schedule that does not reach its floor within the budget (``learning_starts +
  epsilon_decay_steps > steps`` for Empathic DQN) is **warned about**, once for all the runs of a
  sweep, naming the methods and what to set: a run that explores to its last step is legitimate
  (a budget cut short on purpose) but rarely what was meant, and its greedy evaluations are then
  of an agent trained mostly at random.

:func:`empathy_zoo.training.preflight.check_before_training` calls :func:`check_budgets` for every
run :func:`~empathy_zoo.training.runner.train_runs` is about to train (``train``, ``reproduce`` and
the Python API alike).
"""

from __future__ import annotations

from collections.abc import Sequence

from agents.phases import TrainingPhases, training_phases
from empathy_zoo.experiment.model import RunSpec

__all__ = ["warmup_refusal", "exploration_shortfall", "check_budgets"]


def _lower_to(phases: TrainingPhases, steps: int) -> str:
    """What to do about a budget of ``steps`` that ends inside the warm-up, as one phrase."""
    suggested = max(phases.learning_starts_least, steps // 10)
    raise_steps = f"raise steps above {phases.learning_starts:,}"
    if suggested >= steps:
        return raise_steps
    why = "a tenth of the budget" if suggested == steps // 10 else "the least it may be"
    option = f", train's {phases.learning_starts_option.format(suggested)}" if phases.learning_starts_option else ""
    return f"lower {phases.learning_starts_setting} to {suggested:,} ({why}{option}) or {raise_steps}"


def warmup_refusal(spec: RunSpec) -> str | None:
    """Why ``spec`` cannot train, where its budget ends inside its warm-up; ``None`` otherwise."""
    phases = training_phases(spec.method_settings())
    if phases is None or spec.steps > phases.learning_starts:
        return None
    return (
        f"run {spec.run_id} ({spec.display_label()}): its budget of {spec.steps:,} env steps ends inside the warm-up "
        f"({phases.learning_starts_setting} = {phases.learning_starts:,}: no gradient step before env step "
        f"{phases.learning_starts:,}), so it would learn nothing; {_lower_to(phases, spec.steps)}"
    )


def exploration_shortfall(spec: RunSpec) -> str | None:
    """Where ``spec``'s ε does not reach its floor within its budget: the method's label, when ε
    reaches it, and what to set; ``None`` otherwise."""
    phases = training_phases(spec.method_settings())
    if phases is None or phases.exploration_ends is None or phases.exploration_ends <= spec.steps:
        return None
    fix = phases.exploration_fix(spec.steps) if phases.exploration_fix is not None else ""
    rule = f" ({phases.exploration_rule})" if phases.exploration_rule else ""
    return (
        f"{spec.display_label()}: ε reaches its floor at env step {phases.exploration_ends:,}{rule}, "
        f"after its {spec.steps:,} steps" + (f"; set {fix}" if fix else "")
    )


def check_budgets(specs: Sequence[RunSpec]) -> list[str]:
    """``ValueError`` (:func:`warmup_refusal`) for the first of ``specs`` whose budget ends inside
    its warm-up; else the warnings to show: none, or one line naming every method whose ε does
    not reach its floor within its budget (:func:`exploration_shortfall`, each said once)."""
    for spec in specs:
        refusal = warmup_refusal(spec)
        if refusal is not None:
            raise ValueError(refusal)
    shortfalls = list(dict.fromkeys(text for spec in specs if (text := exploration_shortfall(spec)) is not None))
    if not shortfalls:
        return []
    return [
        f"WARNING: ε does not reach its floor within the budget for {len(shortfalls)} method(s), whose runs explore "
        f"until their last step: {'; '.join(shortfalls)}. Intended for a budget cut short on purpose; otherwise "
        "shorten the decay as said"
    ]
