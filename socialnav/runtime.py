"""Runtime set-up of the ``socialnav`` command: XLA host devices, vector width and JAX's
compilation cache (kept on disk, and repaired where an entry was cut short).

All must happen before JAX is imported to take full effect, which is why only the composition
root does them (this module does not import JAX; the cache's repair uses JAX's own reading of an
entry once JAX has warned about one, and the check of ``JAX_PLATFORMS`` runs once the command's
module has imported JAX): library code never changes the process's devices or caches
behind a user's back."""

from __future__ import annotations

import os
import re

from socialnav.common.cache import folder_problem
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


# JAX's reading of a boolean environment variable (``jax._src.config.bool_env``): any other value
# stops ``import jax`` with a ValueError.
_JAX_FALSE = ("n", "no", "f", "false", "off", "0")


def request_float32() -> None:
    """Run JAX with its x64 switch off, as every program, seed and table of the toolkit is defined
    (:mod:`jaxsim.precision`), where ``JAX_ENABLE_X64`` asks for it: a one-line note says the
    setting is ignored, and the variable is set off for this process and the processes it starts
    (a backend's workers): under it the same seed gives other numbers and the arena's programs
    fail to trace. A value JAX cannot read (``maybe``) is named and ignored the same way, where
    ``import jax`` would stop with a traceback. Must run before ``import jax``."""
    import sys

    value = os.environ.get("JAX_ENABLE_X64")
    if value is None or value.strip().lower() in _JAX_FALSE:
        return
    os.environ["JAX_ENABLE_X64"] = "0"
    print(
        f"socialnav: note: JAX_ENABLE_X64={value} ignored: the toolkit runs in float32, as its seeds and "
        "tables are defined",
        file=sys.stderr,
    )


def variables_problem() -> str | None:
    """The toolkit's own environment variables with a value it cannot use, in one line naming the
    variable (``SOCIALNAV_GRID_SOLVER``: read by the planners when they first plan, deep in a
    run); None where every one set is usable. Imports what reads them only where they are set."""
    if os.environ.get("SOCIALNAV_GRID_SOLVER"):
        from socialnav.planners.global_planners.grid_planner import solver_variable_problem

        return solver_variable_problem()
    return None


def jax_platforms_problem() -> str | None:
    """Why JAX cannot start the platforms ``JAX_PLATFORMS`` names (``cuda`` where no GPU or no JAX
    for one is installed, ``tpu`` ...), in one line; None where it can, or where the variable is
    unset (JAX then chooses, the CPU where nothing else starts). JAX's own error is a bare
    ``AssertionError`` deep in the first array op for a platform no plugin provides (jax 0.10), a
    traceback for one whose plugin fails. Imports JAX and starts its backends: call it where the
    command's module has imported JAX anyway."""
    platforms = os.environ.get("JAX_PLATFORMS", "").strip()
    if not platforms:
        return None
    import jax

    try:
        jax.devices()
    except (RuntimeError, AssertionError) as e:
        reason = str(e).split(" (set JAX_PLATFORMS=")[0].strip() or "no installed JAX plugin provides it"
        install = " (a GPU: pip install -e '.[cuda12]')" if "cuda" in platforms.lower() else ""
        return (
            f"JAX_PLATFORMS={platforms}: JAX cannot start it ({reason}); unset JAX_PLATFORMS to let JAX "
            f"choose (the CPU where nothing else starts), or install JAX for that platform{install}"
        )
    return None


def request_compilation_cache(path: str | None = None) -> None:
    """Keep XLA's compiled programs on disk (JAX's persistent compilation cache), so that a later
    process skips compiling what an earlier one compiled: measured here, the first GSCL dataset
    of a new process costs 14.8 s with compilation and 8.3 s from the cache (tracing remains).

    The folder is ``path``, else ``$SOCIALNAV_JAX_CACHE``, else ``~/.cache/socialnav-jax/xla``;
    ``SOCIALNAV_JAX_CACHE=off`` switches it off. Does nothing if ``JAX_COMPILATION_CACHE_DIR`` is
    already set. A folder that cannot hold the cache (a file, read-only) is named in a one-line
    warning and the cache left off, where JAX would silently compile everything in every process.
    Best called before ``import jax``; afterwards it updates JAX's config.
    """
    import pathlib
    import sys

    if os.environ.get("JAX_COMPILATION_CACHE_DIR"):
        return
    setting = path or os.environ.get("SOCIALNAV_JAX_CACHE", "")
    if setting.lower() in ("off", "0", "none", "false"):
        return
    folder = setting or str(pathlib.Path.home() / ".cache" / "socialnav-jax" / "xla")
    problem = folder_problem(folder)
    if problem:  # JAX would run without its cache, silently compiling everything in every process
        print(
            f"socialnav: warning: the compilation cache {folder}: {problem}; running without it "
            "(SOCIALNAV_JAX_CACHE names another folder, or 'off')",
            file=sys.stderr,
        )
        return
    os.environ["JAX_COMPILATION_CACHE_DIR"] = folder
    if "jax" in sys.modules:
        sys.modules["jax"].config.update("jax_compilation_cache_dir", folder)


