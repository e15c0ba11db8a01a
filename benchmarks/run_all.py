"""Every batch job's speed on this machine in one command: what to run first on a new machine.

    python benchmarks/run_all.py                           # every job at its quick size (about 15 min on 2 cores)
    python benchmarks/run_all.py --jobs warehouse,env      # some of them
    python benchmarks/run_all.py --cores 1,2               # the CPU runs pinned to 1, then 2 cores: parallel efficiency
    python benchmarks/run_all.py --size full --timeout 3600   # the sizes the docs' figures use (hours on 2 cores)

Each job is one of the benchmark scripts beside this one (``benchmarks/bench_*.py``, listed in
:data:`JOBS`), run in a new process with a time limit, so that its compilation is a first run's and
one job failing or running out of time leaves the others' figures. The scripts print their own
report (kept in ``logs/``) and hand their headline figures back through
:func:`benchmarks.record.record`: the figure, its unit, the seconds spent compiling apart from the
timed run where the script measures them, the size it ran at, and the device and JAX version it ran
on.

**Platforms.** Where JAX finds an accelerator (a GPU), every job runs twice in the same call: on
it (JAX's default) and on the CPU (``JAX_PLATFORMS=cpu``), so each accelerator figure has the CPU's
beside it. ``--platforms cpu`` runs the CPU only.

**Cores.** ``--cores 1,2,4`` runs each CPU job once per count, pinned to the first k of the cores
this process may use (``os.sched_setaffinity``, what ``taskset -c`` does); the jobs' host devices
and XLA's threads follow the pinning (:func:`socialnav.runtime.request_host_devices`). Each figure's
parallel efficiency is then given against the fewest cores measured, k0:
``rate(k) / rate(k0) / (k / k0)`` (1 is perfect scaling). Without ``--cores`` the CPU runs use
every usable core.

Writes into ``--out`` (default ``runs/bench-<host>-<UTC time>``, a new folder): ``results.jsonl``
(every figure, one JSON object a line, with the run's platform, cores, command and status),
``results.md`` (the table, the machine above it) and ``logs/<job>-<platform>-<cores>.log`` (each
script's own output), all rewritten after every run so that a call stopped part way keeps what it
measured. Exits 1 if any run failed or ran out of time (its row says which), 0 otherwise.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import json
import os
import pathlib
import platform
import re
import signal
import socket
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from benchmarks.record import RECORD_VARIABLE  # noqa: E402
from socialnav.cli.argtypes import positive_float  # noqa: E402
from socialnav.common.atomic import write_text_atomic  # noqa: E402
from socialnav.common.machine import cpu_model, usable_cores  # noqa: E402
from socialnav.common.provenance import source  # noqa: E402
from socialnav.runtime import cpu_has_avx512  # noqa: E402


@dataclasses.dataclass(frozen=True)
class Job:
    """A benchmark script and its arguments at each size."""

    script: str
    quick: tuple[str, ...]
    full: tuple[str, ...]
    what: str


JOBS = {
    "warehouse": Job(
        "bench_simulator.py",
        ("--batches", "64", "1024", "--seconds", "3", "--no-peers", "--no-reference"),
        ("--batches", "64", "1024", "4096", "16384", "--seconds", "5", "--no-peers", "--no-reference"),
        "the warehouse step, every part switched on",
    ),
    "protocol": Job("bench_evaluation.py", ("--replicas", "2"), ("--replicas", "32"), "seed 000's evaluation protocol"),
    "env": Job(
        "bench_env.py",
        ("--batches", "64", "1024", "--repeats", "2"),
        ("--batches", "64", "1024", "16384", "131072", "--repeats", "3"),
        "the arena's environment, 10 people, a trivial actor",
    ),
    "human_models": Job(
        "bench_human_models.py",
        ("--people", "64", "--worlds", "256", "--steps", "20", "--repeats", "2"),
        (),
        "one crowd step of every human model",
    ),
    "arena": Job(
        "bench_arena.py",
        ("--scenes", "gscl_group,casn_crossing", "--variants", "20", "--skip-profile"),
        ("--held-out", "--skip-profile"),
        "socialnav arena, compilation included",
    ),
    "gscl_generate": Job(
        "bench_gscl.py",
        ("--skip-throughput", "--skip-train", "--generation-fraction", "0.1"),
        ("--skip-throughput", "--skip-train"),
        "GSCL's dataset generation",
    ),
    "gscl_train": Job(
        "bench_gscl_loop.py",
        ("--rounds", "2", "--steps", "20"),
        ("--rounds", "3", "--steps", "100"),
        "GSCL's training step",
    ),
    "ppo": Job(
        "bench_policy.py",
        ("--scenes", "gscl_group", "--updates", "2"),
        (),
        "PPO in the arena: a whole update and the collection alone",
    ),
    "irl": Job("bench_irl.py", ("--batches", "32", "--seconds", "3"), (), "GSCL trained through the planner"),
}

# The fields of a figure that say what was measured where, not at what size.
_NOT_SIZE = {"job", "figure", "value", "unit", "compile_s", "platform", "device", "devices", "jax", "note", "wall_s"}
_NOT_SIZE |= {"new_process_s", "cached_process_s", "cores", "status", "command", "run_s", "efficiency"}


def parse_cores(text: str) -> list[int]:
    """``"1,2,4"`` -> ``[1, 2, 4]``: distinct positive counts, at most the usable cores."""
    try:
        cores = sorted({int(v) for v in text.split(",") if v.strip()})
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a comma-separated list of integers") from None
    if not cores or cores[0] < 1 or cores[-1] > usable_cores():
        raise argparse.ArgumentTypeError(f"{text!r}: each count must be 1 to {usable_cores()} (the usable cores)")
    return cores


def parse_jobs(text: str) -> list[str]:
    names = [v.strip() for v in text.split(",") if v.strip()]
    unknown = [n for n in names if n not in JOBS]
    if unknown or not names:
        raise argparse.ArgumentTypeError(f"unknown job(s) {unknown or [text]}; known: {', '.join(JOBS)}")
    return names


def accelerator() -> str | None:
    """The platform JAX picks by default where it is not the CPU (``"gpu"``, ``"tpu"``), asked in a
    child process so that this one never holds the accelerator's memory; None if the CPU."""
    env = {k: v for k, v in os.environ.items() if k != "JAX_PLATFORMS"}
    code = "import jax; print(jax.default_backend())"
    try:
        done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=300)
    except subprocess.TimeoutExpired:
        return None
    backend = done.stdout.strip().splitlines()[-1] if done.returncode == 0 and done.stdout.strip() else "cpu"
    return None if backend == "cpu" else backend


