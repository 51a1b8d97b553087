"""The runner: trains K compatible runs in lockstep on one batched engine.

``train_runs(specs, out_dir)`` groups the runs into ensembles (same env, method family and
shared settings), skips the runs whose result file exists, resumes an ensemble from its
checkpoint, and writes one result file per run, atomically, when it finishes. A run's numbers
depend only on its own spec: its seed drives its networks, exploration, replay sampling and
environments, so it gives the same result alone or beside other runs.
"""

from __future__ import annotations

import multiprocessing
import os
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import torch

from agents.base import StepBatch
from empathy_zoo.atomic import check_output_dir, remove_stale_temp_files
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.provenance import git_commit
from empathy_zoo.randomness import derive_key
from empathy_zoo.training.checkpoint import from_safe, load_checkpoint, save_checkpoint, to_safe
from empathy_zoo.training.evaluation import evaluate_greedy
from empathy_zoo.training.progress import QueueDrain, QueueReporter, Report, SweepProgress
from empathy_zoo.training.results import (
    RUNS_DIR, build_result, check_one_experiment_per_label, empty_columns, read_result, result_path, write_result,
)
from empathy_zoo.training.resume import (
    CHECKPOINT_DIR, checkpoint_path, plan_ensembles, remove_checkpoint, write_manifest,
)
from empathy_zoo.training.spec import RunSpec
from empathy_zoo.vector import VectorEnv, VectorStep

__all__ = ["RunnerOptions", "train_runs", "train_ensemble", "checkpoint_path", "learner_batch", "CHECKPOINT_DIR"]

STREAM_ENV = 20


@dataclass(frozen=True)
class RunnerOptions:
    """How runs are executed (not what they compute: results do not depend on these)."""

    device: str = "cpu"
    """Torch device for the networks and replay (``cpu``, ``cuda``, ``cuda:1``)."""
    max_parallel_runs: int = 32
    """Most runs trained together in one lockstep ensemble (bounds memory: ~45 MB per run at the paper's replay size)."""
    checkpoint_interval: int = 50_000
    """Env steps between checkpoints of an unfinished ensemble (0 = never)."""
    progress: bool = True
    """Show progress bars (drawn by this process only: one per running ensemble, and one for the
    sweep's env steps when it has several ensembles; see :mod:`empathy_zoo.training.progress`)."""
    threads: int | None = None
    """Torch CPU threads per process (None = torch's default; worker processes default to 1)."""
    workers: int = 1
    """Processes training ensembles side by side (the sweep's ensembles are spread over them)."""
    backend: str = "local"
    """Where ensembles run: ``local`` (this machine, ``workers`` processes) or ``ray``."""
    address: str | None = None
    """Ray cluster address for ``backend="ray"`` (``None`` starts a local Ray instance)."""