cache_folder_problem = folder_problem  # why a folder cannot hold the compilation cache (common.cache)


def verbose() -> bool:
    """Whether ``SOCIALNAV_VERBOSE`` asks for everything: libraries' log lines and tracebacks."""
    return os.environ.get("SOCIALNAV_VERBOSE", "") not in ("", "0")


def quiet_third_party_logs() -> None:
    """Keep libraries' chatter out of the user's terminal: absl's log lines from orbax (``read_only=True,
    setting max_to_keep=None``, ``Given directory is read only``, its own error for a damaged checkpoint
    that the toolkit reports in one line of its own) and asyncio's "Event loop is closed" from orbax's
    background threads at exit. ``SOCIALNAV_VERBOSE=1`` keeps them."""
    import logging
    import sys

    if verbose():
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


# JAX's warning when a cache entry cannot be read, naming the program (its entry's file is
# ``<program>-<hash>-cache`` in the cache folder).
_UNREADABLE_ENTRY = re.compile(r"Error reading persistent compilation cache entry for '([^'/]+)'")


def repair_compilation_cache() -> None:
    """Remove a compilation-cache entry that cannot be read when JAX warns about it, so that the
    program compiled again is stored again.

    JAX writes an entry in place (``path.write_bytes``) and never replaces an existing one: an
    entry cut short (a full disk, a file-size limit, a process killed while writing it) stays in
    the cache, and every later process reads it, warns "Error reading persistent compilation
    cache entry for 'jit_step'" and compiles that program again, for good. Installed as a hook
    on ``warnings.showwarning``: on that warning, each entry of that program in the cache folder
    that JAX's own decompression refuses is removed (with its access-time file), before JAX
    compiles it and writes it afresh. Entries that read are left alone; a warning filtered out
    (``-W ignore``) repairs nothing; nothing happens without the warning.
    """
    import warnings

    previous = warnings.showwarning
    if getattr(previous, "repairs_compilation_cache", False):
        return  # installed already (a second command run in one process)

    def show(message, category, filename, lineno, file=None, line=None):
        found = _UNREADABLE_ENTRY.search(str(message))
        if found:
            removed = remove_unreadable_entries(found.group(1))
            if removed:
                message = f"{message} (removed {', '.join(removed)}: it is stored again once compiled)"
        previous(message, category, filename, lineno, file, line)

    show.repairs_compilation_cache = True
    warnings.showwarning = show


def one_line_warnings() -> None:
    """Show the toolkit's own warnings (a message that starts with ``socialnav.``: the C++
    kernels that could not be built) as the commands' other warnings are, one line on stderr,
    ``socialnav: warning: <message>``, without Python's file, line and source line; other warnings
    keep Python's format. ``SOCIALNAV_VERBOSE=1`` keeps Python's format for all."""
    import sys
    import warnings

    previous = warnings.showwarning
    if verbose() or getattr(previous, "one_line", False):
        return

    def show(message, category, filename, lineno, file=None, line=None):
        if not str(message).startswith("socialnav."):
            previous(message, category, filename, lineno, file, line)
            return
        try:
            print(f"socialnav: warning: {message}", file=sys.stderr if file is None else file)
        except OSError:  # no terminal left to say it on (as Python's own showwarning)
            pass

    show.one_line = True
    warnings.showwarning = show


def remove_unreadable_entries(program: str, folder: str | None = None) -> list[str]:
    """Remove the cache entries of ``program`` (``jit_step``) in ``folder`` (default: JAX's cache
    folder) that JAX cannot decompress; returns their file names."""
    import glob
    import pathlib
    import sys

    if folder is None:
        jax = sys.modules.get("jax")
        folder = jax.config.jax_compilation_cache_dir if jax is not None else None
    try:
        from jax._src.compilation_cache import decompress_executable  # JAX's own reading of an entry
    except ImportError:  # a JAX without it: leave the cache as JAX keeps it
        return []
    if not folder or not pathlib.Path(folder).is_dir():
        return []
    removed = []
    for entry in sorted(pathlib.Path(folder).glob(f"{glob.escape(program)}-*-cache")):
        try:
            decompress_executable(entry.read_bytes())
        except OSError:
            continue  # gone or unreadable for another reason: not ours to remove
        except Exception:
            entry.unlink(missing_ok=True)
            entry.with_name(entry.name.removesuffix("-cache") + "-atime").unlink(missing_ok=True)
            removed.append(entry.name)
    return removed
