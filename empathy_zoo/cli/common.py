"""What the subcommands share: the program's name, the run defaults, the runner's options (on the
parser and checked into :class:`~empathy_zoo.training.options.RunnerOptions`), the device check,
reading the result files a command will touch, and the one-line summaries it prints."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

# (the names only: agents.empathic_dqn imports torch, which the command line loads anyway)
from agents.base import UPDATE_KERNELS

if TYPE_CHECKING:
    from empathy_zoo.experiment.records import RunResult

__all__ = [
    "PROG",
    "RUN_DEFAULTS",
    "add_progress_style",
    "add_runner_options",
    "AgentPolicies",
    "agent_policy",
    "check_device",
    "read_results",
    "help_text",
    "path_text",
    "positive",
    "print_written",
    "run_summary",
    "runner_options",
]

PROG = "empathy-zoo"

RUNNER_KEYS = ("device", "max_parallel_runs", "checkpoint_interval", "progress", "threads", "workers", "log", "update_kernel")
"""The fields of :class:`~empathy_zoo.training.options.RunnerOptions` that ``train`` options and
its ``--config`` file set (the others have options of their own: ``--backend``, ``--address``,
``--rerun-changed``)."""


def _run_defaults() -> dict[str, Any]:
    from empathy_zoo.experiment.model import DEFAULT_METHOD, Budget, EnvVariant
    from empathy_zoo.training.options import RunnerOptions

    runner = RunnerOptions()
    return {
        "env": EnvVariant.env,
        "method": DEFAULT_METHOD,
        "seeds": [0],
        **{name: getattr(Budget, name) for name in ("steps", "eval_interval", "eval_episodes")},
        "out": "runs",
        **{name: getattr(runner, name) for name in RUNNER_KEYS},
        "label": None,
        "fixed": None,
    }


RUN_DEFAULTS: dict[str, Any] = _run_defaults()
"""What a ``train`` run does when neither the config file nor the command line says otherwise: the
defaults of :class:`~empathy_zoo.experiment.Budget`, :class:`~empathy_zoo.experiment.EnvVariant`
and :class:`~empathy_zoo.training.options.RunnerOptions`, with one seed and ``runs/`` as output."""


def help_text(text: str) -> str:
    """``text`` as an argparse help string (a literal ``%`` escaped)."""
    return text.replace("%", "%%")


def agent_policy(text: str) -> tuple[str, str]:
    """``AGENT=POLICY`` of ``--fixed`` as a pair."""
    agent, sep, policy = text.partition("=")
    if not sep or not agent or not policy:
        raise argparse.ArgumentTypeError(f"expected AGENT=POLICY (e.g. cat_0=stay), got {text!r}")
    return agent, policy


class AgentPolicies(argparse.Action):
    """The action of a repeatable ``--fixed AGENT=POLICY`` (``type=agent_policy``): the table
    ``{agent: policy}`` of every one given; an agent given twice is a usage error naming it
    (never the last one silently)."""

    def __call__(
        self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: Any, option_string: str | None = None
    ) -> None:
        agent, policy = values
        table = dict(getattr(namespace, self.dest, None) or {})
        if agent in table:
            raise argparse.ArgumentError(
                self, f"{agent} is given twice ({agent}={table[agent]} and {agent}={policy}): give each agent one policy"
            )
        table[agent] = policy
        setattr(namespace, self.dest, table)


def path_text(text: str) -> str:
    """A path option's or argument's value, refused when empty (which would silently mean the
    current directory: name it, ``.``)."""
    if not text:
        raise argparse.ArgumentTypeError("an empty path: name the directory ('.' for the current one)")
    return text


def check_device(device: str) -> str:
    """``device`` if torch can use it here; a clear ``ValueError`` otherwise (e.g. no CUDA)."""
    import torch

    try:
        parsed = torch.device(device)
    except (RuntimeError, TypeError) as error:
        raise ValueError(f"--device {device!r} is not a torch device ({error}); use cpu or cuda") from None
    if parsed.type == "cuda":
        if not torch.cuda.is_available():
            raise ValueError(
                f"--device {device}: CUDA is not available on this machine (torch {torch.__version__}); "
                "use --device cpu or install a CUDA build of torch"
            )
        if parsed.index is not None and parsed.index >= torch.cuda.device_count():
            raise ValueError(f"--device {device}: only {torch.cuda.device_count()} CUDA device(s) here")
    elif parsed.type == "mps":
        if not torch.backends.mps.is_available():
            raise ValueError(f"--device {device}: MPS is not available on this machine; use --device cpu")
    elif parsed.type != "cpu":
        raise ValueError(f"--device {device}: unsupported device type {parsed.type!r}; use cpu or cuda")
    return device


def positive(name: str, value: int, allow_zero: bool = False) -> int:
    """``value`` if it is positive (or zero, with ``allow_zero``); a ``ValueError`` naming ``name`` otherwise."""
    if value < (0 if allow_zero else 1):
        raise ValueError(f"{name} must be {'non-negative' if allow_zero else 'positive'}, got {value}")
    return value


def read_results(specs: Sequence[Any], out: Path) -> tuple[dict[Path, RunResult], int]:
    """Every result file in ``out/runs``, read once (a corrupted or malformed one raises,
    untouched), and how many of the runs ``specs`` have one."""
    from empathy_zoo.result_file import result_path
    from empathy_zoo.training.runner import read_finished

    finished = read_finished(out)
    return finished, sum(result_path(out, spec.run_id) in finished for spec in specs)


def _fmt(value: float) -> str:
    return "n/a" if not np.isfinite(value) else f"{value:.3g}" if abs(value) < 100 else f"{value:.0f}"


def run_summary(result: RunResult) -> str:
    """One line: the run's final-10 % training means and its last greedy evaluation, of the
    metrics that mean something in its environment (the leaderboard's table columns)."""
    from empathy_zoo.environments import ENVIRONMENT_TABLE
    from leaderboard.aggregate import run_scalars

    metrics = ENVIRONMENT_TABLE[result.env].table_metrics
    scalars = run_scalars(result, metrics)
    train = ", ".join(f"{m} {_fmt(scalars['train_final10'][m])}" for m in metrics)
    evaluation = ", ".join(f"{m} {_fmt(scalars['eval'][m])}" for m in metrics)
    last = max(result.eval_steps(), default=None)
    return f"{result.run_id} [{result.method_label}]: final 10% of training: {train} | last eval (step {last}): {evaluation}"


def print_written(paths: dict[str, Path]) -> None:
    """Name the leaderboard's files, one line each."""
    for key in ("markdown", "csv", "html"):
        print(f"{PROG}: wrote {paths[key]}")


def runner_options(args: argparse.Namespace, values: dict[str, Any]) -> Any:
    """The checked :class:`~empathy_zoo.training.runner.RunnerOptions` of ``values`` and ``args``."""
    from empathy_zoo.training.runner import RunnerOptions

    return RunnerOptions(
        device=check_device(values["device"]),
        max_parallel_runs=positive("max_parallel_runs", values["max_parallel_runs"]),
        checkpoint_interval=positive("checkpoint_interval", values["checkpoint_interval"], allow_zero=True),
        progress=values["progress"],
        progress_style=getattr(args, "progress_style", None) or "auto",
        workers=positive("workers", values["workers"]),
        threads=positive("threads", values["threads"]),
        backend=getattr(args, "backend", None) or "local",
        address=_ray_address(args),
        rerun_changed=bool(getattr(args, "rerun_changed", False)),
        log=values["log"],
        update_kernel=values["update_kernel"],
    )


def _ray_address(args: argparse.Namespace) -> str | None:
    address = getattr(args, "address", None)
    if address is not None and getattr(args, "backend", None) != "ray":
        raise ValueError("--address is the Ray cluster to join: use it with --backend ray")
    return address


def add_progress_style(parser: argparse.ArgumentParser) -> None:
    """``--progress STYLE``: bars on a terminal and plain lines elsewhere (``auto``), or either."""
    from empathy_zoo.training.progress import PROGRESS_STYLES

    parser.add_argument(
        "--progress",
        dest="progress_style",
        choices=PROGRESS_STYLES,
        default="auto",
        metavar="STYLE",
        help="how progress shows: auto (bars on a terminal, else a plain line every 30 s), bars or plain (default: auto)",
    )


def add_runner_options(parser: argparse.ArgumentParser, default: Any = None) -> None:
    """The options of how runs train (device, parallelism, checkpoints, progress, backend)."""

    def d(key: str) -> str:
        return f" (default: {RUN_DEFAULTS[key]})"

    parser.add_argument("--device", default=default, help="torch device: cpu, cuda, cuda:N" + d("device"))
    parser.add_argument(
        "--max-parallel-runs",
        type=int,
        default=default,
        metavar="K",
        help="most runs trained in lockstep in one ensemble" + d("max_parallel_runs"),
    )
    parser.add_argument(
        "--workers",
        type=int,
        default=default,
        metavar="N",
        help="processes training ensembles side by side"
        + (d("workers") if default is not None else " (default: one per ensemble, at most the CPUs)"),
    )
    parser.add_argument(
        "--threads",
        type=int,
        default=default,
        metavar="N",
        help="torch CPU threads per process; these small networks gain nothing from more, and "
        "extra threads are much slower on a busy machine" + d("threads"),
    )
    parser.add_argument(
        "--checkpoint-interval",
        type=int,
        default=default,
        metavar="N",
        help="env steps between checkpoints (0 = never)" + d("checkpoint_interval"),
    )
    parser.add_argument("--no-progress", action="store_true", default=default, help="no progress bars")
    add_progress_style(parser)
    parser.add_argument(
        "--log",
        default=default,
        metavar="BACKENDS",
        help="log every run's scalars live to tensorboard, csv and/or wandb, comma-separated, under "
        'OUT/logs/<backend>/<run id>/ (tensorboard, wandb: pip install -e ".[tensorboard]" / ".[wandb]"; '
        "none: no logging) (default: none)",
    )
    parser.add_argument(
        "--update-kernel",
        choices=UPDATE_KERNELS,
        default=default,
        help="how Empathic DQN and the methods built on it take a gradient step: compiled (numba), "
        "PyTorch (torch), or auto: numba where it builds on a CPU; the two differ in the last bits of a run, "
        "and each result file records which made it" + d("update_kernel"),
    )
    parser.add_argument(
        "--rerun-changed",
        action="store_true",
        help="retrain (over their files) the finished runs made by another empathy-zoo version or "
        "an edited plug-in; without it such runs are refused, never silently reused",
    )
    parser.add_argument(
        "--backend",
        choices=["local", "ray"],
        default=default,
        help='where ensembles train: this machine, or Ray tasks (pip install -e ".[ray]") (default: local)',
    )
    parser.add_argument(
        "--address",
        default=default,
        metavar="ADDR",
        help="with --backend ray: the cluster to join (auto, ray://host:10001); default: start Ray on this machine",
    )
