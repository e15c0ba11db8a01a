"""One writer per run folder, and no writer while a job reads it: advisory locks on the folder.

``with run_lock(folder, "socialnav simulate"):`` takes an exclusive ``flock`` on
``folder/.socialnav-lock`` without waiting; if another process holds it, :class:`RunLocked`
names the holder (its command, pid, host and start time, written in the file). The file is
removed when the job ends; the operating system drops the lock when its process ends, killed or
not, so a crashed run leaves at most an unlocked ``.socialnav-lock`` file that the next job
takes over. The name is the toolkit's own: an ``--out`` may be a user's folder, and a user's
``.lock`` there is not ours to truncate or remove. Within one process the lock is re-entrant
(``socialnav run`` holds its folder while its steps take it again).

``with read_lock(folder):`` takes a shared ``flock`` on the same file for a job that reads a run
(``learn`` its logs, ``evaluate`` its tables): several readers at once, but a writer is refused
while one reads and a reader while one writes, so that a job never reads a run that another
replaces under it (``simulate --overwrite`` renames the old logs away while ``learn`` reads
them). POSIX only: elsewhere both do nothing.
"""

from __future__ import annotations

import contextlib
import datetime
import os
import pathlib
import socket
from collections.abc import Iterator

LOCK_FILE = ".socialnav-lock"
_held: dict[pathlib.Path, int] = {}  # folder -> depth, locks this process holds


class RunFolderError(RuntimeError):
    """The run folder cannot be used (a file of that name, no permission, a full disk); the
    message is one line naming it."""


class RunLocked(RunFolderError):
    """Another process is writing the run folder, or reading it; the message names it."""


def _linked(path: pathlib.Path) -> RunFolderError:
    """The refusal of a lock file that is a symbolic link (never opened through it)."""
    target = os.readlink(path)
    return RunFolderError(f"{path} is a symbolic link (to {target}): the lock is not taken through it; remove it")


def _holder_of(fd: int) -> str:
    """Who holds the lock file open at ``fd``: a writer's line, else the readers (who write none)."""
    text = os.pread(fd, 1000, 0).decode("utf-8", "replace").strip()
    return f"written by {text}" if text else "read by another socialnav job"


def _lock_file(folder: pathlib.Path, operation: int, advice: str) -> int:
    """Open ``folder``'s lock file (creating it; never through a symbolic link) and ``flock`` it
    with ``operation`` without waiting; the open descriptor. A file its last holder removed
    between the open and the lock is opened again. ``advice`` ends the refusal's message.

    Raises:
      RunLocked: another process holds a lock that conflicts.
      OSError: the file cannot be opened (a link, no permission).
    """
    import fcntl

    path = folder / LOCK_FILE
    while True:
        # O_NOFOLLOW: a lock file that is a symbolic link is refused, never opened: the lock's
        # truncate and write would land in whatever file it points to, outside the folder.
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o644)
        try:
            fcntl.flock(fd, operation | fcntl.LOCK_NB)
        except OSError:
            holder = _holder_of(fd)
            os.close(fd)
            raise RunLocked(f"{folder} is being {holder}; {advice}") from None
        try:  # the file may have been removed by its last holder between our open and our lock
            if os.stat(path).st_ino == os.fstat(fd).st_ino:
                return fd
        except FileNotFoundError:
            pass
        os.close(fd)


@contextlib.contextmanager
def run_lock(folder: str | pathlib.Path, job: str) -> Iterator[pathlib.Path]:
    """Hold ``folder``'s lock (creating the folder) for the duration of the block.

    Raises:
      RunLocked: another process holds it.
      RunFolderError: ``folder`` is a file or cannot be created or written.
    """
    folder = pathlib.Path(folder).resolve()
    if folder in _held:
        _held[folder] += 1
        try:
            yield folder
        finally:
            _held[folder] -= 1
        return
    try:
        import fcntl
    except ImportError:  # not POSIX: no lock
        yield folder
        return
    if folder.exists() and not folder.is_dir():
        raise RunFolderError(f"{folder} is a file, not a folder")
    made = [p for p in (folder, *folder.parents) if not p.exists()]  # deepest first
    path = folder / LOCK_FILE
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd = _lock_file(folder, fcntl.LOCK_EX, "wait for it or choose another --out")
    except OSError as e:
        _remove_empty(made)
        if path.is_symlink():
            raise _linked(path) from None
        raise RunFolderError(f"{folder}: cannot write there ({e.strerror or e})") from None
    try:
        since = datetime.datetime.now().isoformat(timespec="seconds")
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{job} (pid {os.getpid()} on {socket.gethostname()}, since {since})\n".encode(), 0)
        _held[folder] = 1
        try:
            yield folder
        finally:
            del _held[folder]
            path.unlink(missing_ok=True)  # removed while still held, so nobody locks a file on its way out
            _remove_empty(made)  # a job that wrote nothing leaves no folder behind, nor the ones above it
            fcntl.flock(fd, fcntl.LOCK_UN)
    finally:
        os.close(fd)


def _remove_empty(made: list[pathlib.Path]) -> None:
    """Remove the folders of ``made`` (deepest first, those the lock created) that are still
    empty, stopping at the first that is not."""
    for folder in made:
        try:
            if any(folder.iterdir()):
                return
            folder.rmdir()
        except OSError:  # gone or not ours to remove: leave the rest
            return


@contextlib.contextmanager
def read_lock(folder: str | pathlib.Path) -> Iterator[pathlib.Path]:
    """Hold a shared lock on the run ``folder`` a job reads, for the duration of the block.

    A folder this process is writing (its :func:`run_lock` held), one that does not exist, or one
    where the lock file cannot be made (read-only: no job writes there either) is read without a
    lock. The lock file is removed at the end by the last reader out, as a writer removes it.

    Raises:
      RunLocked: another process is writing ``folder``.
      RunFolderError: ``folder``'s lock file is a symbolic link.
    """
    folder = pathlib.Path(folder).resolve()
    try:
        import fcntl
    except ImportError:  # not POSIX: no lock
        yield folder
        return
    if folder in _held or not folder.is_dir():
        yield folder
        return
    path = folder / LOCK_FILE
    try:
        fd = _lock_file(folder, fcntl.LOCK_SH, "wait for it to finish before reading the run")
    except OSError:
        if path.is_symlink():
            raise _linked(path) from None
        fd = None  # cannot be made here (read-only): nobody can write the run either
    if fd is None:
        yield folder
        return
    try:
        yield folder
        try:  # the last reader out (no other holder: the lock turns exclusive) removes the file
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            path.unlink(missing_ok=True)
        except OSError:
            pass
    finally:
        os.close(fd)
