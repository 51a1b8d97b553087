"""The ensemble trainer: K compatible runs in lockstep on one batched engine.

:func:`train_ensemble` trains the runs of one ensemble (same env, learner and shared settings)
step by step: the learner acts for every run at once, the vector env steps every run's
environment, and :func:`learner_batch` hands the learner what happened, unshaped (with the
agents' cells and distances at the end of the step, :class:`AgentCells`, and whatever the step
watcher a reward transform names fills in, :func:`agents.rewards.step_watcher`). It resumes from
the ensemble's checkpoint, evaluates greedily every ``eval_interval`` steps, and writes one
result file per run (atomically) at the end, with the run's trained agent beside it
(:mod:`empathy_zoo.agent_file`) when its learner keeps one. A run's numbers depend only
on its own spec.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import torch

from agents.base import StepBatch
from agents.rewards import TrainRewards, step_watcher
from agents.transform_state import StateBounds
from empathy_zoo.agent_file import agent_bytes
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.grid import torus_distance
from empathy_zoo.metrics import INTEGER_METRICS, METRIC_NAMES
from empathy_zoo.provenance import git_commit
from empathy_zoo.randomness import STREAMS, derive_key
from empathy_zoo.result_file import PRICE_COLUMN, result_path
from empathy_zoo.training.checkpoint import (
    DIVERGED_FIX,
    CheckpointError,
    DivergedError,
    check_checkpoint_keys,
    check_writable,
    corrupted,
    diverged_runs,
    from_safe,
    load_checkpoint,
    save_checkpoint,
    to_safe,
)
from empathy_zoo.training.evaluation import evaluate_greedy
from empathy_zoo.training.fingerprint import kernel_argument, update_kernel_of
from empathy_zoo.training.options import RunnerOptions
from empathy_zoo.training.progress import Report, SweepProgress
from empathy_zoo.training.results import ResultWriteError, build_result, empty_columns, stored, write_result
from empathy_zoo.training.resume import checkpoint_path, remove_checkpoint, write_manifest
from empathy_zoo.training.tracking import LOG_INTERVAL, EnsembleTracker, open_tracker
from empathy_zoo.vector import VectorEnv, VectorStep

__all__ = ["train_ensemble", "learner_batch", "AgentCells", "STREAM_ENV"]

STREAM_ENV = STREAMS["train_env"]
CHECKPOINT_KEYS: dict[str, type | tuple[type, ...]] = {
    "run_ids": list,
    "step": int,
    "elapsed": (int, float),
    "learner": dict,
    "vector": dict,
    "logs": list,
    "evaluations": list,
}
"""What an ensemble's checkpoint holds (and ``obs``, ``rewards``), with the types they have."""


class _EpisodeLog:
    """Training episodes of one run, as columns (with the price of its cost after each episode,
    :data:`~empathy_zoo.result_file.PRICE_COLUMN`, where its reward transform prices costs when sampled)."""

    def __init__(self, priced: bool = False) -> None:
        self.columns = empty_columns(priced)

    def add(self, end_step: int, metrics: dict[str, np.ndarray], row: int, price: float | None = None) -> None:
        self.columns["episode_end_step"].append(int(end_step))
        for name in METRIC_NAMES:
            value = metrics[name][row]
            self.columns[name].append(int(value) if name in INTEGER_METRICS else round(float(value), 6))
        if price is not None:
            self.columns[PRICE_COLUMN].append(round(float(price), 6))

    def recent(self, name: str, count: int = 100) -> float:
        values = self.columns[name][-count:]
        return float(np.mean(values)) if values else float("nan")


def train_ensemble(
    specs: Sequence[RunSpec],
    out_dir: str | Path,
    options: RunnerOptions = RunnerOptions(),
    write_results: bool = True,
    report: Callable[[Report], None] | None = None,
    ensemble: int = 0,
    on_evaluation: Callable[[int, list[dict[str, list]]], None] | None = None,
) -> list[dict[str, Any]]:
    """Train the compatible runs ``specs`` in lockstep and return their results; write them
    (atomically) unless ``write_results`` is False (a remote worker hands them to the driver).

    With ``options.progress``, progress goes to ``report`` (as ensemble number ``ensemble`` of a
    sweep), or, without one, to bars drawn here. With ``options.log``, every run logs its scalars
    under ``out_dir/logs`` as it trains (:mod:`empathy_zoo.training.tracking`). ``on_evaluation``
    is told each greedy evaluation, ``(step, per_run)`` as :func:`evaluate_greedy` gives it, after
    it is recorded; it only reads them (a tuning study's pruner: :mod:`empathy_zoo.training.tuning`),
    and an exception it raises stops the ensemble there."""
    git_commit()  # read (and kept for this process) now: the code that trains is the code checked out now
    tracker = open_tracker(options.log, out_dir, specs)
    own = None
    if options.progress and report is None:
        own = SweepProgress([(len(specs), specs[0].steps)], style=options.progress_style)
    try:
        return _train_ensemble(
            specs,
            Path(out_dir),
            options,
            write_results,
            (own.update if own else report) if options.progress else None,
            ensemble,
            tracker,
            on_evaluation,
        )
    finally:
        if tracker is not None:
            tracker.close()
        if own is not None:
            own.close()


