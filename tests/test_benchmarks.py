"""benchmarks/run_all.py: one command for every job's speed, its figures gathered from the scripts."""

from __future__ import annotations

import importlib.util
import json
import os
import pathlib
import shutil
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent


def _load(name: str):
    spec = importlib.util.spec_from_file_location(f"benchmarks_{name}", ROOT / "benchmarks" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


run_all = _load("run_all")
record = _load("record")


def _row(cores, value, figure="env-steps/s", platform="cpu", **size):
    return {"job": "env", "figure": figure, "value": value, "unit": "x", "platform": platform, "cores": cores, **size}


def test_parallel_efficiency_is_against_the_fewest_cores_per_figure_and_size():
    rows = [
        _row(1, 100.0, batch=64),
        _row(2, 150.0, batch=64),
        _row(4, 200.0, batch=64),
        _row(2, 80.0, batch=1024),  # another size: its own base
        _row(4, 160.0, batch=1024),
        _row(4, 999.0, figure="collection"),  # one count only: no efficiency
        _row(16, 5000.0, platform="gpu", batch=64),  # an accelerator's figure is not a CPU's scaling
        _row(1, None, batch=64) | {"figure": "a run that failed"},
    ]
    run_all.add_efficiency(rows)
    assert [r.get("efficiency") for r in rows] == [1.0, 0.75, 0.5, 1.0, 1.0, None, None, None]
    run_all.add_efficiency(rows)  # again, as after every run: the same
    assert [r.get("efficiency") for r in rows[:3]] == [1.0, 0.75, 0.5]
    assert run_all.size_of(rows[0] | {"efficiency": 1.0, "compile_s": 2.0, "jax": "x"}) == "batch=64"


def test_bad_arguments_are_refused_in_one_line_naming_the_option(tmp_path, capsys):
    usable = len(os.sched_getaffinity(0))
    for argv, said in (
        (["--jobs", "warehouse,nonsense"], "argument --jobs: unknown job(s) ['nonsense']; known: warehouse"),
        (["--cores", "0"], f"each count must be 1 to {usable}"),
        (["--cores", str(usable + 1)], f"each count must be 1 to {usable}"),
        (["--cores", "1,two"], "is not a comma-separated list of integers"),
        (["--timeout", "0"], "argument --timeout: must be a finite number > 0, got 0"),
    ):
        with pytest.raises(SystemExit) as exit_:
            run_all.main([*argv, "--out", str(tmp_path / "new")])
        assert exit_.value.code == 2 and said in capsys.readouterr().err
    (tmp_path / "used").mkdir()
    (tmp_path / "used" / "results.md").write_text("an earlier run")
    with pytest.raises(SystemExit):
        run_all.main(["--out", str(tmp_path / "used")])
    assert "exists and is not empty" in capsys.readouterr().err
    assert (tmp_path / "used" / "results.md").read_text() == "an earlier run"
    assert not (tmp_path / "new").exists()


@pytest.mark.slow
def test_a_run_out_of_time_is_stopped_with_its_children_and_named_in_the_table(tmp_path):
    """bench_gscl.py starts a process of its own to generate (a few seconds in); stopped at 20 s,
    neither is left, the row says so and the call exits 1."""
    out = tmp_path / "bench"
    assert run_all.main(["--jobs", "gscl_generate", "--timeout", "20", "--platforms", "cpu", "--out", str(out)]) == 1
    (row,) = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    assert row["status"] == "timed out (20 s)" and row["value"] is None and row["job"] == "gscl_generate"
    assert "| timed out (20 s) |" in (out / "results.md").read_text()
    if shutil.which("pgrep"):
        pattern = "bench_gscl.py|from models import dataset"
        assert subprocess.run(["pgrep", "-f", pattern], capture_output=True, text=True).stdout == ""


def test_every_job_is_a_script_here_that_records_its_figures():
    for name, job in run_all.JOBS.items():
        source = (ROOT / "benchmarks" / job.script).read_text()
        assert f'record("{name}"' in source, name
    assert [run_all.number(v) for v in (52.44, 433718.2, 12.34e6, 2.5e9)] == ["52.4", "433,718", "12.3 M", "2.5 G"]


def test_a_figure_is_recorded_only_where_asked_with_its_device(tmp_path, monkeypatch):
    monkeypatch.delenv(record.RECORD_VARIABLE, raising=False)
    record.record("env", "env-steps/s", 1.0, "env-steps/s")  # nowhere to write: nothing written, no error
    path = tmp_path / "figures.jsonl"
    monkeypatch.setenv(record.RECORD_VARIABLE, str(path))
    record.record("env", "env-steps/s", 12.5, "env-steps/s", compile_s=1.23456, batch=64)
    record.record("env", "env-steps/s", 13.5, "env-steps/s", batch=1024)
    rows = [json.loads(line) for line in path.read_text().splitlines()]
    import jax

    assert [r["value"] for r in rows] == [12.5, 13.5] and [r["batch"] for r in rows] == [64, 1024]
    assert rows[0]["compile_s"] == 1.235 and rows[1]["compile_s"] is None
    assert rows[0]["platform"] == jax.devices()[0].platform and rows[0]["jax"] == jax.__version__


@pytest.mark.slow
def test_one_job_pinned_to_one_core_writes_its_figures_table_and_log(tmp_path):
    out = tmp_path / "bench"
    command = [sys.executable, str(ROOT / "benchmarks" / "run_all.py"), "--jobs", "env", "--cores", "1"]
    done = subprocess.run([*command, "--out", str(out), "--platforms", "cpu"], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    rows = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    assert {r["batch"] for r in rows} == {64, 1024}
    for r in rows:
        assert r["status"] == "ok" and r["platform"] == "cpu" and r["cores"] == 1 and r["devices"] == 1
        assert r["value"] > 0 and r["compile_s"] >= 0 and r["command"].startswith("taskset -c ")
    table = (out / "results.md").read_text()
    assert table.count("| env | env-steps/s |") == 2 and "commit" in table
    log = (out / "logs" / "env-cpu-1.log").read_text()
    assert "env-steps/s" in log and f", 1 of {os.cpu_count()} cores usable" in log  # pinned: it saw one core
