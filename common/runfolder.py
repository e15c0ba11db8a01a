"""A run folder as a unit that knows its own files: a job's results appear together or not at
all, and nothing the toolkit did not write is ever removed or replaced.

Every job that writes a folder records what it wrote in the folder's **manifest**
(:data:`MANIFEST`, ``.socialnav-run.json``): the job's name, its marker file and the relative
path of every file it wrote. The manifest is what makes a folder a run:

* ``--overwrite`` replaces only a run of the same job, recognised by its manifest, and removes
  only the files listed there (and the runs that later jobs derived from it in its subfolders,
  each by its own manifest). A user's file in the folder is never touched; a user's file under
  a name the job would write is refused with one line naming it, with or without
  ``--overwrite``. A folder without a manifest holds no run (a run of socialnav before 0.3
  wrote none: it is refused the same way, never guessed at).
* A job's inputs are never inside its output: :func:`check_inputs` refuses an ``--out`` equal to
  or containing an input (``learn --logs L --out L``).

Jobs that replace a run whole (``simulate``, ``learn``, ``evaluate``, ``ablation``) write into a
private ``.socialnav-staging-<pid>`` folder (:func:`staged`) and commit when it is complete
(:func:`commit`), under the folder's lock (:mod:`common.runlock`), in this order:

1. the manifest is rewritten as a journal listing the old run's files and the new one's, so that
   at every later instant each file of either run is listed;
2. the old run's files are renamed into ``.socialnav-old-<pid>/`` (its marker first: from then on the
   folder reads as an incomplete run, never as a mix of two);
3. the new run's files are renamed into place, its marker last;
4. the manifest is rewritten with the new run's files only, then ``.socialnav-old-<pid>/`` is
   removed.

Renames within one file system do not copy and do not fail for lack of space. If any step of 2-3
raises (a file that cannot be moved: read-only, busy, gone), every rename done so far is undone
in reverse and the old run is left whole, with one line naming the file; if even the undo fails,
the message says which files are where. A kill (no clean-up) at any point is settled by the next
job on the folder (:func:`recover`): with the new marker in place the commit is finished,
otherwise the old run is put back. Removing ``.socialnav-old-<pid>/`` at the end is best effort: a file
that cannot be removed is named in a warning and left for the next job, never a failure.

Jobs that add to a folder as they go (``arena``, ``gscl train``, ``gscl evaluate``/``rules``,
``layers``) :func:`claim` the folder before writing (the same refusals) and :func:`record` each
file they finish.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import pathlib
import re
import shutil
import sys
from collections.abc import Callable, Iterable, Iterator, Sequence

from socialnav.common.names import check_name
from socialnav.common.runlock import LOCK_FILE, RunFolderError

MANIFEST = ".socialnav-run.json"
MANIFEST_FORMAT = "socialnav-run/1"
STAGING_PREFIX = ".socialnav-staging-"
OLD_PREFIX = ".socialnav-old-"
# What a killed job of this toolkit leaves at the top of a run folder: a temporary of
# common.atomic (.socialnav-tmp-<pid>-<name>), a staging folder (.socialnav-staging-<pid>) or a
# folder of the old run's files moved aside (.socialnav-old-<pid>). Only these exact forms are
# removed, each under the toolkit's own prefix: an --out may be a user's folder, whose
# ``.old-2024/`` or ``.tmp-1-draft.txt`` is not ours.
_LEFTOVER = re.compile(r"^\.socialnav-(tmp-\d+-.+|staging-\d+|old-\d+)$")
# The scratch names of versions before the prefix: recognised only where a manifest's journal
# names them (an interrupted commit of such a version), never by their look alone.
_JOURNALED = re.compile(r"^\.(socialnav-)?(staging|old)-\d+$")


class PreviousRun(RunFolderError):
    """The folder holds an earlier run's results and ``--overwrite`` was not given."""


class CommitStuck(RunFolderError):
    """A commit failed and could not be undone; the journal in the manifest lets the next job
    on the folder settle it (:func:`recover`)."""