def _train_ensemble(
    specs: Sequence[RunSpec],
    out_dir: Path,
    options: RunnerOptions,
    write_results: bool,
    report: Callable[[Report], None] | None,
    ensemble: int,
    tracker: EnsembleTracker | None = None,
    on_evaluation: Callable[[int, list[dict[str, list]]], None] | None = None,
) -> list[dict[str, Any]]:
    if len({s.ensemble_key() for s in specs}) != 1:
        raise ValueError("these runs cannot share an ensemble (different env, method family or shared settings)")
    if options.threads:
        torch.set_num_threads(options.threads)
    first = specs[0]
    k = len(specs)
    method = first.method_object()
    fixed, env_kwargs = first.fixed_policies(), dict(first.env_kwargs)
    venv = VectorEnv(first.env, k, fixed=fixed, in_view_only=method.in_view_only, **env_kwargs)
    if options.checkpoint_interval > 0:
        venv.check_checkpointable()  # (a fixed policy whose state a checkpoint would lose: refused before training)
    if len(venv.learners) != 1:
        raise ValueError(f"training needs exactly one learning agent; {first.env} has {venv.learners} (fix the others)")
    seeds = [s.seed for s in specs]
    learner = method.learner(
        [s.method_settings() for s in specs],
        seeds,
        venv.obs_size,
        venv.num_actions,
        options.device,
        num_others=len(venv.others[0]),
        **kernel_argument(method.learner, options.update_kernel),
    )
    train_rewards = TrainRewards([s.reward_transform() for s in specs], seeds=seeds)
    priced = train_rewards.priced_runs
    if priced.any():  # (a transform that prices its costs when they are sampled: the learner keeps them)
        price_costs = _optional(learner, "price_costs")
        if price_costs is None:
            raise ValueError(
                f"method {specs[int(np.flatnonzero(priced)[0])].method!r}: its reward transform prices costs when they "
                "are sampled, and its learner "
                f"{type(learner).__name__} cannot (it has no price_costs)"
            )
        price_costs(priced)
    cells = AgentCells(venv)
    watcher = step_watcher(venv, train_rewards.distinct)  # None unless a transform needs one
    logs = [_EpisodeLog(bool(p)) for p in priced]
    evaluations: list[list[dict[str, Any]]] = [[] for _ in specs]
    obs = venv.reset(seed=[derive_key(s, STREAM_ENV) for s in seeds])[:, 0]
    if options.checkpoint_interval > 0:
        venv.check_checkpointable()  # (now reset: each fixed policy's state() is taken once, as a checkpoint takes it)
    step, elapsed = 0, 0.0
    check_range = _optional(learner, "check_observation_range")
    if check_range is not None:  # fail now, not mid-run; a checkpoint's replay is checked against it
        check_range(venv.engine.obs_low, venv.engine.obs_high)
    ckpt = checkpoint_path(out_dir, specs)
    if ckpt.exists():
        obs, evaluations, step, elapsed = _restore(ckpt, specs, learner, train_rewards, venv, logs)
    replay_bytes = _optional(learner, "replay_bytes_per_run")
    replay_of = _optional(learner, "replay_bytes_of")
    bytes_of = _optional(learner, "memory_bytes_of")
    largest = learner.memory_bytes_per_run()
    memory = [
        {
            "replay_per_run": replay_of(r) if replay_of is not None else 0 if replay_bytes is None else replay_bytes(),
            "learner_per_run": largest if bytes_of is None else bytes_of(r),
        }
        for r in range(k)
    ]
    total = first.steps
    label = f"{first.env} ×{k} runs"
    if report is not None:
        mb = 2**20
        report(
            Report(
                ensemble,
                step,
                total,
                k,
                label,
                line=(
                    f"{first.env}: {k} run(s) in lockstep on {options.device}; memory per run up to "
                    f"{largest / mb:.1f} MB (replay {memory[0]['replay_per_run'] / mb:.1f} MB), "
                    f"total {sum(m['learner_per_run'] for m in memory) / mb:.0f} MB"
                ),
            )
        )
    started = time.perf_counter() - elapsed
    first_step = step
    if tracker is not None:
        tracker.start(step, train_rewards.transforms)
    rows = np.arange(k)
    while step < total:
        actions = learner.act(obs[:, None, :])
        result = venv.step(actions.reshape(k, 1))
        batch = cells.fill(learner_batch(obs, actions, result))
        if watcher is not None:
            batch = watcher.fill(batch)
        trained = train_rewards(batch)
        learner.observe(trained)
        step += 1
        finished = result.finished
        prices = train_rewards.prices() if len(finished["env"]) else None  # (each run's price after the step)
        for j, env_id in enumerate(finished["env"]):
            logs[env_id].add(step, finished, j, prices[env_id] if prices is not None and priced[env_id] else None)
        if tracker is not None:
            tracker.after_step(step, finished, batch.rewards, trained.priced_rewards)
        obs = result.observations[:, 0]
        if step % first.eval_interval == 0 or step == total:
            per_run = evaluate_greedy(learner, first.env, seeds, first.eval_episodes, fixed, env_kwargs)
            for row in rows:
                evaluations[row].append({"step": step, **per_run[row]})
            if tracker is not None:
                tracker.evaluation(step, per_run)
            if on_evaluation is not None:
                on_evaluation(step, per_run)
        if options.checkpoint_interval and step % options.checkpoint_interval == 0 and step < total:
            if tracker is not None:
                tracker.flush()  # (the logs up to a checkpoint are on disk before it: a resumed run logs on from it)
            _checkpoint(ckpt, specs, step, time.perf_counter() - started, learner, venv, obs, logs, evaluations, train_rewards)
        if report is not None and (step % 500 == 0 or step == total):
            rate = (step - first_step) * k / max(time.perf_counter() - started - elapsed, 1e-9)
            report(Report(ensemble, step, total, k, label, stats=_live(logs, learner, rate), done=step == total))
        if tracker is not None and (step % LOG_INTERVAL == 0 or step == total):
            tracker.interval(step, learner, (step - first_step) / max(time.perf_counter() - started - elapsed, 1e-9))
    wall = time.perf_counter() - started
    _refuse_diverged(ckpt, specs, step, learner)  # (before any result or agent file of them is written)
    results = []
    for r, spec in enumerate(specs):
        agent = agent_bytes(learner, r, {"run_id": spec.run_id, **spec.config()})  # (None: the method keeps none)
        document = build_result(spec, logs[r].columns, evaluations[r], wall, memory[r], agent, update_kernel_of(learner))
        if write_results and not result_path(out_dir, spec.run_id).exists():  # (a resumed ensemble's finished runs)
            try:
                write_result(out_dir, document)
            except ResultWriteError as error:  # (a full disk, a directory removed): keep the training, say where
                kept = _keep_finished(
                    ckpt, lambda: _checkpoint(ckpt, specs, step, wall, learner, venv, obs, logs, evaluations, train_rewards)
                )
                raise ResultWriteError(error.errno, f"{error.strerror}; {kept}") from error
        results.append(stored(document) if write_results else document)
        if tracker is not None:
            tracker.finish(r, stored(document), result_path(out_dir, spec.run_id))
    remove_checkpoint(ckpt)  # (only once every result is written)
    return results


