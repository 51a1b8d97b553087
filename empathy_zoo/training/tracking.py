"""Live tracking: every run's scalars to TensorBoard, CSV files or Weights & Biases as it trains.

``RunnerOptions(log=("tensorboard", "csv"))`` (``--log tensorboard,csv`` on ``train`` and
``reproduce``; ``log = ["tensorboard"]`` in a sweep file's ``[sweep]`` table or a ``train
--config`` file) makes each ensemble open one logger per run and backend where it trains (this
process, a worker process or a Ray task), from the plain option alone. Each run writes its own
directory, ``<out>/logs/<backend>/<run id>/``, so ``tensorboard --logdir <out>/logs/tensorboard``
over a sweep shows every run side by side. Logging reads what the trainer has already computed
and never draws a random number or changes a learner: a run's result file is the same with and
without it (time stamps aside).

Backends (:data:`BACKENDS`); TensorBoard and W&B are optional extras, checked before anything
trains (:func:`check_installed`):

* ``tensorboard``: event files through ``torch.utils.tensorboard.SummaryWriter``
  (``pip install -e ".[tensorboard]"``). A resumed ensemble purges the steps after its
  checkpoint, so a curve is never drawn twice.
* ``csv``: ``<out>/logs/csv/<run id>/scalars.csv`` with rows ``step,name,value`` (the standard
  library only), flushed every :data:`LOG_INTERVAL` steps and at each checkpoint: a crash loses at
  most the rows since the last flush, and a resumed ensemble, which first drops any rows after its
  checkpoint, logs those steps again.
* ``wandb``: one W&B run per run (``pip install -e ".[wandb]"``), named by its run id,
  grouped by its experiment, with the run's config, and its result file logged as an artifact
  when it finishes. It runs online only where the user logged in (``wandb login`` or
  ``WANDB_API_KEY``) or asked for it (``WANDB_MODE``); otherwise it runs offline, with W&B's
  error reporting off, so nothing leaves the machine (``wandb sync <dir>`` uploads it later).
  A resumed ensemble starts a new W&B run of the same name.

The scalars (:data:`SCALARS`), at the run's env step: on every training episode's end the
episode's metrics (:data:`~empathy_zoo.metrics.METRIC_NAMES`) as ``charts/<metric>`` (the return
as ``charts/episodic_return``, CleanRL's name) and, for a run with a reward transform, what it
trained on (``charts/train_return``) and the transform's own term (``charts/shaping_return``);
every :data:`LOG_INTERVAL` env steps ``charts/SPS``, ``charts/epsilon`` and the learner's own
figures (:meth:`agents.base.Learner.tracked_scalars`: Empathic DQN's ``losses/td_loss`` and
``losses/q_values`` per head); after each greedy evaluation ``eval/<metric>``.
"""

from __future__ import annotations

import csv
import hashlib
import importlib.util
import json
import netrc
import os
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Protocol
from urllib.parse import urlparse

import numpy as np

from empathy_zoo.experiment.log_backends import BACKENDS, parse_log
from empathy_zoo.extras import install_command
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.names import check_no_links, check_replaceable
from empathy_zoo.training.log_files import (
    after_earlier_event_files,
    check_csv_log,
    check_event_file_names,
    keep_csv_rows_up_to,
)

__all__ = [
    "BACKENDS",
    "EXTRAS",
    "LOG_DIR",
    "LOG_INTERVAL",
    "EPISODE_SCALARS",
    "SCALARS",
    "EnsembleTracker",
    "RunLogger",
    "TrackingNotInstalledError",
    "check_installed",
    "check_log_places",
    "log_dir",
    "log_subdirs",
    "open_tracker",
    "parse_log",
]

