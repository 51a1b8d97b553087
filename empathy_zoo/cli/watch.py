"""``watch``: greedy episodes of a trained agent in its own environment, their metrics printed,
optionally the grid every step (``--render ansi``) and a GIF of the first episode (``--gif``).

    empathy-zoo watch RUN_ID [--dir runs] [--episodes 3] [--seed 0] [--fixed cat_0=stay] [--gif run.gif]
    empathy-zoo watch path/to/<run id>.agent.pt

A run id is looked up as ``<dir>/runs/<run id>.json`` (``--dir``: what ``train --out`` or a sweep
wrote to, default ``runs``), whose ``agent`` entry names the agent file beside it and its
SHA-256 (:func:`~empathy_zoo.agent_file.load_run_agent`); a path is read as an agent file (checked
against the result file beside it when that one names it) or as a result file. An episode is
played for at most :data:`~empathy_zoo.limits.MAX_WATCH_STEPS` steps (an agent file may record a
``max_cycles`` of up to 10⁹): a longer one is cut short there, said before anything plays, and its
line says which steps its metrics are of.
"""

from __future__ import annotations

import argparse
import difflib
import os
import tempfile
from pathlib import Path
from typing import Any

from empathy_zoo.cli.allow_import import add_allow_import
from empathy_zoo.cli.common import PROG, RUN_DEFAULTS, AgentPolicies, agent_policy, positive

__all__ = ["add_watch", "check_episodes", "check_gif_path", "cmd_watch", "find_agent", "is_path", "write_gif"]

GIF_PROBE_PREFIX = ".ezoo-gif-probe-"
"""Name prefix of the empty file ``--gif`` writes and removes to see that its directory takes a file."""

_LISTED = 5
"""Run ids an unknown one's error names at most."""


def _run_agent(result_file: Path) -> Any:
    """The agent its result file names, a missing agent file said as such. The result file is read
    first as every reader reads one (:func:`~empathy_zoo.experiment.result_reader.read_result`, by
    any name: a copy renamed to watch it still plays): a malformed one, or a JSON file that only
    holds an ``agent`` entry (an evaluation file, a file written by hand), is refused naming it and
    the field, before its agent file is loaded."""
    from empathy_zoo.agent_file import load_run_agent
    from empathy_zoo.experiment.result_reader import read_result

    read_result(result_file, named=False)
    try:
        return load_run_agent(result_file)
    except FileNotFoundError as error:
        raise ValueError(
            f"result file {result_file} names agent file {Path(str(error.filename)).name}, which is missing"
        ) from None


def _agent_file(path: Path) -> Any:
    """The agent of the agent (or result) file at ``path``."""
    from empathy_zoo.agent_file import AGENT_SUFFIX, LIBRARY_AGENT_SUFFIX, RESULT_FIELD, load_agent
    from empathy_zoo.atomic import read_json

    if not path.is_file():
        raise ValueError(f"no agent file {path}")
    if path.suffix == ".json":
        return _run_agent(path)
    for suffix in (AGENT_SUFFIX, LIBRARY_AGENT_SUFFIX):
        result = path.with_name(path.name.removesuffix(suffix) + ".json")
        if path.name.endswith(suffix) and result.is_file():
            entry = read_json(result)
            entry = entry.get(RESULT_FIELD) if isinstance(entry, dict) else None
            if isinstance(entry, dict) and entry.get("file") == path.name:  # (its run's: checked against its SHA-256)
                return _run_agent(result)  # (the file that names it is read as a result file: a malformed one is refused)
    return load_agent(path)


def _unknown_run(run_id: str, results_dir: Path) -> ValueError:
    from empathy_zoo.result_file import RUNS_DIR

    runs = results_dir / RUNS_DIR
    if not runs.is_dir():
        return ValueError(
            f"unknown run id {run_id!r}: there is no {runs} (--dir names the directory train --out or a sweep wrote)"
        )
    ids = sorted(path.stem for path in runs.glob("*.json") if not path.name.startswith("."))
    if not ids:
        return ValueError(f"unknown run id {run_id!r}: {runs} holds no result files")
    close = difflib.get_close_matches(run_id, ids, n=_LISTED, cutoff=0.5)
    shown = close + [i for i in ids if i not in close][: _LISTED - len(close)]
    more = f" and {len(ids) - len(shown)} more" if len(ids) > len(shown) else ""
    return ValueError(
        f"unknown run id {run_id!r}: no result file {runs / (run_id + '.json')}; runs there: {', '.join(shown)}{more}"
    )


def find_agent(target: str, results_dir: str | Path = RUN_DEFAULTS["out"]) -> Any:
    """The trained agent ``target`` names: a run id (its result file in ``results_dir/runs``, the
    agent file checked against the SHA-256 that records), or the path of an agent file or a
    result file. Anything not found, not an agent file, changed since its run wrote it, of a method
    neither registered here nor a ``package.module:NAME`` plug-in (never imported), or a run that
    kept no agent, raises ``ValueError`` saying which."""
    from empathy_zoo.experiment.agent_method import check_agent_method
    from empathy_zoo.result_file import result_path

    path = Path(target)
    try:
        if is_path(target):
            return check_agent_method(_agent_file(path))
        result = result_path(Path(results_dir), target)
        if not os.path.lexists(result):
            raise _unknown_run(target, Path(results_dir))
        return check_agent_method(_run_agent(result))  # (anything but a regular file there is refused, named)
    except ImportError as error:  # (a Stable-Baselines3 agent without SB3 installed)
        raise ValueError(str(error)) from None