class NotOurs(RunFolderError):
    """The folder holds a file the job would write or remove that no socialnav job recorded
    writing (or another job's run); the message names it."""


@dataclasses.dataclass(frozen=True)
class Manifest:
    """What a run folder holds.

    Attributes:
      job: the job that wrote the run (``"socialnav simulate"``).
      marker: the file committed last (its absence beside other files: an unfinished run).
      files: relative POSIX paths of every file the run wrote; an entry ending in ``/`` is a
        working folder the job owns whole (``shards/``, ``checkpoints/``).
      journal: during a commit only: ``{"old": [...], "new": [...], "stage": name, "aside": name}``.
      name: the name of the folder the job wrote it in (:func:`write_manifest` records it; None in
        a manifest of a version that did not): a run kept inside another under another name is a
        user's copy, never a result derived from it (:func:`owned_files`).
    """

    job: str
    marker: str | None
    files: tuple[str, ...]
    journal: dict | None = None
    name: str | None = None

    def to_json(self) -> str:
        raw = {"format": MANIFEST_FORMAT, "job": self.job, "marker": self.marker, "files": list(self.files)}
        if self.journal is not None:
            raw["journal"] = self.journal
        if self.name is not None:
            raw["name"] = self.name
        return json.dumps(raw, indent=1) + "\n"


def read_manifest(folder: str | pathlib.Path) -> Manifest | None:
    """The manifest of ``folder``; None if it has none.

    Raises:
      NotOurs: the file exists but is not a manifest this toolkit wrote (damaged, foreign).
    """
    path = pathlib.Path(folder) / MANIFEST
    if not path.is_file():
        return None
    try:
        raw = json.loads(path.read_text(encoding="utf-8"))
        ok = isinstance(raw, dict) and raw.get("format") == MANIFEST_FORMAT
        files = raw["files"] if ok else None
        ok = ok and isinstance(raw.get("job"), str) and isinstance(files, list)
        ok = ok and all(isinstance(f, str) and _safe_relative(f.rstrip("/")) for f in files)
        journal = raw.get("journal") if ok else None
        if isinstance(journal, dict):  # a commit's journal names files too: the same rule
            lists = [journal.get("old", []), journal.get("new", [])]
            ok = all(isinstance(entries, list) for entries in lists)
            ok = ok and all(isinstance(f, str) and _safe_relative(f.rstrip("/")) for f in lists[0] + lists[1])
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        ok = False
    if not ok:
        raise NotOurs(f"{path}: not a socialnav run manifest (damaged or foreign); remove the folder yourself")
    name = raw.get("name") if isinstance(raw.get("name"), str) else None
    return Manifest(raw["job"], raw.get("marker"), tuple(files), journal if isinstance(journal, dict) else None, name)


def write_manifest(folder: pathlib.Path, manifest: Manifest) -> None:
    """Write ``folder``'s manifest atomically (a temporary beside it, then a rename), with the
    folder's name as the job writes it (:attr:`Manifest.name`)."""
    from socialnav.common.atomic import write_text_atomic

    named = dataclasses.replace(manifest, name=pathlib.Path(folder).resolve().name)
    write_text_atomic(pathlib.Path(folder) / MANIFEST, named.to_json())


def _safe_relative(rel: str) -> bool:
    parts = pathlib.PurePosixPath(rel).parts
    return bool(parts) and not rel.startswith("/") and all(p not in ("..", ".", "") for p in parts)


def _listed_path(folder: pathlib.Path, rel: str, base: pathlib.Path | None = None) -> pathlib.Path:
    """``base / rel`` (``base`` defaults to ``folder``) for a file a manifest lists, if the
    folder holding it lies inside ``folder`` with every symbolic link followed; else
    :class:`NotOurs` naming the entry. The entry itself may be a link: it is moved or removed
    as a link, never followed, so only the folders above it are resolved. A hand-edited
    manifest listing ``link/precious.txt`` beside ``link -> ../victim`` is refused before
    anything is moved."""
    path = (base if base is not None else folder) / rel.rstrip("/")
    root = folder.resolve()
    holder = path.parent.resolve()
    if holder != root and not holder.is_relative_to(root):
        raise NotOurs(
            f"{folder / MANIFEST}: entry '{rel}' lies in {holder}, outside the run folder {root} (a symbolic link "
            "on its way); refused, nothing moved or removed: fix or remove the manifest yourself"
        )
    return path


