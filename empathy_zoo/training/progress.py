"""Progress of a sweep on one terminal: every bar is drawn by the process that started the sweep.

Ensembles (in this process or in worker processes) only *report* (:class:`Report`): where they
are, their live numbers, a line to print. :class:`SweepProgress` draws them: one bar per running
ensemble, redrawn in place and removed when it finishes, and, for a sweep of several ensembles,
one sweep bar counting the env steps of every run still to train, so its rate and ETA are those
of the whole sweep (a bar counting finished runs would stand still until whole ensembles end).
Worker processes send their reports through a queue (:class:`QueueReporter`); nothing they do
touches the terminal, so bars of several workers cannot overwrite one another.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from tqdm.auto import tqdm

__all__ = ["Report", "SweepProgress", "QueueReporter", "QueueDrain"]


@dataclass(frozen=True)
class Report:
    """What an ensemble says about itself."""

    ensemble: int
    """Index of the ensemble in the sweep's plan."""
    step: int
    """Env steps each of its runs has taken (its checkpoint's step at a resume)."""
    total: int
    """Env steps each of its runs takes in all."""
    runs: int
    """Runs trained in lockstep."""
    label: str
    """Short name of the ensemble (env and runs) for its bar."""
    stats: dict[str, str] = field(default_factory=dict)
    """Live numbers for the bar's postfix."""
    line: str | None = None
    """A line to print above the bars (e.g. the ensemble's memory), once."""
    done: bool = False
    """The ensemble finished (its bar goes away)."""


class SweepProgress:
    """The bars of a sweep of ``ensembles`` (``(runs, steps)`` per ensemble) in this process."""

    def __init__(self, ensembles: Sequence[tuple[int, int]], enabled: bool = True) -> None:
        self.enabled = enabled
        self.lock = threading.Lock()
        self.bars: dict[int, tqdm] = {}
        self.steps: dict[int, int] = {}
        total = sum(runs * steps for runs, steps in ensembles)
        self.sweep = tqdm(
            total=total,
            unit="step",
            unit_scale=True,
            desc="sweep",
            dynamic_ncols=True,
            position=0,
            disable=not enabled or len(ensembles) < 2,
            mininterval=1.0,
        )
        """Env steps of every run still to train here (a resumed ensemble's steps are left out)."""

    def update(self, report: Report) -> None:
        with self.lock:
            if report.line and self.enabled:
                tqdm.write(report.line)
            first = report.ensemble not in self.steps
            previous = self.steps.get(report.ensemble, report.step)
            self.steps[report.ensemble] = report.step
            if first and report.step:  # resumed: those steps are not this sweep's work
                self.sweep.total -= report.step * report.runs
            self.sweep.update((report.step - previous) * report.runs)
            bar = self.bars.get(report.ensemble)
            if bar is None and not report.done:
                taken = {b.pos for b in self.bars.values()}
                position = next(p for p in range(1 if not self.sweep.disable else 0, 1 << 16) if p not in taken)
                bar = self.bars[report.ensemble] = tqdm(
                    total=report.total,
                    initial=report.step,
                    unit="step",
                    unit_scale=True,
                    desc=report.label,
                    dynamic_ncols=True,
                    leave=False,
                    position=position,
                    disable=not self.enabled,
                    mininterval=1.0,
                )
            if bar is not None:
                bar.set_postfix(report.stats, refresh=False)
                bar.update(report.step - bar.n)
                if report.done:
                    bar.close()
                    del self.bars[report.ensemble]

    def close(self) -> None:
        with self.lock:
            for bar in self.bars.values():
                bar.close()
            self.bars.clear()
            self.sweep.close()


class QueueReporter:
    """A picklable ``report`` for a worker process: puts every :class:`Report` on ``queue``."""

    def __init__(self, queue: Any) -> None:
        self.queue = queue

    def __call__(self, report: Report) -> None:
        self.queue.put(report)


class QueueDrain:
    """A thread of this process that hands every report arriving on ``source`` to ``progress``."""

    def __init__(self, source: Any, progress: SweepProgress) -> None:
        self.source, self.progress = source, progress
        self.stopping = threading.Event()
        self.thread = threading.Thread(target=self._run, name="sweep-progress", daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while not self.stopping.is_set() or not self._empty():
            try:
                report = self.source.get(timeout=0.2)
            except queue.Empty:
                continue
            except (EOFError, OSError):  # the queue's manager went away (the sweep is ending)
                return
            self.progress.update(report)

    def _empty(self) -> bool:
        try:
            return self.source.empty()
        except (EOFError, OSError):
            return True

    def stop(self) -> None:
        self.stopping.set()
        self.thread.join()
