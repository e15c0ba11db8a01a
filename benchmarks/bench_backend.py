"""The Ray backend's overhead against the local one, job by job, on this machine.

    python benchmarks/bench_backend.py                                  # simulate, gscl generate, arena
    python benchmarks/bench_backend.py --tables runs/warehouse/causal/engine_tables.npz   # + evaluate

Each job runs twice with the same shard layout, ``--backend local`` then ``--backend ray`` (a
local Ray instance on this machine, started before the clock), each in a fresh process of the
``socialnav`` command (compilation included, as a user meets it); prints both wall times, the
overhead and whether the outputs are the same bit for bit. Sizes are set so that each run lasts
a minute or more here.
"""

from __future__ import annotations

import argparse
import pathlib
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from benchmarks.bench_simulator import machine  # noqa: E402

JOBS = {
    "simulate": ["simulate", "--worlds", "8", "--shard-worlds", "4", "--no-progress"],
    "gscl generate": ["gscl", "generate", "--scale", "8", "--shard-samples", "32768", "--no-progress"],
    "arena": [
        "arena",
        "--scenes",
        "casn_crossing,casn_head_on,gscl_group,snape_walking",
        "--variants",
        "100",
        "--shard-variants",
        "50",
        "--keep-trajectories",
        "0",
        "--no-progress",
    ],
}
OUTPUT = {"simulate": "logs.parquet", "gscl generate": "out.npz", "arena": "episodes", "evaluate": "tasks.parquet"}


def _same(a: pathlib.Path, b: pathlib.Path) -> bool:
    import numpy as np
    import pandas as pd

    if a.suffix == ".npz":
        x, y = np.load(a), np.load(b)
        return all(np.array_equal(x[k], y[k]) for k in x.files)
    if a.is_dir() and a.name == "episodes":
        return all(pd.read_parquet(f).equals(pd.read_parquet(b / f.name)) for f in sorted(a.glob("*.parquet")))
    return pd.read_parquet(a).equals(pd.read_parquet(b))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tables", type=pathlib.Path, default=None, help="engine tables: also time 'evaluate'")
    parser.add_argument("--jobs", default=None, help="comma-separated subset of the jobs")
    args = parser.parse_args()
    jobs = dict(JOBS)
    if args.tables is not None:
        jobs["evaluate"] = ["evaluate", "--tables", str(args.tables.resolve()), "--replicas", "8"]
        jobs["evaluate"] += ["--shard-replicas", "4", "--slots", "S1,S6,S11", "--no-progress"]
    if args.jobs:
        jobs = {k: v for k, v in jobs.items() if k in args.jobs.split(",")}
    import ray

    print(f"machine: {machine()}, ray {ray.__version__}")
    exe = str(pathlib.Path(sys.executable).with_name("socialnav"))
    ray_cli = str(pathlib.Path(sys.executable).with_name("ray"))
    with tempfile.TemporaryDirectory() as tmp_dir:
        tmp = pathlib.Path(tmp_dir)
        subprocess.run([ray_cli, "start", "--head", "--num-cpus", "2", "--disable-usage-stats"], check=True,
                       capture_output=True)  # fmt: skip
        try:
            for job, command in jobs.items():
                walls = {}
                for backend in ("local", "ray"):
                    out = tmp / f"{job.replace(' ', '_')}-{backend}"
                    target = ["--out", str(out / "out.npz")] if job == "gscl generate" else ["--out", str(out)]
                    extra = ["--backend", backend] + (["--ray-address", "auto"] if backend == "ray" else [])
                    start = time.perf_counter()
                    subprocess.run([exe, *command, *target, *extra], check=True, capture_output=True, cwd=tmp)
                    walls[backend] = time.perf_counter() - start
                name = OUTPUT[job]
                same = _same(tmp / f"{job.replace(' ', '_')}-local" / name, tmp / f"{job.replace(' ', '_')}-ray" / name)
                overhead = 100.0 * (walls["ray"] / walls["local"] - 1.0)
                print(
                    f"{job:<14} local {walls['local']:6.1f} s   ray {walls['ray']:6.1f} s   "
                    f"overhead {overhead:+5.1f} %   same bits: {same}",
                    flush=True,
                )
        finally:
            subprocess.run([ray_cli, "stop", "--force"], capture_output=True)


if __name__ == "__main__":
    main()
