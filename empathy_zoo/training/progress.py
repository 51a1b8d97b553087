"""Progress of a sweep on one terminal: every bar is drawn by the process that started the sweep.

Ensembles (in this process or in worker processes) only *report* (:class:`Report`): where they
are, their live numbers, a line to print. :class:`SweepProgress` draws them: one bar per running
ensemble, redrawn in place and removed when it finishes, and, for a sweep of several ensembles,
one sweep bar counting the env steps of every run still to train, so its rate and ETA are those
of the whole sweep (a bar counting finished runs would stand still until whole ensembles end).
Worker processes send their reports through a queue (:class:`QueueReporter`); nothing they do
touches the terminal, so bars of several workers cannot overwrite one another.

Where the output is no terminal (a log file, a CI job), bars would fill it with carriage returns:
there progress is plain lines (:class:`PlainBar`), one every :data:`PLAIN_INTERVAL_S` seconds and one
at the end, each with the steps done, the rate and the time left. ``style`` chooses: ``auto`` (bars
on a terminal, else lines), ``bars`` or ``plain``.
"""

from __future__ import annotations

import queue
import sys
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from tqdm.auto import tqdm

__all__ = [
    "PLAIN_INTERVAL_S",
    "PROGRESS_STYLES",
    "PlainBar",
    "QueueDrain",
    "QueueReporter",
    "Report",
    "SweepProgress",
    "progress_bar",
    "resolve_style",
]

PROGRESS_STYLES = ("auto", "bars", "plain")
"""How progress is shown: ``auto`` (bars on a terminal, plain lines elsewhere), ``bars``, ``plain``."""
PLAIN_INTERVAL_S = 30.0
"""Seconds between two plain progress lines of the same bar (the last line comes at the end)."""


def resolve_style(style: str) -> str:
    """``bars`` or ``plain``: ``style`` itself, or for ``auto`` bars where standard error is a
    terminal and plain lines where it is not (``ValueError`` for a style not in :data:`PROGRESS_STYLES`)."""
    if style not in PROGRESS_STYLES:
        raise ValueError(f"progress style must be one of {', '.join(PROGRESS_STYLES)}, got {style!r}")
    if style != "auto":
        return style
    isatty = getattr(sys.stderr, "isatty", None)
    return "bars" if isatty is not None and isatty() else "plain"


def _duration(seconds: float) -> str:
    """``seconds`` as a person reads a time left: ``40 s``, ``12 min``, ``3 h 05 min``."""
    if seconds < 60:
        return f"{seconds:.0f} s"
    minutes = round(seconds / 60)
    return f"{minutes} min" if minutes < 60 else f"{minutes // 60} h {minutes % 60:02d} min"


class PlainBar:
    """A progress bar written as plain lines on standard error: ``desc: n of total units (p %),
    rate units/s, about T left`` at most once every ``interval`` seconds of ``clock`` (default
    ``time.monotonic``), and once when
    it closes. It takes the calls the suite makes of a ``tqdm`` bar."""

    def __init__(
        self,
        total: int,
        desc: str,
        unit: str,
        initial: int = 0,
        disable: bool = False,
        interval: float = PLAIN_INTERVAL_S,
        clock: Callable[[], float] | None = None,
    ) -> None:
        self.total, self.desc, self.unit, self.n, self.disable = total, desc, unit, initial, disable
        self.interval = interval
        self.clock = clock or time.monotonic
        self.started = self.printed = self.clock()
        self.first = initial
        self.postfix = ""
        self.shown = initial
        self.closed = False

    def update(self, n: int = 1) -> None:
        """Count ``n`` more; write a line if the last one is ``interval`` seconds old."""
        self.n += n
        if not self.disable and self.clock() - self.printed >= self.interval:
            self._line()

    def set_postfix(self, stats: dict[str, Any] | None = None, refresh: bool = False) -> None:
        """Live numbers shown at the end of the next line."""
        self.postfix = ", ".join(f"{key}={value}" for key, value in (stats or {}).items())

    def set_postfix_str(self, text: str = "", refresh: bool = False) -> None:
        """A text shown at the end of the next line."""
        self.postfix = text

    def close(self) -> None:
        """Write the last line (if anything was counted since the one before)."""
        if not self.closed and not self.disable and self.n != self.shown:
            self._line()
        self.closed = True

    def __enter__(self) -> PlainBar:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _line(self) -> None:
        now = self.clock()
        elapsed = now - self.started
        rate = (self.n - self.first) / elapsed if elapsed > 0 else 0.0
        parts = [f"{self.desc}: {self.n:,} of {self.total:,} {self.unit}s"]
        if self.total > 0:
            parts[0] += f" ({100 * self.n / self.total:.0f} %)"
        if rate > 0:
            parts.append(f"{rate:,.1f} {self.unit}s/s" if rate < 10 else f"{rate:,.0f} {self.unit}s/s")
            if self.n < self.total:
                parts.append(f"about {_duration((self.total - self.n) / rate)} left")
        if self.postfix:
            parts.append(self.postfix)
        print(", ".join(parts), file=sys.stderr, flush=True)
        self.printed, self.shown = now, self.n


def progress_bar(style: str, *, total: int, desc: str, unit: str, initial: int = 0, disable: bool = False) -> Any:
    """A ``tqdm`` bar (style ``bars``) or a :class:`PlainBar` (style ``plain``; ``auto`` as
    :func:`resolve_style` decides) counting ``total`` units."""
    if resolve_style(style) == "plain":
        return PlainBar(total, desc, unit, initial=initial, disable=disable)
    return tqdm(total=total, initial=initial, desc=desc, unit=unit, disable=disable, dynamic_ncols=True, mininterval=1.0)


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
    """The bars of a sweep of ``ensembles`` (``(runs, steps)`` per ensemble) in this process; in
    the ``plain`` style (:func:`resolve_style`) one :class:`PlainBar` of the sweep's env steps, a
    line per ensemble that finishes and the ensembles' own lines."""

    def __init__(self, ensembles: Sequence[tuple[int, int]], enabled: bool = True, style: str = "auto") -> None:
        self.enabled = enabled
        self.plain = resolve_style(style) == "plain"
        self.lock = threading.Lock()
        self.bars: dict[int, tqdm] = {}
        self.steps: dict[int, int] = {}
        total = sum(runs * steps for runs, steps in ensembles)
        self.sweep: Any
        if self.plain:
            self.sweep = PlainBar(total, "sweep", "step", disable=not enabled)
            return
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
                if self.plain:
                    print(report.line, file=sys.stderr, flush=True)
                else:
                    tqdm.write(report.line)
            first = report.ensemble not in self.steps
            previous = self.steps.get(report.ensemble, report.step)
            self.steps[report.ensemble] = report.step
            if first and report.step:  # resumed: those steps are not this sweep's work
                self.sweep.total -= report.step * report.runs
            self.sweep.update((report.step - previous) * report.runs)
            if self.plain:
                if report.done and self.enabled:
                    line = f"finished {report.label} ({report.runs} run(s), {report.step:,} steps each)"
                    print(line, file=sys.stderr, flush=True)
                return
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