EXTRAS = {"tensorboard": ("tensorboard", "tensorboard"), "wandb": ("wandb", "wandb")}
"""``{backend: (module it imports, empathy-zoo extra that installs it)}`` (CSV needs none)."""
LOG_DIR = "logs"
"""The directory of ``<out>`` that holds ``<backend>/<run id>/``."""
LOG_INTERVAL = 500
"""Env steps between two logs of the learner's figures and the speed (the progress bar's cadence)."""
CSV_FILE = "scalars.csv"
"""A run's CSV file, in ``<out>/logs/csv/<run id>/``."""

EPISODE_SCALARS: dict[str, str] = {name: f"charts/{'episodic_return' if name == 'return' else name}" for name in METRIC_NAMES}
"""The name of each episode metric in the logs (the return by CleanRL's name)."""

_END, _EVERY = "at each training episode's end", f"every {LOG_INTERVAL} env steps"
SCALARS: dict[str, str] = {
    **{EPISODE_SCALARS[m]: f"{_END}: its {m} (empathy_zoo.metrics.METRIC_DEFINITIONS)" for m in METRIC_NAMES},
    "charts/train_return": f"{_END}: the rewards the run trained on, summed (a run with a reward transform)",
    "charts/shaping_return": f"{_END}: training minus environment reward, summed (the transform's own term)",
    "charts/SPS": f"{_EVERY}: the run's env steps per second (an ensemble of K runs steps K times as many)",
    "charts/epsilon": f"{_EVERY}: the exploration rate (the learner's live_stats 'eps', where it has one)",
    "losses/td_loss": f"{_EVERY}: mean squared TD error of Q on the last gradient step's batch (Empathic DQN)",
    "losses/q_values": f"{_EVERY}: mean Q(s, a) on that batch (Empathic DQN)",
    "losses/td_loss_emp": "as losses/td_loss, of Q_emp (Empathic DQN runs with β < 1)",
    "losses/q_values_emp": "as losses/q_values, of Q_emp (Empathic DQN runs with β < 1)",
    "learner/<name>": f"{_EVERY}, for a learner without tracked_scalars: its other live_stats (the ensemble's)",
    **{f"eval/{m}": f"after each greedy evaluation: the mean {m} of its episodes" for m in METRIC_NAMES},
}
"""Every scalar a run may log, and when (the learner's own names come from its ``tracked_scalars``)."""


class TrackingNotInstalledError(ImportError, ValueError):
    """A logging backend's package is missing (a ``ValueError`` too: the command line reports it as a usage error)."""


def check_installed(backends: Sequence[str]) -> None:
    """Raise :class:`TrackingNotInstalledError` saying which extra to install when a backend's
    package is missing (found without importing it)."""
    for backend in backends:
        if backend in EXTRAS:
            module, extra = EXTRAS[backend]
            if importlib.util.find_spec(module) is None:
                raise TrackingNotInstalledError(
                    f"--log {backend} needs the {module} package, which is not installed: {install_command(extra)}"
                )


def log_dir(out_dir: str | Path, backend: str, run_id: str) -> Path:
    """Where run ``run_id`` logs to ``backend``: ``<out_dir>/logs/<backend>/<run id>``."""
    return Path(out_dir) / LOG_DIR / backend / run_id


def log_subdirs(backends: Sequence[str]) -> tuple[str, ...]:
    """The directories of an output directory that runs logging to ``backends`` write into
    (``logs/<backend>``), for :func:`empathy_zoo.atomic.check_output_dir` to check (no symbolic
    link among them) before anything is written."""
    return tuple(f"{LOG_DIR}/{backend}" for backend in backends)


