"""``socialnav simulate``: worlds of the warehouse in parallel; Parquet logs and pictures."""

from __future__ import annotations

import argparse
import pathlib
import sys

from socialnav.backend import BackendError, add_backend_options
from socialnav.cli.argtypes import (
    non_negative_float,
    output_folder,
    positive_float,
    positive_int,
    probability,
    seed_int,
)
from socialnav.common import runfolder
from socialnav.common.logschema import LOG_FILE, META_FILE
from socialnav.common.memory import shortfall
from socialnav.jaxsim import logs, viz
from socialnav.jaxsim.humans import HUMAN_MODELS
from socialnav.jaxsim.route_follower import route_follower
from socialnav.jaxsim.scenario import WAREHOUSE_DIR, ScenarioError, load_scenario
from socialnav.jaxsim.world import build_world
from socialnav.locking import locks_folder
from socialnav.planners.warehouse.routes import shortest_path_plan


def add_parser(sub) -> None:
    sim = sub.add_parser(
        "simulate",
        help="simulate the warehouse; write Parquet logs and pictures",
        description="Simulate worlds of the warehouse in parallel (the robot on shortest-path "
        "routes) and write logs.parquet, run.json, snapshot.png and "
        "density_by_slot.png to --out.",
    )
    sim.add_argument(
        "--scenario", type=pathlib.Path, default=None, help="scenario folder (default: the built-in warehouse)"
    )
    sim.add_argument("--worlds", type=positive_int, default=8, help="worlds simulated in parallel (default 8)")
    length = sim.add_mutually_exclusive_group()
    length.add_argument(
        "--slots",
        type=positive_int,
        default=None,
        help="simulated time slots from 08:00 (default: the whole day, 11 slots)",
    )
    length.add_argument(
        "--hours", type=positive_float, default=None, help="simulated hours from 08:00 (alternative to --slots)"
    )
    sim.add_argument(
        "--slot-length-s",
        type=positive_float,
        default=None,
        help="length of a time slot in s (default from params.json: 3600)",
    )
    sim.add_argument("--seed", type=seed_int, default=0, help="random seed (default 0)")
    sim.add_argument(
        "--out",
        type=output_folder,
        default=pathlib.Path("runs/warehouse"),
        help="output folder (default runs/warehouse); a folder holding a run is refused without --overwrite",
    )
    sim.add_argument(
        "--overwrite", action="store_true", help="replace the run in --out whole (only once the new one is complete)"
    )
    sim.add_argument(
        "--sample-interval-s",
        type=positive_float,
        default=1.0,
        help="logging interval in s, a multiple of dt (default 1.0)",
    )
    sim.add_argument(
        "--obstacle-probability",
        type=probability,
        default=None,
        help="probability of a static obstacle on a robot leg (default 0.25)",
    )
    sim.add_argument(
        "--snapshot-time-s",
        type=non_negative_float,
        default=None,
        help="time of the snapshot picture (default: the middle of the lunch slot S6, or of the run)",
    )
    sim.add_argument("--log-positions", action="store_true", help="also log every worker's position and status")
    sim.add_argument(
        "--human-model",
        choices=HUMAN_MODELS,
        default=None,
        help="how the workers move (default social_force, the warehouse's; docs/humans.md measures each against "
        "real pedestrians)",
    )
    sim.add_argument(
        "--human-fit",
        default=None,
        metavar="FIT_JSON[:METHOD]",
        help="the workers as a calibration fitted them, in place of --human-model: socialnav humans calibrate's "
        "fit.json (Jülich or --data tracks), its model with the fitted constants; METHOD gradient or nelder_mead "
        "(default: the one of lower training loss)",
    )
    sim.add_argument(
        "--shard-worlds",
        type=positive_int,
        default=None,
        help="worlds per shard (default: all in one, logs.parquet one file; with shards, logs.parquet is a "
        "folder of parts, one per shard, that pandas and pyarrow read as one table)",
    )
    sim.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    add_backend_options(sim)
    sim.set_defaults(handler=run)


def _human_fit(args: argparse.Namespace) -> str | None:
    """``--human-fit``'s model and values into ``args.human_model`` and ``args.human_values``
    (the named model's own without it); why not, in one line."""
    args.human_values = ()
    if args.human_fit is None:
        args.human_model = args.human_model or "social_force"
        return None
    from socialnav.evaluation.humans import fit_file

    try:
        people = fit_file.for_command(args.human_fit, args.human_model)
    except ValueError as e:
        return str(e)
    print(f"simulate: {fit_file.describe(people)}", flush=True)
    args.human_model, args.human_values = people.model, tuple(sorted(people.values.items()))
    return None


