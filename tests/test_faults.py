"""Kill a job between any two of its file operations: nothing is lost or half visible.

A subprocess runs a job whose every file operation in the run folder (``os.replace``,
``os.unlink``, ``shutil.rmtree``, ``os.rmdir``, ``os.mkdir``, ``os.rename``) is counted, and is
killed with ``os._exit`` (no clean-up, no ``finally``: as a SIGKILL) just before operation
``k``, for every ``k`` of a whole run. After each kill the folder holds either the previous run
whole or no ``run.json`` (an incomplete run, which readers refuse); every file under a final
name is complete; and the next job with ``--overwrite`` leaves the new run whole with no
temporaries.
"""

from __future__ import annotations

import io
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys
import textwrap

import pytest

from socialnav.common import runfolder
from socialnav.common.runlock import run_lock

ROOT = pathlib.Path(__file__).resolve().parents[1]

# Wraps the file operations of the job run after it; kills the process before operation KILL_AT.
KILLER = textwrap.dedent(
    """
    import os, shutil, sys
    KILL_AT = int(os.environ["KILL_AT"])
    FOLDER = os.path.realpath(sys.argv[1])
    SKIP_STAGED = os.environ.get("SKIP_STAGED", "0")  # "1": writes inside the private staging folder are not counted
    # Set: before each counted operation k, copy the folder to SNAPSHOTS/k (what a kill there leaves).
    SNAPSHOTS = os.environ.get("SNAPSHOTS", "")
    count = [0]
    def counted(fn):
        def wrapper(*a, **k):
            paths = [os.path.realpath(str(x)) for x in a if isinstance(x, (str, os.PathLike))]
            staged = lambda p: "/.socialnav-staging-" in p[len(FOLDER):]
            if any(p.startswith(FOLDER) and (SKIP_STAGED == "0" or not staged(p)) for p in paths):
                count[0] += 1
                if count[0] == KILL_AT:
                    os._exit(9)
                if SNAPSHOTS:
                    copy_tree(FOLDER, os.path.join(SNAPSHOTS, str(count[0])), symlinks=True)
            return fn(*a, **k)
        return wrapper
    copy_tree = shutil.copytree  # the copy's own writes land outside FOLDER and are never counted
    for name in ("replace", "unlink", "rmdir", "mkdir", "rename"):
        setattr(os, name, counted(getattr(os, name)))
    shutil.rmtree = counted(shutil.rmtree)
    import atexit
    atexit.register(lambda: open(os.environ["COUNT_FILE"], "w").write(str(count[0])))
    """
)

# A job on a run folder: the previous run's files replaced by a new one through common.runfolder.
JOB = textwrap.dedent(
    """
    import pathlib, sys
    from socialnav.common import runfolder
    folder = pathlib.Path(sys.argv[1])
    runfolder.prepare(folder, ("run.json", "logs.parquet", "snapshot.png", "causal"), overwrite=True, job="test")
    with runfolder.staged(folder, "run.json", overwrite=True, job="test") as stage:
        (stage / "logs.parquet").write_text("new logs")
        (stage / "snapshot.png").write_text("new picture")
        (stage / "causal").mkdir()
        (stage / "causal" / "tables.npz").write_text("new tables")
        (stage / "run.json").write_text("new")
    """
)

OLD = {"run.json": "old", "logs.parquet": "old logs", "snapshot.png": "old picture", "causal/tables.npz": "old tables"}
NEW = {"run.json": "new", "logs.parquet": "new logs", "snapshot.png": "new picture", "causal/tables.npz": "new tables"}


def _write_old(folder: pathlib.Path) -> None:

    for name, text in OLD.items():
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_text(text)
    (folder / "density_by_slot.png").write_text("old only")
    (folder / "my-notes.txt").write_text("the user's")  # never touched
    runfolder.record(folder, "test", [*OLD, "density_by_slot.png"], marker="run.json")


def _state(folder: pathlib.Path) -> str:
    """'old' (the previous run whole), 'new' (the new one whole) or 'incomplete' (no marker);
    fails on a file holding anything but a whole old or new content."""
    for path in folder.rglob("*"):
        rel = str(path.relative_to(folder))
        if path.is_file() and not rel.startswith("."):  # temporaries are hidden and cleared next time
            text = path.read_text()
            assert text in (OLD.get(rel), NEW.get(rel), "old only", "the user's"), f"{rel} holds {text!r}"
    if not (folder / "run.json").exists():
        return "incomplete"
    marker = (folder / "run.json").read_text()
    expected = OLD if marker == "old" else NEW
    for name, text in expected.items():
        assert (folder / name).read_text() == text, f"{marker} run without its {name}"
    return marker


