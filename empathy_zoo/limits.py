"""The bounds of every size an input may give, in one table (docs/limits.md states each, one row per bound).

Every number a user, a sweep file, a config file or a result file gives that sizes work or memory
is bounded here: a value beyond its bound is refused with a ``ValueError`` that states the bound
(:func:`check_at_most`), before anything is built, trained or written. The bounds lie far beyond
what the suite's profiles use (the paper's run is 1,000,000 steps, 10 seeds, 10 evaluation
episodes), so nothing within them trains differently; what they refuse would not finish, or not
fit, on any machine. Two bounds are the machine's own: the CPUs (:func:`cpu_count`) and the memory
available when a learner is built (:func:`available_memory`, :func:`check_memory`).

This module imports nothing of the suite: every layer may read it.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Mapping
from typing import Any, BinaryIO

__all__ = [
    "BOUNDS",
    "MAX_AGENT_BYTES",
    "MAX_CHECKPOINT_BYTES",
    "MAX_CONFIG_BYTES",
    "MAX_CYCLES",
    "MAX_EVALUATIONS",
    "MAX_EVAL_EPISODES",
    "MAX_EXACT_TEST_SEEDS",
    "MAX_EXACT_WORK",
    "MAX_EVALUATE_CYCLES",
    "MAX_EVALUATION_BYTES",
    "MAX_FIGURE_PIXELS",
    "MAX_FIGURE_SIDE",
    "MAX_GIF_FRAME_SIDE",
    "MAX_HIDDEN_SIZE",
    "MAX_JOURNAL_BYTES",
    "MAX_JSON_DEPTH",
    "MAX_LABEL",
    "MAX_LOG_CSV_BYTES",
    "MAX_LEARNER_BYTES",
    "MAX_NAME",
    "MAX_NOTE_BYTES",
    "MAX_RANGE_END",
    "MAX_REFERENCE_CYCLES",
    "MAX_REFERENCE_SIZE",
    "MAX_REFERENCE_WORK",
    "MAX_RESULT_BYTES",
    "MAX_RUNS_LIST_BYTES",
    "MAX_RUNS",
    "MAX_SCENARIOS",
    "MAX_SEED",
    "MAX_SEEDS",
    "MAX_SEPARATION_WORK",
    "MAX_SIZE",
    "MAX_STEPS",
    "MAX_TABLE_BYTES",
    "MAX_TRIALS",
    "MAX_VECTOR_ENVS",
    "MAX_WALL_TIME_S",
    "MAX_WATCH_STEPS",
    "available_memory",
    "check_at_most",
    "check_memory",
    "cpu_count",
    "format_bytes",
    "not_a_regular_file",
    "open_regular",
    "read_at_most",
    "read_bounded",
]

MAX_SIZE = 255
"""Largest ``size`` (side of the torus) an environment accepts: the range the suite tests."""
MAX_TABLE_BYTES = 1 << 30
"""Most memory an engine's lookup tables may need (1 GiB); a larger ``view`` is refused."""
MAX_CYCLES = 10**9
"""Longest episode (``max_cycles``), in steps: no run is longer (:data:`MAX_STEPS`)."""
MAX_STEPS = 10**9
"""Most env steps a run trains (``steps``; also the bound of ``eval_interval`` and
``checkpoint_interval``): a thousand times the paper's budget, weeks of training."""
MAX_EVALUATIONS = 10_000
"""Most greedy evaluations of a run (``steps / eval_interval``, rounded up): each is a row of its
result file."""
MAX_EVAL_EPISODES = 10_000
"""Most episodes of one greedy evaluation (``eval_episodes``): an ensemble evaluates
``runs × eval_episodes`` environments at once."""
MAX_EVALUATE_CYCLES = 100_000
"""Longest episode ``empathy-zoo evaluate`` plays (a run's ``max_cycles``, or a scenario's): a
result file may record up to :data:`MAX_CYCLES`, and an evaluation plays every scenario's episodes
to their end; a longer world is refused, naming the run, before anything is written."""
MAX_SEEDS = 10_000
"""Most seeds of one experiment (``seeds = N`` or a list of seeds)."""
MAX_SEED = 2**63 - 1
"""Largest seed (a run id holds it, and it seeds 64-bit random streams)."""
MAX_RUNS = 100_000
"""Most runs one sweep declares (environment variants × grid points × seeds): checked before
the runs are built."""
MAX_SCENARIOS = 1_000
"""Most scenarios of one scenario set (``[scenarios.*]`` tables of a scenario file, the scenarios of
an evaluation file): each is played ``episodes`` times for every run evaluated and is a row of
the held-out tables; the shipped sets hold a few. Counted before any scenario is read."""
MAX_NAME = 200
"""Longest name that becomes part of a file name (a variant, a run id), in characters (file
names are at most 255 bytes on common file systems)."""
MAX_LABEL = 200
"""Longest label (a table row's name: ``--label``, ``label`` of a sweep entry, a method's own
name), in characters."""
MAX_NOTE_BYTES = 1 << 20
"""Largest ``--note`` file of ``reproduction`` and ``sensitivity`` (1 MiB of prose)."""
MAX_CONFIG_BYTES = 1 << 20
"""Largest sweep file or ``train --config`` file (1 MiB)."""
MAX_RESULT_BYTES = 2 << 30
"""Largest result file read (2 GiB): a run's file holds ≈ 60 bytes per training episode, 200 KB at
the paper's settings, 0.6 GB for a run of 10⁹ steps in episodes of 100 steps."""
MAX_EVALUATION_BYTES = 1 << 30
"""Largest evaluation file read (1 GiB): ≈ 100 bytes per episode of each scenario, 10,000
episodes of a few dozen scenarios take a few tens of MB."""
MAX_AGENT_BYTES = 4 << 30
"""Largest agent file read (4 GiB): its networks only, 0.2 MB at the paper's settings."""
MAX_CHECKPOINT_BYTES = 1 << 40
"""Largest checkpoint read (1 TiB): an ensemble's replay memories and networks, ≈ 1 GB for 25
runs at the paper's settings; bounded in practice by the memory of the machine that wrote it."""
MAX_RUNS_LIST_BYTES = 256 << 20
"""Largest list of runs beside a checkpoint read (256 MiB): ≈ 1 KB per run of its ensemble."""
MAX_JOURNAL_BYTES = 1 << 30
"""Largest tuning journal (``study.journal``) read (1 GiB): a few KB per trial."""
MAX_LOG_CSV_BYTES = 16 << 30
"""Largest CSV log (``scalars.csv``) a resumed run reads (16 GiB), row by row: ≈ 0.4 GB for a run
of 10⁹ steps at the default log interval, more where episodes are very short."""
MAX_JSON_DEPTH = 64
"""Deepest nesting of arrays and objects in a JSON file (or journal line) read: the suite's own
nest at most 6 deep; a deeper one is refused before it is parsed."""
MAX_VECTOR_ENVS = 1_000_000
"""Most environments one vector env steps at once (``num_envs``): an ensemble's greedy evaluation
steps ``runs × eval_episodes`` of them, a few KB each at the default sizes."""
MAX_TRIALS = 10_000
"""Most trials of a tuning study (``tune --trials``, ``--startup-trials``)."""
MAX_REFERENCE_SIZE = 21
"""Largest ``size`` of a run whose leaderboard curves get the exact reference: its step matrix is
``(size² + 2)²`` floats (1.5 MB at 21, 31.5 GiB at 255)."""
MAX_REFERENCE_CYCLES = 10_000
"""Longest ``max_cycles`` of a run whose leaderboard curves get the exact reference: it takes one
product with the step matrix per step of an episode, at every point of the curve."""
MAX_REFERENCE_WORK = 100_000_000_000
"""Most work of a leaderboard's reference curves, all groups of runs together, counted as
``points × max_cycles × (size² + 2)²`` per group (``points``: the curve's, 50 by default): one
group at both bounds above takes about 10¹¹, some 20 s on a laptop core; the paper's 50 points at
size 7 and 500 cycles take 6.5·10⁷. A group that would pass it gets no reference curve, said in
one line: a forged directory of many such groups costs one group's time, not each one's."""
MAX_EXACT_WORK = 100_000_000
"""Most work of ``analyse exact``'s table, counted as its model's ``states × max_cycles`` (each of
its 15 points steps every state once a step): about 2.4 µs each on a laptop core, so at most some
four minutes; the default Coexistence (2,401 states, 500 steps) takes 1.2·10⁶, a few seconds."""
MAX_SEPARATION_WORK = 30_000_000_000
"""Most work of ``analyse separation``'s table, counted from its arguments alone as its model's
``states × draws × (value solves × sweeps + outcomes × max_cycles)`` (:func:`baselines.separation_bounds.table_work`:
each solve its value iteration's 3,308 sweeps at γ = 0.99; the Lagrangian's bisection, 19 a ε, counted
where it is computed). Measured at about 8·10⁻⁸ s each on small models (the charger table: 1.05·10⁹,
85 s; Sharing's: 7.2·10⁹, some ten minutes) and 2·10⁻⁷ s or more on large ones (charger size 14:
1.3·10¹⁰, some 48 minutes, estimated from one solve and one outcome timed), so a table past it takes
an hour or more; the charger table at size 21, 6.5·10¹⁰, would take some three hours and is
refused, and the shipped tables take at most a quarter of it. Checked before any model is built."""
MAX_EXACT_TEST_SEEDS = 200
"""Most seeds one exact permutation test compares, both sides together (``N``; the leaderboard's
P(improves on DQN) cells, ``analyse versus-dqn``, ``equivalence``, ``tuning-effect``,
``reproduction``, ``heldout-verdicts``): its null distribution is counted in a table of
``(n + 1) × (N(N + 1) + 1)`` floats (``n`` seeds on the first side), swept once per seed, so memory
grows as ``8·n·N²`` and time as ``n·N³``. Measured on a laptop core: 50 a side 0.07 s; 100 a side
2.0 s and 32 MB; 199 against 1 (the costliest split of 200) about 2.5 times that, 64 MB; 200 a
side 44.5 s and 258 MB; 1,000 a side 8 GB and some 7 hours. The paper compares 10 a side."""
MAX_GIF_FRAME_SIDE = 1_600
"""Most pixels a side of an episode GIF's frame (``watch --gif``, the leaderboard's greedy
episodes) takes for its grid and panel: a grid whose 24-pixel cells would pass it is drawn with
smaller cells (12, 8, 6, 4, 3, 2 or 1 pixels: every 2nd, 3rd, … pixel of the 24-pixel picture),
so sizes up to 54 keep their 24-pixel cells and a 255 × 255 grid is drawn at 4 pixels a cell."""
MAX_WATCH_STEPS = MAX_REFERENCE_CYCLES
"""Most steps ``watch`` plays of one episode: an agent file's ``max_cycles`` may be up to
:data:`MAX_CYCLES`, and a longer episode is cut short there, said before it plays, as the
leaderboard's greedy episodes are (it plays no episode step by step past :data:`MAX_REFERENCE_CYCLES`)."""
MAX_WALL_TIME_S = 10 * 365 * 24 * 3600
"""Longest training time a result file records (``wall_time_s``), in seconds: ten years."""
MAX_LEARNER_BYTES = 1 << 40
"""Most memory of one run's learner a result file records (each figure of ``memory_bytes``), 1 TiB:
the learner's networks and replay memory are what its checkpoint holds (:data:`MAX_CHECKPOINT_BYTES`)."""
MAX_HIDDEN_SIZE = 1 << 19
"""Widest hidden layer a result file records (``hidden_size`` of its settings): one layer of
``hidden_size²`` float32 weights already takes :data:`MAX_LEARNER_BYTES`."""
MAX_RANGE_END = 1e300
"""Largest magnitude of a tuned range's end (``tune --param``, a study's ``plan.params``); a
``log`` range's ``LOW`` is at least its inverse. Every float drawn within such a range, and the
figure's margins past its ends, stay finite."""
MAX_FIGURE_SIDE = 16_384
"""Most pixels a side of ``analyse tuning-summary --figure`` (6.2 inches per variant, 0.38 per study
of a variant, at 110 dpi: 24 variants, or 389 studies of one)."""
MAX_FIGURE_PIXELS = 32_000_000
"""Most pixels of ``analyse tuning-summary --figure`` in all: 128 MB of RGBA buffer while it is drawn."""

