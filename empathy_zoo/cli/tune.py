"""``tune``: one experiment of a sweep file tuned with Optuna, on seeds its results are not reported on.

    empathy-zoo tune SWEEP_FILE --method NAME --param NAME=KIND:... [--param ...] [--env VARIANT]
                     [--trials N] [--batch B] [--jobs N] [--budget STEPS] [--tuning-seeds N]
                     [--objective METRIC] [--objective-over last|curve] [--log BACKENDS] [--out DIR]

The study (:mod:`empathy_zoo.training.tuning`) writes ``study.json``, ``tuned.toml`` (a sweep file
of the best settings on the sweep's reporting seeds: ``empathy-zoo reproduce --profile
DIR/tuned.toml``), ``trials.png`` and ``importance.png`` (:mod:`empathy_zoo.training.trials_figure`)
into ``--out``, after every trial; the same command resumes a stopped study. ``--batch`` is part
of the plan (trials proposed at once); ``--jobs`` is not (processes that train a batch), so any
``--jobs`` gives the same study. The objective is, unless ``--objective`` says
otherwise, the environment's task metric (its entry's
:attr:`~empathy_zoo.environments.Environment.task`: Coexistence's survival, Sharing's batteries),
maximised or minimised as :data:`empathy_zoo.metrics.HIGHER_IS_BETTER` says. Optuna is the
``tune`` extra. The protocol a fair comparison needs is docs/tuning.md.
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from empathy_zoo.cli.common import PROG, add_progress_style, check_device, help_text, path_text, positive

if TYPE_CHECKING:
    from collections.abc import Mapping

    from empathy_zoo.experiment.search_space import ParamSpec

__all__ = ["DEFAULT_TRIALS", "DEFAULT_TUNING_SEEDS", "add_tune", "cmd_tune", "default_objective"]

DEFAULT_TRIALS = 20
"""Trials of a study when ``--trials`` does not say (the same for every method of a comparison)."""
DEFAULT_TUNING_SEEDS = 2
"""Tuning seeds every trial trains when ``--tuning-seeds`` does not say."""


def default_objective(env: str, metric: str | None = None) -> tuple[str, str]:
    """``(metric, direction)`` of a study on environment ``env``: ``metric`` (default: the
    environment's task metric), maximised unless fewer is better."""
    from empathy_zoo.environments import ENVIRONMENT_TABLE
    from empathy_zoo.training.study_plan import objective_direction

    if metric is None:
        if env not in ENVIRONMENT_TABLE:
            raise ValueError(f"{env} has no task metric on record: name the objective with --objective METRIC")
        metric = ENVIRONMENT_TABLE[env].task
    return metric, objective_direction(metric)


def check_objective_moves(env: str, env_kwargs: Mapping[str, Any], metric: str) -> None:
    """A ``ValueError`` where ``metric`` takes one value in every episode of ``env`` built with
    ``env_kwargs`` (:func:`~empathy_zoo.result_file.constant_metrics`: no battery, no one to harm):
    every trial would tie, and the study would choose nothing. Named with the metrics that move."""
    from empathy_zoo.metrics import METRIC_NAMES
    from empathy_zoo.result_file import constant_metrics

    constant = constant_metrics(env, env_kwargs)
    if metric in constant:
        moving = ", ".join(name for name in METRIC_NAMES if name not in constant)
        raise ValueError(
            f"--objective {metric}: every episode of {env} gives {metric} {constant[metric]:g} (the environment table: "
            f"{'no one to harm' if metric == 'harms' else 'no batteries'}), so every trial would tie; name one that "
            f"moves there: {moving}"
        )


def cmd_tune(args: argparse.Namespace, command: str) -> int:
    """Run (or resume) the study; print what it wrote and its best trial. Every argument is
    checked, each size within its bound, before anything is written."""
    from empathy_zoo.evaluation_file import check_not_read_folder
    from empathy_zoo.experiment.log_backends import parse_log
    from empathy_zoo.experiment.model import Budget
    from empathy_zoo.experiment.search_space import parse_params
    from empathy_zoo.experiment.sweep_file import load_sweep, profile_path, profiles
    from empathy_zoo.limits import MAX_STEPS, check_at_most, cpu_count
    from empathy_zoo.names import check_label
    from empathy_zoo.training.options import RunnerOptions
    from empathy_zoo.training.study_plan import OVER_WORDS, StudyPlan, select_experiment, ties_at_best, tuning_seeds
    from empathy_zoo.training.trials_figure import IMPORTANCE_FIGURE, TRIALS_FIGURE
    from empathy_zoo.training.tuning import STUDY_FILE, TUNED_FILE, import_optuna, run_study

    import_optuna()  # (said first: nothing else is worth checking without it)
    jobs = check_at_most("--jobs", positive("--jobs", args.jobs), cpu_count(), "the CPUs of this machine, os.cpu_count()")
    log = parse_log(args.log, "--log")
    if args.label is not None:
        check_label(args.label, "--label")
    path = profile_path(args.sweep)
    specs = load_sweep(path)
    reporting = sorted({spec.seed for spec in specs})
    base = select_experiment(specs, args.method, args.env, args.label)
    steps = check_at_most("--budget", positive("--budget", args.budget), MAX_STEPS) if args.budget is not None else base.steps
    interval = (
        check_at_most("--eval-interval", positive("--eval-interval", args.eval_interval), MAX_STEPS)
        if args.eval_interval is not None
        else base.eval_interval
    )
    budget = Budget(steps, min(interval, steps), base.eval_episodes)
    params = parse_params(args.param, base.method_object())
    metric, direction = default_objective(base.env, args.objective)
    check_objective_moves(base.env, base.env_kwargs, metric)
    plan = StudyPlan(
        source=args.sweep if args.sweep in profiles() else str(path),  # (a shipped profile by its name, not its path here)
        base=replace(base, budget=budget),
        params=params,
        metric=metric,
        direction=direction,
        seeds=tuning_seeds(positive("--tuning-seeds", args.tuning_seeds), reporting),
        reporting_seeds=tuple(reporting),
        reporting_budget=base.budget,
        trials=positive("--trials", args.trials),
        sampler_seed=args.sampler_seed,
        prune=not args.no_prune,
        startup_trials=positive("--startup-trials", args.startup_trials),
        over=args.objective_over,
        prune_from=args.prune_from,
        batch=positive("--batch", args.batch),
    )
    options = RunnerOptions(
        device=check_device(args.device),
        threads=positive("--threads", args.threads),
        progress=False,
        progress_style=args.progress_style,
        update_kernel=args.update_kernel,
        workers=jobs,
        log=log,
    )
    out = Path(args.out) if args.out else Path("results") / "tuning" / base.variant.label / base.method
    check_not_read_folder(out, f"--out {out} (its study.json, tuned.toml and trials' results)")
    if (out / TUNED_FILE).exists() and (out / TUNED_FILE).samefile(path):
        raise ValueError(f"--out {out}: its {TUNED_FILE} is the sweep file {args.sweep} this study reads; give another --out")
    side_by_side = min(jobs, plan.batch)
    batches = f" in batches of {plan.batch} ({side_by_side} trained at a time)" if plan.batch > 1 else ""
    if jobs > plan.batch:
        print(
            f"{PROG}: note: --jobs {jobs} trains at most the {plan.batch} trial(s) of a batch side by side: "
            f"{side_by_side} process(es) will; --batch B proposes B trials at once"
        )
    print(
        f"{PROG}: tuning {base.display_label()} on {base.variant.label} ({plan.source}): {plan.trials} trials{batches} × "
        f"{len(plan.seeds)} tuning seeds ({plan.seeds[0]}..{plan.seeds[-1]}) × {steps:,} steps; objective {metric} "
        f"({direction}) {OVER_WORDS[plan.over]}; reporting seeds {reporting} kept apart; results in {out}",
        flush=True,
    )
    document = run_study(
        plan,
        out,
        options,
        command=command,
        progress=not args.no_progress,
        on_trial=lambda study: _draw(study, plan.params, out),
        also_writes=(TRIALS_FIGURE, IMPORTANCE_FIGURE),
    )
    skipped = _draw(document, plan.params, out)
    for name in (STUDY_FILE, TRIALS_FIGURE):
        print(f"{PROG}: wrote {out / name}")
    print(f"{PROG}: {skipped}" if skipped else f"{PROG}: wrote {out / IMPORTANCE_FIGURE}")
    if log:
        print(f"{PROG}: the trials' runs logged under {out / 'logs'} ({', '.join(log)})")
    best = document["best"]
    if best is None:
        print(f"{PROG}: no trial finished (all pruned or refused): no {TUNED_FILE}; widen the ranges or raise --trials")
        return 0
    print(f"{PROG}: wrote {out / TUNED_FILE}")
    tied = ties_at_best(document)
    if len(tied) > 1:
        print(
            f"{PROG}: note: {len(tied)} finished trials tie at the best value ({tied}): the objective could not tell "
            "them apart, and the first was kept"
            + (
                "; --objective-over curve ranks such trials by how soon they got there (docs/tuning.md)"
                if plan.over == "last"
                else ""
            )
        )
    shown = ", ".join(f"{name} = {value!r}" for name, value in best["params"].items())
    print(
        f"{PROG}: best: trial {best['number']}, {metric} {best['value']:.4g} ({shown}); report it on the reporting seeds: "
        f"{PROG} reproduce --profile {out / TUNED_FILE}"
        + (f" --update-kernel {options.update_kernel}" if options.update_kernel != RunnerOptions.update_kernel else "")
    )
    return 0


def _draw(study: dict[str, Any], params: tuple[ParamSpec, ...], out: Path) -> str | None:
    """Draw ``trials.png`` and ``importance.png`` of the study document ``study`` (whose search
    space is ``params``) into ``out`` (after every trial); returns why there is no importance
    figure (one line; an earlier one is removed then), or ``None``."""
    from empathy_zoo.training.trials_figure import IMPORTANCE_FIGURE, TRIALS_FIGURE, write_importance_figure, write_trials_figure
    from empathy_zoo.training.tuning_journal import param_distribution

    write_trials_figure(study, out / TRIALS_FIGURE)
    skipped = write_importance_figure(study, {spec.name: param_distribution(spec) for spec in params}, out / IMPORTANCE_FIGURE)
    if skipped is not None:
        (out / IMPORTANCE_FIGURE).unlink(missing_ok=True)  # (a figure of earlier trials would disagree with the study)
    return skipped


def add_tune(sub: Any) -> None:
    """The ``tune`` subcommand."""
    from agents.base import UPDATE_KERNELS
    from empathy_zoo.environments import ENVIRONMENT_TABLE
    from empathy_zoo.experiment.search_space import KINDS
    from empathy_zoo.metrics import HIGHER_IS_BETTER, METRIC_NAMES
    from empathy_zoo.training.options import RunnerOptions
    from empathy_zoo.training.study_plan import OBJECTIVE_OVER, STARTUP_TRIALS, TUNING_SEED_BASE

    task_metrics = ", ".join(f"{env.task} in {name}" for name, env in ENVIRONMENT_TABLE.items())
    lower = ", ".join(metric for metric in METRIC_NAMES if not HIGHER_IS_BETTER[metric])

    tune = sub.add_parser(
        "tune",
        help='tune a method\'s settings or reward fields with Optuna on tuning seeds (pip install -e ".[tune]")',
        description=__doc__.splitlines()[0],
    )
    tune.add_argument(
        "sweep", type=path_text, metavar="SWEEP_FILE", help="a sweep file or a shipped profile (methods, quick, ...)"
    )
    tune.add_argument("--method", required=True, metavar="NAME", help="the method of the sweep file to tune")
    tune.add_argument(
        "--param",
        required=True,
        action="append",
        metavar="NAME=KIND:...",
        help=help_text(
            f"a parameter and its range (repeatable); kinds: {', '.join(KINDS)}: learning_rate=log:1e-4:1e-2, "
            "penalty=float:-50:-1, batch_size=int:16:128, others=choice:closest,mean,min (docs/tuning.md)"
        ),
    )
    tune.add_argument("--env", metavar="VARIANT", help="the variant to tune on, where the method runs on several")
    tune.add_argument("--label", metavar="LABEL", help="the experiment to tune, where the method has several on the variant")
    tune.add_argument(
        "--trials",
        type=int,
        default=DEFAULT_TRIALS,
        metavar="N",
        help=f"trials (finished, pruned or refused); give every method of a comparison the same (default: {DEFAULT_TRIALS})",
    )
    tune.add_argument(
        "--batch",
        type=int,
        default=1,
        metavar="B",
        help="trials the sampler proposes at once, from the trials finished before them, trained side by side "
        "(--jobs) and told back in trial order; part of the study's plan (default: 1, one trial at a time)",
    )
    tune.add_argument(
        "--jobs",
        type=int,
        default=1,
        metavar="N",
        help="processes that train a batch's trials side by side, at most the CPUs; the study is the same for any (default: 1)",
    )
    tune.add_argument(
        "--budget", type=int, metavar="STEPS", help="env steps per run of a trial (default: the sweep file's steps)"
    )
    tune.add_argument(
        "--eval-interval",
        type=int,
        metavar="STEPS",
        help="env steps between a trial's greedy evaluations, where the pruner looks (default: the sweep file's)",
    )
    tune.add_argument(
        "--tuning-seeds",
        type=int,
        default=DEFAULT_TUNING_SEEDS,
        metavar="N",
        help=f"seeds every trial trains, {TUNING_SEED_BASE} and on; refused if the sweep file reports on one "
        f"(default: {DEFAULT_TUNING_SEEDS})",
    )
    tune.add_argument(
        "--objective",
        choices=METRIC_NAMES,
        metavar="METRIC",
        help="the metric to optimise, in the greedy evaluations --objective-over names (default: the environment's task metric: "
        f"{task_metrics}); {lower} are minimised, the others maximised",
    )
    tune.add_argument(
        "--objective-over",
        choices=OBJECTIVE_OVER,
        default="last",
        help="which greedy evaluations a trial's value summarises: last (the leaderboard's greedy figure) or curve "
        "(their mean: the area under the greedy learning curve, which tells apart trials that all reach a "
        "saturated metric's ceiling, as Coexistence's survival does) (default: last)",
    )
    tune.add_argument("--sampler-seed", type=int, default=0, metavar="S", help="seed of the TPE sampler (default: 0)")
    tune.add_argument(
        "--startup-trials",
        type=int,
        default=STARTUP_TRIALS,
        metavar="N",
        help=f"trials sampled at random before TPE models the rest (default: {STARTUP_TRIALS})",
    )
    tune.add_argument("--no-prune", action="store_true", help="train every trial to its end (no median pruner)")
    tune.add_argument(
        "--prune-from",
        type=int,
        default=0,
        metavar="STEPS",
        help="the env step from which the pruner may stop a trial; a later one where the first greedy evaluations "
        "are too noisy to judge a trial by (default: 0, every evaluation)",
    )
    tune.add_argument(
        "--out", type=path_text, metavar="DIR", help="output directory (default: results/tuning/<variant>/<method>)"
    )
    tune.add_argument("--device", default="cpu", help="torch device: cpu, cuda, cuda:N (default: cpu)")
    tune.add_argument("--threads", type=int, default=1, metavar="N", help="torch CPU threads (default: 1)")
    tune.add_argument(
        "--update-kernel",
        choices=UPDATE_KERNELS,
        default=RunnerOptions.update_kernel,
        help="how Empathic DQN and the methods built on it take a gradient step (numba: compiled, faster; the "
        f"runs differ in their last bits; a study resumes only with its own) (default: {RunnerOptions.update_kernel})",
    )
    tune.add_argument(
        "--log",
        metavar="BACKENDS",
        help="log every trial's runs' scalars live to tensorboard, csv and/or wandb, comma-separated, under "
        'OUT/logs/<backend>/<run id>/ (tensorboard, wandb: pip install -e ".[tensorboard]" / ".[wandb]"; '
        "none: no logging) (default: none)",
    )
    tune.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_progress_style(tune)
    tune.set_defaults(handler=cmd_tune)