def _run(
    code: str,
    folder: pathlib.Path,
    kill_at: int,
    count_file: pathlib.Path,
    skip_staged: bool = False,
    snapshots: pathlib.Path | None = None,
) -> int:
    env = dict(os.environ, KILL_AT=str(kill_at), COUNT_FILE=str(count_file), PYTHONPATH=str(ROOT))
    env["SKIP_STAGED"] = "1" if skip_staged else "0"
    env["SNAPSHOTS"] = str(snapshots or "")
    # The jobs read and write the test session's compilation cache (JAX_COMPILATION_CACHE_DIR,
    # inherited from tests/conftest.py), never the user's.
    return subprocess.run([sys.executable, "-c", KILLER + code, str(folder)], env=env, cwd=ROOT).returncode


@pytest.mark.slow
def test_a_run_folder_killed_at_every_file_operation(tmp_path):
    count_file = tmp_path / "count"
    whole = tmp_path / "whole"
    whole.mkdir()
    _write_old(whole)
    assert _run(JOB, whole, 0, count_file) == 0
    assert _state(whole) == "new" and not (whole / "density_by_slot.png").exists()
    assert (whole / "my-notes.txt").read_text() == "the user's"
    n_ops = int(count_file.read_text())
    assert n_ops >= 8
    seen = set()
    for k in range(1, n_ops + 1):
        folder = tmp_path / f"kill{k}"
        folder.mkdir()
        _write_old(folder)
        assert _run(JOB, folder, k, count_file) == 9
        seen.add(_state(folder))
        assert (folder / "my-notes.txt").read_text() == "the user's"
        settled = tmp_path / f"settled{k}"  # what the next job finds once it has settled the commit
        shutil.copytree(folder, settled, symlinks=True)
        runfolder.clear_leftovers(settled)
        assert _state(settled) in ("old", "new")
        assert _run(JOB, folder, 0, count_file) == 0  # the next job recovers
        assert _state(folder) == "new"
        hidden = [p.name for p in folder.iterdir() if p.name.startswith(".")]
        assert hidden == [runfolder.MANIFEST], "temporaries left"
    assert seen >= {"old", "incomplete"}


def _count_and_fail(monkeypatch, folder: pathlib.Path, fail_at: int) -> list[int]:
    """Make the ``fail_at``-th file operation on ``folder`` raise OSError (0: none); returns the
    counter (its one element: the operations seen)."""
    count = [0]
    root = os.path.realpath(folder)

    def counted(fn):
        def wrapper(*a, **k):
            paths = [os.path.realpath(str(x)) for x in a if isinstance(x, (str, os.PathLike))]
            if any(p.startswith(root) for p in paths):
                count[0] += 1
                if count[0] == fail_at:
                    raise PermissionError(1, "Operation not permitted", paths[0])
            return fn(*a, **k)

        return wrapper

    for name in ("replace", "unlink", "rmdir", "mkdir", "rename"):
        monkeypatch.setattr(os, name, counted(getattr(os, name)))
    monkeypatch.setattr(shutil, "rmtree", counted(shutil.rmtree))
    return count


def _commit_job(folder: pathlib.Path) -> None:

    with runfolder.staged(folder, "run.json", overwrite=True, job="test") as stage:
        for name, text in NEW.items():
            (stage / name).parent.mkdir(parents=True, exist_ok=True)
            (stage / name).write_text(text)