BOUNDS: Mapping[str, int] = {
    "size": MAX_SIZE,
    "lookup tables": MAX_TABLE_BYTES,
    "max_cycles": MAX_CYCLES,
    "steps": MAX_STEPS,
    "eval_interval": MAX_STEPS,
    "checkpoint_interval": MAX_STEPS,
    "evaluations per run": MAX_EVALUATIONS,
    "eval_episodes": MAX_EVAL_EPISODES,
    "evaluate episode steps": MAX_EVALUATE_CYCLES,
    "seeds per experiment": MAX_SEEDS,
    "seed": MAX_SEED,
    "runs per sweep": MAX_RUNS,
    "scenarios per set": MAX_SCENARIOS,
    "names": MAX_NAME,
    "labels": MAX_LABEL,
    "note file": MAX_NOTE_BYTES,
    "sweep and config files": MAX_CONFIG_BYTES,
    "result file": MAX_RESULT_BYTES,
    "evaluation file": MAX_EVALUATION_BYTES,
    "agent file": MAX_AGENT_BYTES,
    "checkpoint": MAX_CHECKPOINT_BYTES,
    "list of runs": MAX_RUNS_LIST_BYTES,
    "tuning journal": MAX_JOURNAL_BYTES,
    "CSV log": MAX_LOG_CSV_BYTES,
    "JSON nesting": MAX_JSON_DEPTH,
    "num_envs": MAX_VECTOR_ENVS,
    "trials": MAX_TRIALS,
    "reference curve size": MAX_REFERENCE_SIZE,
    "reference curve max_cycles": MAX_REFERENCE_CYCLES,
    "reference curves' work": MAX_REFERENCE_WORK,
    "exact table's work": MAX_EXACT_WORK,
    "separation table's work": MAX_SEPARATION_WORK,
    "seeds of one exact test": MAX_EXACT_TEST_SEEDS,
    "watch episode steps": MAX_WATCH_STEPS,
    "GIF frame size": MAX_GIF_FRAME_SIDE,
    "wall_time_s": MAX_WALL_TIME_S,
    "memory_bytes": MAX_LEARNER_BYTES,
    "hidden_size recorded": MAX_HIDDEN_SIZE,
}
"""Every fixed bound, by what docs/limits.md calls it (the machine's own, ``threads``, ``workers``
and a learner's memory, are :func:`cpu_count` and :func:`available_memory`)."""