def machine_line() -> str:
    avx = "AVX-512" if cpu_has_avx512() else "no AVX-512"
    return (
        f"{cpu_model()} ({avx}), {usable_cores()} of {os.cpu_count()} cores usable, {platform.system()}, "
        f"Python {platform.python_version()}"
    )


def _commit() -> str:
    """The checkout's commit as the run folders name it (:func:`common.provenance.source`)."""
    made_from = source()
    if made_from["source_commit"] is None:
        return "commit unknown"
    dirty = " with uncommitted changes" if made_from["source_dirty"] else ""
    return f"commit {made_from['source_commit'][:12]}{dirty}"


def child_env(platform_name: str, cores: int | None, record_path: str) -> dict[str, str]:
    """The environment of one run: the figures' file, the CPU forced where asked, and without a host
    device count set by the caller when the run is pinned (the job then asks for its cores)."""
    env = dict(os.environ, **{RECORD_VARIABLE: record_path})
    if platform_name == "cpu":
        env["JAX_PLATFORMS"] = "cpu"
    else:
        env.pop("JAX_PLATFORMS", None)
    if cores is not None:
        flags = re.sub(r"--xla_force_host_platform_device_count=\S+", "", env.get("XLA_FLAGS", "")).strip()
        env["XLA_FLAGS"] = flags
    return env