def test_a_commit_failing_at_every_file_operation_leaves_one_whole_run(tmp_path, monkeypatch):
    """An error (not a kill) at any file operation of a commit: the folder holds exactly one
    whole run, the old one when the error came before the new marker was in place (every rename
    undone) and the new one after; the error names a file; the user's file is untouched."""

    probe = tmp_path / "probe"
    probe.mkdir()
    _write_old(probe)
    with monkeypatch.context() as m:
        count = _count_and_fail(m, probe, 0)
        _commit_job(probe)
    assert _state(probe) == "new"
    n_ops = count[0]
    assert n_ops >= 12
    outcomes = set()
    for k in range(1, n_ops + 1):
        folder = tmp_path / f"fail{k}"
        folder.mkdir()
        _write_old(folder)
        with monkeypatch.context() as m:
            _count_and_fail(m, folder, k)
            m.setattr(sys, "stderr", io.StringIO())
            try:
                _commit_job(folder)
                failed = None
            except (OSError, runfolder.RunFolderError) as e:
                failed = str(e)
        state = _state(folder)
        assert state in ("old", "new"), f"operation {k}: {state}"
        if failed is not None:
            assert state == "old" and str(folder) in failed, f"operation {k}: {failed}"
        elif k <= n_ops:  # a failure after the commit: a warning naming what was left
            assert state == "new"
        assert (folder / "my-notes.txt").read_text() == "the user's"
        outcomes.add((state, failed is None))
        runfolder.clear_leftovers(folder)
        assert _state(folder) == state
    assert ("old", False) in outcomes and ("new", True) in outcomes


def _entries(folder: pathlib.Path) -> list[str]:
    """The folder's entries, pid-stamped names (``.socialnav-tmp-<pid>-*``,
    ``.socialnav-staging-<pid>``, ``.socialnav-old-<pid>``) with the pid written as ``PID``, so
    that two jobs' folders compare."""
    stamped = re.compile(r"^(\.socialnav-(?:tmp|staging|old)-)\d+")
    return sorted(stamped.sub(r"\1PID", p.relative_to(folder).as_posix()) for p in folder.rglob("*"))


