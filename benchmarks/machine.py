"""The machine a benchmark ran on, as printed lines (shared by every script in benchmarks/)."""

from __future__ import annotations

import os
import platform
from pathlib import Path

import numpy as np


def cpu_model() -> str:
    try:
        lines = Path("/proc/cpuinfo").read_text().splitlines()
    except OSError:
        lines = []
    return next(
        (line.split(":", 1)[1].strip() for line in lines if line.startswith("model name")), platform.processor() or "unknown CPU"
    )


def describe_machine(*extra: str) -> list[str]:
    """CPU, cores, load, Python and numpy versions, then ``extra`` version strings."""
    load = " ".join(f"{x:.1f}" for x in os.getloadavg())
    versions = ", ".join([f"Python {platform.python_version()}", f"numpy {np.__version__}", *extra])
    return [
        f"CPU: {cpu_model()}, {os.cpu_count()} logical cores, load average {load}",
        f"{versions}, {platform.system()} {platform.release()}",
    ]