def _checkpoint(
    ckpt: Path,
    specs: Sequence[RunSpec],
    step: int,
    elapsed: float,
    learner: Any,
    venv: VectorEnv,
    obs: np.ndarray,
    logs: list[_EpisodeLog],
    evaluations: list[list[dict[str, Any]]],
    train_rewards: TrainRewards,
) -> None:
    """Write the ensemble's checkpoint ``ckpt`` at ``step`` (and the list of its runs beside it);
    where a run diverged, write nothing (:func:`_refuse_diverged`; the checkpoint of an earlier step is kept)."""
    _refuse_diverged(ckpt, specs, step, learner)
    payload = {
        "run_ids": [s.run_id for s in specs],
        "step": step,
        "elapsed": elapsed,
        "learner": learner.state_dict(),
        "vector": to_safe(venv.state()),
        "obs": to_safe(obs),
        "logs": [log.columns for log in logs],
        "evaluations": evaluations,
        "rewards": to_safe(train_rewards.state()),
    }
    check_writable(ckpt, payload)  # (before the list of its runs: nothing is written for a checkpoint refused)
    write_manifest(ckpt, specs)
    save_checkpoint(ckpt, payload)


def _refuse_diverged(ckpt: Path, specs: Sequence[RunSpec], step: int, learner: Any) -> None:
    """Raise :class:`~empathy_zoo.training.checkpoint.DivergedError` naming the runs of ``specs``
    whose networks (``learner.agent_state(run)``'s heads, where the learner keeps an agent that
    way) hold a weight that is no finite number at ``step``: no result, agent file or checkpoint of
    their ensemble is written; an earlier checkpoint ``ckpt`` is kept (a rerun resumes from it, and
    meets the same refusal). Only reads the weights. A learner of another kind is checked where
    its checkpoint is written (:func:`~empathy_zoo.training.checkpoint.save_checkpoint`)."""
    agent_state = _optional(learner, "agent_state")
    if agent_state is None:
        return
    diverged = [
        spec.run_id
        for r, spec in enumerate(specs)
        if not all(
            bool(torch.isfinite(torch.as_tensor(layer)).all()) for layers in agent_state(r)["heads"].values() for layer in layers
        )
    ]
    if not diverged:
        return
    one = len(diverged) == 1
    networks = "its network's" if one else "their networks'"
    others = len(specs) - len(diverged)
    stop = f" (its {others} other run(s) stop with {'it' if one else 'them'})" if others else ""
    kept = f"its checkpoint {ckpt} of an earlier step is kept" if ckpt.exists() else "no checkpoint of it was written"
    raise DivergedError(
        f"{diverged_runs(diverged)} diverged by step {step:,}: {networks} weights are no longer finite numbers; "
        f"{DIVERGED_FIX}; no result of {'its' if one else 'their'} ensemble was written{stop} and {kept}"
    )


