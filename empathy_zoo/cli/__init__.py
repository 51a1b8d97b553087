"""The ``empathy-zoo`` command line: train runs, reproduce a sweep, write the leaderboard.

    empathy-zoo train --env coexistence_v0 --method empathic_dqn --selfishness 0.5 --steps 1000000 --seed 0 --out runs/
    empathy-zoo reproduce --profile quick            # sweep + leaderboard into results/quick/
    empathy-zoo leaderboard results/quick [--out DIR]
    empathy-zoo methods | policies                   # what is registered
    empathy-zoo play --env sharing_v0 --episodes 3 --render ansi

``train`` takes one ``--<field>`` option per field of the method's settings (see
``empathy-zoo train --help``). Its precedence: built-in defaults < the ``--config`` TOML file
(``[settings]`` for method settings, top-level keys for the run) < the command line. A bad
input prints ``empathy-zoo: error: <message>`` and exits with status 2, before any training.
"""

from __future__ import annotations

import argparse
import ast
import inspect
import os
import shlex
import sys
import textwrap
from collections.abc import Sequence
from dataclasses import fields
from pathlib import Path
from typing import Any

import numpy as np

from empathy_zoo.training.sweep import SEEDS, STR_TABLE

__all__ = ["main", "build_parser", "RUN_KEYS", "RUN_DEFAULTS"]

PROG = "empathy-zoo"
SUMMARY_METRICS = ("survival", "harms", "batteries", "equality")

RUN_KEYS: dict[str, Any] = {
    "env": str, "method": str, "seed": int, "seeds": SEEDS, "steps": int, "out": str, "device": str,
    "eval_interval": int, "eval_episodes": int, "checkpoint_interval": int, "max_parallel_runs": int,
    "workers": int, "threads": int, "label": str, "size": int, "view": int, "max_cycles": int, "fixed": STR_TABLE,
    "start": str, "inventory_encoding": str, "progress": bool,
}
"""Top-level keys of a ``train --config`` file and their types (method settings go in ``[settings]``)."""
ENV_ARGUMENTS = ("size", "view", "max_cycles", "start", "inventory_encoding")
"""Keys of a run that are environment arguments (the env checks which it takes)."""

RUN_DEFAULTS: dict[str, Any] = {
    "env": "coexistence_v0", "method": "empathic_dqn", "seeds": [0], "steps": 1_000_000, "out": "runs",
    "device": "cpu", "eval_interval": 50_000, "eval_episodes": 10, "checkpoint_interval": 50_000,
    "max_parallel_runs": 32, "workers": 1, "threads": 1, "label": None, "fixed": None, "progress": True,
}
"""What a ``train`` run does when neither the config file nor the command line says otherwise."""


# ---------------------------------------------------------------------------- helpers
def field_docs(cls: type) -> dict[str, str]:
    """The docstring under every field of a dataclass (``{}`` when the source is unavailable)."""
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(cls)))
    except (OSError, TypeError, SyntaxError):
        return {}
    body = tree.body[0].body if tree.body and isinstance(tree.body[0], ast.ClassDef) else []
    docs = {}
    for node, after in zip(body, body[1:]):
        if (isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name) and isinstance(after, ast.Expr)
                and isinstance(after.value, ast.Constant) and isinstance(after.value.value, str)):
            docs[node.target.id] = " ".join(after.value.value.split())
    return docs


def _help(text: str) -> str:
    return text.replace("%", "%%")


def _agent_policy(text: str) -> tuple[str, str]:
    agent, sep, policy = text.partition("=")
    if not sep or not agent or not policy:
        raise argparse.ArgumentTypeError(f"expected AGENT=POLICY (e.g. cat_0=stay), got {text!r}")
    return agent, policy


