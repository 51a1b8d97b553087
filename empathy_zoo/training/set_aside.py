"""Result and agent files set aside while their runs are retrained (``rerun_changed``).

A run retrained because other code made its result file keeps the old files until the new ones
are written: :func:`set_aside` renames ``runs/<run id>.json`` and its agent file to
``<name>.superseded-<pid>-<8 hex>`` (this process's id and a random mark), and afterwards
:func:`settle_superseded` removes each once its run has a new result file, or puts it back.

The suite deletes only names it made: a set-aside file is removed or put back only where its whole
name is of that form, it is a regular file (no link, FIFO or directory), and the process that set
it aside is this one or no live process (a process killed outright leaves its files set aside; the
next call settles them). Any other name (a user's ``x.json.superseded`` backup, one of an earlier
version) is left alone.
"""

from __future__ import annotations

import os
import re
import secrets
import stat
from collections.abc import Collection, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

from empathy_zoo.atomic import MAX_PID, process_alive
from empathy_zoo.result_file import AGENT_SUFFIXES, RUNS_DIR, result_path

__all__ = ["SUPERSEDED_SUFFIX", "set_aside", "settle_superseded"]

SUPERSEDED_SUFFIX = ".superseded"
"""What a set-aside file's name adds to its own before its mark (``-<pid>-<8 hex>``)."""
_SET_ASIDE = re.compile(rf"(?P<name>.+){re.escape(SUPERSEDED_SUFFIX)}-(?P<pid>[1-9][0-9]{{0,9}})-[0-9a-f]{{8}}")
"""The whole name of a file this module set aside, with the setter's process id."""


@contextmanager
def set_aside(out_dir: Path, run_ids: Collection[str]) -> Iterator[None]:
    """Set the result files of ``run_ids`` and the agent files beside them aside while they are
    retrained; afterwards each run's are removed if its new result was written, else put back."""
    mark = f"{os.getpid()}-{secrets.token_hex(4)}"
    moved: list[Path] = []
    try:
        for run_id in sorted(run_ids):
            path = result_path(out_dir, run_id)
            for kept in (path, *(path.with_name(run_id + suffix) for suffix in AGENT_SUFFIXES)):
                if kept == path or kept.exists():
                    moved.append(kept.rename(kept.with_name(f"{kept.name}{SUPERSEDED_SUFFIX}-{mark}")))
        yield
    finally:
        settle_superseded(out_dir / RUNS_DIR, moved)


def _ours(path: Path) -> tuple[str, str] | None:
    """``(its own name, its run id)`` of a file this module set aside that may be settled now (see
    the module page), or ``None``."""
    found = _SET_ASIDE.fullmatch(path.name)
    if found is None:
        return None
    pid = int(found["pid"])
    if pid > MAX_PID or (pid != os.getpid() and process_alive(pid)):
        return None
    try:
        if not stat.S_ISREG(os.lstat(path).st_mode):
            return None
    except OSError:
        return None
    name = found["name"]
    run_id = next((name.removesuffix(end) for end in (".json", *AGENT_SUFFIXES) if name.endswith(end)), None)
    return None if run_id is None else (name, run_id)


def settle_superseded(runs_dir: Path, restore: Iterable[Path] = ()) -> None:
    """Remove every set-aside file of ``runs_dir`` (a result file and its agent file, see the module
    page) whose run has a new result file; put those of ``restore`` without one back."""
    restore = set(restore)
    for old in sorted(runs_dir.glob(f"*{SUPERSEDED_SUFFIX}-*")):
        ours = _ours(old)
        if ours is None:
            continue
        name, run_id = ours
        if (runs_dir / f"{run_id}.json").exists():
            old.unlink()
        elif old in restore:
            old.rename(old.with_name(name))