def _keep_finished(ckpt: Path, save: Callable[[], None]) -> str:
    """Keep a finished ensemble whose results could not be written: ``save()`` its checkpoint at its
    last step (the same command then writes the results without training again); say what was
    kept, and where."""
    try:
        save()
    except (OSError, RuntimeError) as error:  # (torch reports a failed write as RuntimeError)
        if ckpt.exists():
            return (
                f"its finished training could not be kept either ({error}); its last checkpoint {ckpt} is kept: "
                "free space and run the same command again to resume from there"
            )
        return f"its finished training could not be kept either ({error}): the same command retrains its runs"
    return (
        f"the finished training of its ensemble is kept in checkpoint {ckpt}: free space and run the same command "
        "again to write the results without training again"
    )


def _restore(
    ckpt: Path, specs: Sequence[RunSpec], learner: Any, train_rewards: TrainRewards, venv: VectorEnv, logs: list[_EpisodeLog]
) -> tuple[np.ndarray, list[list[dict[str, Any]]], int, float]:
    """Continue from checkpoint ``ckpt``: restore the learner, reward transforms, environments and
    logs; return the observations, evaluations, step and elapsed seconds. The loaded checkpoint
    is dropped on return (in the paper profile it is ≈ 1 GB: the replay memories)."""
    saved = check_checkpoint_keys(ckpt, load_checkpoint(ckpt), {**CHECKPOINT_KEYS, "obs": object})
    if saved["run_ids"] != [s.run_id for s in specs]:
        raise ValueError(f"checkpoint {ckpt} belongs to other runs; move it away")
    if not len(saved["logs"]) == len(saved["evaluations"]) == len(specs):
        counts = len(saved["logs"]), len(saved["evaluations"])
        raise corrupted(ckpt, f"it holds the logs of {counts[0]} runs and the evaluations of {counts[1]}, not {len(specs)}")
    learner_state = saved["learner"]
    kernel = update_kernel_of(learner)
    if kernel is not None and isinstance(learner_state, dict) and ("update_kernel" in learner_state or "online" in learner_state):
        saved_kernel = learner_state.get("update_kernel", "torch")  # (checkpoints older than the field: torch's)
        if saved_kernel != kernel:
            raise CheckpointError(
                f"checkpoint {ckpt} was made with the {saved_kernel} update kernel and these runs would go on with "
                f"{kernel}, whose sums run in another order: resume with --update-kernel {saved_kernel} "
                "(update_kernel in RunnerOptions), or move the checkpoint away to restart"
            )
    try:
        vector = from_safe(saved["vector"])
        forged_key = venv.saved_key_problem(vector)  # (venv is reset with the runs' seeds: each key rederived)
        if forged_key is not None:
            raise corrupted(ckpt, f"vector.{forged_key}")
        learner.load_state_dict(learner_state)
        engine = venv.engine

        def bounds(runs: int) -> StateBounds:
            """What the checkpoint's runs allow a reward transform's state to hold."""
            return StateBounds(
                runs=runs,
                envs_per_run=1,
                step=int(saved["step"]),
                obs_size=engine.obs_size,
                obs_low=float(engine.obs_low),
                obs_high=float(engine.obs_high),
                reward_bound=float(engine.step_reward_bound),
                others=engine.num_agents - 1,
            )

        train_rewards.load_state(from_safe(saved.get("rewards", [None] * len(train_rewards.states))), bounds)
        venv.load_state(vector)
        observations = from_safe(saved["obs"])
    except CheckpointError:
        raise
    except ValueError as error:  # (says what is wrong: an earlier version's layout, another shape)
        raise CheckpointError(f"checkpoint {ckpt} cannot be resumed: {error}") from error
    except (KeyError, IndexError, TypeError, AttributeError, RuntimeError) as error:  # a state that is not the learner's
        raise corrupted(ckpt, error) from error
    for log, columns in zip(logs, saved["logs"], strict=True):
        log.columns = columns
    return observations, saved["evaluations"], int(saved["step"]), float(saved["elapsed"])