# ------------------------------------------------------------------ names and paths


def inside(folder: str | pathlib.Path, path: str | pathlib.Path) -> pathlib.Path:
    """``path`` if it resolves (symbolic links followed) to a place inside ``folder``, else
    :class:`NotOurs`: a job never writes outside its ``--out``."""
    root = pathlib.Path(folder).resolve()
    resolved = pathlib.Path(path).resolve()
    if resolved != root and not resolved.is_relative_to(root):
        raise NotOurs(f"{path} resolves to {resolved}, outside the output folder {root}; nothing written there")
    return pathlib.Path(path)


def check_writable(folder: str | pathlib.Path) -> None:
    """Create ``folder`` if needed and write and remove a file in it, before any work: a folder
    that cannot hold the results (read-only, another file system's limits, a file in the way)
    is refused at once, with one line naming it, not after hours of computing."""
    import tempfile

    folder = pathlib.Path(folder)
    missing = [p for p in (folder, *folder.parents) if not _exists(p)]
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".socialnav-tmp-0-probe-"):
            pass
    except OSError as e:
        raise RunFolderError(f"{folder}: cannot write there ({e.strerror or e})") from None
    finally:
        _remove_made(missing)  # the job creates its folders when it writes, not before


def check_inputs(out: str | pathlib.Path, inputs: Iterable[str | pathlib.Path | None], option: str = "--out") -> None:
    """Refuse an output folder that is, or contains, one of the job's inputs (the job would
    write its results among what it reads, and ``--overwrite`` could remove them)."""
    root = pathlib.Path(out).resolve()
    for given in inputs:
        if given is None:
            continue
        path = pathlib.Path(given).resolve()
        if path == root or path.is_relative_to(root):
            raise NotOurs(
                f"{option} {out} contains the job's input {given}; choose an output folder outside what it reads"
            )


# ------------------------------------------------------------------ what a folder holds


def _remove(path: pathlib.Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path)
    else:
        path.unlink(missing_ok=True)


def _exists(path: pathlib.Path) -> bool:
    return path.exists() or path.is_symlink()


def owned_files(folder: pathlib.Path, manifest: Manifest | None = None, with_runs_inside: bool = True) -> list[str]:
    """The files of ``folder``'s run that exist (working folders expanded), its manifest
    included, and, with ``with_runs_inside``, those of every run derived from it in a subfolder
    (a later job's results kept beside it: ``causal/``, ``evaluation/``, ``arena/``; each by its
    own manifest, ``_derived_from``)."""
    folder = pathlib.Path(folder)
    manifest = manifest if manifest is not None else read_manifest(folder)
    found: list[str] = []
    if manifest is not None:
        for rel in manifest.files:
            path = _listed_path(folder, rel)
            if rel.endswith("/"):
                if path.is_dir() and not path.is_symlink():
                    found += [p.relative_to(folder).as_posix() for p in sorted(path.rglob("*")) if not p.is_dir()]
            elif _exists(path) and not (path.is_dir() and not path.is_symlink()):
                found.append(rel)
        if _exists(folder / MANIFEST):
            found.append(MANIFEST)
    if with_runs_inside and folder.is_dir():
        for sub in sorted(p for p in folder.iterdir() if p.is_dir() and not p.is_symlink()):
            if sub.name.startswith(".") or not (sub / MANIFEST).is_file():
                continue
            if manifest is not None and any(f.startswith(sub.name + "/") for f in manifest.files):
                continue  # a folder of this run's own, not a run of its own
            inner = read_manifest(sub)
            if _derived_from(manifest, sub, inner):
                found += [f"{sub.name}/{rel}" for rel in owned_files(sub, inner)]
    return list(dict.fromkeys(found))


