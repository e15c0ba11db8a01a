"""One writer per run folder: a second job is refused with the holder's name; no stale locks; a
lock file that is a symbolic link is refused, never written through."""

from __future__ import annotations

import os
import pathlib
import subprocess
import sys
import textwrap

import pytest

from socialnav import cli
from socialnav.common.runlock import LOCK_FILE, RunFolderError, RunLocked, read_lock, run_lock

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _holder(folder: pathlib.Path, lock: str = 'run_lock({folder!r}, "socialnav simulate")') -> subprocess.Popen:
    """Another process holding ``folder``'s lock (``lock``, a writer's by default) until its
    stdin closes."""
    code = textwrap.dedent(
        f"""
        import sys
        from socialnav.common.runlock import read_lock, run_lock
        with {lock.format(folder=str(folder))}:
            print("held", flush=True)
            sys.stdin.read()
        """
    )
    proc = subprocess.Popen(
        [sys.executable, "-c", code], cwd=ROOT, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )
    assert proc.stdout.readline().strip() == "held"
    return proc


def test_a_second_job_on_a_folder_is_refused_naming_the_holder_and_the_lock_dies_with_it(tmp_path, capsys):
    folder = tmp_path / "run"
    holder = _holder(folder)
    try:
        with pytest.raises(RunLocked, match=rf"being written by socialnav simulate \(pid {holder.pid} "):
            with run_lock(folder, "test"):
                pass
        code = cli.main(["simulate", "--worlds", "1", "--hours", "0.01", "--out", str(folder), "--no-progress"])
        assert code == 2
        err = capsys.readouterr().err
        assert err.startswith("socialnav simulate: ") and f"pid {holder.pid}" in err and len(err.splitlines()) == 1
        assert sorted(p.name for p in folder.iterdir()) == [LOCK_FILE]  # nothing written
    finally:
        holder.kill()  # killed, not closed: the operating system drops the lock
        holder.wait()
    with run_lock(folder, "test") as held:
        assert held == folder.resolve()


def test_the_lock_is_reentrant_in_one_process_and_an_idle_job_leaves_no_folder(tmp_path):
    folder = tmp_path / "new"
    with run_lock(folder, "outer"):
        with run_lock(folder, "inner"):  # socialnav run's steps take their folder again
            assert (folder / LOCK_FILE).read_text().startswith(f"outer (pid {os.getpid()}")
    assert not folder.exists()  # created for nothing: removed
    kept = tmp_path / "kept"
    with run_lock(kept, "job"):
        (kept / "result.txt").write_text("x")
    assert sorted(p.name for p in kept.iterdir()) == ["result.txt"]  # the lock file goes with the job


def test_a_job_refused_on_bad_input_leaves_no_folder(tmp_path):
    out = tmp_path / "never"
    assert cli.main(["simulate", "--out", str(out), "--scenario", str(tmp_path / "missing")]) == 2
    assert not out.exists()
    nested = tmp_path / "a" / "b" / "never"  # nor the folders above it that the job made
    assert cli.main(["simulate", "--out", str(nested), "--scenario", str(tmp_path / "missing")]) == 2
    assert list(tmp_path.iterdir()) == []


# Every command that writes a run folder, with the least it parses; the lock is taken first.
WRITERS = {
    "humans validate": ["humans", "validate", "--quick"],
    "humans predict": ["humans", "predict", "--run", "uo-050-180-180"],
    "humans calibrate": ["humans", "calibrate"],
    "gscl evaluate": ["gscl", "evaluate", "--run", "data/gscl/default"],
    "gscl rules": ["gscl", "rules", "--run", "data/gscl/default"],
    "gscl export": ["gscl", "export", "--run", "data/gscl/default"],
    "gscl fit-tracks": ["gscl", "fit-tracks", "--scene", "gscl_queue"],
    "gscl train": ["gscl", "train"],
    "layers": ["layers"],
    "simulate": ["simulate"],
    "arena": ["arena", "--scenes", "casn_head_on"],
    "run": ["run"],
    "ablation": ["ablation"],
    "evaluate": ["evaluate"],
    "referee": ["referee"],
    "policy train": ["policy", "train"],
}