def is_path(target: str) -> bool:
    """Whether ``watch``'s ``target`` is read as a path (an agent or result file), not as a run id."""
    from empathy_zoo.agent_file import AGENT_SUFFIX, LIBRARY_AGENT_SUFFIX

    return Path(target).is_file() or target.endswith((AGENT_SUFFIX, LIBRARY_AGENT_SUFFIX, ".json")) or "/" in target


def check_episodes(episodes: int, seed: int) -> None:
    """Refuse (``ValueError``) ``--episodes`` outside ``1 … MAX_EVAL_EPISODES`` (the bound of
    ``evaluate --episodes``) and a ``--seed`` below 0 or so large that the last episode's seed,
    ``seed + episodes - 1``, passes ``MAX_SEED``: checked before anything is played."""
    from empathy_zoo.limits import MAX_EVAL_EPISODES, MAX_SEED, check_at_most

    positive("--episodes", episodes)
    check_at_most("--episodes", episodes, MAX_EVAL_EPISODES, "the bound of evaluate --episodes")
    positive("--seed", seed, allow_zero=True)
    check_at_most(
        "--seed",
        seed,
        MAX_SEED - episodes + 1,
        f"the seed of the last of {episodes:,} episode(s), seed + {episodes - 1:,}, is at most 2⁶³ − 1",
    )


def write_gif(path: str, data: bytes) -> Path:
    """Write the GIF ``data`` to ``path`` atomically; a write that fails (a full disk) raises
    ``OSError`` naming the file, with the failed write's ``errno``."""
    from empathy_zoo.atomic import write_bytes_atomic

    try:
        return write_bytes_atomic(path, data)
    except OSError as error:
        raise OSError(error.errno, f"cannot write the GIF {path} ({error.strerror or error})") from error


def check_gif_path(path: str) -> Path:
    """``path`` if a GIF may be written there, checked before any episode is played and creating
    nothing: a path ending in ``.gif`` is given (``""`` is refused, not read as the current
    directory; any other suffix too, so a result or agent file is never replaced), nothing or a
    regular file is there (never a directory, a link, a device or a pipe: only a regular file is
    ever replaced, :func:`empathy_zoo.names.check_replaceable`), a regular file there is a GIF
    ``watch`` wrote (its :data:`~empathy_zoo.names.WATCH_GIF_MARK` comment:
    :func:`empathy_zoo.names.check_marked_figure`), and its directory takes a file
    (probed with a file of the suite's own name, removed at once; where the directory is missing,
    its nearest existing parent is probed and the directory is made only when the GIF is
    written); else a ``ValueError`` naming it."""
    from empathy_zoo.names import GIF_OPENING, WATCH_GIF_MARK, check_marked_figure, check_replaceable

    if not path:
        raise ValueError("--gif '': an empty path; name the GIF's file (e.g. --gif episode.gif)")
    target = Path(path)
    try:
        target.lstat()
    except FileNotFoundError:
        pass
    except OSError as error:
        raise ValueError(f"--gif {path}: cannot be examined ({error.strerror or error})") from None
    if target.is_dir() and not target.is_symlink():
        raise ValueError(f"--gif {path} is a directory; give the GIF's file name")
    if target.suffix.lower() != ".gif":  # (so no input of the suite's own, .json or .agent.pt, is replaced)
        raise ValueError(f"--gif {path} is no GIF file name: name the file to write, ending in .gif (e.g. --gif episode.gif)")
    try:
        check_replaceable(target)
        check_marked_figure(target, "watch GIF", GIF_OPENING, WATCH_GIF_MARK)  # (never a user's or a leaderboard's GIF)
    except ValueError as error:
        raise ValueError(f"--gif {error}") from None
    parent = next((folder for folder in target.absolute().parents if folder.exists() or folder.is_symlink()), None)
    try:
        if parent is None or not parent.is_dir():
            raise NotADirectoryError(20, "not a directory", str(parent))
        descriptor, probe = tempfile.mkstemp(prefix=GIF_PROBE_PREFIX, dir=parent)
        os.close(descriptor)
        os.unlink(probe)
    except OSError as error:
        raise ValueError(f"--gif {path}: cannot write in {parent} ({error.strerror or error})") from None
    return target