def check_device(device: str) -> str:
    """``device`` if torch can use it here; a clear ``ValueError`` otherwise (e.g. no CUDA)."""
    import torch

    try:
        parsed = torch.device(device)
    except (RuntimeError, TypeError) as error:
        raise ValueError(f"--device {device!r} is not a torch device ({error}); use cpu or cuda") from None
    if parsed.type == "cuda":
        if not torch.cuda.is_available():
            raise ValueError(f"--device {device}: CUDA is not available on this machine (torch {torch.__version__}); "
                             "use --device cpu or install a CUDA build of torch")
        if parsed.index is not None and parsed.index >= torch.cuda.device_count():
            raise ValueError(f"--device {device}: only {torch.cuda.device_count()} CUDA device(s) here")
    elif parsed.type == "mps":
        if not torch.backends.mps.is_available():
            raise ValueError(f"--device {device}: MPS is not available on this machine; use --device cpu")
    elif parsed.type != "cpu":
        raise ValueError(f"--device {device}: unsupported device type {parsed.type!r}; use cpu or cuda")
    return device


def _positive(name: str, value: int, allow_zero: bool = False) -> int:
    if value < (0 if allow_zero else 1):
        raise ValueError(f"{name} must be {'non-negative' if allow_zero else 'positive'}, got {value}")
    return value


def _check_results(specs: Sequence[Any], out: Path, others: bool = False) -> int:
    """Read every result file the runs already have, and with ``others`` every other one in
    ``out/runs`` (a corrupted or malformed one raises, untouched); count the runs' files."""
    from empathy_zoo.result_file import RUNS_DIR, read_result, result_path

    done = 0
    ours = set()
    for spec in specs:
        path = result_path(out, spec.run_id)
        ours.add(path.name)
        if path.exists():
            read_result(path)
            done += 1
    if others and (out / RUNS_DIR).is_dir():
        for path in sorted((out / RUNS_DIR).glob("*.json")):
            if path.name not in ours and not path.name.startswith("."):
                read_result(path)
    return done


def _fmt(value: float) -> str:
    return "n/a" if not np.isfinite(value) else f"{value:.3g}" if abs(value) < 100 else f"{value:.0f}"


def run_summary(result: dict[str, Any]) -> str:
    """One line: the run's final-10 % training means and its last greedy evaluation."""
    from leaderboard.aggregate import run_scalars

    scalars = run_scalars(result, SUMMARY_METRICS)
    train = ", ".join(f"{m} {_fmt(scalars['train_final10'][m])}" for m in SUMMARY_METRICS)
    evaluation = ", ".join(f"{m} {_fmt(scalars['eval'][m])}" for m in SUMMARY_METRICS)
    last = max((e["step"] for e in result["eval"]), default=None)
    return (f"{result['run_id']} [{result['method_label']}]: final 10% of training: {train} | "
            f"last eval (step {last}): {evaluation}")


def _runner_options(args: argparse.Namespace, values: dict[str, Any]) -> Any:
    from empathy_zoo.training.runner import RunnerOptions

    return RunnerOptions(
        device=check_device(values["device"]),
        max_parallel_runs=_positive("max_parallel_runs", values["max_parallel_runs"]),
        checkpoint_interval=_positive("checkpoint_interval", values["checkpoint_interval"], allow_zero=True),
        progress=values["progress"], workers=_positive("workers", values["workers"]),
        threads=_positive("threads", values["threads"]),
        backend=getattr(args, "backend", None) or "local", address=_ray_address(args),
    )


def _ray_address(args: argparse.Namespace) -> str | None:
    address = getattr(args, "address", None)
    if address is not None and getattr(args, "backend", None) != "ray":
        raise ValueError("--address is the Ray cluster to join: use it with --backend ray")
    return address


# ---------------------------------------------------------------------------- train
def _train_values(args: argparse.Namespace) -> tuple[dict[str, Any], dict[str, Any]]:
    """Run keys and method settings, merged: defaults < config file < command line."""
    from agents.settings import EmpathicDQNSettings
    from empathy_zoo.training.sweep import SweepConfigError, check_keys, check_value, read_toml, settings_types

    types = settings_types(EmpathicDQNSettings)
    given = vars(args)
    run: dict[str, Any] = dict(RUN_DEFAULTS)
    settings: dict[str, Any] = {}
    if "config" in given:
        path = given["config"]
        data = read_toml(path)
        check_keys(data, [*RUN_KEYS, "settings"], f"{path}: top level")
        if "seed" in data and "seeds" in data:
            raise SweepConfigError(f"{path}: give 'seed' or 'seeds', not both")
        for key, value in data.items():
            if key == "settings":
                if not isinstance(value, dict):
                    raise SweepConfigError(f"{path}: [settings] must be a table")
                check_keys(value, types, f"{path}: [settings]")
                settings |= {k: check_value(v, types[k], f"{path}: [settings] {k}") for k, v in value.items()}
            elif key == "seed":
                run["seeds"] = [check_value(value, int, f"{path}: seed")]
            else:
                run[key] = check_value(value, RUN_KEYS[key], f"{path}: {key}")
    for key in RUN_KEYS.keys() - {"seed", "fixed"}:
        if key in given:
            run[key] = given[key]
    if "seed" in given:
        run["seeds"] = [given["seed"]]
    if "fixed" in given:
        run["fixed"] = dict(given["fixed"])
    if "no_progress" in given:
        run["progress"] = False
    settings |= {name: given[name] for name in types if name in given}
    return run, settings