def learner_batch(obs: np.ndarray, actions: np.ndarray, result: VectorStep) -> StepBatch:
    """What the learner is told of one step of every run (one env per run, one learner): the
    environment's facts, as the vector env reports them for its learner and by the same names,
    unshaped. An other agent's term may bootstrap only while it is present and not terminal
    (``others_present``, SPEC §6): a harmed cat has left, and the human's episode ends for good
    when the last battery is taken; a time-limit truncation still bootstraps. With
    ``in_view_only``, an other out of view is *unseen* (``others_unseen``), not absent: the
    empathic target is then the robot's own (SPEC §4)."""
    return StepBatch(
        obs=obs[:, None, :],
        actions=actions,
        rewards=result.learner_rewards,
        terminated=result.learner_terminated,
        next_obs=result.final_observations,
        closest=result.closest,
        others_swapped=result.others_swapped,
        others_present=result.others_present,
        others_live=result.others_live,
        others_unseen=result.others_unseen,
        harms=result.harms,
        battery_return=result.learner_battery_return,
        others_battery_return=result.others_battery_return,
        truncated=result.learner_truncated,
        others_rewards=result.others_rewards,
    )


class AgentCells:
    """The cells of the learner and of its other agents at the end of every step of ``venv``, and
    their torus distances, as the engine holds them before any autoreset: it watches ``venv``'s
    engine steps (:meth:`empathy_zoo.vector.VectorEnv.watch_engine`) from its construction on, and
    :meth:`fill` puts the last step's into a :class:`StepBatch` (``position``, ``others_position``,
    ``others_distance``; one learner, one environment per run)."""

    def __init__(self, venv: VectorEnv) -> None:
        self._learner = int(venv.learner_index[0])
        self._others = np.asarray(venv.engine.other_agents[self._learner], dtype=np.int64)
        self._size = venv.engine.size
        self._last: tuple[np.ndarray, np.ndarray] | None = None
        """The cells ``(N, A, 2)`` and presence ``(N, A)`` at the end of the last step, until :meth:`fill` takes them."""
        venv.watch_engine(self)

    def before_engine_step(self, engine: Any, actions: np.ndarray) -> None:
        """Nothing: the cells are read after the step (:class:`empathy_zoo.vector.EngineWatcher`)."""

    def after_engine_step(self, engine: Any, actions: np.ndarray, events: Any) -> None:
        """Keep the cells and presence the step ended with (:class:`empathy_zoo.vector.EngineWatcher`)."""
        self._last = (np.array(engine.pos, dtype=np.int64), engine.present.copy())

    def fill(self, batch: StepBatch) -> StepBatch:
        """``batch`` (of the step just taken) with the learner's and the others' cells and their
        torus distances, ``(−1, −1)`` and −1 for an agent no longer in the environment."""
        if self._last is None:
            raise RuntimeError("no engine step has been watched since the last fill()")
        pos, present = self._last
        self._last = None
        own, others = pos[:, self._learner], pos[:, self._others]
        own_present, others_present = present[:, self._learner], present[:, self._others]
        distance = torus_distance(own[:, None, :], others, self._size).astype(np.int64)
        distance[~(own_present[:, None] & others_present)] = -1
        own = np.where(own_present[:, None], own, -1)
        others = np.where(others_present[:, :, None], others, -1)
        return replace(batch, position=own[:, None], others_position=others[:, None], others_distance=distance[:, None])


def _optional(learner: Any, name: str) -> Callable[..., Any] | None:
    """The learner's method ``name`` that :class:`agents.base.Learner` declares optional, or
    ``None`` where the learner has none."""
    method = getattr(learner, name, None)
    return method if callable(method) else None


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
