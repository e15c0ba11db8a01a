"""The machine a result came from, for run.json and the benchmarks' reports."""

from __future__ import annotations

import os
import platform


def cpu_model() -> str:
    """The CPU's model name (``/proc/cpuinfo``), else what ``platform`` knows."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    return cpu


def usable_cores() -> int:
    """The cores this process may run on: its CPU affinity (what ``taskset``, ``numactl`` or a
    container's cpuset leave it), not the machine's count (``os.cpu_count()``), so that a job
    pinned to 4 of 16 cores asks for 4 host devices, not 16 (XLA sizes its threads the same way)."""
    try:
        return len(os.sched_getaffinity(0)) or 1
    except (AttributeError, OSError):  # no affinity on this platform (macOS, Windows)
        return os.cpu_count() or 1
