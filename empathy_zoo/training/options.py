"""How runs are executed: :class:`RunnerOptions` (results never depend on these but for the last
bits that :attr:`RunnerOptions.update_kernel` chooses, which every result file records), checked when
they are made, so the command line and Python callers get the same refusals (docs/limits.md)."""

from __future__ import annotations

from dataclasses import dataclass

from agents.base import UPDATE_KERNELS
from empathy_zoo.experiment.log_backends import parse_log
from empathy_zoo.limits import MAX_STEPS, check_at_most, cpu_count
from empathy_zoo.training.progress import PROGRESS_STYLES
from empathy_zoo.training.tracking import check_installed

__all__ = ["BACKENDS", "RunnerOptions"]

BACKENDS = ("local", "ray")
"""Where ensembles may run (:attr:`RunnerOptions.backend`)."""


@dataclass(frozen=True)
class RunnerOptions:
    """How runs are executed (not what they compute: results do not depend on these, but for the
    last bits of the runs whose learner has a choice of update kernels: :attr:`update_kernel`)."""

    device: str = "cpu"
    """Torch device for the networks and replay (``cpu``, ``cuda``, ``cuda:1``)."""
    max_parallel_runs: int = 32
    """Most runs trained together in one lockstep ensemble (bounds memory: ~45 MB per run at the paper's replay size)."""
    checkpoint_interval: int = 50_000
    """Env steps between checkpoints of an unfinished ensemble (0 = never)."""
    progress: bool = True
    """Show progress bars (drawn by this process only: one per running ensemble, and one for the
    sweep's env steps when it has several ensembles; see :mod:`empathy_zoo.training.progress`)."""
    progress_style: str = "auto"
    """How progress shows: ``auto`` (bars on a terminal, plain lines where standard error is not
    one: a log file), ``bars`` or ``plain`` (:data:`empathy_zoo.training.progress.PROGRESS_STYLES`)."""
    threads: int | None = 1
    """Torch CPU threads per process (``None`` = torch's default, every core), at most the CPUs of
    this machine: these small networks gain nothing from more than one, and extra threads are much
    slower on a busy machine."""
    workers: int = 1
    """Processes training ensembles side by side (the sweep's ensembles are spread over them), at
    most the CPUs of this machine."""
    backend: str = "local"
    """Where ensembles run: ``local`` (this machine, ``workers`` processes) or ``ray``."""
    address: str | None = None
    """Ray cluster address for ``backend="ray"`` (``None`` starts a local Ray instance)."""
    rerun_changed: bool = False
    """Retrain the finished runs whose result files were made by other code (another empathy-zoo
    version or an edited plug-in module, or code that cannot be told: see
    :mod:`empathy_zoo.training.fingerprint`) and overwrite their files with the new results;
    ``False`` refuses a sweep asking for changed runs, before training anything (runs whose code
    cannot be told are reused then, with a note)."""
    log: tuple[str, ...] = ()
    """Where each run logs its scalars live: any of ``tensorboard``, ``csv``, ``wandb``
    (:mod:`empathy_zoo.training.tracking`; ``()``: nowhere). A comma-separated string is taken too;
    an unknown backend, or one whose package is missing, is refused here."""

    update_kernel: str = "auto"
    """How learners that have a choice compute a gradient step (Empathic DQN and the methods built on
    it: :attr:`agents.empathic_dqn.EmpathicDQN.update_kernel`): ``auto`` (each learner's own
    default: for Empathic DQN the compiled ``numba`` kernel where it builds on a CPU, else
    ``torch``), ``numba`` or ``torch``. The two compute the
    same algorithm in float32 with sums in another order, so a run's last bits depend on it (their
    metrics were shown statistically equivalent: BENCHMARKS.md); each result file records the
    kernel that made it, a finished run made by the other one counts as made by other code, and a
    checkpoint resumes only with the kernel that wrote it. Other learners ignore it."""

    def __post_init__(self) -> None:
        for name, low in (("max_parallel_runs", 1), ("checkpoint_interval", 0), ("workers", 1), ("threads", 1)):
            value = getattr(self, name)
            if name == "threads" and value is None:
                continue
            if isinstance(value, bool) or not isinstance(value, int) or value < low:
                raise ValueError(f"{name} must be an int >= {low}, got {value!r}")
        check_at_most("checkpoint_interval", self.checkpoint_interval, MAX_STEPS)
        for name in ("threads", "workers"):
            value = getattr(self, name)
            if value is not None:
                check_at_most(name, value, cpu_count(), "the CPUs of this machine, os.cpu_count()")
        if self.progress_style not in PROGRESS_STYLES:
            raise ValueError(f"progress_style must be one of {', '.join(PROGRESS_STYLES)}, got {self.progress_style!r}")
        if self.backend not in BACKENDS:
            raise ValueError(f"unknown backend {self.backend!r}; choose one of {', '.join(BACKENDS)}")
        if self.update_kernel not in UPDATE_KERNELS:
            raise ValueError(f"update_kernel must be one of {', '.join(UPDATE_KERNELS)}, got {self.update_kernel!r}")
        object.__setattr__(self, "log", parse_log(self.log))
        check_installed(self.log)
        if not isinstance(self.device, str) or not self.device:
            raise ValueError(f"device must be a torch device name (cpu, cuda, cuda:1), got {self.device!r}")
