"""Run the command line and SIGKILL this very process at a chosen moment (for the crash test).

    python tests/helpers_crash.py '{"hook": "checkpoint", "count": 3, "when": "after"}' reproduce --profile …

``hook`` names a place the suite passes through (an env step, a checkpoint, a result file, the
rename or the fsync of an atomic write, the list of an ensemble's runs); the process kills itself
with SIGKILL on the ``count``-th pass, ``before`` or ``after`` it. No handler, ``finally`` or
atexit runs: it is the same as ``kill -9`` from outside at that moment, but always the same moment.
"""

from __future__ import annotations

import json
import os
import signal
import sys
from collections.abc import Callable
from typing import Any


def killing(function: Callable[..., Any], count: int, when: str) -> Callable[..., Any]:
    passes = [0]

    def wrapper(*args: Any, **kwargs: Any) -> Any:
        passes[0] += 1
        if passes[0] == count and when == "before":
            os.kill(os.getpid(), signal.SIGKILL)
        result = function(*args, **kwargs)
        if passes[0] == count and when == "after":
            os.kill(os.getpid(), signal.SIGKILL)
        return result

    return wrapper


def install(hook: str, count: int, when: str) -> None:
    import empathy_zoo.training.ensemble as ensemble
    from empathy_zoo.vector import VectorEnv

    if hook == "step":
        VectorEnv.step = killing(VectorEnv.step, count, when)
    elif hook in ("checkpoint", "result", "manifest"):
        name = {"checkpoint": "save_checkpoint", "result": "write_result", "manifest": "write_manifest"}[hook]
        setattr(ensemble, name, killing(getattr(ensemble, name), count, when))
    elif hook in ("replace", "fsync"):
        setattr(os, hook, killing(getattr(os, hook), count, when))
    else:
        raise ValueError(f"unknown hook {hook!r}")


if __name__ == "__main__":
    plan = json.loads(sys.argv[1])
    if plan:
        install(plan["hook"], int(plan["count"]), plan["when"])
    from empathy_zoo.cli import main

    sys.exit(main(sys.argv[2:]))