@pytest.mark.parametrize("command", list(WRITERS))
def test_every_command_that_writes_a_folder_waits_for_no_one(command, tmp_path, capsys):
    """A second job on a folder another job is writing is refused at once naming the holder, by
    every command that writes one (the humans and gscl model commands wrote without the lock: a
    second one's clean-up could remove the first one's staging folder)."""
    folder = tmp_path / "run"
    holder = _holder(folder)
    try:
        assert cli.main([*WRITERS[command], "--out", str(folder)]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"socialnav {command}: --out: ") and f"pid {holder.pid}" in err, err
        assert sorted(p.name for p in folder.iterdir()) == [LOCK_FILE]
    finally:
        holder.kill()
        holder.wait()


def test_an_out_that_is_a_file_is_refused_before_any_work(tmp_path, capsys):
    file = tmp_path / "taken"
    file.write_text("mine")
    assert cli.main(["arena", "--out", str(file), "--scenes", "casn_crossing", "--variants", "1"]) == 2
    err = capsys.readouterr().err
    assert err == f"socialnav arena: --out: {file} is a file, not a folder\n"
    assert file.read_text() == "mine"
    assert cli.main(["simulate", "--out", str(file / "below"), "--worlds", "1", "--hours", "0.01"]) == 2
    assert "cannot write there" in capsys.readouterr().err


def test_a_lock_file_that_is_a_symbolic_link_is_refused_and_its_target_untouched(tmp_path, capsys):
    """Opening it would truncate and write the file it points to, outside the run folder."""
    precious = tmp_path / "precious.txt"
    precious.write_text("mine")
    out = tmp_path / "out"
    out.mkdir()
    (out / LOCK_FILE).symlink_to(precious)
    with pytest.raises(RunFolderError, match=r"\.socialnav-lock is a symbolic link \(to .*precious\.txt\)"):
        with run_lock(out, "socialnav simulate"):
            pass
    assert cli.main(["simulate", "--out", str(out), "--worlds", "1", "--hours", "0.01"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("socialnav simulate: --out: ") and "symbolic link" in err and err.count("\n") == 1
    assert precious.read_text() == "mine" and (out / LOCK_FILE).is_symlink()


SHORT = ["--worlds", "1", "--slots", "1", "--slot-length-s", "60", "--no-progress"]
ADVICE = "wait for it or choose another --out"


def test_a_run_being_read_is_not_replaced_and_a_run_being_replaced_is_not_read(tmp_path, capsys):
    """``learn`` reading a run holds it shared: ``simulate --overwrite`` on it is refused while it
    reads (the commit would rename the logs away under it), and ``learn`` is refused while a
    writer holds the run; readers share, and the last one out removes the lock file."""
    run = tmp_path / "run"
    assert cli.main(["simulate", "--out", str(run), *SHORT]) == 0
    logs = (run / "logs.parquet").read_bytes()
    capsys.readouterr()
    reader = _holder(run, "read_lock({folder!r})")
    try:
        assert cli.main(["simulate", "--out", str(run), "--overwrite", "--seed", "3", *SHORT]) == 2
        err = capsys.readouterr().err
        assert err == f"socialnav simulate: --out: {run} is being read by another socialnav job; {ADVICE}\n"
        assert (run / "logs.parquet").read_bytes() == logs
        with read_lock(run), read_lock(run):  # readers share, in one process and beside another
            assert (run / LOCK_FILE).exists()
    finally:
        reader.kill()
        reader.wait()
    with read_lock(run):
        pass
    assert not (run / LOCK_FILE).exists()  # the last reader out removed it

    writer = _holder(run)
    try:
        out = tmp_path / "engine"
        assert cli.main(["learn", "--logs", str(run), "--out", str(out), "--no-progress"]) == 2
        err = capsys.readouterr().err
        assert err.startswith(
            f"socialnav learn: --logs: {run} is being written by socialnav simulate (pid {writer.pid} "
        )
        assert err.endswith("wait for it to finish before reading the run\n") and not out.exists()
    finally:
        writer.kill()
        writer.wait()