@locks_folder(lambda args: args.out, "simulate")
def run(args: argparse.Namespace) -> int:
    problem = _human_fit(args)  # sets args.human_model and args.human_values
    if problem is not None:
        return _usage(problem)
    overrides = {}
    if args.slot_length_s is not None:
        overrides["slot_length_s"] = args.slot_length_s
    if args.obstacle_probability is not None:
        overrides["robot_obstacle_probability"] = args.obstacle_probability
    try:
        scenario = load_scenario(args.scenario or WAREHOUSE_DIR, **overrides)
    except ScenarioError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    p = scenario.params
    if args.slots is not None and args.slots > scenario.n_slots:
        return _usage(f"--slots {args.slots}: the scenario has {scenario.n_slots} slots")
    if args.hours is not None:
        duration_s = args.hours * 3600.0
    else:
        duration_s = (args.slots or scenario.n_slots) * p.slot_length_s
    every = args.sample_interval_s / p.dt_s
    if abs(every - round(every)) > 1e-6 or round(every) < 1:
        return _usage(f"--sample-interval-s {args.sample_interval_s:g}: must be a multiple of dt_s = {p.dt_s:g} s")
    if args.snapshot_time_s is not None and args.snapshot_time_s > duration_s:
        return _usage(f"--snapshot-time-s {args.snapshot_time_s:g}: after the run's end ({duration_s:g} s)")
    in_memory = min(args.worlds, args.shard_worlds or args.worlds)
    needed = logs.estimate_memory_bytes(scenario, in_memory, args.log_positions)
    available = shortfall(needed, logs.MEMORY_SHARE)
    if available is not None:
        return _usage(
            f"--worlds {args.worlds}: about {needed / 1e9:.1f} GB at once, this machine has {available / 1e9:.1f} GB "
            "available; split the run with --shard-worlds (each shard in turn, or one per Ray task)"
        )
    try:
        runfolder.check_inputs(args.out, [args.scenario])
        runfolder.prepare(args.out, RESULTS, args.overwrite, job=JOB)
    except runfolder.RunFolderError as e:
        print(f"socialnav simulate: {e}", file=sys.stderr)
        return 2
    if args.snapshot_time_s is not None:
        snap_t = args.snapshot_time_s
    elif duration_s >= 6 * p.slot_length_s:
        snap_t = 5.5 * p.slot_length_s
    else:
        snap_t = duration_s / 2
    snap_t = round(snap_t / args.sample_interval_s) * args.sample_interval_s
    sharded = args.backend != "local" or (args.shard_worlds is not None and args.shard_worlds < args.worlds)
    try:
        with runfolder.staged(args.out, META_FILE, args.overwrite, job=JOB) as stage:
            if sharded:
                from socialnav import simulate_shards

                run = simulate_shards.run_sharded(args, scenario, overrides, duration_s, snap_t, stage)
            else:
                run = logs.simulate_to_parquet(
                    scenario,
                    stage,
                    route_follower(shortest_path_plan(scenario), build_world(scenario)),
                    n_worlds=args.worlds,
                    duration_s=duration_s,
                    seed=args.seed,
                    sample_interval_s=args.sample_interval_s,
                    log_positions=args.log_positions,
                    snapshot_time_s=snap_t,
                    progress=not args.no_progress,
                    human_model=args.human_model,
                    human_values=args.human_values,
                )
            pictures = []
            if run.snapshot is not None:
                pictures.append(viz.snapshot_png(scenario, run.snapshot, stage / "snapshot.png").name)
            pictures.append(
                viz.density_by_slot_png(scenario, run.mean_density_by_slot, stage / "density_by_slot.png").name
            )
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except (BackendError, runfolder.RunFolderError) as e:
        print(f"socialnav simulate: {e}", file=sys.stderr)
        return 2
    except OSError as e:  # a full disk or a folder made read-only during the run: the old run is kept
        print(f"socialnav simulate: cannot write {args.out}: {e.strerror or e}", file=sys.stderr)
        return 2

    f = run.final
    n = len(f["tasks_started"])
    mean = lambda k: sum(f[k]) / n
    print(
        f"\nsimulated {args.worlds} world(s) x {duration_s:.0f} s ({duration_s / p.slot_length_s:.2f} slots of "
        f"{p.slot_length_s:.0f} s), {p.n_workers} workers ({args.human_model}) + robot, seed {args.seed}"
    )
    print(
        f"wall time {run.wall_s:.1f} s (until the first chunk, compile included: {run.compile_s:.1f} s), "
        f"{run.agent_steps_per_s / 1e6:.2f} M agent-steps/s"
    )
    print(
        f"robot per world: {mean('tasks_succeeded'):.1f} tasks succeeded, {mean('tasks_failed'):.1f} failed, "
        f"stalled {mean('stalled_s'):.0f} s, final battery {mean('battery_pct'):.1f} %"
    )
    for k in range(scenario.n_slots):
        if run.slot_samples[k]:
            d = run.mean_density_by_slot[k]
            top = [scenario.waypoint_ids[i] for i in d.argsort()[::-1][:2] if d[i] > 0]
            print(f"  {scenario.slot_names[k]:>3} {scenario.slot_clock[k]:>11}: most crowded {', '.join(top) or '-'}")
    print(f"wrote {args.out / LOG_FILE} ({run.rows} rows), {args.out / META_FILE}")
    for pic in pictures:
        print(f"wrote {args.out / pic}")
    return 0


# What a finished run leaves in its folder (a folder holding any of them holds a run).
RESULTS = (META_FILE, LOG_FILE, "snapshot.png", "density_by_slot.png")
JOB = "socialnav simulate"  # the name its run folders' manifest records


def _usage(message: str) -> int:
    print(f"socialnav simulate: error: {message}", file=sys.stderr)
    return 2