def cmd_train(args: argparse.Namespace, command: str) -> int:
    from empathy_zoo.result_file import read_result
    from empathy_zoo.training.runner import train_runs
    from empathy_zoo.training.spec import RunSpec

    run, settings = _train_values(args)
    env_kwargs = {key: run[key] for key in ENV_ARGUMENTS if run.get(key) is not None}
    fixed = None
    if run["fixed"] is not None:
        from empathy_zoo.policies import DEFAULT_POLICIES

        fixed = {**DEFAULT_POLICIES.get(run["env"], {}), **run["fixed"]}
    specs = [
        RunSpec(env=run["env"], method=run["method"], settings=settings, seed=seed, steps=run["steps"],
                eval_interval=run["eval_interval"], eval_episodes=run["eval_episodes"], fixed=fixed,
                env_kwargs=env_kwargs, label=run["label"])
        for seed in run["seeds"]
    ]
    options = _runner_options(args, run)
    out = Path(run["out"])
    done = _check_results(specs, out)
    print(f"{PROG}: {len(specs)} run(s) of {specs[0].display_label()} on {run['env']}, {run['steps']:,} steps each"
          + (f" ({done} already finished)" if done else "") + f"; results in {out / 'runs'}", flush=True)
    paths = train_runs(specs, out, options)
    for path in paths:
        print(run_summary(read_result(path)))
    return 0


# ---------------------------------------------------------------------------- reproduce
def cmd_reproduce(args: argparse.Namespace, command: str) -> int:
    from empathy_zoo.result_file import RUNS_DIR
    from empathy_zoo.training.runner import train_runs
    from empathy_zoo.training.spec import group_specs
    from leaderboard.report import write_leaderboard
    from leaderboard.reproduction import NotThePaperSweep, write_reproduction
    from empathy_zoo.training.sweep import load_sweep, profile_path

    path = profile_path(args.profile)
    specs = load_sweep(path, seeds=args.seeds)
    out = Path(args.out) if args.out else Path("results") / path.stem
    values = {**RUN_DEFAULTS, **{k: v for k, v in vars(args).items() if k in RUN_DEFAULTS and v is not None}}
    values["progress"] = not args.no_progress
    ensembles = len(group_specs(specs, _positive("max_parallel_runs", values["max_parallel_runs"])))
    if args.workers is None:  # one process per ensemble, as many as there are CPUs
        values["workers"] = max(1, min(os.cpu_count() or 1, ensembles))
    workers = values["workers"]
    options = _runner_options(args, values)
    done = _check_results(specs, out, others=True)  # the leaderboard reads them all: refuse now, not after training
    experiments = len({spec.run_id.rsplit("__s", 1)[0] for spec in specs})
    print(f"{PROG}: sweep {path} — {len(specs)} runs ({experiments} experiments × {len(specs) // experiments} seeds) "
          f"in {ensembles} ensemble(s) on {workers} worker process(es); {done} already finished; results in {out}",
          flush=True)
    ours = {f"{spec.run_id}.json" for spec in specs}
    others = sorted(p.name for p in (out / RUNS_DIR).glob("*.json") if p.name not in ours) if (out / RUNS_DIR).is_dir() else []
    if others:
        print(f"{PROG}: note: {len(others)} result file(s) in {out / RUNS_DIR} are not part of this sweep "
              f"(e.g. {others[0]}); the leaderboard includes them", flush=True)
    train_runs(specs, out, options)
    _print_written(write_leaderboard(out, command=command))
    try:
        print(f"{PROG}: wrote {write_reproduction(out, command=command)}")
    except NotThePaperSweep as reason:
        print(f"{PROG}: no REPRODUCTION.md: {reason}; the paper's claims are judged only on its own experiments")
    return 0