def train_runs(
    specs: Sequence[RunSpec], out_dir: str | Path, options: RunnerOptions = RunnerOptions(),
    on_result: Callable[[dict[str, Any]], None] | None = None, on_note: Callable[[str], None] | None = None,
) -> list[Path]:
    """Train every run not finished yet; returns the result files of all ``specs``.

    ``out_dir`` is checked first (created, written to): one that cannot hold the results raises
    ``ValueError`` before any training starts. Checkpointed ensembles resume as they were
    (:mod:`empathy_zoo.training.resume`); what is resumed, restarted or removed, and the temporary
    files of writes killed mid-way that are removed, is said through ``on_note`` (default: printed
    to stderr). ``on_result`` gets every result of ``specs`` written here."""
    note = on_note or _print_note
    out_dir = Path(out_dir)
    ids = [s.run_id for s in specs]
    duplicates = sorted({i for i in ids if ids.count(i) > 1})
    if duplicates:
        raise ValueError(f"the same run is listed twice: {duplicates}")
    if options.workers < 1:
        raise ValueError(f"workers must be positive, got {options.workers}")
    if options.max_parallel_runs < 1:
        raise ValueError(f"max_parallel_runs must be positive, got {options.max_parallel_runs}")
    if options.backend not in ("local", "ray"):
        raise ValueError(f"unknown backend {options.backend!r}; choose 'local' or 'ray'")
    if options.backend == "ray":
        from empathy_zoo.training.ray_backend import check_ray_address, import_ray, train_with_ray

        if not import_ray().is_initialized():  # (missing Ray, or no cluster there, is said before anything is written)
            check_ray_address(options.address)
    check_one_experiment_per_label(
        [*_finished_runs(out_dir), *((s.variant or s.env, s.display_label(), s.run_id, f"run {s.run_id}") for s in specs)]
    )
    local_checkpoints = options.backend == "local" and options.checkpoint_interval > 0
    check_output_dir(out_dir, (RUNS_DIR, *((CHECKPOINT_DIR,) if local_checkpoints else ())))
    stale = [path for sub in ("", RUNS_DIR, CHECKPOINT_DIR) for path in remove_stale_temp_files(out_dir / sub)]
    if stale:
        note(f"removed {len(stale)} temporary file(s) of writes killed mid-way (e.g. {stale[0]})")
    todo = [s for s in specs if not result_path(out_dir, s.run_id).exists()]
    chunks = plan_ensembles(todo, out_dir, options.max_parallel_runs, note)
    wanted = {s.run_id for s in todo}
    if on_result is not None:  # (a resumed ensemble may finish runs not asked for here)
        given, on_result = on_result, lambda result: given(result) if result["run_id"] in wanted else None
    progress = SweepProgress([(len(chunk), chunk[0].steps) for chunk in chunks], enabled=options.progress)
    try:
        if options.backend == "ray":  # (the tasks report nothing: the sweep bar counts finished runs' steps)
            train_with_ray(chunks, out_dir, options, _counting(on_result, progress))
        elif options.workers == 1 or len(chunks) <= 1:
            for index, chunk in enumerate(chunks):
                for result in train_ensemble(chunk, out_dir, options, report=progress.update, ensemble=index):
                    if on_result is not None:
                        on_result(result)
        else:
            _train_in_processes(chunks, out_dir, options, on_result, progress)
    finally:
        progress.close()
    return [result_path(out_dir, s.run_id) for s in specs]


def _counting(
    on_result: Callable[[dict[str, Any]], None] | None, progress: SweepProgress
) -> Callable[[dict[str, Any]], None]:
    def counted(result: dict[str, Any]) -> None:
        progress.sweep.update(result["steps"])
        if on_result is not None:
            on_result(result)

    return counted


def _print_note(text: str) -> None:
    print(f"empathy-zoo: {text}", file=sys.stderr, flush=True)


def _finished_runs(out_dir: Path) -> list[tuple[str, str, str, str]]:
    """``(table env, label, run id, path)`` of every result file in ``out_dir`` (each one checked)."""
    runs = []
    for path in sorted((out_dir / RUNS_DIR).glob("*.json")) if (out_dir / RUNS_DIR).is_dir() else []:
        if not path.name.startswith("."):
            result = read_result(path)
            runs.append((result.get("variant") or result["env"], result["method_label"], result["run_id"], str(path)))
    return runs


def _exit_with_parent(parent: int) -> None:
    """In a worker: end this process if the sweep's process goes away (killed, not interrupted),
    so no orphan keeps training and writing checkpoints beside a restarted sweep."""

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(2.0)
        os._exit(1)

    threading.Thread(target=watch, daemon=True, name="exit-with-parent").start()


def _train_in_processes(
    chunks: list[list[RunSpec]], out_dir: Path, options: RunnerOptions,
    on_result: Callable[[dict[str, Any]], None] | None, progress: SweepProgress,
) -> None:
    """Spread ensembles over ``options.workers`` processes (one torch thread each by default);
    their progress comes back through a queue and is drawn here."""
    context = multiprocessing.get_context("spawn")
    workers = min(options.workers, len(chunks))
    manager = context.Manager() if options.progress else None
    drain = QueueDrain(manager.Queue(), progress) if manager is not None else None
    reporter = QueueReporter(drain.source) if drain is not None else None
    try:
        with ProcessPoolExecutor(workers, mp_context=context, initializer=_exit_with_parent,
                                 initargs=(os.getpid(),)) as pool:
            futures = [
                pool.submit(train_ensemble, chunk, out_dir, replace(options, workers=1, threads=options.threads or 1),
                            True, reporter, i)
                for i, chunk in enumerate(chunks)
            ]
            try:
                for future in as_completed(futures):
                    for result in future.result():
                        if on_result is not None:
                            on_result(result)
            except BaseException:
                for future in futures:
                    future.cancel()
                raise
    finally:
        if drain is not None:
            drain.stop()
            manager.shutdown()