@pytest.mark.slow
def test_simulate_killed_at_every_file_operation(tmp_path):
    """The same for ``socialnav simulate`` itself, a previous run (seed 1) replaced with
    ``--overwrite`` (seed 0): after a kill at any operation the folder holds the old run whole,
    the new one whole, or no run.json; a plain rerun is refused while any result is visible; the
    next job's clean-up leaves no temporaries, and (at three of the kills) ``--overwrite`` then
    writes the new run. The writes inside the private staging folder are not counted here (the
    test above kills at every operation of a job, those included); every operation on the run
    folder's own entries is.

    One job copies its folder just before each operation (what a kill there leaves: the job
    writes through the OS, which the copy reads), instead of one killed job per operation (a
    whole simulation each); at the first, a middle and the last operation a job is also killed
    for real, and its folder holds the same entries as the copy."""
    from socialnav.cli.simulate import RESULTS

    argv = ["--worlds", "1", "--slots", "1", "--slot-length-s", "60", "--no-progress"]
    cli = "import sys; from socialnav.cli import main; sys.exit(main(['simulate', '--out', sys.argv[1]] + {argv}))"
    count_file = tmp_path / "count"
    pristine = tmp_path / "old"
    assert _run(cli.format(argv=argv + ["--seed", "1"]), pristine, 0, count_file) == 0
    old_meta = (pristine / "run.json").read_text()
    job = cli.format(argv=argv + ["--overwrite"])
    probe, snapshots = tmp_path / "probe", tmp_path / "snapshots"
    shutil.copytree(pristine, probe)
    assert _run(job, probe, 0, count_file, skip_staged=True, snapshots=snapshots) == 0
    n_ops = int(count_file.read_text())
    assert n_ops >= 6 and sorted(int(p.name) for p in snapshots.iterdir()) == list(range(1, n_ops + 1))
    for k in range(1, n_ops + 1):
        folder = snapshots / str(k)
        if k in (1, n_ops // 2, n_ops):  # a real kill there leaves what the copy holds
            killed = tmp_path / f"kill{k}"
            shutil.copytree(pristine, killed)
            assert _run(job, killed, k, count_file, skip_staged=True) == 9
            assert _entries(killed) == _entries(folder), f"operation {k}"
            folder = killed
        if (folder / "run.json").exists():
            meta = json.loads((folder / "run.json").read_text())
            assert (folder / "logs.parquet").exists() and meta["seed"] in (0, 1)
            if meta["seed"] == 1:
                assert (folder / "run.json").read_text() == old_meta
        if any((folder / name).exists() for name in RESULTS):  # what is left is never reused silently
            with pytest.raises(runfolder.PreviousRun, match="--overwrite"):
                runfolder.prepare(folder, RESULTS, overwrite=False, job="socialnav simulate")
        runfolder.clear_leftovers(folder)  # what the next job does first, here without its cost
        # The killed job's lock file stays until the next job takes it over (its holder is dead).
        left = {p.name for p in folder.iterdir() if p.name.startswith(".")}
        assert left - {runfolder.LOCK_FILE} == {runfolder.MANIFEST}
        if (folder / "run.json").exists():
            assert json.loads((folder / "run.json").read_text())["seed"] in (0, 1)
        if k in (1, n_ops // 2, n_ops):  # the whole next job, at the first, a middle and the last kill
            assert _run(job, folder, 0, count_file) == 0
            assert json.loads((folder / "run.json").read_text())["seed"] == 0
            assert [p.name for p in folder.iterdir() if p.name.startswith(".")] == [runfolder.MANIFEST]


USER_FILES = {
    "notes.txt": "my notes",
    "data/measurements.csv": "t,x\n0,1\n",
    "logs.txt": "not a run",
    ".keep": "",
    # A user's hidden files under the names the toolkit's scratch files had before they took its
    # prefix (its lock, a killed job's temporary, staging and aside folders): a job truncated and
    # removed the first and cleared the others as its own leftovers.
    ".lock": "a user's lock",
    ".tmp-1-draft.txt": "a draft",
    ".old-2024/thesis.tex": "last year's thesis",
    ".staging-1/plan.txt": "a plan",
}


def _commands(learned_run):
    tables = str(learned_run / "causal" / "engine_tables.npz")
    short = ["--worlds", "1", "--slots", "1", "--slot-length-s", "60", "--no-progress"]
    return {
        "simulate": ["simulate", *short, "--out", "{out}", "--overwrite"],
        "learn": ["learn", "--logs", str(learned_run), "--out", "{out}", "--overwrite", "--no-progress"],
        "evaluate": ["evaluate", "--tables", tables, "--out", "{out}", "--replicas", "1", "--slots", "S11"]
        + ["--no-progress", "--overwrite"],
        "ablation": ["ablation", "--out", "{out}", "--seeds", "1", "--probabilities", "0.3", "--no-progress"]
        + ["--overwrite"],
        "arena": ["arena", "--out", "{out}", "--scenes", "casn_head_on", "--methods", "navfn", "--variants", "2"]
        + ["--keep-trajectories", "1", "--no-progress", "--overwrite"],
        "layers": ["layers", "--out", "{out}"],
        "gscl generate": ["gscl", "generate", "--out", "{out}/d.npz", "--count", "group=4", "--overwrite"],
    }


@pytest.mark.parametrize(
    "job",
    [
        "simulate",
        pytest.param("learn", marks=pytest.mark.slow),
        pytest.param("evaluate", marks=pytest.mark.slow),
        pytest.param("ablation", marks=pytest.mark.slow),
        pytest.param("arena", marks=pytest.mark.slow),
        pytest.param("layers", marks=pytest.mark.slow),
        "gscl generate",
    ],
)
@pytest.mark.slow
def test_every_command_leaves_a_users_files_alone(job, learned_run, tmp_path):
    """Each command that writes a folder, run twice (the second time replacing its own run) into
    a folder of a user's files: they stay as they were, and every file the command left there is
    listed in the folder's manifest."""
    from socialnav import cli

    out = tmp_path / "mine"
    for name, text in USER_FILES.items():
        (out / name).parent.mkdir(parents=True, exist_ok=True)
        (out / name).write_text(text)
    argv = [a.replace("{out}", str(out)) for a in _commands(learned_run)[job]]
    assert cli.main(argv) == 0
    assert cli.main(argv) == 0
    for name, text in USER_FILES.items():
        assert (out / name).read_text() == text, name
    manifest = runfolder.read_manifest(out)
    written = {p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file()} - set(USER_FILES)
    if manifest is not None:
        assert written - {runfolder.MANIFEST} <= set(runfolder.owned_files(out)), written
    else:  # gscl generate writes a file and its record, not a folder
        assert written == {"d.npz", "d.json"}


def _victim_beside(folder: pathlib.Path) -> pathlib.Path:
    """A user's folder ``victim`` beside ``folder`` and a symbolic link ``folder/link`` to it."""
    victim = folder.parent / "victim"
    victim.mkdir()
    (victim / "precious.txt").write_text("the user's thesis")
    (folder / "link").symlink_to(victim, target_is_directory=True)
    return victim


@pytest.mark.slow
def test_a_manifest_naming_a_file_through_a_symbolic_link_is_refused(tmp_path, capsys):
    """A hand-edited manifest listing ``link/precious.txt`` beside ``link -> ../victim``:
    ``--overwrite`` refuses it in one line naming the entry, before moving anything; the user's
    file and the previous run stay whole."""
    from socialnav import cli

    out = tmp_path / "out"
    short = ["--worlds", "1", "--slots", "1", "--slot-length-s", "60", "--no-progress"]
    assert cli.main(["simulate", "--out", str(out), *short]) == 0
    logs = (out / "logs.parquet").read_bytes()
    victim = _victim_beside(out)
    manifest = json.loads((out / runfolder.MANIFEST).read_text())
    manifest["files"].append("link/precious.txt")
    (out / runfolder.MANIFEST).write_text(json.dumps(manifest))
    capsys.readouterr()

    assert cli.main(["simulate", "--out", str(out), "--overwrite", "--seed", "5", *short]) == 2
    err = capsys.readouterr().err
    assert "link/precious.txt" in err and "outside" in err and err.count("\n") == 1, err
    assert (victim / "precious.txt").read_text() == "the user's thesis"
    assert (out / "logs.parquet").read_bytes() == logs and (out / "run.json").is_file()


def test_a_journal_naming_a_file_through_a_symbolic_link_is_not_settled(tmp_path):
    """The same entry in an interrupted commit's journal: settling it refuses before a move."""
    folder = tmp_path / "run"
    folder.mkdir()
    _write_old(folder)
    victim = _victim_beside(folder)
    manifest = runfolder.read_manifest(folder)
    journal = {"old": ["link/precious.txt"], "new": [], "stage": ".staging-1", "aside": ".old-1"}
    runfolder.write_manifest(
        folder, runfolder.Manifest("test", "run.json", (*manifest.files, "link/precious.txt"), journal)
    )
    with pytest.raises(runfolder.NotOurs, match="link/precious.txt"):
        runfolder.clear_leftovers(folder)
    assert (victim / "precious.txt").read_text() == "the user's thesis"
    assert _state(folder) == "old"


def test_overwrite_takes_the_runs_derived_from_the_old_one_and_keeps_a_users_copies(tmp_path):
    """``--overwrite`` removes the old run with the runs later jobs derived from it inside its
    folder (another job's run under the name it was written in, or, in a manifest older than the
    name, any other job's run), never a user's copy kept there: the folder's run copied into
    ``backup/`` (the same job) or a derived run copied under another name (``learned-monday/``)."""
    folder = tmp_path / "run"
    folder.mkdir()
    _write_old(folder)
    shutil.copytree(folder, tmp_path / "copy")
    (tmp_path / "copy").rename(folder / "backup")
    for name in ("learned", "legacy"):
        (folder / name).mkdir()
        (folder / name / "report.json").write_text(f"{name} of the old run")
        runfolder.record(folder / name, "socialnav learn", ["report.json"], marker="report.json")
    shutil.copytree(folder / "learned", folder / "learned-monday")
    legacy = json.loads((folder / "legacy" / runfolder.MANIFEST).read_text())
    assert legacy.pop("name") == "legacy"  # as a version before the name wrote it
    (folder / "legacy" / runfolder.MANIFEST).write_text(json.dumps(legacy))
    kept = {p: p.read_bytes() for p in (folder / "backup").rglob("*") if p.is_file()}
    kept[folder / "learned-monday" / "report.json"] = b"learned of the old run"

    runfolder.prepare(folder, ("run.json", "logs.parquet", "snapshot.png", "causal"), overwrite=True, job="test")
    with runfolder.staged(folder, "run.json", overwrite=True, job="test") as stage:
        for name, text in NEW.items():
            (stage / name).parent.mkdir(parents=True, exist_ok=True)
            (stage / name).write_text(text)
    assert all((folder / name).read_text() == text for name, text in NEW.items())
    assert not (folder / "learned" / "report.json").exists() and not (folder / "legacy" / "report.json").exists()
    assert {p: p.read_bytes() for p in kept} == kept and len(kept) == 8
    assert runfolder.read_manifest(folder / "backup").name == "run"  # the copy says where its job wrote it


LOOK_ALIKES = {name: text for name, text in USER_FILES.items() if name.startswith(".") and name != ".keep"}


def test_only_the_toolkits_own_leftovers_are_cleared(tmp_path):
    """A killed job's scratch entries carry the toolkit's prefix and are removed by the next job's
    clean-up; a user's hidden files that look like scratch (``.old-2024/``, ``.tmp-1-...``) are
    not, nor a user's ``.lock``, which the job's lock never opens."""
    folder = tmp_path / "mine"
    for name, text in LOOK_ALIKES.items():
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_text(text)
    (folder / ".socialnav-tmp-4242-logs.parquet").write_text("half a file")
    (folder / ".socialnav-staging-4242").mkdir()
    (folder / ".socialnav-old-4242" / "causal").mkdir(parents=True)
    gone = runfolder.clear_leftovers(folder)
    assert gone == [".socialnav-old-4242", ".socialnav-staging-4242", ".socialnav-tmp-4242-logs.parquet"]
    with run_lock(folder, "test"):
        assert (folder / runfolder.LOCK_FILE).read_text().startswith("test (pid ")
    assert {p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file()} == set(LOOK_ALIKES)
    assert all((folder / name).read_text() == text for name, text in LOOK_ALIKES.items())


def test_a_commit_interrupted_under_the_older_scratch_names_is_settled_and_cleared(tmp_path):
    """A journal naming ``.staging-7`` and ``.old-7`` (the names before the toolkit's prefix): the
    journal makes them ours, so the old run is put back and both folders go; a user's
    ``.old-2024/`` beside them stays."""
    folder = tmp_path / "run"
    folder.mkdir()
    _write_old(folder)
    (folder / ".old-2024").mkdir()
    (folder / ".old-2024" / "thesis.tex").write_text("last year's thesis")
    stage, aside = folder / ".staging-7", folder / ".old-7"
    for name, text in NEW.items():
        (stage / name).parent.mkdir(parents=True, exist_ok=True)
        (stage / name).write_text(text)
    (aside / "causal").mkdir(parents=True)
    for name in OLD:  # killed after step 2: the old run's files aside, none of the new in place
        (folder / name).rename(aside / name)
    manifest = runfolder.read_manifest(folder)
    journal = {"old": sorted(OLD), "new": sorted(NEW), "stage": stage.name, "aside": aside.name}
    runfolder.write_manifest(folder, runfolder.Manifest("test", "run.json", manifest.files, journal))
    assert _state(folder) == "incomplete"
    assert runfolder.clear_leftovers(folder) == [".old-7", ".staging-7"]
    assert _state(folder) == "old" and runfolder.read_manifest(folder).journal is None
    assert (folder / ".old-2024" / "thesis.tex").read_text() == "last year's thesis"


@pytest.mark.slow
@pytest.mark.parametrize("entry", ["../victim/precious.txt", "/etc/passwd", "a/../../b"])
def test_a_manifest_naming_a_path_outside_is_not_a_manifest(tmp_path, entry):
    folder = tmp_path / "run"
    folder.mkdir()
    (folder / runfolder.MANIFEST).write_text(
        json.dumps({"format": runfolder.MANIFEST_FORMAT, "job": "test", "marker": None, "files": [entry]})
    )
    with pytest.raises(runfolder.NotOurs, match="not a socialnav run manifest"):
        runfolder.read_manifest(folder)


# ------------------------------------------------ the machine's faults: a full disk, Ctrl-C, SIGTERM


@pytest.fixture
def file_size_limit():
    """Lower this process's file-size limit (``ulimit -f``) for one test, then put it back: a
    write past it fails with EFBIG ("File too large"; Python ignores SIGXFSZ), the way a full
    disk's writes fail with ENOSPC, with no file system mounted."""
    import resource

    before = resource.getrlimit(resource.RLIMIT_FSIZE)

    def lower(limit_bytes: int) -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit_bytes, before[1]))

    yield lower
    resource.setrlimit(resource.RLIMIT_FSIZE, before)