# ---------------------------------------------------------------------------- leaderboard, lists, play
def cmd_reproduction(args: argparse.Namespace, command: str) -> int:
    from leaderboard.aggregate import load_results
    from leaderboard.reproduction import write_reproduction
    from leaderboard.sensitivity import sensitivity_markdown

    produced_by = args.produced_by or "(the command that trained these runs is in each result file's config)"
    appendix = ""
    if args.sensitivity:
        appendix = sensitivity_markdown(
            load_results(args.sensitivity),
            f"empathy-zoo reproduce --profile sharing_sensitivity --out {args.sensitivity}   "
            f"(result files in {args.sensitivity}; its LEADERBOARD.md names the exact command)",
        )
    note = Path(args.note).read_text() if args.note else ""
    print(f"{PROG}: wrote {write_reproduction(args.results, args.out, command=produced_by, note=note, appendix=appendix)}")
    return 0


def cmd_sensitivity(args: argparse.Namespace, command: str) -> int:
    from leaderboard.sensitivity import write_sensitivity

    produced_by = args.produced_by or "(the command that trained these runs is in each result file's config)"
    note = Path(args.note).read_text() if args.note else ""
    print(f"{PROG}: wrote {write_sensitivity(args.results, args.out, command=produced_by, note=note)}")
    return 0


def cmd_leaderboard(args: argparse.Namespace, command: str) -> int:
    from leaderboard.report import write_leaderboard

    _print_written(write_leaderboard(args.results, args.out, command=command))
    return 0


def _print_written(paths: dict[str, Path]) -> None:
    for key in ("markdown", "csv", "html"):
        print(f"{PROG}: wrote {paths[key]}")


def cmd_methods(args: argparse.Namespace, command: str) -> int:
    from agents.registry import METHODS

    width = max(map(len, METHODS))
    for name, method in METHODS.items():
        print(f"{name:<{width}}  {method.description}")
    return 0


def cmd_policies(args: argparse.Namespace, command: str) -> int:
    from empathy_zoo.policies import DEFAULT_POLICIES, POLICIES

    width = max(map(len, POLICIES))
    for name, policy in POLICIES.items():
        doc = " ".join((inspect.getdoc(policy) or "").split("\n\n")[0].split())
        first = doc.split(". ")[0].rstrip(".") + "." if doc else ""
        uses = [f"{agent} in {env}" for env, agents in DEFAULT_POLICIES.items() for agent, p in agents.items() if p == name]
        print(f"{name:<{width}}  {first}" + (f" (default: {', '.join(uses)})" if uses else ""))
    return 0


def cmd_play(args: argparse.Namespace, command: str) -> int:
    from empathy_zoo import ENVIRONMENTS, FixedAgents
    from empathy_zoo.metrics import METRIC_NAMES
    from empathy_zoo.policies import DEFAULT_POLICIES

    if args.env not in ENVIRONMENTS:
        raise ValueError(f"unknown environment {args.env!r}; registered: {sorted(ENVIRONMENTS)}")
    _positive("--episodes", args.episodes)
    fixed = {**DEFAULT_POLICIES.get(args.env, {}), **dict(args.fixed or [])}
    env = FixedAgents(ENVIRONMENTS[args.env].parallel_env(render_mode=args.render), fixed)
    engine = env.unwrapped.engine
    learner = env.possible_agents[0]
    rng = np.random.default_rng(args.seed)
    for episode in range(args.episodes):
        env.reset(seed=args.seed + episode)
        if args.render:
            print(env.render())
        while env.agents:
            env.step({agent: int(rng.integers(5)) for agent in env.agents})
            if args.render:
                print(env.render())
        metrics = engine.episode_metrics(np.array([0]), engine.agents.index(learner))
        print(f"episode {episode} (seed {args.seed + episode}): "
              + ", ".join(f"{name} {float(metrics[name][0]):g}" for name in METRIC_NAMES), flush=True)
    return 0


