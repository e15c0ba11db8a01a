"""Atomic file writes: write to a temporary name in the same folder, then rename.

A reader never sees a half-written file under the final name, and a killed writer leaves at
most a ``.tmp-*`` file beside it. ``os.replace`` is atomic on POSIX and Windows when both names
are on one file system, which a temporary in the same folder guarantees.
"""

from __future__ import annotations

import contextlib
import os
import pathlib
from collections.abc import Callable, Iterator


def temporary_path(path: str | pathlib.Path) -> pathlib.Path:
    """The temporary name used for ``path``: same folder and suffix (so libraries that pick a
    format from the suffix, matplotlib and numpy among them, still see it), hidden prefix."""
    path = pathlib.Path(path)
    return path.with_name(f".tmp-{os.getpid()}-{path.name}")


@contextlib.contextmanager
def atomic_path(path: str | pathlib.Path) -> Iterator[pathlib.Path]:
    """Yield a temporary path to write; on success it is renamed to ``path``, on error removed.

    Example::

        with atomic_path(out / "table.parquet") as tmp:
            frame.to_parquet(tmp)
    """
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = temporary_path(path)
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def write_atomic(path: str | pathlib.Path, write: Callable[[pathlib.Path], object]) -> pathlib.Path:
    """Call ``write(tmp)`` and rename ``tmp`` to ``path``; returns ``path``."""
    with atomic_path(path) as tmp:
        write(tmp)
    return pathlib.Path(path)


def write_text_atomic(path: str | pathlib.Path, text: str) -> pathlib.Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; returns ``path``."""
    return write_atomic(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))


def write_bytes_atomic(path: str | pathlib.Path, write: Callable[[object], object]) -> pathlib.Path:
    """Call ``write(handle)`` on a binary handle of the temporary file, then rename.

    For writers that append a suffix to a file *name* (``np.savez`` adds ``.npz``) but not to a
    handle.
    """

    def through_handle(tmp: pathlib.Path) -> None:
        with open(tmp, "wb") as handle:
            write(handle)

    return write_atomic(path, through_handle)