def check_at_most(name: str, value: Any, bound: int, why: str = "") -> Any:
    """``value`` if it is at most ``bound``, else a ``ValueError`` naming ``name`` and stating the bound."""
    if value > bound:
        reason = f" ({why})" if why else ""
        raise ValueError(f"{name} must be at most {bound:,}{reason}, got {_shown(value)} (docs/limits.md)")
    return value


def _shown(value: Any) -> str:
    """``value`` for a message: a huge integer by its number of digits, not its 5,000 digits."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**30:
        return f"an integer of about {int(abs(value).bit_length() * 0.30103) + 1:,} digits"
    return f"{value:,}" if isinstance(value, int) else repr(value)


def cpu_count() -> int:
    """The CPUs of this machine (``os.cpu_count()``; 1 where it cannot tell): the bound of
    ``threads`` and ``workers``."""
    return os.cpu_count() or 1


def format_bytes(count: float) -> str:
    """``count`` bytes in the unit that reads best (``"41.0 MB"``, ``"40.0 PB"``; powers of 1024)."""
    for unit in ("bytes", "KB", "MB", "GB", "TB", "PB", "EB"):
        if abs(count) < 1024 or unit == "EB":
            return f"{count:,.0f} {unit}" if unit == "bytes" else f"{count:,.1f} {unit}"
        count /= 1024
    raise AssertionError("unreachable")


def _meminfo_available(path: str = "/proc/meminfo") -> int | None:
    """``MemAvailable`` of ``/proc/meminfo`` in bytes (Linux), or ``None`` where there is none."""
    try:
        with open(path, encoding="ascii") as handle:
            for line in handle:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


def available_memory(device: str = "cpu") -> tuple[int | None, str]:
    """Bytes of memory free for a new allocation on ``device``, and where the figure comes from:
    on a CUDA device, what it has free (``torch.cuda.mem_get_info``); elsewhere, the host's
    available memory (``MemAvailable`` of ``/proc/meminfo``, else the free physical pages of
    ``os.sysconf``, else its physical memory). ``(None, why)`` where nothing tells."""
    if device.startswith("cuda"):
        try:
            import torch

            return int(torch.cuda.mem_get_info(torch.device(device))[0]), f"free on {device}"
        except Exception as error:  # no CUDA here: the device check says so elsewhere
            return None, f"{device} cannot tell ({type(error).__name__})"
    if device != "cpu" and not device.startswith("cpu:"):
        return None, f"{device} cannot tell"
    available = _meminfo_available()
    if available is not None:
        return available, "available on this machine (MemAvailable)"
    for pages, what in (("SC_AVPHYS_PAGES", "free on this machine"), ("SC_PHYS_PAGES", "of this machine")):
        try:
            return int(os.sysconf(pages)) * int(os.sysconf("SC_PAGE_SIZE")), what
        except (AttributeError, ValueError, OSError):
            continue
    return None, "this machine cannot tell"


def check_memory(needed: int, device: str, what: str, advice: str) -> None:
    """Refuse (``ValueError``) ``what`` when the ``needed`` bytes exceed the memory available on
    ``device`` (:func:`available_memory`), stating both figures and ``advice``; nothing is
    refused where the machine cannot tell."""
    available, source = available_memory(device)
    if available is not None and needed > available:
        raise ValueError(
            f"{what} need about {format_bytes(needed)} of memory, more than the {format_bytes(available)} "
            f"{source}: {advice} (docs/limits.md)"
        )


def open_regular(path: str | os.PathLike[str], what: str) -> BinaryIO:
    """``path`` opened for reading in binary, once it is known to be a regular file of at most the
    size it has; anything else (a FIFO, a device, a directory, a socket) is refused with a
    ``ValueError`` naming it, without waiting on it: it is opened with ``O_NONBLOCK`` (a FIFO with no
    writer does not hang), then checked with ``fstat`` on the open descriptor. A missing file raises
    ``FileNotFoundError``, as ``open`` does."""
    name = os.fspath(path)
    try:
        fd = os.open(name, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
    except FileNotFoundError:
        raise  # (as open() raises it: a caller says which file is missing, and why it was looked for)
    except OSError as error:
        raise ValueError(f"cannot read {what} {name} ({error.strerror or error})") from None
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            kind = _KINDS.get(stat.S_IFMT(mode), "not a regular file")
            raise ValueError(f"{what} {name} is {kind}, not a regular file; give a file")
        if hasattr(os, "set_blocking"):
            os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


_KINDS = {
    stat.S_IFIFO: "a FIFO (named pipe)",
    stat.S_IFCHR: "a character device",
    stat.S_IFBLK: "a block device",
    stat.S_IFDIR: "a directory",
    stat.S_IFSOCK: "a socket",
}
"""What a file that is no regular file is, as a refusal says it."""


def not_a_regular_file(path: str | os.PathLike[str]) -> str | None:
    """What is at ``path`` when it is no regular file (or link to one), as a refusal says it after
    the file's name (``"does not exist"``, ``"is a FIFO (named pipe), not a regular file"``, ``"is a
    dangling symbolic link (to x), not a regular file"``), or ``None`` for a regular file. Nothing is
    opened: a FIFO or a device is told apart by ``stat`` alone."""
    name = os.fspath(path)
    try:
        mode = os.stat(name).st_mode
    except FileNotFoundError:
        if os.path.islink(name):
            return f"is a dangling symbolic link (to {os.readlink(name)}), not a regular file"
        return "does not exist"
    except OSError as error:
        return f"cannot be examined ({error.strerror or error})"
    if stat.S_ISREG(mode):
        return None
    kind = _KINDS.get(stat.S_IFMT(mode), "not a regular file")
    link = f" (a symbolic link to {os.readlink(name)})" if os.path.islink(name) else ""
    return f"is {kind}{link}, not a regular file"


def read_bounded(path: str | os.PathLike[str], bound: int, what: str) -> bytes:
    """The bytes of the regular file ``path`` (:func:`open_regular`), or a ``ValueError`` naming it
    when it holds more than ``bound`` bytes: its size (``fstat`` of the open file) is compared with
    ``bound`` before a byte is read, and at most ``bound + 1`` bytes are read (a file growing
    meanwhile is refused too), so a huge file is refused at once, never read. A dangling symbolic
    link in the file's place is a ``ValueError`` naming it; a missing file raises
    ``FileNotFoundError``, as ``open`` does."""
    name = os.fspath(path)
    too_large = f"{what} {name} is larger than {format_bytes(bound)}, the most it may be (docs/limits.md)"
    try:
        handle = open_regular(path, what)
    except FileNotFoundError:
        if os.path.islink(name):
            raise ValueError(
                f"{what} {name} is a dangling symbolic link (to {os.readlink(name)}), not a regular file; move it away"
            ) from None
        raise
    with handle:
        size = os.fstat(handle.fileno()).st_size
        if size > bound:
            raise ValueError(too_large)
        data = read_at_most(handle, bound + 1, size + 1)
    if len(data) > bound:
        raise ValueError(too_large)
    return data


READ_CHUNK = 1 << 20
"""Bytes :func:`read_at_most` asks for at once past a file's stated size (1 MiB)."""


def read_at_most(handle: BinaryIO, most: int, expected: int = 0) -> bytes:
    """At most ``most`` bytes of ``handle``, read until its end, with memory that tracks the bytes
    actually read: ``min(expected, most)`` bytes first (a regular file's size and one more, so its
    end is seen in one read), then :data:`READ_CHUNK` at a time (a file that grows meanwhile, one
    whose size says nothing, as ``/proc``'s). Never one read of ``most`` bytes: ``read(n)``
    reserves ``n`` bytes before it reads one, so a small file read under a cap of 4 GB would take
    4 GB of memory."""
    chunks: list[bytes] = []
    total = 0
    want = min(max(expected, 1), most)
    while total < most:
        chunk = handle.read(want)
        chunks.append(chunk)
        total += len(chunk)
        if len(chunk) < want:  # (a buffered read returns less only at the file's end)
            break
        want = min(READ_CHUNK, most - total)
    return chunks[0] if len(chunks) == 1 else b"".join(chunks)