# ---------------------------------------------------------------------------- parser
def _add_runner_options(parser: argparse.ArgumentParser, default: Any = None) -> None:
    def d(key: str) -> str:
        return f" (default: {RUN_DEFAULTS[key]})"

    parser.add_argument("--device", default=default, help="torch device: cpu, cuda, cuda:N" + d("device"))
    parser.add_argument("--max-parallel-runs", type=int, default=default, metavar="K",
                        help="most runs trained in lockstep in one ensemble" + d("max_parallel_runs"))
    parser.add_argument("--workers", type=int, default=default, metavar="N",
                        help="processes training ensembles side by side" + (
                            d("workers") if default is not None else " (default: one per ensemble, at most the CPUs)"))
    parser.add_argument("--threads", type=int, default=default, metavar="N",
                        help="torch CPU threads per process; these small networks gain nothing from more, and "
                             "extra threads are much slower on a busy machine" + d("threads"))
    parser.add_argument("--checkpoint-interval", type=int, default=default, metavar="N",
                        help="env steps between checkpoints (0 = never)" + d("checkpoint_interval"))
    parser.add_argument("--no-progress", action="store_true", default=default, help="no progress bars")
    parser.add_argument("--backend", choices=["local", "ray"], default=default,
                        help="where ensembles train: this machine, or Ray tasks (pip install \"empathy-zoo[ray]\")"
                        " (default: local)")
    parser.add_argument("--address", default=default, metavar="ADDR",
                        help="with --backend ray: the cluster to join (auto, ray://host:10001); "
                        "default: start Ray on this machine")


