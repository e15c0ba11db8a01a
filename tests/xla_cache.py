"""The folder the test sessions keep JAX's compiled programs in, from one session to the next.

A test session compiles thousands of programs; most are the same as the last session's (XLA's
compiling is about half of the suite's test-seconds on a 2-core machine: docs/testing.md). JAX's
persistent cache keys an entry by the program, the jax and jaxlib versions, the platform, the
devices and ``XLA_FLAGS``; its key names no processor model or instruction set, which XLA compiles
for (:func:`socialnav.common.machine.compiler_host`), so the folder is one per processor:
``$XDG_CACHE_HOME`` (else ``~/.cache``) ``/socialnav-jax/tests/<processor>``, never the folder the
user's own commands use (``~/.cache/socialnav-jax/xla``). An entry cut short (a process killed
while writing it) is compressed, so JAX finds it damaged, warns and compiles the program again;
the damaged file stays until the folder is removed.

:func:`prune` keeps the folder under :data:`MAX_BYTES`. Run as a script (stdlib only, so that CI can
call it with the system's Python before anything is installed), it makes the folder if missing,
prunes it and prints its path; it fails where the folder cannot be made.
"""

from __future__ import annotations

import importlib.util
import os
import pathlib
import platform
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
# Past this size the oldest entries go until half of it is left (a full suite writes about a
# hundred megabytes; each change to a program adds its new entries beside the old).
MAX_BYTES = 2 * 1024**3


def _machine():
    """``common/machine.py`` loaded from the source tree by its path (stdlib only), so that the
    folder can be named before the package is installed."""
    spec = importlib.util.spec_from_file_location("_socialnav_machine", ROOT / "common" / "machine.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def processor() -> str:
    """A folder name for this processor: its model, widest vector instructions and architecture."""
    machine = _machine()
    name = f"{machine.cpu_model()}-{machine.cpu_isa()}-{platform.machine()}"
    return re.sub(r"[^A-Za-z0-9.]+", "-", name).strip("-").lower()


def kept_folder(suffix: str = "") -> pathlib.Path:
    """The test sessions' compilation cache on this processor (see the module docstring), or with
    ``suffix`` another folder they keep beside it (``-humans``: the recorded pedestrians' measures,
    tests/conftest.py)."""
    cache = os.environ.get("XDG_CACHE_HOME") or str(pathlib.Path.home() / ".cache")
    return pathlib.Path(cache) / "socialnav-jax" / "tests" / (processor() + suffix)


def prune(folder: pathlib.Path, max_bytes: int = MAX_BYTES) -> int:
    """Remove the oldest files of ``folder`` (by modification time, which is when JAX wrote them)
    until half of ``max_bytes`` is left, if it holds more than ``max_bytes``; how many it removed.
    A file another process removes first is skipped."""
    if not folder.is_dir():
        return 0
    entries = []
    with os.scandir(folder) as listing:
        for entry in listing:
            try:
                if entry.is_file():
                    stat = entry.stat()
                    entries.append((stat.st_mtime, stat.st_size, entry.path))
            except FileNotFoundError:  # removed by another process meanwhile
                continue
    total = sum(size for _, size, _ in entries)
    if total <= max_bytes:
        return 0
    removed = 0
    for _, size, path in sorted(entries):
        if total <= max_bytes // 2:
            break
        try:
            os.unlink(path)
            removed += 1
        except FileNotFoundError:
            pass
        total -= size
    return removed


def made_folder(suffix: str = "", max_bytes: int = MAX_BYTES) -> pathlib.Path:
    """:func:`kept_folder`, made if missing and pruned to ``max_bytes`` (:func:`prune`); OSError if
    it cannot be made (a read-only home)."""
    folder = kept_folder(suffix)
    folder.mkdir(parents=True, exist_ok=True)
    prune(folder, max_bytes)
    return folder


if __name__ == "__main__":
    try:
        print(made_folder())
    except OSError as error:
        sys.exit(f"tests/xla_cache.py: no kept compilation cache ({error})")