def _derived_from(manifest: Manifest | None, sub: pathlib.Path, inner: Manifest | None) -> bool:
    """Whether the run in ``sub`` (its manifest ``inner``) is a result derived from the run of the
    folder holding it (``manifest``), and so goes with that run: another job's run, still under
    the name its job wrote it in. A run of the same job (a copy of the folder's run kept inside
    it) or one under another name (``causal/`` copied to ``causal-monday/``) is a user's copy. A
    manifest written before the name was recorded is judged by its job alone."""
    if manifest is None or inner is None or inner.job == manifest.job:
        return False
    return inner.name in (None, sub.name)


def clear_leftovers(folder: pathlib.Path, warn: Callable[[str], None] | None = None) -> list[str]:
    """Settle an interrupted commit (:func:`recover`) and remove what a killed job of this
    toolkit left at the top of ``folder`` (``.socialnav-tmp-<pid>-*``, ``.socialnav-staging-<pid>``,
    ``.socialnav-old-<pid>``, and the scratch folders an interrupted commit's journal names;
    nothing else); returns the names removed. A leftover that cannot be removed
    is named through ``warn`` and kept."""
    folder = pathlib.Path(folder)
    if not folder.is_dir():
        return []
    journaled = _journal_scratch(folder)
    recover(folder)
    gone = []
    for entry in folder.iterdir():
        if _LEFTOVER.match(entry.name) or entry.name in journaled:
            try:
                _remove(entry)
                gone.append(entry.name)
            except OSError as e:
                if warn is not None:
                    warn(f"cannot remove {entry}: {e.strerror or e} (left for later)")
    return sorted(gone)


def _journal_scratch(folder: pathlib.Path) -> set[str]:
    """The staging and aside folders an interrupted commit's journal names (ours by that record,
    whatever version of the toolkit named them); empty where there is no journal."""
    try:
        manifest = read_manifest(folder)
    except NotOurs:
        return set()
    if manifest is None or manifest.journal is None:
        return set()
    names = {str(manifest.journal.get(key, "")) for key in ("stage", "aside")}
    return {name for name in names if _JOURNALED.match(name)}


def claim(
    folder: str | pathlib.Path,
    job: str,
    names: Sequence[str],
    overwrite: bool = False,
    marker: str | None = None,
    adopt: Callable[[pathlib.Path], bool] | None = None,
) -> Manifest | None:
    """Check that ``job`` may write ``names`` (top-level entries of its results) in ``folder``.

    Returns the folder's manifest (None for a folder holding no run). Raises :class:`NotOurs`
    for another job's run in the folder, or for an entry of ``names`` that exists without a
    manifest listing it; :class:`PreviousRun` for a run of this job when ``overwrite`` is not
    set and ``marker`` is given (jobs that resume, with ``marker=None``, are not refused).

    Args:
      adopt: for a folder without a manifest, a test that recognises a run of this job written
        by an earlier version (``gscl train``'s ``config.json``): such a folder is given one
        when the job records its first file.
    """
    folder = pathlib.Path(folder)
    if _exists(folder) and not folder.is_dir():
        raise NotOurs(f"{folder} is a file, not a folder")
    manifest = read_manifest(folder) if folder.is_dir() else None
    if manifest is not None and manifest.job != job:
        raise NotOurs(
            f"{folder} holds a run of '{manifest.job}' ({MANIFEST}); '{job}' does not write into another "
            "job's run: choose another folder"
        )
    if manifest is None and adopt is not None and folder.is_dir() and adopt(folder):
        listed = sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file())
        listed = [f for f in listed if not f.startswith(".") and f.split("/")[0] in names]
        manifest = Manifest(job, marker, tuple(listed))
        return manifest  # written with the job's first record(), not before it writes anything
    if manifest is None:
        clash = [n for n in names if _exists(folder / n)]
        if clash:
            raise NotOurs(
                f"{folder} holds {', '.join(clash)}, which no socialnav job recorded writing there (no {MANIFEST}; "
                "a run of socialnav before 0.3 has none): move it away or choose another folder"
            )
        return None
    listed_top = {f.rstrip("/").split("/")[0] for f in manifest.files}
    clash = [n for n in names if _exists(folder / n) and n not in listed_top]
    if clash:
        raise NotOurs(
            f"{folder} holds {', '.join(clash)}, which its run ({MANIFEST}) did not write: move it away or "
            "choose another folder"
        )
    if marker is not None and not overwrite:
        present = [n for n in names if _exists(folder / n)]
        if present:
            what = "a previous run"
            if not _exists(folder / marker):
                what = f"an incomplete run (no {marker}: killed while saving)"
            raise PreviousRun(
                f"{folder} holds {what} ({', '.join(present)}); pass --overwrite to replace it whole, "
                "or choose another --out"
            )
    return manifest