def _add_train(sub: Any) -> None:
    from agents.settings import EmpathicDQNSettings
    from empathy_zoo.training.sweep import settings_types

    parser = sub.add_parser(
        "train", help="train one run (or several seeds as one ensemble)", argument_default=argparse.SUPPRESS,
        description="Train runs of one method on one environment. Precedence: defaults < --config file < command line.",
    )
    parser.add_argument("--config", metavar="FILE.toml",
                        help="TOML file: top-level run keys (env, method, seed(s), steps, …) and a [settings] table")
    parser.add_argument("--env", help=f"environment (default: {RUN_DEFAULTS['env']})")
    parser.add_argument("--method", help=f"registered method or package.module:NAME (default: {RUN_DEFAULTS['method']})")
    seeds = parser.add_mutually_exclusive_group()
    seeds.add_argument("--seed", type=int, help="seed of the run (default: 0)")
    seeds.add_argument("--seeds", type=int, nargs="+", metavar="S", help="several seeds, trained as one ensemble")
    parser.add_argument("--steps", type=int, help=f"env steps per run (default: {RUN_DEFAULTS['steps']})")
    parser.add_argument("--out", metavar="DIR", help=f"output directory (default: {RUN_DEFAULTS['out']})")
    parser.add_argument("--eval-interval", type=int, metavar="N",
                        help=f"env steps between greedy evaluations (default: {RUN_DEFAULTS['eval_interval']})")
    parser.add_argument("--eval-episodes", type=int, metavar="N",
                        help=f"episodes per greedy evaluation (default: {RUN_DEFAULTS['eval_episodes']})")
    parser.add_argument("--label", help="display name in tables (default: the method's)")
    parser.add_argument("--size", type=int, help="side of the torus (default: 7)")
    parser.add_argument("--view", type=int, help="side of the observation window (default: 5)")
    parser.add_argument("--max-cycles", type=int, help="steps before truncation (default: 500)")
    parser.add_argument("--start", help="Sharing only: start cells, random or centre (default: random)")
    parser.add_argument("--inventory-encoding", metavar="ENCODING",
                        help="Sharing only: how an agent is drawn, count_plus_one or authors (default: count_plus_one)")
    parser.add_argument("--fixed", type=_agent_policy, action="append", metavar="AGENT=POLICY",
                        help="fixed agent policy, a name or package.module:ClassName (repeatable)")
    _add_runner_options(parser, default=argparse.SUPPRESS)
    group = parser.add_argument_group("method settings", "every field of EmpathicDQNSettings (paper values by default)")
    docs = field_docs(EmpathicDQNSettings)
    types = settings_types(EmpathicDQNSettings)
    for field in fields(EmpathicDQNSettings):
        option = "--" + field.name.replace("_", "-")
        text = _help(f"{docs.get(field.name, '')} (default: {field.default})")
        if types[field.name] is bool:
            group.add_argument(option, action=argparse.BooleanOptionalAction, help=text)
        else:
            kind = types[field.name] if types[field.name] in (int, float) else str
            group.add_argument(option, type=kind, metavar=kind.__name__.upper(), help=text)
    parser.set_defaults(handler=cmd_train)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog=PROG, description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    _add_train(sub)

    reproduce = sub.add_parser("reproduce", help="train a sweep (resumable) and write its leaderboard")
    reproduce.add_argument("--profile", required=True, metavar="quick|paper|PATH.toml",
                           help="a shipped sweep (empathy_zoo/profiles/<name>.toml) or a sweep file")
    reproduce.add_argument("--seeds", type=int, metavar="N", help="replace the sweep's seeds with 0..N-1")
    reproduce.add_argument("--out", metavar="DIR", help="output directory (default: results/<profile>)")
    _add_runner_options(reproduce)
    reproduce.set_defaults(handler=cmd_reproduce)

    board = sub.add_parser("leaderboard", help="write the leaderboard of existing results")
    board.add_argument("results", metavar="DIR", help="results directory (with runs/ or *.json)")
    board.add_argument("--out", metavar="OUT", help="where to write (default: DIR)")
    board.set_defaults(handler=cmd_leaderboard)

    report = sub.add_parser("reproduction", help="check the paper's claims on existing results (REPRODUCTION.md)")
    report.add_argument("results", metavar="DIR", help="results directory of a reproduce sweep")
    report.add_argument("--out", metavar="PATH", help="where to write (default: DIR/REPRODUCTION.md)")
    report.add_argument("--produced-by", metavar="COMMAND", help="the command that produced the results, for the report")
    report.add_argument("--sensitivity", metavar="DIR",
                        help="results of the Sharing fidelity sweep (profile sharing_sensitivity): adds C5's table per condition")
    report.add_argument("--note", metavar="FILE.md", help="prose placed before the rules (how the run was made, what it shows)")
    report.set_defaults(handler=cmd_reproduction)

    sensitivity = sub.add_parser("sensitivity", help="Sharing's claims per fidelity condition (SENSITIVITY.md)")
    sensitivity.add_argument("results", metavar="DIR", help="results directory of a sharing_sensitivity sweep")
    sensitivity.add_argument("--out", metavar="PATH", help="where to write (default: DIR/SENSITIVITY.md)")
    sensitivity.add_argument("--produced-by", metavar="COMMAND", help="the command that produced the results")
    sensitivity.add_argument("--note", metavar="FILE.md", help="prose placed before the rules")
    sensitivity.set_defaults(handler=cmd_sensitivity)

    sub.add_parser("methods", help="list the registered learning methods").set_defaults(handler=cmd_methods)
    sub.add_parser("policies", help="list the registered fixed-agent policies").set_defaults(handler=cmd_policies)

    play = sub.add_parser("play", help="random robot beside the fixed agents; prints episode metrics")
    play.add_argument("--env", default="coexistence_v0", help="environment (default: coexistence_v0)")
    play.add_argument("--episodes", type=int, default=1, help="episodes (default: 1)")
    play.add_argument("--seed", type=int, default=0, help="seed of the first episode (default: 0)")
    play.add_argument("--render", choices=["ansi"], default=None, help="print the grid every step")
    play.add_argument("--fixed", type=_agent_policy, action="append", metavar="AGENT=POLICY",
                      help="fixed agent policy, a name or package.module:ClassName (repeatable)")
    play.set_defaults(handler=cmd_play)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line ``argv`` (default: ``sys.argv[1:]``); returns the exit status."""
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exit_:  # argparse: --help (0) or a usage error (2, message printed)
        return int(exit_.code or 0)
    command = shlex.join([PROG, *argv])
    try:
        return args.handler(args, command)
    except ValueError as error:
        print(f"{PROG}: error: {error}", file=sys.stderr)
        return 2
    except OSError as error:  # a write that failed mid-way (disk full, a directory removed): no traceback
        print(f"{PROG}: error: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted; run the same command again to resume from the last checkpoint", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
