"""What a resumed run reads of its earlier logs, each file checked before anything trains.

A resumed ensemble finds the logs of its runs' earlier part in ``<out>/logs/<backend>/<run id>/``
(:mod:`empathy_zoo.training.tracking`). Those files lie in a directory anyone may have written
to, so they are data: :func:`check_earlier_logs` checks them before the first logger opens.

* ``csv``: ``scalars.csv`` at most :data:`~empathy_zoo.limits.MAX_LOG_CSV_BYTES`, read row by row
  (memory stays flat), UTF-8, its header ``step,name,value``, each row a whole step within
  :data:`~empathy_zoo.limits.MAX_STEPS`, a printable name of at most
  :data:`~empathy_zoo.limits.MAX_NAME` characters and a number. Only the last row may be cut
  short (a crash): :func:`keep_csv_rows_up_to` drops it.
* ``tensorboard``: every ``events.out.tfevents.<second>.…`` name's second at most
  :data:`CLOCK_SLACK_S` past this machine's clock. A resumed run waits until its own file's name
  sorts after theirs (:func:`after_earlier_event_files`), so a name from the far future would
  make it wait for ever.

A refusal is one ``ValueError`` line naming the file.
"""

from __future__ import annotations

import csv
import io
import math
import time
from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO

from empathy_zoo.atomic import write_with_atomic
from empathy_zoo.limits import MAX_LOG_CSV_BYTES, MAX_NAME, MAX_STEPS

__all__ = [
    "CLOCK_SLACK_S",
    "CSV_HEADER",
    "EVENT_FILE_PREFIX",
    "after_earlier_event_files",
    "check_csv_log",
    "check_event_file_names",
    "keep_csv_rows_up_to",
]

CSV_HEADER = ["step", "name", "value"]
"""The first row of every ``scalars.csv``."""
EVENT_FILE_PREFIX = "events.out.tfevents."
"""How every TensorBoard event file's name begins; its next part is the second it was begun."""
CLOCK_SLACK_S = 5
"""Seconds an earlier event file's name may lie ahead of this machine's clock (clocks of two
machines sharing a directory differ by that much); a resumed run waits at most that long."""
_MOVE_AWAY = "not the log a run of this suite writes: move it away (the resumed run logs afresh)"


def _refuse(path: Path, line: int, why: str) -> ValueError:
    return ValueError(f"{path}: line {line:,}: {why}; {_MOVE_AWAY}")


def _row_problem(row: list[str]) -> str | None:
    """Why ``row`` is no ``step,name,value`` row of a log, or ``None``."""
    if len(row) != 3:
        return f"{len(row)} fields where a row has 3 (step, name, value)"
    step, name, value = row
    if not step.isascii() or not step.isdigit() or len(step) > 10 or int(step) > MAX_STEPS:
        return f"the step {step[:40]!r} is no whole number of steps (at most {MAX_STEPS:,})"
    if not name or len(name) > MAX_NAME or not name.isprintable():
        return f"the name {name[:40]!r} is no printable name of 1 to {MAX_NAME} characters"
    if len(value) > 40:
        return f"the value {value[:40]!r}… is no number"
    try:
        float(value)
    except ValueError:
        return f"the value {value!r} is no number"
    return None


def _rows(path: Path) -> Iterator[tuple[int, list[str], bool]]:
    """``(line, row, last)`` of the CSV file ``path``, read row by row; a row the CSV reader or
    UTF-8 cannot read is a ``ValueError`` naming the file and line."""
    with path.open(newline="", encoding="utf-8") as file:
        reader = csv.reader(file)
        line = 0
        try:
            previous = next(reader, None)
            while previous is not None:
                line = reader.line_num
                current = next(reader, None)
                yield line, previous, current is None
                previous = current
        except csv.Error as error:
            raise _refuse(path, reader.line_num, f"no CSV row ({error})") from None
        except UnicodeDecodeError as error:
            raise _refuse(path, line + 1, f"no UTF-8 text ({error.reason} at byte {error.start})") from None


def check_csv_log(path: Path) -> None:
    """Refuse (``ValueError`` naming it) a run's ``scalars.csv`` that is no log a run wrote: larger
    than :data:`~empathy_zoo.limits.MAX_LOG_CSV_BYTES`, not UTF-8, a header other than
    ``step,name,value``, or a row but the last that is no ``step,name,value`` (the last may be cut
    short by a crash). Nothing there, or an empty file, passes."""
    if not path.is_file():
        return
    size = path.stat().st_size
    if size > MAX_LOG_CSV_BYTES:
        raise ValueError(
            f"{path}: {size:,} bytes, past the bound of {MAX_LOG_CSV_BYTES:,} of a run's CSV log a resumed run reads "
            "(docs/limits.md); move it away (the resumed run logs afresh)"
        )
    for line, row, last in _rows(path):
        if line == 1:
            if row != CSV_HEADER:
                raise _refuse(path, 1, f"the header {','.join(row)[:80]!r} is not {','.join(CSV_HEADER)}")
            continue
        problem = _row_problem(row)
        if problem is not None and not last:
            raise _refuse(path, line, problem)


def keep_csv_rows_up_to(path: Path, step: int) -> None:
    """Rewrite the CSV file ``path`` (checked by :func:`check_csv_log`) keeping its header and the
    rows of steps up to ``step`` (a resumed run logs the later ones again), row by row; a row cut
    by a crash is dropped."""
    check_csv_log(path)

    def write(handle: BinaryIO) -> None:
        text = io.TextIOWrapper(handle, encoding="utf-8", newline="")
        writer = csv.writer(text)
        for line, row, _ in _rows(path):
            if line == 1 or (_row_problem(row) is None and int(row[0]) <= step):
                writer.writerow(row)
        text.flush()
        text.detach()

    write_with_atomic(path, write)


def _event_second(path: Path) -> float | None:
    """The second an event file's name says it was begun (``math.inf`` for a number of more than
    12 digits: past any clock), or ``None`` for a name that holds none."""
    part = path.name.removeprefix(EVENT_FILE_PREFIX).partition(".")[0]
    if not part.isascii() or not part.isdigit():
        return None
    return math.inf if len(part) > 12 else int(part)


def check_event_file_names(directory: Path) -> float | None:
    """The latest second an event file of ``directory`` names (``None`` without one); a
    ``ValueError`` naming a file whose second lies more than :data:`CLOCK_SLACK_S` past this
    machine's clock."""
    seconds = {}
    for path in directory.glob(f"{EVENT_FILE_PREFIX}*"):
        second = _event_second(path)
        if second is not None:
            seconds[path] = second
    if not seconds:
        return None
    latest = max(seconds, key=seconds.__getitem__)
    now = time.time()
    if seconds[latest] > now + CLOCK_SLACK_S:
        raise ValueError(
            f"{latest}: its name says it was begun past this machine's clock (more than {CLOCK_SLACK_S} s ahead): a "
            f"resumed run would wait for that second to log after it; {_MOVE_AWAY}"
        )
    return seconds[latest]


def after_earlier_event_files(directory: Path) -> None:
    """Return once a new event file of ``directory`` sorts after its earlier ones (checked by
    :func:`check_event_file_names`: at most :data:`CLOCK_SLACK_S` ahead). TensorBoard reads a run's
    files in the order of their names, ``events.out.tfevents.<second>.<host>.<pid>…``, and a
    resumed run's purge of the steps after its checkpoint holds only for the files before its own:
    one resumed within the second its earlier file was begun waits for the next second."""
    latest = check_event_file_names(directory)
    while latest is not None and int(time.time()) <= latest:
        time.sleep(0.05)
