"""The machine a benchmark runs on, as the benchmarks print it (``from machine import
machine``: the benchmarks run as scripts, ``python benchmarks/NAME.py``, with this
directory on ``sys.path``)."""

from __future__ import annotations

import os
import platform


def machine() -> str:
    """The CPU's model name and the number of logical CPUs."""
    try:
        with open("/proc/cpuinfo") as f:
            name = next(
                line.split(":", 1)[1].strip() for line in f if line.startswith("model name")
            )
    except (OSError, StopIteration):
        name = platform.processor() or "unknown CPU"
    return f"{name}, {os.cpu_count()} logical CPUs"