def check_log_places(out_dir: str | Path, backends: Sequence[str], run_ids: Sequence[str]) -> None:
    """Refuse (``ValueError`` naming it) a place the runs ``run_ids`` would log to that is a
    symbolic link below ``out_dir`` (named with its target) or a file where a directory goes, and a
    CSV file (``scalars.csv``) that is anything but nothing or a regular file
    (:func:`empathy_zoo.names.check_replaceable`): asked of every run and backend before the first
    logger creates its directory, so nothing is ever written through a link. The logs a resumed
    run reads are checked too (:func:`empathy_zoo.training.log_files.check_csv_log`,
    :func:`~empathy_zoo.training.log_files.check_event_file_names`), before anything trains."""
    for run_id in run_ids:
        for backend in backends:
            directory = check_no_links(out_dir, log_dir(out_dir, backend, run_id))
            for folder in (directory, *directory.parents):
                if folder == Path(out_dir):
                    break
                if folder.exists() and not folder.is_dir():
                    raise ValueError(f"{folder} is a file, not a directory: runs log into it; move the file away")
            if backend == "csv":
                check_csv_log(check_replaceable(directory / CSV_FILE))
            if backend == "tensorboard" and directory.is_dir():
                check_event_file_names(directory)


class RunLogger(Protocol):
    """One run's logger of one backend."""

    def scalars(self, values: Mapping[str, float], step: int) -> None:
        """Log every ``name: value`` of ``values`` at env step ``step``."""

    def flush(self) -> None:
        """Write what is buffered."""

    def finish(self, result: Mapping[str, Any], result_file: Path) -> None:
        """The run finished with ``result`` (its result document; ``result_file`` is where it is
        written, or not yet, on Ray): keep what the backend keeps of it, then close."""

    def close(self) -> None:
        """Flush and close (an unfinished run; again after :meth:`finish` does nothing)."""


class CsvLogger:
    """``<dir>/scalars.csv``: a header ``step,name,value`` and one row per scalar."""

    def __init__(self, directory: Path, start_step: int) -> None:
        self.path = check_replaceable(directory / CSV_FILE)  # (appended to: never through a link, never a FIFO)
        directory.mkdir(parents=True, exist_ok=True)
        if start_step > 0 and self.path.exists():
            keep_csv_rows_up_to(self.path, start_step)
        fresh = not self.path.exists() or self.path.stat().st_size == 0
        self._file: Any = self.path.open("a", newline="", encoding="utf-8")
        self._writer = csv.writer(self._file)
        if fresh:
            self._writer.writerow(("step", "name", "value"))

    def scalars(self, values: Mapping[str, float], step: int) -> None:
        self._writer.writerows((step, name, repr(float(value))) for name, value in values.items())

    def flush(self) -> None:
        if self._file is not None:
            self._file.flush()

    def finish(self, result: Mapping[str, Any], result_file: Path) -> None:
        self.close()

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None


class TensorBoardLogger:
    """TensorBoard event files in ``<dir>`` (``torch.utils.tensorboard.SummaryWriter``)."""

    def __init__(self, directory: Path, start_step: int) -> None:
        from torch.utils.tensorboard import SummaryWriter

        directory.mkdir(parents=True, exist_ok=True)
        if start_step > 0:
            after_earlier_event_files(directory)
        # (a resumed run purges what was logged after its checkpoint; the writer batches its writes)
        self._writer: Any = SummaryWriter(str(directory), purge_step=start_step + 1 if start_step > 0 else None, max_queue=1000)

    def scalars(self, values: Mapping[str, float], step: int) -> None:
        for name, value in values.items():
            self._writer.add_scalar(name, float(value), step)

    def flush(self) -> None:
        if self._writer is not None:
            self._writer.flush()

    def finish(self, result: Mapping[str, Any], result_file: Path) -> None:
        self.close()

    def close(self) -> None:
        if self._writer is not None:
            self._writer.close()
            self._writer = None


def wandb_mode() -> str:
    """How W&B runs: ``WANDB_MODE`` where the user set it; else ``online`` where the user logged in
    (``WANDB_API_KEY``, or an entry for the W&B host in ``~/.netrc``, which ``wandb login``
    writes); else ``offline``."""
    if os.environ.get("WANDB_MODE"):
        return os.environ["WANDB_MODE"]
    if os.environ.get("WANDB_API_KEY"):
        return "online"
    host = urlparse(os.environ.get("WANDB_BASE_URL", "https://api.wandb.ai")).hostname or "api.wandb.ai"
    try:
        logged_in = netrc.netrc(os.environ.get("NETRC")).authenticators(host) is not None
    except (OSError, netrc.NetrcParseError):
        logged_in = False
    return "online" if logged_in else "offline"


