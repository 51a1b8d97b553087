"""What a tuning study is, before anything trains: its plan, its seeds, the experiment it tunes and
how a trial's greedy evaluations become its value.

The study that runs a plan, and the decisions behind each of these, is
:mod:`empathy_zoo.training.tuning` (whose page this module's names are also reached from).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from empathy_zoo.experiment.model import Budget, RunSpec
from empathy_zoo.experiment.search_space import ParamSpec
from empathy_zoo.limits import MAX_SEED, MAX_SEEDS, MAX_STEPS, MAX_TRIALS, check_at_most
from empathy_zoo.metrics import HIGHER_IS_BETTER, METRIC_NAMES

__all__ = [
    "DIRECTIONS",
    "OBJECTIVE_OVER",
    "OVER_WORDS",
    "PRUNE_STARTUP_TRIALS",
    "STARTUP_TRIALS",
    "TUNING_SEED_BASE",
    "StudyPlan",
    "curve_value",
    "objective_direction",
    "select_experiment",
    "ties_at_best",
    "trial_value",
    "tuning_seeds",
]

TUNING_SEED_BASE = 10_000
"""The first tuning seed: trials train seeds ``TUNING_SEED_BASE, TUNING_SEED_BASE + 1, …``."""
PRUNE_STARTUP_TRIALS = 3
"""Finished trials before the median pruner stops any trial."""
STARTUP_TRIALS = 5
"""Trials TPE samples at random before it models the others, unless a plan says otherwise (half
of a laptop study of 10 trials; Optuna's own default, 10, would leave such a study all random)."""
DIRECTIONS = ("maximize", "minimize")
"""How an objective is optimised."""


def objective_direction(metric: str) -> str:
    """How ``tune`` optimises ``metric``: ``minimize`` where fewer is better
    (:data:`~empathy_zoo.metrics.HIGHER_IS_BETTER`), else ``maximize``; the one rule ``tune`` and
    the readers of its studies hold a study's direction to."""
    return "maximize" if HIGHER_IS_BETTER.get(metric, True) else "minimize"


OBJECTIVE_OVER: dict[str, str] = {
    "last": "mean over the tuning seeds of the metric's mean in the run's last greedy evaluation",
    "curve": (
        "mean over the tuning seeds and over every greedy evaluation of the metric's mean "
        "(the area under the greedy learning curve)"
    ),
}
"""Which greedy evaluations a trial's value summarises, and how ``study.json`` says it."""
OVER_WORDS = {"last": "of the last greedy evaluation", "curve": "over every greedy evaluation (their mean)"}
"""How a sentence says which greedy evaluations a trial's value summarises."""


@dataclass(frozen=True)
class StudyPlan:
    """Everything a study's trials and outcome depend on (a resumed study must have the same,
    but for :attr:`trials`). Every field is checked when a plan is made, each size within its bound
    (:mod:`empathy_zoo.limits`: trials, tuning seeds, the sampler's seed, steps), before a study
    writes anything."""

    source: str
    """The sweep file the experiment comes from."""
    base: RunSpec
    """The experiment tuned, with the tuning budget (its seed is not used)."""
    params: tuple[ParamSpec, ...]
    """The search space."""
    metric: str
    """The objective's metric (:data:`~empathy_zoo.metrics.METRIC_NAMES`)."""
    direction: str
    """``maximize`` or ``minimize``."""
    seeds: tuple[int, ...]
    """The tuning seeds every trial trains."""
    reporting_seeds: tuple[int, ...]
    """The sweep file's seeds: ``tuned.toml``'s, never tuned on."""
    reporting_budget: Budget
    """The sweep file's budget: ``tuned.toml``'s."""
    trials: int
    """Trials the study runs (finished, pruned or refused)."""
    sampler_seed: int = 0
    """Seed of the TPE sampler."""
    prune: bool = True
    """Stop trials whose learning curve falls below the median (:data:`PRUNE_STARTUP_TRIALS`)."""
    startup_trials: int = STARTUP_TRIALS
    """Trials TPE samples at random before it models the others."""
    prune_from: int = 0
    """The env step from which the pruner may stop a trial (Optuna's ``n_warmup_steps``): 0, at
    every evaluation; later, where the first evaluations are too noisy to judge a trial by."""
    over: str = "last"
    """Which greedy evaluations a trial's value summarises (:data:`OBJECTIVE_OVER`): ``"last"``,
    the leaderboard's greedy figure; ``"curve"``, their mean, for a metric that saturates."""
    batch: int = 1
    """Trials the sampler proposes at once, each from the trials finished before the batch; they
    may train side by side and are told back in trial order before the next batch is proposed.
    The study depends on it, never on how many processes train a batch. 1 (one trial at a time)
    is recorded as nothing, so a plan of 1 is the plan of a study made before batches existed."""

    def __post_init__(self) -> None:
        if self.metric not in METRIC_NAMES:
            raise ValueError(f"objective metric {self.metric!r} is not one of {', '.join(METRIC_NAMES)}")
        if self.direction not in DIRECTIONS:
            raise ValueError(f"direction must be one of {', '.join(DIRECTIONS)}, got {self.direction!r}")
        if isinstance(self.prune_from, bool) or not isinstance(self.prune_from, int) or self.prune_from < 0:
            raise ValueError(f"prune_from must be an int >= 0, got {self.prune_from!r}")
        if not self.prune and self.prune_from:
            raise ValueError("a study without a pruner has no step to start pruning from: drop one of the two")
        if self.prune and self.prune_from >= self.base.steps:
            raise ValueError(
                f"the pruner would never look: it starts at step {self.prune_from:,} and a trial ends at "
                f"{self.base.steps:,}; give an earlier step, or turn pruning off"
            )
        if self.over not in OBJECTIVE_OVER:
            raise ValueError(f"the objective is over one of {', '.join(OBJECTIVE_OVER)}, got {self.over!r}")
        for name in ("trials", "startup_trials", "batch"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"{name} must be a positive int, got {value!r}")
            check_at_most(name, value, MAX_TRIALS, "trials of a study")
        if isinstance(self.sampler_seed, bool) or not isinstance(self.sampler_seed, int) or self.sampler_seed < 0:
            raise ValueError(f"sampler_seed (--sampler-seed) must be an int >= 0, got {self.sampler_seed!r}")
        check_at_most("sampler_seed (--sampler-seed)", self.sampler_seed, MAX_SEED)
        check_at_most("prune_from (--prune-from)", self.prune_from, MAX_STEPS)
        check_at_most("tuning seeds", len(self.seeds), MAX_SEEDS, "seeds every trial trains")
        if not self.params:
            raise ValueError("a study needs at least one parameter to tune")
        overlap = sorted(set(self.seeds) & set(self.reporting_seeds))
        if overlap:
            raise ValueError(f"tuning seeds {overlap} are reporting seeds of {self.source}: tune on other seeds")

    def record(self) -> dict[str, Any]:
        """The plan as ``study.json`` keeps it: with the environment and its arguments (``env``,
        ``env_kwargs``: the world its values are bounded by, as a reader checks them)."""
        return {
            "sweep_file": self.source,
            "experiment": self.base.experiment_id,
            "variant": self.base.variant.label,
            "env": self.base.env,
            "env_kwargs": self.base.env_kwargs,
            "method": self.base.method,
            "label": self.base.display_label(),
            "params": {spec.name: spec.text.partition("=")[2] for spec in self.params},
            "objective": {
                "metric": self.metric,
                "direction": self.direction,
                "over": self.over,
                "of": OBJECTIVE_OVER[self.over],
            },
            "tuning_seeds": list(self.seeds),
            "reporting_seeds": list(self.reporting_seeds),
            "budget": {
                "steps": self.base.steps,
                "eval_interval": self.base.eval_interval,
                "eval_episodes": self.base.eval_episodes,
                "trials": self.trials,
                "env_steps_at_most": self.trials * len(self.seeds) * self.base.steps,
            },
            "reporting_budget": {
                "steps": self.reporting_budget.steps,
                "eval_interval": self.reporting_budget.eval_interval,
                "eval_episodes": self.reporting_budget.eval_episodes,
            },
            "sampler": {
                "name": "TPESampler",
                "seed": self.sampler_seed,
                "n_startup_trials": self.startup_trials,
                **({"batch": self.batch} if self.batch != 1 else {}),
            },
            "pruner": (
                {"name": "MedianPruner", "n_startup_trials": PRUNE_STARTUP_TRIALS, "n_warmup_steps": self.prune_from}
                if self.prune
                else None
            ),
        }


def tuning_seeds(count: int, reporting: Sequence[int], first: int = TUNING_SEED_BASE) -> tuple[int, ...]:
    """``count`` tuning seeds from ``first`` on (at most :data:`~empathy_zoo.limits.MAX_SEEDS`);
    ``ValueError`` where one is a reporting seed."""
    if isinstance(count, bool) or not isinstance(count, int) or count < 1:
        raise ValueError(f"the number of tuning seeds must be a positive int, got {count!r}")
    check_at_most("the number of tuning seeds (--tuning-seeds)", count, MAX_SEEDS, "seeds every trial trains")
    seeds = tuple(range(first, first + count))
    overlap = sorted(set(seeds) & set(reporting))
    if overlap:
        raise ValueError(
            f"tuning seeds {seeds[0]}..{seeds[-1]} overlap the sweep file's reporting seeds {overlap}: a setting chosen on "
            "the seeds that then score it would be scored on its own selection; report on other seeds (the sweep's "
            "[sweep] seeds) or tune on others"
        )
    return seeds


def select_experiment(specs: Sequence[RunSpec], method: str, variant: str | None = None, label: str | None = None) -> RunSpec:
    """The experiment of a sweep's runs ``specs`` to tune: method ``method``, on ``variant`` and
    labelled ``label`` where those are needed to pick one (``ValueError`` naming the choices)."""
    experiments = {spec.experiment_id: spec for spec in specs}
    chosen = [spec for spec in experiments.values() if spec.method == method]
    if not chosen:
        methods = sorted({spec.method for spec in specs})
        raise ValueError(f"the sweep file has no experiment of method {method!r}; its methods: {', '.join(methods)}")
    if variant is not None:
        variants = sorted({spec.variant.label for spec in chosen})
        chosen = [spec for spec in chosen if spec.variant.label == variant]
        if not chosen:
            raise ValueError(
                f"method {method!r} runs on no variant {variant!r} in the sweep file; it runs on {', '.join(variants)}"
            )
    if label is not None:
        labels = sorted({spec.display_label() for spec in chosen})
        chosen = [spec for spec in chosen if spec.display_label() == label]
        if not chosen:
            raise ValueError(f"no experiment of method {method!r} is labelled {label!r}; its labels: {'; '.join(labels)}")
    if len({spec.variant.label for spec in chosen}) > 1:
        variants = sorted({spec.variant.label for spec in chosen})
        raise ValueError(f"method {method!r} runs on {len(variants)} variants ({', '.join(variants)}): choose one with --env")
    if len(chosen) > 1:
        labels = sorted(spec.display_label() for spec in chosen)
        raise ValueError(f"method {method!r} has {len(chosen)} experiments there ({'; '.join(labels)}): choose one with --label")
    return chosen[0]


def trial_value(per_run: Sequence[Mapping[str, Sequence[float]]], metric: str) -> tuple[float, list[float]]:
    """The objective of one greedy evaluation of a trial's runs (``per_run`` as
    :func:`~empathy_zoo.training.evaluation.evaluate_greedy` gives it), and each run's part."""
    per_seed = [float(np.mean(columns[metric])) for columns in per_run]
    return float(np.mean(per_seed)), per_seed


def curve_value(values: Sequence[float], over: str) -> float:
    """A trial's value from its greedy evaluations so far (``values``, each a :func:`trial_value`,
    in step order): the last (``over="last"``) or their mean (``over="curve"``)."""
    if not values:
        raise ValueError("a trial's value needs at least one greedy evaluation")
    if over == "last":
        return float(values[-1])
    if over == "curve":
        return float(np.mean(values))
    raise ValueError(f"the objective is over one of {', '.join(OBJECTIVE_OVER)}, got {over!r}")


def ties_at_best(study: Mapping[str, Any]) -> list[int]:
    """The numbers of the finished trials of ``study`` (a ``study.json`` document) whose value
    equals the best one, the best included; more than one means the objective could not tell them
    apart and the first was kept. ``[]`` where no trial finished."""
    best = study.get("best")
    if best is None:
        return []
    return [t["number"] for t in study["trials"] if t["state"] == "COMPLETE" and t["value"] == best["value"]]
