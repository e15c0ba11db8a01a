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

import json
import os
import pathlib
import subprocess
import sys
import textwrap

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]

# Wraps the file operations of the job run after it; kills the process before operation KILL_AT.
KILLER = textwrap.dedent(
    """
    import os, shutil, sys
    KILL_AT = int(os.environ["KILL_AT"])
    FOLDER = os.path.realpath(sys.argv[1])
    SKIP_STAGED = os.environ.get("SKIP_STAGED", "0")  # "1": writes inside the private staging folder are not counted
    count = [0]
    def counted(fn):
        def wrapper(*a, **k):
            paths = [os.path.realpath(str(x)) for x in a if isinstance(x, (str, os.PathLike))]
            if any(p.startswith(FOLDER) and (SKIP_STAGED == "0" or "/.staging-" not in p[len(FOLDER):]) for p in paths):
                count[0] += 1
                if count[0] == KILL_AT:
                    os._exit(9)
            return fn(*a, **k)
        return wrapper
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
    from common import runfolder
    folder = pathlib.Path(sys.argv[1])
    runfolder.prepare(folder, ("run.json", "logs.parquet", "snapshot.png"), overwrite=True)
    with runfolder.staged(folder, "run.json", overwrite=True) as stage:
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


def _state(folder: pathlib.Path) -> str:
    """'old' (the previous run whole), 'new' (the new one whole) or 'incomplete' (no marker);
    fails on a file holding anything but a whole old or new content."""
    for path in folder.rglob("*"):
        rel = str(path.relative_to(folder))
        if path.is_file() and not rel.startswith("."):  # temporaries are hidden and cleared next time
            text = path.read_text()
            assert text in (OLD.get(rel), NEW.get(rel), "old only"), f"{rel} holds {text!r}"
    if not (folder / "run.json").exists():
        return "incomplete"
    marker = (folder / "run.json").read_text()
    expected = OLD if marker == "old" else NEW
    for name, text in expected.items():
        assert (folder / name).read_text() == text, f"{marker} run without its {name}"
    return marker


def _run(code: str, folder: pathlib.Path, kill_at: int, count_file: pathlib.Path, skip_staged: bool = False) -> int:
    env = dict(os.environ, KILL_AT=str(kill_at), COUNT_FILE=str(count_file), PYTHONPATH=str(ROOT))
    env["SKIP_STAGED"] = "1" if skip_staged else "0"
    # Compiled programs shared between the runs of a test (its own folder, not the user's cache).
    env["SOCIALNAV_JAX_CACHE"] = str(count_file.parent / "xla-cache")
    return subprocess.run([sys.executable, "-c", KILLER + code, str(folder)], env=env, cwd=ROOT).returncode


def test_a_run_folder_killed_at_every_file_operation(tmp_path):
    count_file = tmp_path / "count"
    whole = tmp_path / "whole"
    whole.mkdir()
    _write_old(whole)
    assert _run(JOB, whole, 0, count_file) == 0
    assert _state(whole) == "new" and not (whole / "density_by_slot.png").exists()
    n_ops = int(count_file.read_text())
    assert n_ops >= 8
    seen = set()
    for k in range(1, n_ops + 1):
        folder = tmp_path / f"kill{k}"
        folder.mkdir()
        _write_old(folder)
        assert _run(JOB, folder, k, count_file) == 9
        seen.add(_state(folder))
        assert _run(JOB, folder, 0, count_file) == 0  # the next job recovers
        assert _state(folder) == "new"
        assert not [p.name for p in folder.iterdir() if p.name.startswith(".")], "temporaries left"
    assert seen >= {"old", "incomplete"}


@pytest.mark.slow
def test_simulate_killed_at_every_file_operation(tmp_path):
    """The same for ``socialnav simulate`` itself, a previous run (seed 1) replaced with
    ``--overwrite`` (seed 0): after each kill the folder holds the old run whole, the new one
    whole, or no run.json; a plain rerun is refused while any result is visible, and
    ``--overwrite`` recovers, with no temporaries left. The writes inside the private staging
    folder are not counted here (the test above kills at every operation of a job, those
    included); every operation on the run folder's own entries is."""
    import shutil

    from common import runfolder
    from socialnav.simulate import RESULTS

    argv = ["--worlds", "1", "--slots", "1", "--slot-length-s", "60", "--no-progress"]
    cli = "import sys; from socialnav.cli import main; sys.exit(main(['simulate', '--out', sys.argv[1]] + {argv}))"
    count_file = tmp_path / "count"
    pristine = tmp_path / "old"
    assert _run(cli.format(argv=argv + ["--seed", "1"]), pristine, 0, count_file) == 0
    old_meta = (pristine / "run.json").read_text()
    job = cli.format(argv=argv + ["--overwrite"])
    probe = tmp_path / "probe"
    shutil.copytree(pristine, probe)
    assert _run(job, probe, 0, count_file, skip_staged=True) == 0
    n_ops = int(count_file.read_text())
    assert n_ops >= 6
    for k in range(1, n_ops + 1):
        folder = tmp_path / f"kill{k}"
        shutil.copytree(pristine, folder)
        assert _run(job, folder, k, count_file, skip_staged=True) == 9
        if (folder / "run.json").exists():
            meta = json.loads((folder / "run.json").read_text())
            assert (folder / "logs.parquet").exists() and meta["seed"] in (0, 1)
            if meta["seed"] == 1:
                assert (folder / "run.json").read_text() == old_meta
        if any((folder / name).exists() for name in RESULTS):  # what is left is never reused silently
            with pytest.raises(runfolder.PreviousRun, match="--overwrite"):
                runfolder.prepare(folder, RESULTS, overwrite=False)
        assert _run(job, folder, 0, count_file) == 0
        assert json.loads((folder / "run.json").read_text())["seed"] == 0
        assert not [p.name for p in folder.iterdir() if p.name.startswith(".")]
