"""The Ray backend: a sweep's ensembles as Ray tasks, on this machine or on a cluster.

``train_runs(specs, out_dir, RunnerOptions(backend="ray"))`` lands here. Each ensemble (a list of
compatible :class:`RunSpec`) becomes one Ray task that calls :func:`train_ensemble` with
``write_results=False``; the finished results travel back to the driver, which writes each one
with :func:`write_result` (atomically, one file per run) exactly as the local backend does, so
the result files and the leaderboard built from them are the same. A run's numbers depend only
on its own spec, so they do not depend on the backend either.

* ``options.address is None`` starts a local Ray instance (one CPU per core, no dashboard) and
  stops it at the end; an address (``"auto"``, ``"ray://host:10001"``, ``"host:6379"``) joins a
  running cluster, once something answers there within :data:`CONNECT_TIMEOUT_S` seconds (else a
  ``ValueError`` naming the address, before anything is written). A Ray already initialised in
  this process is used as it is.
* A task whose worker dies (killed, out of memory, node lost) or that raises is retried up to
  :data:`MAX_RETRIES` times. The driver writes each run once; a result whose file already exists
  when it arrives is skipped. When a task still fails, the other tasks are finished and written
  first, then the error is raised: rerunning the same command redoes only the failed runs.
* Ctrl-C (or any error in the driver) cancels the outstanding tasks. Finished runs are already
  written; unfinished ensembles resume from their checkpoints (``<out_dir>/checkpoints``) when
  the directory is shared with the workers, as it is on one machine, else they are redone.
  A worker that cannot create that directory keeps its checkpoints on its own disk
  (``<tmp>/empathy-zoo-checkpoints/<digest of out_dir>``) so a retry on the same node resumes.

Ray is an optional extra: ``pip install -e ".[ray]"``. Every node of a cluster needs the
same version of empathy-zoo (and of any ``package.module:NAME`` method or policy the sweep uses).
"""

from __future__ import annotations

import contextlib
import hashlib
import logging
import os
import socket
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.extras import install_command
from empathy_zoo.names import resolved
from empathy_zoo.result_file import result_path
from empathy_zoo.training.ensemble import train_ensemble
from empathy_zoo.training.options import RunnerOptions
from empathy_zoo.training.results import stored, write_result
from empathy_zoo.training.resume import CHECKPOINT_DIR

__all__ = ["MAX_RETRIES", "CONNECT_TIMEOUT_S", "RayNotInstalledError", "train_with_ray", "import_ray", "check_ray_address"]

MAX_RETRIES = 3
"""Times a failed ensemble task is retried (worker death or exception) before the sweep reports it."""
CONNECT_TIMEOUT_S = 10.0
"""Seconds to wait for an answer at a cluster address before the sweep gives up (:func:`check_ray_address`)."""

INSTALL_HINT = f"the Ray backend needs Ray: {install_command('ray')}"


class RayNotInstalledError(ImportError, ValueError):
    """Ray is missing (an ``ImportError``, and a ``ValueError`` so the command line reports it as a usage error)."""


def import_ray() -> Any:
    """The ``ray`` module, or a :class:`RayNotInstalledError` saying how to install it."""
    try:
        import ray
    except ImportError as error:
        raise RayNotInstalledError(INSTALL_HINT) from error
    return ray


def check_ray_address(address: str | None, timeout: float | None = None) -> None:
    """Raise ``ValueError`` within ``timeout`` seconds (default :data:`CONNECT_TIMEOUT_S`) when the
    cluster ``address`` (``"ray://HOST:PORT"`` or ``"HOST:PORT"``) is malformed or nothing answers
    there, instead of letting ``ray.init`` retry for minutes. ``None`` passes (Ray is started on
    this machine); ``"auto"`` is the cluster Ray finds (``RAY_ADDRESS``, or the last one started on
    this machine), refused when there is none (:func:`auto_address`)."""
    if address is None:
        return
    if address == "auto":
        found = auto_address()
        if found is None:  # (this Ray cannot say before connecting: ray.init will)
            return
        address = found
    host, _, port = address.removeprefix("ray://").rpartition(":")
    if not host or not port.isdigit():
        raise ValueError(f"--address {address!r}: expected auto, ray://HOST:PORT (Ray Client) or HOST:PORT")
    limit = CONNECT_TIMEOUT_S if timeout is None else timeout
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=limit).close()
    except OSError as error:
        raise ValueError(
            f"cannot reach the Ray cluster at {address} ({error.strerror or error}, waited at most {limit:g} s): check "
            "the address, that the head node runs Ray (ray start --head) and that its port is open to this machine"
        ) from None


NO_CLUSTER = (
    "--address auto found no running Ray cluster (RAY_ADDRESS is not set and none was started on this machine): "
    "start one (ray start --head), give its head's address (--address HOST:PORT), or leave --address out to "
    "start Ray on this machine"
)
"""The refusal of ``--address auto`` where there is no cluster (Ray's own says ``--address flag``)."""


