"""Hand-written CPU kernels called from JAX through XLA's FFI, compiled on first use.

:func:`build` compiles any such source; the planners' Dijkstra (``planners/global_planners/grid_dijkstra.cc``,
:func:`socialnav.planners.global_planners.grid_planner.dijkstra_available`) is built by it too. Here, the social
force over a batch of worlds (``social_force.cc``): XLA's CPU
compiler runs that pair computation at 8.6 ns per pair per core, split into about 15 loop
kernels, and no setting or rewriting in JAX moved it (README "Speed"); the C++ loop, with the
worlds as vector lanes, is the same arithmetic in one pass; a batch of more than one block of 64
worlds is shared out over XLA's CPU threads (the bits of one thread). The JAX version
(:func:`jaxsim.social_force.social_force_xla`) stays the reference, the GPU path and the
fallback, and a test holds the two to float rounding.

The library is built with the system's C++ compiler (``$CXX``, else ``c++``) for this processor
(``-march=native``; ``$SOCIALNAV_NATIVE_MARCH`` overrides it) into ``$SOCIALNAV_NATIVE_CACHE``,
else ``~/.cache/socialnav-jax/native``, under a name that hashes the source, the flags, the
compiler's version, jaxlib's FFI headers and the processor's flags, so a changed source or
another machine builds anew (about 3 s). The build writes to a temporary file and renames it,
so processes building at once never load a half-written library. ``SOCIALNAV_NATIVE=off``
uses the JAX version; so does a machine without a compiler (with a warning that says why).
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import os
import pathlib
import shlex
import subprocess
import tempfile
import warnings

from socialnav.common.cache import folder_problem, user_cache_folder
from socialnav.common.machine import cpu_flags, cpu_isa

SOURCE = pathlib.Path(__file__).with_name("social_force.cc")
SOCIAL_FORCE_TARGET = "socialnav_social_force"
# -fno-trapping-math: without it GCC 12 leaves the pair loop scalar on AVX2 ("control flow in
# loop": the selects of max_of / fast_atan2 may not be if-converted when a comparison could trap),
# and the kernel ran slower than the JAX force (bench_simulator, AVX2 build under
# --xla_cpu_max_isa=AVX2, one run while another job shared the cores: 2.14 M agent-steps/s at
# batch 1024 without the flag, 5.68 M with it, JAX 4.37 M; README "Speed" for quiet runs).
# AVX-512's masked instructions vectorised the loop either way. Nothing reads the
# floating-point exception flags, so the flag changes no result. -ffp-contract=off: no fused
# multiply-adds, so that a world alone and a world in a block of worlds get the same bits.
FLAGS = (
    "-O3",
    "-std=c++20",
    "-fPIC",
    "-shared",
    "-fopenmp-simd",
    "-fno-math-errno",
    "-fno-trapping-math",
    "-ffp-contract=off",
)
# GCC's own flags, given to GCC only (another compiler may reject them, and a failed build falls
# back to the JAX force): instruction scheduling before register allocation,
# pressure-aware. The social force's pair loop runs one chain of dependent operations per vector
# of worlds (2 square roots, 3 divisions, 2 exponentials in a row), too long for the processor's
# out-of-order window to overlap two of them; social_force.cc writes the block's vectors as
# independent chains in one loop body, and this pass interleaves them. On one core (AMD
# EPYC, 1024 worlds of 51 agents, ns per pair): AVX2 build 6.0 -> 3.1, AVX-512 build
# 3.5 -> 2.3; the chains without the pass, or the pass without the chains, gained nothing. The
# float operations are the same, so the results are the same bits. Only for the social force:
# the planners' Dijkstra (no such chains) measured 0-15 % slower with it.
GCC_FLAGS = ("-fschedule-insns", "-fsched-pressure")


def march() -> str:
    """The processor the kernel is built for: ``$SOCIALNAV_NATIVE_MARCH``, else ``native``.

    ``x86-64-v3`` builds the AVX2 code on a machine with AVX-512 (with XLA's
    ``--xla_cpu_max_isa=AVX2`` this emulates a processor without AVX-512, as the benchmarks'
    README figures for AVX2 do); any ``-march`` value of the compiler is accepted.
    """
    return os.environ.get("SOCIALNAV_NATIVE_MARCH", "").strip() or "native"


def flags(compiler_version: str = "", source: pathlib.Path = SOURCE) -> tuple[str, ...]:
    """The compiler's flags for ``source``: :data:`FLAGS`, :data:`GCC_FLAGS` for the social force
    where ``compiler_version`` (the compiler's ``--version`` text) is GCC's, and ``-march``
    (:func:`march`)."""
    gcc = "Free Software Foundation" in compiler_version and source == SOURCE
    return (*FLAGS, *(GCC_FLAGS if gcc else ()), f"-march={march()}")


def describe() -> str:
    """Which social force runs on the CPU and for which instruction set, in one line (what the
    benchmarks print and a run's ``run.json`` records): the kernel's ``-march``, the processor's
    instruction set, and XLA's cap when ``--xla_cpu_max_isa`` is set."""
    cap = next((f for f in os.environ.get("XLA_FLAGS", "").split() if f.startswith("--xla_cpu_max_isa=")), "")
    xla = f"; XLA capped at {cap.split('=', 1)[1]}" if cap else ""
    if not social_force_available():
        return f"JAX (SOCIALNAV_NATIVE=off or no compiler); processor {cpu_isa()}{xla}"
    return f"C++ kernel (jaxsim.native, -march={march()}); processor {cpu_isa()}{xla}"


def disabled() -> bool:
    """``SOCIALNAV_NATIVE`` is set to off / 0 / false / no."""
    return os.environ.get("SOCIALNAV_NATIVE", "").lower() in ("off", "0", "false", "no")


def _cache_dir() -> pathlib.Path:
    return user_cache_folder("native", "SOCIALNAV_NATIVE_CACHE")


def build(source: pathlib.Path = SOURCE) -> pathlib.Path:
    """The shared library of ``source``, compiled now unless the cache already holds it.

    Raises:
      RuntimeError: no compiler, or the compiler failed (the message holds its first error line).
    """
    import jax.ffi

    compiler = shlex.split(os.environ.get("CXX", "c++"))
    include = jax.ffi.include_dir()
    try:
        version = subprocess.run([*compiler, "--version"], capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError) as e:
        raise RuntimeError(f"no C++ compiler ({' '.join(compiler)}: {e})") from None
    header = pathlib.Path(include, "xla", "ffi", "api", "ffi.h")
    key = hashlib.sha256(
        b"\0".join(
            s.encode() if isinstance(s, str) else s
            for s in (source.read_bytes(), " ".join(flags(version, source)), version, header.read_bytes(), cpu_flags())
        )
    ).hexdigest()[:16]
    folder = _cache_dir()
    target = folder / f"{source.stem}-{key}.so"
    if target.exists():
        return target
    problem = folder_problem(folder)
    if problem:
        raise RuntimeError(f"its cache {folder}: {problem}; SOCIALNAV_NATIVE_CACHE names another folder")
    fd, tmp = tempfile.mkstemp(dir=folder, suffix=".so.tmp")
    os.close(fd)
    try:
        done = subprocess.run(
            [*compiler, *flags(version, source), f"-I{include}", str(source), "-o", tmp], capture_output=True, text=True
        )
        if done.returncode:
            first = next((line for line in done.stderr.splitlines() if "error" in line), done.stderr.strip()[:200])
            raise RuntimeError(f"compiling {source.name} failed: {first}")
        os.replace(tmp, target)  # atomic: another process sees the whole library or none
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return target


@functools.cache
def social_force_available() -> bool:
    """Whether the social-force kernel is built and registered with XLA (for the CPU).

    False when ``SOCIALNAV_NATIVE`` is off, or, with a warning naming the reason, when it cannot
    be built or loaded; the callers then use the JAX version.
    """
    if disabled():
        return False
    import jax.ffi

    try:
        library = ctypes.cdll.LoadLibrary(str(build()))
        jax.ffi.register_ffi_target(SOCIAL_FORCE_TARGET, jax.ffi.pycapsule(library.SocialForce), platform="cpu")
    except (RuntimeError, OSError) as e:
        warnings.warn(f"socialnav.jaxsim.native: the social force runs in XLA's slower code ({e})", stacklevel=2)
        return False
    return True