class WandbLogger:
    """One W&B run: named by the run id, grouped by its experiment, with the run's config."""

    def __init__(self, directory: Path, start_step: int, spec: Any, mode: Any) -> None:
        import wandb

        directory.mkdir(parents=True, exist_ok=True)
        self._wandb = wandb
        self._run: Any = wandb.init(
            project=None if os.environ.get("WANDB_PROJECT") else "empathy-zoo",
            name=spec.run_id,
            group=spec.experiment_id,
            job_type="train",
            dir=str(directory),
            config={"run_id": spec.run_id, **spec.config()},
            mode=mode,
            reinit="create_new",  # (the K runs of an ensemble are K W&B runs, open together)
            settings=wandb.Settings(console="off", quiet=True),
        )
        self._directory = directory

    def scalars(self, values: Mapping[str, float], step: int) -> None:
        self._run.log({name: float(value) for name, value in values.items()}, step=step)

    def flush(self) -> None:
        """(W&B writes in its own process.)"""

    def finish(self, result: Mapping[str, Any], result_file: Path) -> None:
        if self._run is None:
            return
        if not result_file.exists():  # (on Ray the driver writes the result file: keep the worker's copy)
            result_file = self._directory / f"{result['run_id']}.json"
            result_file.write_text(json.dumps(result, sort_keys=True, default=str), encoding="utf-8")
        name = "result-" + hashlib.sha256(str(result["run_id"]).encode()).hexdigest()[:16]
        artifact = self._wandb.Artifact(name, type="result", metadata={"run_id": result["run_id"]})
        artifact.add_file(str(result_file), name=result_file.name)
        self._run.log_artifact(artifact)
        self.close()

    def close(self) -> None:
        if self._run is not None:
            self._run.finish()
            self._run = None