def record(
    folder: str | pathlib.Path, job: str, paths: Iterable[str | pathlib.Path], marker: str | None = None
) -> None:
    """Add ``paths`` (relative to ``folder``, or absolute inside it; a working folder as
    ``"name/"``) to ``folder``'s manifest, creating it for ``job``."""
    folder = pathlib.Path(folder)
    manifest = read_manifest(folder) or Manifest(job, marker, ())
    added = []
    for p in paths:
        text = str(p)
        rel = pathlib.Path(text)
        if rel.is_absolute():
            rel = rel.relative_to(folder.absolute())
        rel_text = rel.as_posix() + ("/" if text.endswith("/") else "")
        if not _safe_relative(rel_text.rstrip("/")):
            raise NotOurs(f"{text}: not a path inside {folder}")
        added.append(rel_text)
    files = tuple(dict.fromkeys([*manifest.files, *added]))
    if files != manifest.files or manifest.job != job:
        write_manifest(folder, Manifest(job, manifest.marker or marker, files))


def prepare(
    folder: str | pathlib.Path,
    results: Sequence[str],
    overwrite: bool,
    marker: str = "run.json",
    job: str = "socialnav",
) -> None:
    """Make ``folder`` ready for a new run of ``job``: an interrupted commit settled, leftovers
    cleared, an earlier run refused unless ``overwrite``, a file that is not ours refused always.

    Args:
      results: the top-level entries a finished run of this job leaves (``run.json``, ``logs.parquet``).
      marker: the entry committed last (its absence beside other results: a killed commit).

    Raises:
      PreviousRun: a run of this job is there and ``overwrite`` is False.
      NotOurs: a result's name is taken by a file no run of this job wrote, or another job's run.
    """
    folder = pathlib.Path(folder)
    clear_leftovers(folder)
    claim(folder, job, results, overwrite=overwrite, marker=marker)


# ------------------------------------------------------------------ the commit


def _staged_files(stage: pathlib.Path) -> list[str]:
    return sorted(p.relative_to(stage).as_posix() for p in stage.rglob("*") if not p.is_dir() or p.is_symlink())


def _move(src: pathlib.Path, dst: pathlib.Path) -> None:
    dst.parent.mkdir(parents=True, exist_ok=True)
    os.replace(src, dst)


def _prune_empty(folder: pathlib.Path, rels: Iterable[str]) -> None:
    """Remove the folders that held ``rels`` if they are empty now (never ``folder`` itself)."""
    parents = sorted({p for rel in rels for p in pathlib.PurePosixPath(rel).parents if str(p) != "."}, reverse=True)
    for parent in sorted(parents, key=lambda p: len(p.parts), reverse=True):
        path = folder / parent
        with contextlib.suppress(OSError):
            if path.is_dir() and not path.is_symlink() and not any(path.iterdir()):
                path.rmdir()


