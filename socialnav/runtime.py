"""Runtime set-up of the ``socialnav`` command: XLA host devices, vector width and JAX's
compilation cache.

All must happen before JAX is imported to take full effect, which is why only the composition
root does them (this module does not import JAX): library code never changes the process's
devices or caches behind a user's back."""

from __future__ import annotations

import os

from socialnav.common.machine import cpu_isa, usable_cores


def request_host_devices(n: int | None = None) -> None:
    """Ask XLA for ``n`` CPU devices (default: the cores this process may run on,
    :func:`common.machine.usable_cores`) so that ``shard_map`` can use every core; measured here:
    2 devices on 2 cores nearly double the simulator's throughput.

    Must run before ``import jax``; does nothing if ``XLA_FLAGS`` already sets a device count.
    """
    flags = os.environ.get("XLA_FLAGS", "")
    if "xla_force_host_platform_device_count" in flags:
        return
    n = usable_cores() if n is None else n
    os.environ["XLA_FLAGS"] = f"{flags} --xla_force_host_platform_device_count={n}".strip()


# The wider vectors XLA's CPU code may use where the processor has them (LLVM's preferred width;
# XLA's default is 256 bits even on AVX-512 processors).
WIDE_VECTOR_BITS = 512
_WIDTH_FLAG = "--xla_cpu_prefer_vector_width"


def cpu_has_avx512(cpuinfo: str | None = None) -> bool:
    """Whether the processor reports AVX-512F (Linux ``/proc/cpuinfo``, or ``cpuinfo``, that file's
    text; False where unreadable)."""
    return cpu_isa(cpuinfo) == "AVX-512"


def request_wide_vectors(cpuinfo: str | None = None) -> None:
    """Let XLA's CPU code use 512-bit vectors on a processor with AVX-512F.

    Measured on this project's 2-core AMD EPYC: the full warehouse step 14 % faster
    (``benchmarks/bench_simulator.py``, interleaved runs; 16 % in ``benchmarks/profile_step.py``),
    the 4-replica evaluation protocol 11 % (every elementwise kernel of the social force is
    compute-bound).
    Float results per operation are unchanged (IEEE arithmetic does not depend on the vector
    width); sums may be associated differently, so a day's logs are bitwise reproducible for a
    given setting and agree with the other to float rounding (here they were even bitwise equal:
    the same day digest, the same 133,760 protocol tasks). Must run before ``import
    jax``; does nothing if ``XLA_FLAGS`` already sets the width (``--xla_cpu_prefer_vector_width=256``
    turns it off) or the processor lacks AVX-512F. Processes started by :mod:`socialnav.backend`
    inherit the driver's ``XLA_FLAGS``.
    """
    flags = os.environ.get("XLA_FLAGS", "")
    if _WIDTH_FLAG in flags or not cpu_has_avx512(cpuinfo):
        return
    os.environ["XLA_FLAGS"] = f"{flags} {_WIDTH_FLAG}={WIDE_VECTOR_BITS}".strip()


def request_compilation_cache(path: str | None = None) -> None:
    """Keep XLA's compiled programs on disk (JAX's persistent compilation cache), so that a later
    process skips compiling what an earlier one compiled: measured here, the first GSCL dataset
    of a new process costs 14.8 s with compilation and 8.3 s from the cache (tracing remains).

    The folder is ``path``, else ``$SOCIALNAV_JAX_CACHE``, else ``~/.cache/socialnav-jax/xla``;
    ``SOCIALNAV_JAX_CACHE=off`` switches it off. Does nothing if ``JAX_COMPILATION_CACHE_DIR`` is
    already set. Best called before ``import jax``; afterwards it updates JAX's config.
    """
    import pathlib
    import sys

    if os.environ.get("JAX_COMPILATION_CACHE_DIR"):
        return
    setting = path or os.environ.get("SOCIALNAV_JAX_CACHE", "")
    if setting.lower() in ("off", "0", "none", "false"):
        return
    folder = setting or str(pathlib.Path.home() / ".cache" / "socialnav-jax" / "xla")
    os.environ["JAX_COMPILATION_CACHE_DIR"] = folder
    if "jax" in sys.modules:
        sys.modules["jax"].config.update("jax_compilation_cache_dir", folder)


def quiet_third_party_logs() -> None:
    """Keep libraries' chatter out of the user's terminal: absl's log lines from orbax (``read_only=True,
    setting max_to_keep=None``, ``Given directory is read only``, its own error for a damaged checkpoint
    that the toolkit reports in one line of its own) and asyncio's "Event loop is closed" from orbax's
    background threads at exit. ``SOCIALNAV_VERBOSE=1`` keeps them."""
    import logging
    import sys

    if os.environ.get("SOCIALNAV_VERBOSE", "") not in ("", "0"):
        return
    for name in ("absl", "asyncio", "orbax"):
        logging.getLogger(name).setLevel(logging.CRITICAL)
    # JAX's note on backends it did not find ("Unable to initialize backend 'tpu'") is INFO, shown
    # once PedPy has given the root logger a handler at that level.
    logging.getLogger("jax").setLevel(logging.WARNING)
    previous = sys.unraisablehook

    def hook(unraisable):
        if isinstance(unraisable.exc_value, RuntimeError) and "Event loop is closed" in str(unraisable.exc_value):
            return
        previous(unraisable)

    sys.unraisablehook = hook