def _chosen(cores: int) -> list[int]:
    """The first ``cores`` of the cores this process may run on."""
    return sorted(os.sched_getaffinity(0))[:cores]


def _pin(cores: int | None):
    """A ``preexec_fn`` pinning the child to the first ``cores`` usable cores (None: no pinning)."""
    if cores is None:
        return None
    chosen = _chosen(cores)
    return lambda: os.sched_setaffinity(0, chosen)


def number(value: float) -> str:
    """A figure for a person: ``12.3 M``, ``433,718``, ``52.4``."""
    if value >= 1e9:
        return f"{value / 1e9:,.3g} G"
    if value >= 1e6:
        return f"{value / 1e6:,.3g} M"
    return f"{value:,.0f}" if value >= 1000 else f"{value:.3g}"


def run_job(name: str, size: str, platform_name: str, cores: int | None, timeout_s: float, logs: pathlib.Path):
    """Run one job once; returns its figures (each with the run's platform, cores, command, status
    and wall seconds), or one row with status ``failed (exit N)`` or ``timed out`` and no value."""
    job = JOBS[name]
    args = job.quick if size == "quick" else job.full
    command = [sys.executable, str(ROOT / "benchmarks" / job.script), *args]
    label = f"{name}-{platform_name}-{'all' if cores is None else cores}"
    shown = " ".join(["python", f"benchmarks/{job.script}", *args])
    if platform_name == "cpu":
        shown = "JAX_PLATFORMS=cpu " + shown
    if cores is not None:
        shown = f"taskset -c {','.join(map(str, _chosen(cores)))} " + shown
    with tempfile.TemporaryDirectory() as tmp:
        record_path = os.path.join(tmp, "record.jsonl")
        env = child_env(platform_name, cores, record_path)
        t0 = time.perf_counter()
        with open(logs / f"{label}.log", "w", encoding="utf-8") as log:
            log.write(f"$ {shown}\n")
            log.flush()
            # A session of its own, so that a run out of time is stopped with the processes it started
            # (bench_simulator's reference, bench_gscl's generation), not only the script.
            child = subprocess.Popen(
                command, env=env, stdout=log, stderr=subprocess.STDOUT, preexec_fn=_pin(cores), start_new_session=True
            )
            try:
                code = child.wait(timeout=timeout_s)
                status = "ok" if code == 0 else f"failed (exit {code})"
            except subprocess.TimeoutExpired:
                os.killpg(child.pid, signal.SIGKILL)
                child.wait()
                status = f"timed out ({timeout_s:g} s)"
        run_s = round(time.perf_counter() - t0, 1)
        figures = []
        if os.path.exists(record_path):
            with open(record_path, encoding="utf-8") as f:
                figures = [json.loads(line) for line in f if line.strip()]
    common = {"cores": cores if cores is not None else usable_cores(), "status": status, "command": shown}
    common["run_s"] = run_s
    if not figures:
        return [{"job": name, "figure": job.what, "value": None, "unit": "", "platform": platform_name, **common}]
    return [{**row, **common} for row in figures]


def size_of(row: dict) -> str:
    """The size a figure was measured at (``batch=1024``), from its own fields."""
    return ", ".join(f"{k}={row[k]}" for k in sorted(row) if k not in _NOT_SIZE)


def add_efficiency(rows: list[dict]) -> None:
    """Each CPU figure's parallel efficiency against the same figure at the fewest cores measured,
    ``rate(k) / rate(k0) / (k / k0)``, in place (``efficiency``; absent where only one count ran)."""
    groups: dict[tuple, list[dict]] = {}
    for row in rows:
        if row.get("platform") == "cpu" and row.get("value"):
            groups.setdefault((row["job"], row["figure"], size_of(row)), []).append(row)
    for group in groups.values():
        base = min(group, key=lambda r: r["cores"])
        for row in group:
            row.pop("efficiency", None)
            if len({r["cores"] for r in group}) > 1:
                row["efficiency"] = round(row["value"] / base["value"] / (row["cores"] / base["cores"]), 3)


