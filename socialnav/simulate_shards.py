"""``socialnav simulate`` cut into shards of worlds (``--shard-worlds``, ``--backend ray``).

Shard ``k`` simulates worlds ``first .. first + n - 1`` (the same worlds as one run of them all:
:func:`jaxsim.rollout.world_keys`) with :func:`jaxsim.logs.simulate_to_parquet` into a private
folder and returns its Parquet file's bytes and its summary; the driver saves each as
``.shards/part-<first>.parquet`` (+ ``.json``) as it arrives. When every shard is there the
staging folder becomes ``logs.parquet`` (a folder of parts that ``pandas.read_parquet`` and
``pyarrow.parquet.read_table`` open as one table, worlds in order) in one rename, then
``run.json`` is written with the merged counters, the shard layout and the backend. A killed
driver leaves the finished parts; a rerun with the same settings computes only the missing ones.
"""

from __future__ import annotations

import json
import os
import pathlib
import tempfile
import time

import numpy as np

from socialnav import backend as backend_lib
from socialnav.common.atomic import write_atomic, write_text_atomic
from socialnav.common.logschema import LOG_FILE, META_FILE

STAGING = ".shards"


def compute_shard(
    scenario_dir, overrides, first, n, duration_s, seed, sample_interval_s, log_positions, snap_t,
    human_model="social_force", human_values=(),
):  # fmt: skip
    """Simulate one shard of worlds (here or in a Ray worker): ``(Parquet bytes, summary dict)``."""
    from socialnav.jaxsim import logs
    from socialnav.jaxsim.route_follower import route_follower
    from socialnav.jaxsim.scenario import WAREHOUSE_DIR, load_scenario
    from socialnav.jaxsim.world import build_world
    from socialnav.planners.warehouse.routes import shortest_path_plan

    scenario = load_scenario(scenario_dir or WAREHOUSE_DIR, **overrides)
    with tempfile.TemporaryDirectory(prefix="socialnav-shard-") as tmp:
        run = logs.simulate_to_parquet(
            scenario,
            tmp,
            route_follower(shortest_path_plan(scenario), build_world(scenario)),
            n_worlds=n,
            human_model=human_model,
            human_values=human_values,
            duration_s=duration_s,
            seed=seed,
            sample_interval_s=sample_interval_s,
            log_positions=log_positions,
            snapshot_time_s=snap_t,
            progress=False,
            first_world=first,
        )
        data = pathlib.Path(run.log_file).read_bytes()
    density = np.nan_to_num(run.mean_density_by_slot) * run.slot_samples[:, None]
    summary = {
        "first_world": first,
        "n_worlds": n,
        "rows": run.rows,
        "wall_s": run.wall_s,
        "compile_s": run.compile_s,
        "density_sum": density.tolist(),
        "slot_samples": run.slot_samples.tolist(),
        "snapshot": None
        if run.snapshot is None
        else {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in run.snapshot.items()},
        "final": run.final,
    }
    return data, summary


def _save(shard: backend_lib.Shard, result) -> None:
    data, summary = result
    write_text_atomic(shard.output.with_suffix(".json"), json.dumps(summary))
    write_atomic(shard.output, lambda tmp: tmp.write_bytes(data))  # last: marks the shard done


def run_sharded(args, scenario, overrides: dict, duration_s: float, snap_t: float, dest: pathlib.Path):
    """Run the shards with the chosen backend, then write ``logs.parquet`` and ``run.json`` into
    ``dest`` (the run's staging folder, :func:`common.runfolder.staged`); returns a
    :class:`jaxsim.logs.RunSummary` for the command's report."""
    from socialnav.jaxsim import logs

    out = pathlib.Path(args.out)
    size = args.shard_worlds or args.worlds
    staging = out / STAGING
    settings = {
        "scenario": str(args.scenario) if args.scenario else None,
        "overrides": overrides,
        "worlds": args.worlds,
        "shard_worlds": size,
        "duration_s": duration_s,
        "seed": args.seed,
        "sample_interval_s": args.sample_interval_s,
        "log_positions": args.log_positions,
        "snapshot_time_s": snap_t,
        "human_model": args.human_model,
        **({"human_values": dict(args.human_values)} if args.human_values else {}),
    }
    backend_lib.staging_folder(staging, settings)  # another run's parts are not ours to reuse
    scenario_dir = None if args.scenario is None else str(pathlib.Path(args.scenario).resolve())
    shards = [
        backend_lib.Shard(
            name=f"worlds {first}-{first + min(size, args.worlds - first) - 1}",
            output=staging / f"part-{first:06d}.parquet",
            args=(
                scenario_dir,
                overrides,
                first,
                min(size, args.worlds - first),
                duration_s,
                args.seed,
                args.sample_interval_s,
                args.log_positions,
                snap_t if first == 0 else None,
                args.human_model,
                args.human_values,
            ),
            work=min(size, args.worlds - first),
        )
        for first in range(0, args.worlds, size)
    ]
    start = time.perf_counter()
    backend_lib.run_with_args(
        compute_shard, _save, shards, args, desc=f"simulate {args.worlds} world(s)", unit="worlds"
    )
    wall = time.perf_counter() - start
    summaries = [json.loads(s.output.with_suffix(".json").read_text()) for s in shards]
    for s in shards:
        s.output.with_suffix(".json").unlink()
    (staging / "settings.json").unlink()
    # The parts' folder becomes logs.parquet in one rename (same file system: inside --out).
    target = dest / LOG_FILE
    os.replace(staging, target)
    p = scenario.params
    density = sum(np.asarray(s["density_sum"]) for s in summaries)
    samples = sum(np.asarray(s["slot_samples"]) for s in summaries)
    final = {k: [v for s in summaries for v in s["final"][k]] for k in summaries[0]["final"]}
    rows = sum(s["rows"] for s in summaries)
    agent_steps = args.worlds * round(duration_s / p.dt_s) * (p.n_workers + 1)
    meta = logs.run_metadata(
        scenario,
        seed=args.seed,
        n_worlds=args.worlds,
        duration_s=duration_s,
        sample_interval_s=args.sample_interval_s,
        rows=rows,
        wall_s=wall,
        compile_s=max(s["compile_s"] for s in summaries),
        agent_steps_per_s=agent_steps / wall,
        human_model=args.human_model,
        **({"human_values": dict(args.human_values)} if args.human_values else {}),
        shards=[{"first_world": s["first_world"], "n_worlds": s["n_worlds"]} for s in summaries],
        **backend_lib.describe(args),
        final=final,
    )
    write_text_atomic(dest / META_FILE, json.dumps(meta, indent=1))
    snapshot = summaries[0]["snapshot"]
    if snapshot is not None:
        snapshot = {k: (np.asarray(v) if isinstance(v, list) else v) for k, v in snapshot.items()}
    with np.errstate(invalid="ignore"):
        mean_density = density / samples[:, None]
    return logs.RunSummary(
        target,
        dest / META_FILE,
        rows,
        wall,
        meta["compile_s"],
        agent_steps / wall,
        mean_density,
        samples,
        snapshot,
        final,
    )
