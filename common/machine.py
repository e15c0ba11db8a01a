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


def cpu_flags(cpuinfo: str | None = None) -> str:
    """The ``flags`` line of ``/proc/cpuinfo``, or of ``cpuinfo`` (that file's text) when given;
    empty where there is none (macOS, Windows)."""
    if cpuinfo is not None:
        return next((line for line in cpuinfo.splitlines() if line.startswith("flags")), "")
    try:
        with open("/proc/cpuinfo", encoding="ascii", errors="replace") as f:
            return next((line for line in f if line.startswith("flags")), "")
    except OSError:
        return ""


def cpu_isa(cpuinfo: str | None = None) -> str:
    """The processor's widest x86 vector instructions: ``"AVX-512"``, ``"AVX2"``, or ``"other"``
    (``cpuinfo``: :func:`cpu_flags`)."""
    names = set(cpu_flags(cpuinfo).split())
    if "avx512f" in names:
        return "AVX-512"
    return "AVX2" if "avx2" in names else "other"


def compiler_host() -> dict:
    """What a result's rounding depends on beyond its seed and settings: XLA compiles for the host
    CPU (its model as well as its instruction set), so the same program can round differently on
    another processor, even one of the same instruction set (or under another
    ``--xla_cpu_max_isa``), and with other jax/jaxlib versions. ``{"jax", "jaxlib", "cpu",
    "isa", "machine", "xla_flags"}``, for a run's records (``run.json``, a training's history)."""
    import jax
    import jaxlib

    return {
        "jax": jax.__version__,
        "jaxlib": jaxlib.__version__,
        "cpu": cpu_model(),
        "isa": cpu_isa(),
        "machine": platform.machine(),
        "xla_flags": os.environ.get("XLA_FLAGS", ""),
    }


def hosts_of(history: list[dict]) -> list[dict]:
    """The hosts a training ran on: each line's ``host`` (:func:`compiler_host`, recorded per GSCL
    epoch and per PPO update), each once, in the order first met; none for lines written before
    hosts were recorded. A model's weights round as its training's processor did: the same recipe
    and seed trained on another instruction set is another model."""
    hosts = []
    for line in history:
        if "host" in line and line["host"] not in hosts:
            hosts.append(line["host"])
    return hosts


def usable_cores() -> int:
    """The cores this process may run on: its CPU affinity (what ``taskset``, ``numactl`` or a
    container's cpuset leave it), not the machine's count (``os.cpu_count()``), so that a job
    pinned to 4 of 16 cores asks for 4 host devices, not 16 (XLA sizes its threads the same way)."""
    try:
        return len(os.sched_getaffinity(0)) or 1
    except (AttributeError, OSError):  # no affinity on this platform (macOS, Windows)
        return os.cpu_count() or 1