def auto_address() -> str | None:
    """``HOST:PORT`` of the cluster ``address="auto"`` would join, as Ray itself finds it
    (``RAY_ADDRESS``, else the address file of the last cluster started on this machine); ``ValueError``
    (:data:`NO_CLUSTER`) when there is none; ``None`` when this Ray version cannot say before
    connecting (its private finder moved)."""
    try:
        from ray._private.services import canonicalize_bootstrap_address
    except ImportError:  # pragma: no cover - another Ray layout: ray.init says it
        return None
    try:
        found = canonicalize_bootstrap_address("auto")
    except ConnectionError:
        raise ValueError(NO_CLUSTER) from None
    return None if found is None else str(found)


def train_with_ray(
    chunks: Sequence[Sequence[RunSpec]],
    out_dir: str | Path,
    options: RunnerOptions,
    on_result: Callable[[dict[str, Any]], None] | None = None,
    fault_injection: Callable[[Sequence[RunSpec]], None] | None = None,
) -> None:
    """Train the ensembles ``chunks`` as Ray tasks and write their results on this (driver) machine.

    ``on_result`` is called on the driver with every result it writes. ``fault_injection`` is for
    tests only: a picklable callable run inside each task, before training, with the task's
    specs (a test makes it kill its worker once to check that the task is retried).
    """
    ray = import_ray()
    out_dir = resolved(out_dir)
    if not chunks:
        return
    started_here = not ray.is_initialized()
    if started_here:
        settings: dict[str, Any] = {"logging_level": logging.ERROR, "configure_logging": True}
        if options.address is None:
            ray.init(num_cpus=os.cpu_count() or 1, include_dashboard=False, **settings)
        else:
            try:
                ray.init(address=options.address, **settings)
            except ConnectionError as error:  # (gone since the check before training)
                raise ValueError(NO_CLUSTER if options.address == "auto" else f"--address {options.address}: {error}") from None
    try:
        _run_tasks(ray, [list(chunk) for chunk in chunks], out_dir, options, on_result, fault_injection)
    finally:
        if started_here:
            ray.shutdown()


def _run_tasks(
    ray: Any,
    chunks: list[list[RunSpec]],
    out_dir: Path,
    options: RunnerOptions,
    on_result: Callable[[dict[str, Any]], None] | None,
    fault_injection: Callable[[Sequence[RunSpec]], None] | None,
) -> None:
    gpu = options.device.startswith("cuda")
    threads = options.threads or 1
    worker_options = replace(
        options,
        backend="local",
        address=None,
        workers=1,
        progress=False,
        threads=threads,
        device="cuda" if gpu else options.device,  # Ray hands each task its own GPU as cuda:0
    )
    task = ray.remote(_train_chunk).options(
        num_cpus=threads,
        num_gpus=1 if gpu else 0,
        max_retries=MAX_RETRIES,
        retry_exceptions=True,
    )
    pending = {task.remote(chunk, str(out_dir), worker_options, fault_injection): chunk for chunk in chunks}
    failures: list[tuple[list[RunSpec], BaseException]] = []
    written: set[str] = set()
    try:
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            for ref in done:
                chunk = pending.pop(ref)
                try:
                    results = ray.get(ref)
                except ray.exceptions.RayError as error:  # the task failed after its retries, or was cancelled
                    failures.append((chunk, error))
                    continue
                for result in results:
                    run_id = result["run_id"]
                    if run_id in written or result_path(out_dir, run_id).exists():
                        continue  # written already (by this driver or another): never twice
                    write_result(out_dir, result)
                    written.add(run_id)
                    if on_result is not None:
                        on_result(stored(result))
    except BaseException:  # Ctrl-C or an error here: stop the tasks; finished runs are written already
        for ref in pending:
            with contextlib.suppress(Exception):  # Ray may be going down; the original error matters
                ray.cancel(ref, force=True)
        raise
    if failures:
        runs = sorted(spec.run_id for chunk, _ in failures for spec in chunk)
        raise RuntimeError(
            f"{len(failures)} ensemble task(s) failed after {MAX_RETRIES} retries; the other runs are written "
            f"and rerunning the sweep redoes only these runs: {runs}"
        ) from failures[0][1]


def _train_chunk(
    chunk: list[RunSpec],
    out_dir: str,
    options: RunnerOptions,
    fault_injection: Callable[[Sequence[RunSpec]], None] | None,
) -> list[dict[str, Any]]:
    """One Ray task: train an ensemble and return its results (the driver writes them)."""
    if fault_injection is not None:
        fault_injection(chunk)
    return train_ensemble(chunk, _checkpoint_root(Path(out_dir)), options, write_results=False)


def _checkpoint_root(out_dir: Path) -> Path:
    """``out_dir`` if this worker can create its checkpoint directory there, else a node-local stand-in.

    ``train_ensemble`` only writes checkpoints under the directory it is given (results go back
    to the driver), so the stand-in changes where a node keeps its checkpoints, nothing else.
    """
    try:
        (out_dir / CHECKPOINT_DIR).mkdir(parents=True, exist_ok=True)
        if os.access(out_dir / CHECKPOINT_DIR, os.W_OK):
            return out_dir
    except OSError:
        pass
    digest = hashlib.sha256(str(out_dir).encode()).hexdigest()[:16]
    return Path(tempfile.gettempdir()) / "empathy-zoo-checkpoints" / digest
