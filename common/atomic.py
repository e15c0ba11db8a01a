"""Atomic file writes: write to a temporary name in the same folder, then rename.

A reader never sees a half-written file under the final name, and a killed writer leaves at
most a ``.socialnav-tmp-*`` file beside it. ``os.replace`` is atomic on POSIX and Windows when both names
are on one file system, which a temporary in the same folder guarantees.
"""

from __future__ import annotations

import contextlib
import os
import pathlib
import re
from collections.abc import Callable, Iterator


def temporary_path(path: str | pathlib.Path) -> pathlib.Path:
    """The temporary name used for ``path``: same folder and suffix (so libraries that pick a
    format from the suffix, matplotlib and numpy among them, still see it), hidden prefix: the
    toolkit's own (``.socialnav-tmp-<pid>-``), so that a job's clean-up never takes a user's file
    for its own."""
    path = pathlib.Path(path)
    return path.with_name(f".socialnav-tmp-{os.getpid()}-{path.name}")


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
    except OSError as e:
        named = naming(e, path, tmp)
        if named is e:
            raise
        raise named from e
    finally:
        if tmp.exists():
            tmp.unlink()


def naming(error: OSError, path: pathlib.Path, tmp: pathlib.Path) -> OSError:
    """``error``, raised while writing ``tmp`` for ``path``, as the error of writing ``path``.

    A writer deep in a library often says what failed but not where: Pillow's PNG writer on a
    full disk raises ``[Errno 28] No space left on device`` with no file name, pyarrow an
    ``OSError`` with no ``errno`` whose message carries ``[errno 28]``, ``open`` names the
    temporary (``.socialnav-tmp-<pid>-name``), which is removed by then. The error returned names the file
    the caller asked for and keeps the errno (from pyarrow's message where it has none), so that a
    command can tell a full disk from a bug; an error naming some other file is returned as it is.
    """
    if error.filename is not None and os.fspath(error.filename) != os.fspath(tmp):
        return error
    code = error.errno
    if code is None:
        found = re.search(r"\[errno (\d+)\]", str(error), flags=re.IGNORECASE)
        code = int(found.group(1)) if found else None
    reason = error.strerror or (os.strerror(code) if code else str(error))
    return OSError(code, reason, str(path))


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
