"""A run folder as a unit: a job's files appear together or not at all, and an earlier run is
never replaced without being asked.

Used under the folder's lock (:mod:`common.runlock`), so no other writer is alive:

1. :func:`prepare` removes what a killed job left (``.tmp-*`` files of :mod:`common.atomic`,
   ``.staging-*`` and ``.old-*`` entries of this module) and refuses a folder holding a
   previous run's results unless ``overwrite`` is set.
2. :func:`staged` hands the job a private ``.staging-<pid>`` folder to write every result into;
   when the block ends without error it commits them: the old run's marker file (``run.json``)
   is removed first, so from then on the folder reads as an incomplete run, never as a mix of two;
   with ``overwrite`` every other entry of the old run is removed; each staged entry is renamed
   into place; the marker is renamed last. A kill at any point leaves either the old run whole,
   or no marker (readers refuse a folder without it: ``socialnav learn`` says the file is
   missing), and the next job's :func:`prepare` clears the leftovers. On error the staging
   folder is removed and the old run is untouched.
"""

from __future__ import annotations

import contextlib
import os
import pathlib
import shutil
from collections.abc import Iterator, Sequence

from common.runlock import LOCK_FILE, RunFolderError

STAGING_PREFIX = ".staging-"
OLD_PREFIX = ".old-"
TEMPORARY_PREFIXES = (".tmp-", STAGING_PREFIX, OLD_PREFIX)


class PreviousRun(RunFolderError):
    """The folder holds an earlier run's results and ``--overwrite`` was not given."""


def _remove(path: pathlib.Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path)
    else:
        path.unlink(missing_ok=True)


def clear_leftovers(folder: pathlib.Path) -> list[str]:
    """Remove the temporaries a killed job left in ``folder``; returns their names."""
    if not folder.is_dir():
        return []
    gone = []
    for entry in folder.iterdir():
        if entry.name.startswith(TEMPORARY_PREFIXES):
            _remove(entry)
            gone.append(entry.name)
    return sorted(gone)


def prepare(folder: str | pathlib.Path, results: Sequence[str], overwrite: bool, marker: str = "run.json") -> None:
    """Make ``folder`` ready for a new run: leftovers cleared, an earlier run refused unless
    ``overwrite``.

    Args:
      results: the entries a finished run of this job leaves (``run.json``, ``logs.parquet``).
      marker: the entry committed last (its absence beside other results: a killed commit).

    Raises:
      PreviousRun: an entry of ``results`` exists and ``overwrite`` is False.
    """
    folder = pathlib.Path(folder)
    clear_leftovers(folder)
    found = [name for name in results if (folder / name).exists()]
    if found and not overwrite:
        what = "a previous run"
        if not (folder / marker).exists():
            what = f"an incomplete run (no {marker}: killed while saving)"
        raise PreviousRun(
            f"{folder} holds {what} ({', '.join(found)}); pass --overwrite to replace it whole, or choose another --out"
        )


def commit(folder: pathlib.Path, stage: pathlib.Path, marker: str, overwrite: bool) -> None:
    """Move every entry of ``stage`` into ``folder``, ``marker`` last (see the module's steps)."""
    (folder / marker).unlink(missing_ok=True)
    keep = {LOCK_FILE, stage.name}
    if overwrite:
        for entry in folder.iterdir():
            if entry.name not in keep:
                _remove(entry)
    staged_entries = sorted(stage.iterdir(), key=lambda p: p.name == marker)
    for entry in staged_entries:
        target = folder / entry.name
        if target.is_dir() and not target.is_symlink():
            aside = folder / f"{OLD_PREFIX}{os.getpid()}-{entry.name}"
            os.replace(target, aside)
            os.replace(entry, target)
            shutil.rmtree(aside)
        else:
            os.replace(entry, target)
    stage.rmdir()


@contextlib.contextmanager
def staged(folder: str | pathlib.Path, marker: str, overwrite: bool) -> Iterator[pathlib.Path]:
    """Yield a private staging folder inside ``folder``; commit it when the block succeeds."""
    folder = pathlib.Path(folder)
    stage = folder / f"{STAGING_PREFIX}{os.getpid()}"
    if stage.exists():
        _remove(stage)
    stage.mkdir(parents=True)
    try:
        yield stage
    except BaseException:
        _remove(stage)
        raise
    commit(folder, stage, marker, overwrite)