class _EpisodeLog:
    """Training episodes of one run, as columns."""

    def __init__(self) -> None:
        self.columns = empty_columns()

    def add(self, end_step: int, metrics: dict[str, np.ndarray], row: int) -> None:
        self.columns["episode_end_step"].append(int(end_step))
        for name in METRIC_NAMES:
            value = metrics[name][row]
            self.columns[name].append(int(value) if name in ("survival", "harms", "batteries", "other_batteries") else round(float(value), 6))

    def recent(self, name: str, count: int = 100) -> float:
        values = self.columns[name][-count:]
        return float(np.mean(values)) if values else float("nan")


def train_ensemble(
    specs: Sequence[RunSpec], out_dir: str | Path, options: RunnerOptions = RunnerOptions(), write_results: bool = True,
    report: Callable[[Report], None] | None = None, ensemble: int = 0,
) -> list[dict[str, Any]]:
    """Train the compatible runs ``specs`` in lockstep and return their results; write them
    (atomically) unless ``write_results`` is False (a remote worker hands them to the driver).

    With ``options.progress``, progress goes to ``report`` (as ensemble number ``ensemble`` of a
    sweep), or, without one, to bars drawn here."""
    git_commit()  # read (and kept for this process) now: the code that trains is the code checked out now
    own = SweepProgress([(len(specs), specs[0].steps)]) if options.progress and report is None else None
    try:
        return _train_ensemble(specs, Path(out_dir), options, write_results,
                               (own.update if own else report) if options.progress else None, ensemble)
    finally:
        if own is not None:
            own.close()