def commit(
    folder: pathlib.Path,
    stage: pathlib.Path,
    marker: str,
    overwrite: bool,
    job: str = "socialnav",
    warn: Callable[[str], None] | None = None,
) -> None:
    """Move the files of ``stage`` into ``folder``, replacing the previous run of ``job`` when
    ``overwrite`` (the module's steps 1-4).

    Raises:
      NotOurs: a staged file would replace a file the previous run did not write.
      RunFolderError: a rename failed; every rename was undone, the previous run is whole.
    """
    folder = pathlib.Path(folder)
    warn = warn or (lambda message: print(f"warning: {message}", file=sys.stderr))
    previous = read_manifest(folder)
    if previous is not None and previous.job != job:
        raise NotOurs(f"{folder} holds a run of '{previous.job}' ({MANIFEST}); not replaced by '{job}'")
    new = [f for f in _staged_files(stage) if f != MANIFEST]
    old = [f for f in owned_files(folder, previous) if f != MANIFEST] if (overwrite and previous) else []
    for rel in new:
        target = inside(folder, folder / rel)  # a user's symbolic link inside the run never leads out
        taken = _exists(target) and rel not in old
        blocked = next((p for p in target.parents if p != folder and p.is_relative_to(folder) and p.is_file()), None)
        if taken or blocked is not None:
            raise NotOurs(
                f"{blocked or target} is in the way of the new run and no socialnav job recorded writing it: "
                "move it away or choose another --out"
            )
    aside = folder / f"{OLD_PREFIX}{os.getpid()}"
    old.sort(key=lambda rel: rel != marker)  # the old marker first: from then on the folder is unfinished
    new.sort(key=lambda rel: rel == marker)  # the new marker last
    listed = previous.files if previous is not None else ()
    journal = {"old": old, "new": new, "stage": stage.name, "aside": aside.name}
    write_manifest(folder, Manifest(job, marker, tuple(dict.fromkeys([*listed, *old, *new])), journal))
    moved_aside: list[str] = []
    moved_in: list[str] = []
    try:
        for rel in old:
            _move(folder / rel, aside / rel)
            moved_aside.append(rel)
        for rel in new:
            _move(stage / rel, folder / rel)
            moved_in.append(rel)
    except OSError as e:
        failed = e.filename or "?"
        undo_failures = _undo(folder, stage, aside, moved_in, moved_aside)
        if undo_failures:  # the journal stays: the next job on the folder settles it
            raise CommitStuck(
                f"{folder}: could not move {failed} ({e.strerror or e}) and could not put back "
                f"{', '.join(undo_failures)}: the previous run's files are in {aside}, the new run's in {stage}"
            ) from None
        if previous is not None:
            write_manifest(folder, previous)
        else:
            (folder / MANIFEST).unlink(missing_ok=True)
        raise RunFolderError(
            f"{folder}: could not move {failed} ({e.strerror or e}); the previous run is kept whole, "
            "nothing of the new one was saved"
        ) from None
    try:  # the new run is whole and in place: what fails from here on is tidying, not the run
        write_manifest(folder, Manifest(job, marker, tuple(new)))
    except OSError as e:
        warn(f"cannot rewrite {folder / MANIFEST} ({e.strerror or e}); the next job on {folder} finishes it")
        return
    _finish(folder, stage, aside, old, warn)


def _undo(folder, stage, aside, moved_in, moved_aside) -> list[str]:
    failures = []
    for rel in reversed(moved_in):
        try:
            _move(folder / rel, stage / rel)
        except OSError:
            failures.append(str(folder / rel))
    for rel in reversed(moved_aside):
        try:
            _move(aside / rel, folder / rel)
        except OSError:
            failures.append(str(aside / rel))
    _prune_empty(folder, moved_in)
    return failures


def _finish(folder: pathlib.Path, stage: pathlib.Path, aside: pathlib.Path, old: Sequence[str], warn) -> None:
    """Remove the old run's files put aside and the empty staging folder (best effort)."""
    for path in (aside, stage):
        if _exists(path):
            try:
                _remove(path)
            except OSError as e:
                warn(f"cannot remove {e.filename or path}: {e.strerror or e}; left for the next job on {folder}")
    _prune_empty(folder, old)