class EnsembleTracker:
    """The loggers of an ensemble's runs (opened by :meth:`start`), and what they log when."""

    def __init__(self, backends: Sequence[str], out_dir: Path, specs: Sequence[Any]) -> None:
        self.backends = tuple(backends)
        self.out_dir = out_dir
        self.specs = list(specs)
        self.loggers: list[list[RunLogger]] = [[] for _ in self.specs]
        self._sums: np.ndarray | None = None
        """``(2, K)``: each run's training reward and shaping term summed over its episode so far
        (``None``: no run has a reward transform)."""
        self._whole = np.ones(len(self.specs), dtype=bool)
        """Whether each run's sums cover its whole episode (not after a resume, until the episode ends)."""
        self._shaped_runs = np.zeros(len(self.specs), dtype=bool)

    def start(self, step: int, transforms: Sequence[Any]) -> None:
        """Open every run's loggers, the ensemble at env step ``step`` (``> 0``: resumed from a
        checkpoint there); ``transforms`` are the runs' reward transforms (``None``: none). Every
        place a run logs to is checked before the first is opened (:func:`check_log_places`)."""
        check_log_places(self.out_dir, self.backends, [spec.run_id for spec in self.specs])
        mode = wandb_mode() if "wandb" in self.backends else ""
        if mode == "offline":  # (nothing leaves the machine: no error reports either, unless the user asked)
            os.environ.setdefault("WANDB_ERROR_REPORTING", "false")
            if not os.environ.get("WANDB_MODE"):
                print(
                    f"empathy-zoo: W&B logs offline under {self.out_dir / LOG_DIR / 'wandb'} (not logged in, "
                    "WANDB_MODE unset): wandb sync <its offline-run directory> uploads a run",
                    file=sys.stderr,
                    flush=True,
                )
        for r, spec in enumerate(self.specs):
            for backend in self.backends:
                directory = log_dir(self.out_dir, backend, spec.run_id)
                logger: RunLogger
                if backend == "csv":
                    logger = CsvLogger(directory, step)
                elif backend == "tensorboard":
                    logger = TensorBoardLogger(directory, step)
                else:
                    logger = WandbLogger(directory, step, spec, mode)
                self.loggers[r].append(logger)
        self._shaped_runs = np.array([t is not None for t in transforms], dtype=bool)
        if self._shaped_runs.any():
            self._sums = np.zeros((2, len(self.specs)))
            self._whole[:] = step == 0  # (a resumed episode's sums would miss its start: not logged)

    def _log(self, run: int, values: Mapping[str, float], step: int) -> None:
        for logger in self.loggers[run]:
            logger.scalars(values, step)

    def after_step(
        self, step: int, finished: Mapping[str, np.ndarray], env_rewards: np.ndarray, train_rewards: np.ndarray
    ) -> None:
        """One env step of every run: ``finished`` the episodes that ended (the vector env's
        ``finished``), the ``(K, 1)`` rewards of the environment and those the runs trained on."""
        sums = self._sums
        if sums is not None:
            sums[0] += train_rewards[:, 0]
            sums[1] += train_rewards[:, 0] - env_rewards[:, 0]
        for j, run in enumerate(finished["env"]):
            values = {EPISODE_SCALARS[name]: float(finished[name][j]) for name in METRIC_NAMES}
            if sums is not None:
                if self._shaped_runs[run] and self._whole[run]:
                    values["charts/train_return"], values["charts/shaping_return"] = float(sums[0, run]), float(sums[1, run])
                sums[:, run] = 0.0
                self._whole[run] = True
            self._log(int(run), values, step)

    def evaluation(self, step: int, per_run: Sequence[Mapping[str, Sequence[float]]]) -> None:
        """A greedy evaluation at ``step``: each run's metric columns (:func:`evaluate_greedy`'s)."""
        for run, columns in enumerate(per_run):
            self._log(run, {f"eval/{name}": float(np.mean(columns[name])) for name in METRIC_NAMES}, step)

    def interval(self, step: int, learner: Any, steps_per_second: float) -> None:
        """Every :data:`LOG_INTERVAL` steps: the speed, ε and the learner's figures; then flush."""
        live = learner.live_stats()
        shared = {"charts/SPS": float(steps_per_second)}
        if "eps" in live:
            shared["charts/epsilon"] = float(live["eps"])
        tracked = getattr(learner, "tracked_scalars", None)
        if callable(tracked):
            per_run = list(tracked())
        else:
            others = {f"learner/{key}": float(value) for key, value in live.items() if key != "eps"}
            per_run = [others] * len(self.specs)
        for run, own in enumerate(per_run):
            self._log(run, {**shared, **own}, step)
        self.flush()

    def flush(self) -> None:
        for loggers in self.loggers:
            for logger in loggers:
                logger.flush()

    def finish(self, run: int, result: Mapping[str, Any], result_file: Path) -> None:
        """Run ``run`` finished with ``result``: its loggers keep it and close."""
        for logger in self.loggers[run]:
            logger.finish(result, result_file)

    def close(self) -> None:
        """Close every logger still open (an ensemble that stopped before its end)."""
        for loggers in self.loggers:
            for logger in loggers:
                logger.close()


def open_tracker(backends: Sequence[str], out_dir: str | Path, specs: Sequence[Any]) -> EnsembleTracker | None:
    """The tracker of an ensemble of ``specs`` logging to ``backends`` (``None`` for none): its
    packages are checked here (:func:`check_installed`); :meth:`EnsembleTracker.start` opens the
    loggers once the ensemble knows its first step."""
    if not backends:
        return None
    check_installed(backends)
    return EnsembleTracker(backends, Path(out_dir), specs)