def _train_ensemble(
    specs: Sequence[RunSpec], out_dir: Path, options: RunnerOptions, write_results: bool,
    report: Callable[[Report], None] | None, ensemble: int,
) -> list[dict[str, Any]]:
    if len({s.ensemble_key() for s in specs}) != 1:
        raise ValueError("these runs cannot share an ensemble (different env, method family or shared settings)")
    if options.threads:
        torch.set_num_threads(options.threads)
    first = specs[0]
    k = len(specs)
    method = first.method_object()
    fixed, env_kwargs = first.fixed_policies(), dict(first.env_kwargs)
    venv = VectorEnv(first.env, k, fixed=fixed, **env_kwargs)
    learner_agent = venv.learners[0]
    robot = venv.agents.index(learner_agent)
    if len(venv.learners) != 1:
        raise ValueError(f"training needs exactly one learning agent; {first.env} has {venv.learners} (fix the others)")
    other = 1 - robot if len(venv.agents) == 2 else None
    seeds = [s.seed for s in specs]
    learner = method.learner([s.method_settings() for s in specs], seeds, venv.obs_size, 5, options.device)
    logs = [_EpisodeLog() for _ in specs]
    evaluations: list[list[dict[str, Any]]] = [[] for _ in specs]
    obs = venv.reset(seed=[derive_key(s, STREAM_ENV) for s in seeds])[:, 0]
    step, elapsed = 0, 0.0
    ckpt = checkpoint_path(out_dir, specs)
    if ckpt.exists():
        saved = load_checkpoint(ckpt)
        if saved["run_ids"] != [s.run_id for s in specs]:
            raise ValueError(f"checkpoint {ckpt} belongs to other runs; move it away")
        learner.load_state_dict(saved["learner"])
        venv.load_state(from_safe(saved["vector"]))
        obs = from_safe(saved["obs"])
        for log, columns in zip(logs, saved["logs"]):
            log.columns = columns
        evaluations = saved["evaluations"]
        step, elapsed = int(saved["step"]), float(saved["elapsed"])
    if hasattr(learner, "replay") and hasattr(learner.replay, "check_range"):  # fail now, not mid-run
        learner.replay.check_range(venv.engine.obs_low, venv.engine.obs_high)
    memory = {"replay_per_run": learner.replay.nbytes_per_run() if hasattr(learner, "replay") else 0,
              "learner_per_run": learner.memory_bytes_per_run()}
    total = first.steps
    label = f"{first.env} ×{k} runs"
    if report is not None:
        mb = 2**20
        report(Report(ensemble, step, total, k, label, line=(
            f"{first.env}: {k} run(s) in lockstep on {options.device}; memory per run "
            f"{memory['learner_per_run'] / mb:.1f} MB (replay {memory['replay_per_run'] / mb:.1f} MB), "
            f"total {k * memory['learner_per_run'] / mb:.0f} MB"
        )))
    started = time.perf_counter() - elapsed
    first_step = step
    rows = np.arange(k)
    while step < total:
        actions = learner.act(obs[:, None, :])
        result = venv.step(actions.reshape(k, 1))
        batch = learner_batch(obs, actions, result, robot, other)
        learner.observe(batch)
        step += 1
        finished = result.finished
        for j, env_id in enumerate(finished["env"]):
            logs[env_id].add(step, finished, j)
        obs = result.observations[:, 0]
        if step % first.eval_interval == 0 or step == total:
            per_run = evaluate_greedy(learner, first.env, seeds, first.eval_episodes, fixed, env_kwargs)
            for r in rows:
                evaluations[r].append({"step": step, **per_run[r]})
        if options.checkpoint_interval and step % options.checkpoint_interval == 0 and step < total:
            write_manifest(ckpt, specs)
            save_checkpoint(ckpt, {
                "run_ids": [s.run_id for s in specs], "step": step, "elapsed": time.perf_counter() - started,
                "learner": learner.state_dict(), "vector": to_safe(venv.state()),
                "obs": to_safe(obs),
                "logs": [log.columns for log in logs], "evaluations": evaluations,
            })
        if report is not None and (step % 500 == 0 or step == total):
            rate = (step - first_step) * k / max(time.perf_counter() - started - elapsed, 1e-9)
            report(Report(ensemble, step, total, k, label, stats=_live(logs, learner, rate), done=step == total))
    wall = time.perf_counter() - started
    results = []
    for r, spec in enumerate(specs):
        document = build_result(spec, logs[r].columns, evaluations[r], wall, memory)
        if write_results and not result_path(out_dir, spec.run_id).exists():  # (a resumed ensemble's finished runs)
            write_result(out_dir, document)
        results.append(document)
    remove_checkpoint(ckpt)
    return results


def learner_batch(obs: np.ndarray, actions: np.ndarray, result: VectorStep, robot: int, other: int | None) -> StepBatch:
    """What the learner is told of one step of every run (one env per run): the environment's
    facts, unshaped. The other-term may bootstrap only while the closest other agent is present
    and not terminal (SPEC §6): a harmed cat has left, and the human's episode ends for good
    when the last battery is taken; a time-limit truncation still bootstraps."""
    k = actions.shape[0]
    battery = result.battery_return
    return StepBatch(
        obs=obs[:, None, :],
        actions=actions,
        rewards=result.rewards[:, robot, None],
        terminated=result.terminated[:, robot, None],
        next_obs=result.final_observations[:, 0, None, :],
        swapped_next_obs=result.swapped[:, 0, None, :],
        other_present=(result.swapped_valid[:, 0] & ~result.swapped_other_terminated[:, 0])[:, None],
        harmed_other=(result.harmed_by == robot).sum(axis=1)[:, None],
        battery_return=battery[:, robot, None],
        other_battery_return=(battery[:, other] if other is not None else np.zeros(k))[:, None],
        truncated=result.truncated[:, robot, None],
    )


def _live(logs: list[_EpisodeLog], learner: Any, steps_per_second: float) -> dict[str, str]:
    episodes = sum(len(log.columns["survival"]) for log in logs)
    stats = {
        "episodes": str(episodes),
        "survival": f"{np.nanmean([log.recent('survival') for log in logs]):.0f}",
        "harms": f"{np.nanmean([log.recent('harms') for log in logs]):.2f}",
        "equality": f"{np.nanmean([log.recent('equality') for log in logs]):.2f}",
    }
    stats |= {key: f"{value:.3g}" for key, value in learner.live_stats().items()}
    stats["steps/s"] = f"{steps_per_second:.0f}"
    return stats
