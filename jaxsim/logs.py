"""Rollouts written to Parquet, in chunks, atomically.

One row per logged sample per world; rows come in time chunks, world by world within a chunk
(sort by ``world, time_s`` for one series per world). The files and columns are the written
contract of :mod:`common.logschema` (the causal pipeline reads them through it):

* ``world``, ``seed``, and the settings ``dt_s``, ``slot_length_s``, ``n_workers``,
  ``obstacle_probability``: so runs can be concatenated and still told apart;
* ``time_s``, ``slot`` (0-based index; names in ``run.json``);
* robot: ``robot_x_m``, ``robot_y_m``, ``robot_speed_mps`` (V), ``battery_pct`` (B),
  ``battery_change_pct`` (L of the last step), ``charging`` (C), ``obstacle`` (O), ``robot_mode``
  (0 task, 1 to charger, 2 charging), ``robot_waypoint`` (nearest visible waypoint: W),
  ``goal_wp``, ``leg_elapsed_s``, ``tasks_started``, ``tasks_succeeded``, ``tasks_failed``,
  ``stalled_s``, ``n_present``;
* ``density_<waypoint>``: Eq. (3) people per m^2 in each waypoint disc;
* ``dist_worker_<i>``: robot-worker centre distance in m, NaN while worker i is absent;
* with ``log_positions``: ``worker_x_<i>``, ``worker_y_<i>``, ``worker_status_<i>``.

The log is written to a temporary file and renamed when complete, so a killed run leaves no half
file under the final name; ``run.json`` (settings, names, timings) is written the same way.
"""

from __future__ import annotations

import dataclasses
import json
import pathlib
import time

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from socialnav.common import logschema, memory
from socialnav.common import progress as progress_lib
from socialnav.common.atomic import atomic_path, write_text_atomic
from socialnav.common.logschema import LOG_FILE, META_FILE, density_column, distance_column, position_columns
from socialnav.jaxsim import native
from socialnav.jaxsim.actor import Driver
from socialnav.jaxsim.scenario import Scenario
from socialnav.jaxsim.state import ACTIVITY, WALKING

# Device memory for one time chunk of records (all worlds); bounds the host memory too.
CHUNK_BUDGET_BYTES = 256 * 2**20


@dataclasses.dataclass
class RunSummary:
    """What a :func:`simulate_to_parquet` run did.

    Attributes:
      log_file, meta_file: the files written.
      rows: rows in the log.
      wall_s: wall time of the whole run (compile included); ``compile_s`` of the first chunk.
      agent_steps_per_s: (workers + robot) x steps x worlds / wall_s.
      mean_density_by_slot: (S, W) mean Eq. (3) density per slot and waypoint over all worlds.
      slot_samples: (S,) samples that went into each slot's mean.
      snapshot: worker/robot positions of world 0 at the snapshot time (or None).
      final: per-world final counters (tasks succeeded/failed, battery).
    """

    log_file: pathlib.Path
    meta_file: pathlib.Path
    rows: int
    wall_s: float
    compile_s: float
    agent_steps_per_s: float
    mean_density_by_slot: np.ndarray
    slot_samples: np.ndarray
    snapshot: dict | None
    final: dict


def record_table(rec, world_ids: np.ndarray, scenario: Scenario, seed: int, log_positions: bool) -> pa.Table:
    """Flatten batched numpy records (B, T, ...) into a table of B*T rows."""
    p = scenario.params
    b, t = rec.time_s.shape
    fixed = {
        "world": np.repeat(world_ids, t),
        "seed": np.full(b * t, seed),
        "dt_s": np.full(b * t, p.dt_s),
        "slot_length_s": np.full(b * t, p.slot_length_s),
        "n_workers": np.full(b * t, p.n_workers),
        "obstacle_probability": np.full(b * t, p.robot_obstacle_probability),
        **{
            name: np.asarray(getattr(rec, name)).reshape(-1)
            for name, _ in logschema.CLOCK_COLUMNS + logschema.ROBOT_COLUMNS
        },
    }
    columns = logschema.ID_COLUMNS + logschema.SETTING_COLUMNS + logschema.CLOCK_COLUMNS + logschema.ROBOT_COLUMNS
    cols: dict[str, pa.Array] = {name: pa.array(fixed[name].astype(dtype)) for name, dtype in columns}
    for k, wp in enumerate(scenario.waypoint_ids):
        cols[density_column(wp)] = pa.array(rec.density_ppm2[:, :, k].reshape(-1))
    for i in range(p.n_workers):
        cols[distance_column(i)] = pa.array(rec.worker_dist_m[:, :, i].reshape(-1))
    if log_positions:
        for i in range(p.n_workers):
            x, y, status = position_columns(i)
            cols[x] = pa.array(rec.worker_x_m[:, :, i].reshape(-1))
            cols[y] = pa.array(rec.worker_y_m[:, :, i].reshape(-1))
            cols[status] = pa.array(rec.worker_status[:, :, i].reshape(-1).astype(np.int8))
    return pa.table(cols)