def cmd_watch(args: argparse.Namespace, command: str) -> int:
    """Greedy episodes of a trained agent, each one's metrics printed; a GIF of the first."""
    from empathy_zoo.episode_gif import GIF_STEPS, EpisodeRecorder
    from empathy_zoo.greedy_episode import EpisodeStep, agent_env, agent_policies, format_metrics, play_greedy
    from empathy_zoo.limits import MAX_CYCLES, MAX_WATCH_STEPS, check_at_most
    from empathy_zoo.names import WATCH_GIF_MARK
    from empathy_zoo.policies import check_allowed_imports_named, entry_label
    from empathy_zoo.render import render_text

    check_episodes(args.episodes, args.seed)
    given = args.gif_steps is not None
    args.gif_steps = args.gif_steps if given else GIF_STEPS
    positive("--gif-steps", args.gif_steps)
    check_at_most("--gif-steps", args.gif_steps, MAX_CYCLES, "the bound of max_cycles: no episode is longer")
    if given and args.gif is None:  # (a GIF's length with no GIF: never silently ignored)
        raise ValueError("--gif-steps sets the length of the GIF --gif writes: give --gif PATH too, or leave --gif-steps out")
    if args.gif is not None:
        check_gif_path(args.gif)  # (its directory is made when the GIF is written: a refusal creates none)
    if args.dir is not None and is_path(args.target):  # (an option that cannot act: never silently ignored)
        raise ValueError(f"--dir names where a run id is looked up; {args.target} is a path, read as given: leave --dir out")
    agent = find_agent(args.target, RUN_DEFAULTS["out"] if args.dir is None else args.dir)
    fixed = dict(args.fixed or [])
    named = [*dict(agent.describe().get("fixed") or {}).values(), *fixed.values()]
    check_allowed_imports_named(args.allow_import or (), named, "of the agent file or --fixed")
    allowed = frozenset(args.allow_import or ())
    env = agent_env(agent, fixed, render_mode="rgb_array" if args.gif else None, allowed_imports=allowed)
    d = agent.describe()
    beside = ", ".join(f"{a}={entry_label(p)}" for a, p in agent_policies(agent, fixed, allowed).items())
    run = f" of run {d['run_id']}" if d.get("run_id") else ""
    print(f"{d.get('method')} agent{run} ({d['file']}) on {d['env']} {d['env_kwargs']}, beside {beside}")
    engine = env.unwrapped.engine
    if engine.max_cycles > MAX_WATCH_STEPS:  # (an agent file's header may say up to 10⁹: said before anything plays)
        print(
            f"{PROG}: {d['file']}: max_cycles {engine.max_cycles:,} is more than watch plays of an episode "
            f"({MAX_WATCH_STEPS:,}, docs/limits.md): each episode is cut short there, as the leaderboard's greedy "
            "episodes are, and its metrics are those of the steps played"
        )
    recorder = None
    if args.gif:
        title = str(d.get("label") or d.get("method"))  # (a run's label names its settings: β, the penalty)
        recorder = EpisodeRecorder(title, f"{d['env']} · seed {args.seed}", args.gif_steps)
    for episode in range(args.episodes):
        seed = args.seed + episode

        def on_step(step: EpisodeStep, first: bool = episode == 0) -> None:
            if args.render:
                print(render_text(engine))
            if recorder is not None and first:
                recorder(step)

        outcome = play_greedy(agent, env, seed, max_steps=MAX_WATCH_STEPS, on_step=on_step)
        cut = "" if outcome.ended else f" (its first {outcome.steps:,} steps)"
        print(f"episode {episode} (seed {seed}){cut}: {format_metrics(outcome.metrics)}", flush=True)
    if recorder is not None:
        data = recorder.gif(WATCH_GIF_MARK)  # (the mark check_gif_path reads before replacing it)
        path = write_gif(args.gif, data)
        steps = recorder.frames - 1
        shown = f"the whole of episode 0, {steps} steps" if recorder.whole_episode else f"episode 0's first {steps} steps"
        print(f"{PROG}: wrote {path} ({recorder.frames} frames: {shown}; {len(data) / 1024:.0f} KB)")
    return 0


def add_watch(sub: Any) -> None:
    """The ``watch`` subcommand."""
    from empathy_zoo.episode_gif import GIF_STEPS

    watch = sub.add_parser("watch", help="greedy episodes of a trained agent; prints episode metrics, optionally a GIF")
    watch.add_argument("target", metavar="RUN_ID_OR_AGENT_FILE", help="a run id (in --dir), or an agent or result file")
    watch.add_argument(
        "--dir",
        default=None,
        metavar="RESULTS_DIR",
        help=f"where a run id's result file is: RESULTS_DIR/runs/<run id>.json (default: {RUN_DEFAULTS['out']}, as train --out)",
    )
    watch.add_argument("--episodes", type=int, default=1, help="episodes (default: 1)")
    watch.add_argument("--seed", type=int, default=0, help="seed of the first episode (default: 0)")
    watch.add_argument("--render", choices=["ansi"], default=None, help="print the grid every step")
    watch.add_argument(
        "--fixed",
        type=agent_policy,
        action=AgentPolicies,
        metavar="AGENT=POLICY",
        help="replace a fixed agent's policy, a name or package.module:ClassName (repeatable, once per agent)",
    )
    watch.add_argument("--gif", metavar="FILE", default=None, help="write a GIF of the first episode")
    watch.add_argument(
        "--gif-steps", type=int, default=None, metavar="N", help=f"steps the GIF shows at most (default: {GIF_STEPS})"
    )
    add_allow_import(watch)
    watch.set_defaults(handler=cmd_watch)