def test_a_write_the_disk_refuses_names_the_file_asked_for(tmp_path, file_size_limit):
    """Python's own write and pyarrow's (an OSError with no errno, '[errno 27]' in its message)
    fail past the limit; the error names the final file, never the removed temporary, and keeps
    the errno, and nothing is left under either name."""
    import errno

    import pyarrow as pa
    import pyarrow.parquet as pq

    from socialnav.common.atomic import write_atomic

    file_size_limit(10_000)
    table = pa.table({"x": list(range(100_000))})
    for name, write in (
        ("bytes.bin", lambda tmp: tmp.write_bytes(b"x" * 20_000)),
        ("table.parquet", lambda tmp: pq.write_table(table, tmp, compression="none")),
    ):
        with pytest.raises(OSError) as caught:
            write_atomic(tmp_path / name, write)
        assert caught.value.errno == errno.EFBIG, (name, caught.value)
        assert caught.value.filename == str(tmp_path / name)
        assert list(tmp_path.iterdir()) == []


def test_an_error_naming_another_file_is_left_as_it_is(tmp_path):
    from socialnav.common.atomic import write_atomic

    with pytest.raises(FileNotFoundError) as caught:
        write_atomic(tmp_path / "out.txt", lambda tmp: (tmp_path / "absent" / "input.csv").read_text())
    assert caught.value.filename == str(tmp_path / "absent" / "input.csv")