def table(rows: list[dict], header: str) -> str:
    lines = [
        header,
        "",
        "| job | figure | size | device | cores | value | compile s | parallel efficiency | status |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        value = "" if r.get("value") is None else f"{number(r['value'])} {r['unit']}"
        compile_s = "" if r.get("compile_s") is None else f"{r['compile_s']:.1f}"
        eff = "" if r.get("efficiency") is None else f"{r['efficiency']:.2f}"
        device = r.get("device", r.get("platform", ""))
        lines.append(
            f"| {r['job']} | {r['figure']} | {size_of(r)} | {device} | {r['cores']} | {value} | {compile_s} | {eff} "
            f"| {r['status']} |"
        )
    lines += ["", "Commands, as run (in `logs/`, each job's own report):", ""]
    for command in dict.fromkeys(r["command"] for r in rows):
        lines.append(f"    {command}")
    return "\n".join(lines) + "\n"


def _write(out: pathlib.Path, rows: list[dict], header: str) -> None:
    add_efficiency(rows)
    write_text_atomic(out / "results.jsonl", "".join(json.dumps(r) + "\n" for r in rows))
    write_text_atomic(out / "results.md", table(rows, header))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--jobs", type=parse_jobs, default=list(JOBS), help=f"comma-separated, of: {', '.join(JOBS)}")
    parser.add_argument("--size", choices=("quick", "full"), default="quick")
    parser.add_argument("--cores", type=parse_cores, default=None, help="pin the CPU runs to each count, e.g. 1,2,4")
    parser.add_argument("--platforms", choices=("all", "cpu"), default="all", help="cpu: skip an accelerator")
    parser.add_argument("--timeout", type=positive_float, default=900.0, help="seconds a run may take (default 900)")
    parser.add_argument(
        "--out", type=pathlib.Path, default=None, help="a new folder (default runs/bench-<host>-<time>)"
    )
    args = parser.parse_args(argv)
    stamp = datetime.datetime.now(datetime.UTC).strftime("%Y%m%dT%H%M%SZ")
    out = args.out or ROOT / "runs" / f"bench-{socket.gethostname()}-{stamp}"
    if out.exists() and any(out.iterdir()):
        parser.error(f"--out: {out} exists and is not empty; give a new folder")
    (out / "logs").mkdir(parents=True, exist_ok=True)
    gpu = None if args.platforms == "cpu" else accelerator()
    header = f"machine: {machine_line()}; accelerator: {gpu or 'none'}; {_commit()}; {stamp}"
    print(header, flush=True)
    runs = [(job, gpu, None) for job in args.jobs] if gpu else []
    runs += [(job, "cpu", k) for job in args.jobs for k in (args.cores or [None])]
    rows: list[dict] = []
    for i, (job, platform_name, cores) in enumerate(runs, 1):
        where = f"{platform_name}" + ("" if cores is None else f", {cores} core(s)")
        print(f"[{i}/{len(runs)}] {job} on {where} ...", flush=True)
        got = run_job(job, args.size, platform_name, cores, args.timeout, out / "logs")
        rows += got
        _write(out, rows, header)
        for r in got:
            value = "-" if r.get("value") is None else f"{number(r['value'])} {r['unit']}"
            print(f"    {r['figure']} {size_of(r)}: {value} ({r['status']}, {r['run_s']:.0f} s)", flush=True)
    print()
    print(table(rows, header), end="")
    print(f"wrote {out / 'results.md'} and {out / 'results.jsonl'}")
    return 0 if all(r["status"] == "ok" for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