def recover(folder: pathlib.Path) -> str | None:
    """Settle a commit that a kill interrupted (its manifest still holds the journal): finish it
    when the new marker is in place, else put the previous run back. Returns ``"finished"``,
    ``"rolled back"`` or None (nothing to settle).

    Raises:
      NotOurs: the journal names a file whose folder lies outside ``folder`` (symbolic links
        followed); nothing is moved.
    """
    try:
        manifest = read_manifest(folder)
    except NotOurs:
        return None
    if manifest is None or manifest.journal is None:
        return None
    journal = manifest.journal
    old, new = list(journal.get("old", [])), list(journal.get("new", []))
    stage, aside = folder / str(journal.get("stage", "")), folder / str(journal.get("aside", ""))
    if not (_JOURNALED.match(stage.name) and _JOURNALED.match(aside.name)):
        return None
    if stage.is_symlink() or aside.is_symlink():
        raise NotOurs(f"{folder / MANIFEST}: the journal's {stage.name} or {aside.name} is a symbolic link; refused")
    for rel in old + new:  # every file the settling would move, checked before the first move
        for base in (folder, stage, aside):
            _listed_path(folder, rel, base)
    marker = manifest.marker
    new_marker_in = marker in new and _exists(folder / marker) and not _exists(stage / marker)
    if new_marker_in:
        write_manifest(folder, Manifest(manifest.job, marker, tuple(new)))
        _finish(folder, stage, aside, old, lambda message: None)
        return "finished"
    for rel in new:  # the new run's files moved in so far go back to its (abandoned) stage
        if _exists(folder / rel) and not _exists(stage / rel) and rel not in old:
            _move(folder / rel, stage / rel)
        elif _exists(folder / rel) and rel in old and _exists(aside / rel):
            _move(folder / rel, stage / rel)
    for rel in old:
        if _exists(aside / rel):
            _move(aside / rel, folder / rel)
    listed = tuple(f for f in manifest.files if f not in new or f in old)
    write_manifest(folder, Manifest(manifest.job, marker, listed))
    _prune_empty(folder, new)
    return "rolled back"


@contextlib.contextmanager
def staged(folder: str | pathlib.Path, marker: str, overwrite: bool, job: str = "socialnav") -> Iterator[pathlib.Path]:
    """Yield a private staging folder inside ``folder``; commit it when the block succeeds
    (:func:`commit`); on error the staging folder is removed and the old run is untouched."""
    folder = pathlib.Path(folder)
    stage = folder / f"{STAGING_PREFIX}{os.getpid()}"
    missing = [p for p in (folder, *folder.parents) if not _exists(p)]
    if _exists(stage):
        _remove(stage)
    stage.mkdir(parents=True)
    try:
        yield stage
    except BaseException as e:
        _remove(stage)
        _remove_made(missing)
        named = _named_in_folder(e, stage, folder)
        if named is e:
            raise
        raise named from e
    try:
        commit(folder, stage, marker, overwrite, job)
    except CommitStuck:
        raise  # the new run's files stay where the message says
    except BaseException:
        if _exists(stage):
            with contextlib.suppress(OSError):
                _remove(stage)
        _remove_made(missing)
        raise


def _named_in_folder(error: BaseException, stage: pathlib.Path, folder: pathlib.Path) -> BaseException:
    """An ``OSError`` naming a file in the (removed) staging folder, as naming the file of the run
    it was to become (``out/.socialnav-staging-123/pictures/a.png`` -> ``out/pictures/a.png``); any other
    error as it is."""
    if not isinstance(error, OSError) or error.filename is None:
        return error
    path = pathlib.Path(os.fsdecode(error.filename))
    if not path.is_relative_to(stage):
        return error
    return OSError(error.errno, error.strerror or str(error), str(folder / path.relative_to(stage)))


def _remove_made(folders: Sequence[pathlib.Path]) -> None:
    """Remove the ``folders`` a failed job created (deepest first) where they are still empty: a
    run stopped by a full disk or Ctrl-C leaves no empty output folder behind."""
    for made in folders:
        with contextlib.suppress(OSError):
            made.rmdir()


__all__ = [
    "LOCK_FILE",
    "MANIFEST",
    "CommitStuck",
    "Manifest",
    "NotOurs",
    "PreviousRun",
    "check_inputs",
    "check_name",
    "check_writable",
    "claim",
    "clear_leftovers",
    "commit",
    "inside",
    "owned_files",
    "prepare",
    "read_manifest",
    "record",
    "recover",
    "staged",
]