def test_a_staged_run_the_disk_refuses_keeps_the_old_run_and_names_the_run_s_file(tmp_path, file_size_limit):
    """A staged job's write past the limit: the error names the file of the run it was to become
    (not the staging folder's), the previous run stays whole, and a folder the job created is
    removed with its staging folder."""
    from socialnav.common.atomic import write_text_atomic

    old = tmp_path / "old"
    with runfolder.staged(old, "run.json", False, job="test") as stage:
        write_text_atomic(stage / "run.json", "{}")
        write_text_atomic(stage / "data" / "a.txt", "first run")
    fresh = tmp_path / "new" / "run"
    file_size_limit(1_000)
    for folder in (old, fresh):
        with pytest.raises(OSError) as caught:
            with runfolder.staged(folder, "run.json", True, job="test") as stage:
                write_text_atomic(stage / "data" / "a.txt", "x" * 2_000)
        assert caught.value.filename == str(folder / "data" / "a.txt")
    assert (old / "data" / "a.txt").read_text() == "first run"
    assert not list(old.glob(f"{runfolder.STAGING_PREFIX}*"))
    assert not (tmp_path / "new").exists()


def test_a_command_ends_a_machine_fault_in_one_line(tmp_path, file_size_limit, capsys):
    """``cli.run_command``: a write past the limit is exit status 2 and one line naming the file;
    Ctrl-C 130; a real SIGTERM to this process 143 (the handler's ``finally`` ran), with the
    previous SIGTERM handler back afterwards; an error that is not the machine's propagates."""
    import signal

    from socialnav import cli
    from socialnav.common.atomic import write_atomic

    def write_too_much(args):
        write_atomic(tmp_path / "big.bin", lambda tmp: tmp.write_bytes(b"x" * 20_000))
        return 0

    file_size_limit(10_000)
    assert cli.run_command("socialnav test", write_too_much, None) == 2
    assert capsys.readouterr().err.strip() == f"socialnav test: cannot write {tmp_path / 'big.bin'}: File too large"

    def interrupted(args):
        raise KeyboardInterrupt

    assert cli.run_command("socialnav test", interrupted, None) == 130
    assert capsys.readouterr().err.strip() == "socialnav test: interrupted"

    cleaned = []

    def terminated(args):
        try:
            os.kill(os.getpid(), signal.SIGTERM)  # the handler raises at the next bytecode
            return 0
        finally:
            cleaned.append(True)

    import threading

    if threading.current_thread() is not threading.main_thread():  # a handler can be set in the main thread only
        pytest.skip("the SIGTERM half needs the main thread (it would end this worker)")
    previous = signal.signal(signal.SIGTERM, signal.SIG_DFL)
    try:
        assert cli.run_command("socialnav test", terminated, None) == 143
        assert signal.getsignal(signal.SIGTERM) == signal.SIG_DFL
    finally:
        signal.signal(signal.SIGTERM, previous)
    assert cleaned == [True]
    assert capsys.readouterr().err.strip() == "socialnav test: terminated (SIGTERM)"

    def a_bug(args):
        return (tmp_path / "absent.json").read_text()

    with pytest.raises(FileNotFoundError):
        cli.run_command("socialnav test", a_bug, None)