# The share of the available memory a run's estimate may take (the estimate is an upper one).
MEMORY_SHARE = 0.9


def estimate_memory_bytes(scenario: Scenario, n_worlds: int, log_positions: bool = False) -> int:
    """A rough upper estimate of the memory a run of ``n_worlds`` worlds holds at once: the
    states (about 64 bytes per worker and 400 for the robot, three copies: input, output, host),
    one chunk of records on the device and on the host (at least one sample per world), and the
    social force's pair arrays of one chunk of worlds (N/2 x N floats, about ten live at once).
    Measured: 3.2 kB of state per world for 50 workers."""
    from socialnav.jaxsim.rollout import DEFAULT_WORLD_CHUNK

    n = scenario.params.n_workers
    state = 64 * n + 400
    per_sample = 4 * (scenario.n_waypoints + n * (4 if log_positions else 2) + 32)
    records = 2 * max(CHUNK_BUDGET_BYTES, per_sample * n_worlds)
    pairs = min(n_worlds, DEFAULT_WORLD_CHUNK) * (n + 1) * max((n + 1) // 2, 1) * 4 * 10
    return 3 * state * n_worlds + records + pairs


def chunk_samples(n_samples: int, bytes_per_sample: int, budget: int = CHUNK_BUDGET_BYTES, min_chunks: int = 20) -> int:
    """Largest divisor of ``n_samples`` whose chunk fits ``budget`` and leaves at least
    ``min_chunks`` chunks for the progress bar (equal chunks: one compile)."""
    cap = max(1, min(budget // max(bytes_per_sample, 1), n_samples // min_chunks))
    best = 1
    for d in range(1, int(np.sqrt(n_samples)) + 1):
        if n_samples % d == 0:
            for c in (d, n_samples // d):
                if c <= cap:
                    best = max(best, c)
    return best


class SimulationDiverged(ValueError):
    """A world's state turned NaN or infinite; the message names the world, the time and the field."""


def check_finite(rec, first_world: int = 0) -> None:
    """Raise :class:`SimulationDiverged` if a logged robot signal, density or present worker's
    position is NaN or infinite (extreme parameters can make the explicit integration blow up;
    such a day is stopped, not written)."""
    present = (rec.worker_status == WALKING) | (rec.worker_status == ACTIVITY)
    fields = {
        "robot_x_m": rec.robot_x_m,
        "robot_y_m": rec.robot_y_m,
        "robot_speed_mps": rec.robot_speed_mps,
        "battery_pct": rec.battery_pct,
        "density_ppm2": rec.density_ppm2,
        "worker_x_m": np.where(present, rec.worker_x_m, 0.0),
        "worker_y_m": np.where(present, rec.worker_y_m, 0.0),
    }
    for name, values in fields.items():
        bad = ~np.isfinite(values)
        if bad.any():
            first = tuple(np.argwhere(bad)[0])
            world, sample = first[:2]
            raise SimulationDiverged(
                f"the simulation diverged: {name} is {values[first]} in world "
                f"{first_world + world} at t = {rec.time_s[world, sample]:.1f} s; nothing was written "
                "(check the scenario's force and speed parameters)"
            )


def reproducibility() -> dict:
    """What the logs' bits depend on, for ``run.json``: the same seed and settings give the same
    logs bit for bit whatever the batch size, shard layout and number of host devices (tested:
    ``tests/test_determinism.py``); across machines, XLA compiles for the host CPU's instruction
    set, so the CPU model and the jax/jaxlib versions are recorded too (not tested across CPUs)."""
    from socialnav.common.machine import compiler_host

    return {
        "independent_of": ["batch size", "shards", "number of host devices"],
        **compiler_host(),
        "social_force": native.describe(),  # floats differ between the kernel and JAX, not the model
    }


def run_metadata(scenario: Scenario, *, final: dict, **fields) -> dict:
    """``run.json``'s content: the schema version, ``fields`` (seed, worlds, duration, rows,
    timings, ...), the JAX devices, the scenario's names and parameters, the final counters."""
    import jax

    return {
        "schema_version": logschema.SCHEMA_VERSION,
        **fields,
        "jax_devices": [str(d) for d in jax.devices()],
        "reproducibility": reproducibility(),
        "scenario": scenario.name,
        "waypoints": list(scenario.waypoint_ids),
        "slots": list(scenario.slot_names),
        "slot_clock": list(scenario.slot_clock),
        "params": dataclasses.asdict(scenario.params),
        "final": final,
    }


def simulate_to_parquet(
    scenario: Scenario,
    out_dir: str | pathlib.Path,
    driver: Driver,
    *,
    n_worlds: int,
    duration_s: float,
    seed: int = 0,
    sample_interval_s: float = 1.0,
    log_positions: bool = False,
    snapshot_time_s: float | None = None,
    progress: bool = True,
    chunk_budget_bytes: int = CHUNK_BUDGET_BYTES,
    first_world: int = 0,
    human_model: str = "social_force",
    human_values=(),
) -> RunSummary:
    """Simulate ``n_worlds`` worlds for ``duration_s`` and write ``logs.parquet`` + ``run.json``.

    Args:
      scenario: the validated scenario (its params included).
      out_dir: output folder (created); each file is renamed into place when written (the
        command line stages the whole run and commits it at once: :mod:`common.runfolder`).
      driver: the robot's actor and its params, e.g.
        ``route_follower(planners.warehouse.routes.shortest_path_plan(s), world)``
        (:func:`jaxsim.route_follower.route_follower`).
      n_worlds: batch size; world ``b`` is the same world bit for bit for a given seed whatever
        ``n_worlds`` and the number of host devices.
      duration_s: simulated time, a multiple of ``sample_interval_s``.
      sample_interval_s: logging interval, a multiple of ``dt_s``.
      log_positions: also log every worker's position and status.
      snapshot_time_s: keep the first world's positions at this time for a picture.
      first_world: the first world's index (a shard of a larger run: worlds ``first_world ..
        first_world + n_worlds - 1``, the same worlds as in one run of them all).
      human_model: how the workers move (:data:`jaxsim.humans.HUMAN_MODELS`; recorded in
        ``run.json``).
      human_values: ``("<part>.<field>", value)`` pairs setting that model's constants (a
        calibration's fit, :func:`jaxsim.world.build_world`; recorded in ``run.json`` when given).

    Raises:
      ValueError: on inconsistent sizes, or a batch whose estimate (:func:`estimate_memory_bytes`)
        is past :data:`MEMORY_SHARE` of the memory available, before anything is written.
    """

    from socialnav.jaxsim import rollout
    from socialnav.jaxsim import world as world_lib

    p = scenario.params
    every = sample_interval_s / p.dt_s
    if n_worlds < 1:
        raise ValueError(f"n_worlds must be >= 1, got {n_worlds}")
    if sample_interval_s <= 0 or abs(every - round(every)) > 1e-6 or round(every) < 1:
        raise ValueError(f"sample_interval_s={sample_interval_s} must be a positive multiple of dt_s={p.dt_s}")
    every = int(round(every))
    n_samples = duration_s / (every * p.dt_s)
    if duration_s <= 0 or abs(n_samples - round(n_samples)) > 1e-6:
        raise ValueError(
            f"duration_s={duration_s} must be a positive multiple of sample_interval_s={sample_interval_s}"
        )
    n_samples = int(round(n_samples))
    needed = estimate_memory_bytes(scenario, n_worlds, log_positions)
    available = memory.shortfall(needed, MEMORY_SHARE)
    if available is not None:
        raise ValueError(
            f"n_worlds={n_worlds}: about {needed / 1e9:.1f} GB at once, this machine has {available / 1e9:.1f} GB "
            "available; simulate the worlds in shards (first_world, n_worlds) as socialnav simulate --shard-worlds does"
        )
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)

    start = time.perf_counter()
    world = world_lib.build_world(scenario, human_model, human_values)
    keys = rollout.world_keys(seed, n_worlds, first_world)
    states = rollout.init_batch(p, world, driver, keys)
    per_sample = 4 * (scenario.n_waypoints + p.n_workers * (4 if log_positions else 2) + 32)
    chunk = chunk_samples(n_samples, per_sample * n_worlds, chunk_budget_bytes)
    n_chunks = n_samples // chunk

    n_slots = scenario.n_slots
    dens_sum = np.zeros((n_slots, scenario.n_waypoints))
    dens_n = np.zeros(n_slots)
    snapshot = None
    final = {}
    writer = None
    rows = 0
    compile_s = 0.0
    with (
        atomic_path(out / LOG_FILE) as tmp,
        progress_lib.bar(f"simulate {n_worlds} world(s)", unit="sim s", enabled=progress) as bar,
    ):
        try:
            pending = rollout.run_samples(p, world, driver, states, keys, chunk, every)
            for c in range(n_chunks):
                states, rec = pending
                if c + 1 < n_chunks:  # dispatch the next chunk before converting this one
                    pending = rollout.run_samples(p, world, driver, states, keys, chunk, every)
                rec = rollout.to_numpy(rec)
                check_finite(rec, first_world)
                if c == 0:
                    compile_s = time.perf_counter() - start
                table = record_table(rec, np.arange(first_world, first_world + n_worlds), scenario, seed, log_positions)
                if writer is None:
                    writer = pq.ParquetWriter(tmp, table.schema, compression="zstd")
                writer.write_table(table)
                rows += table.num_rows
                np.add.at(dens_sum, rec.slot.reshape(-1), rec.density_ppm2.reshape(-1, scenario.n_waypoints))
                np.add.at(dens_n, rec.slot.reshape(-1), 1)
                if snapshot_time_s is not None and snapshot is None:
                    hit = np.flatnonzero(rec.time_s[0] >= snapshot_time_s - 1e-6)
                    if hit.size:
                        k = hit[0]
                        snapshot = {
                            "time_s": float(rec.time_s[0, k]),
                            "slot": int(rec.slot[0, k]),
                            "worker_x_m": rec.worker_x_m[0, k],
                            "worker_y_m": rec.worker_y_m[0, k],
                            "worker_status": rec.worker_status[0, k],
                            "robot_x_m": float(rec.robot_x_m[0, k]),
                            "robot_y_m": float(rec.robot_y_m[0, k]),
                        }
                final = {
                    f: getattr(rec, f)[:, -1].tolist()
                    for f in ("tasks_started", "tasks_succeeded", "tasks_failed", "battery_pct", "stalled_s")
                }
                bar.update((c + 1) * chunk * every * p.dt_s, n_samples * every * p.dt_s)
        finally:
            if writer is not None:
                writer.close()
        wall = time.perf_counter() - start

    agent_steps = n_worlds * n_samples * every * (p.n_workers + 1)
    meta = run_metadata(
        scenario,
        seed=seed,
        n_worlds=n_worlds,
        first_world=first_world,
        human_model=human_model,
        **({"human_values": dict(sorted(dict(human_values).items()))} if human_values else {}),
        duration_s=duration_s,
        sample_interval_s=sample_interval_s,
        rows=rows,
        wall_s=wall,
        compile_s=compile_s,
        agent_steps_per_s=agent_steps / wall,
        final=final,
    )
    write_text_atomic(out / META_FILE, json.dumps(meta, indent=1))
    with np.errstate(invalid="ignore"):
        mean_density = dens_sum / dens_n[:, None]
    return RunSummary(
        out / LOG_FILE,
        out / META_FILE,
        rows,
        wall,
        compile_s,
        agent_steps / wall,
        mean_density,
        dens_n,
        snapshot,
        final,
    )
