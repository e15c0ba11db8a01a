"""``socialnav evaluate``: seed 000's causal planner against the shortest-path baseline."""

from __future__ import annotations

import argparse
import json
import pathlib
import sys

from socialnav import backend as backend_lib
from socialnav import evaluate_shards
from socialnav.backend import add_backend_options
from socialnav.cli.argtypes import comma_names, output_folder, positive_float, positive_int, seed_int
from socialnav.common import runfolder
from socialnav.common.memory import shortfall
from socialnav.evaluation import warehouse
from socialnav.evaluation.protocol import ProtocolConfig
from socialnav.jaxsim.scenario import WAREHOUSE_DIR, Scenario, ScenarioError, load_scenario
from socialnav.locking import locks_folder
from socialnav.planners.warehouse.tables import TABLES_FILE, CausalTables, TablesError


def add_parser(sub) -> None:
    ev = sub.add_parser(
        "evaluate",
        help="causal planner vs shortest-path baseline (seed 000 Sec. 5.2-5.4)",
        description="Every slot's experiment (200 tasks, S11 the 90-leg tour) with both methods "
        "and common random numbers, for --replicas independent replicas; writes "
        "tasks.parquet, per_slot.csv, summary.json and Fig. 9-11 to --out.",
    )
    ev.add_argument(
        "--tables",
        type=pathlib.Path,
        default=pathlib.Path("runs/warehouse/causal") / TABLES_FILE,
        help=f"the causal engine's tables, written by 'socialnav learn' (default runs/warehouse/causal/{TABLES_FILE})",
    )
    add_evaluation_options(ev, default_out=None)
    ev.add_argument("--scenario", type=pathlib.Path, default=None, help="scenario folder (default: the warehouse)")
    ev.add_argument(
        "--shard-replicas",
        type=positive_int,
        default=None,
        help="replicas per shard (default: all in one; a Ray task per shard with --backend ray)",
    )
    add_backend_options(ev)
    ev.set_defaults(handler=run)


# What a finished evaluation leaves in its folder; summary.json is written last.
RESULTS = (
    "summary.json",
    "tasks.parquet",
    "per_slot.csv",
    "distance_hist.npz",
    "fig9_efficiency.png",
    "fig10_safety.png",
    "fig11_routes.png",
)
JOB = "socialnav evaluate"
# Memory of one experiment (a replica of a slot) in the batch, measured as the growth of the peak
# resident set of `socialnav evaluate --slots S11` (/usr/bin/time -v): 602 MB at 1 replica, 678
# MB at 4, 733 MB at 16, so about 4.6 MB per experiment beyond the first few; and of its tasks' rows
# kept until the report (about 400 tasks of two methods, an estimate). For the refusal before a run
# the machine cannot hold.
EXPERIMENT_BYTES = 5_000_000
TASK_ROWS_BYTES = 150_000
# Seconds of one experiment, both methods, on this project's 2-core machine: the 32-replica
# protocol of 11 slots took 281.9 s (README "What it finds"), 0.8 s per replica and slot.
EXPERIMENT_S = 0.8


def add_evaluation_options(p: argparse.ArgumentParser, default_out, replicas: int = 32) -> None:
    """The options ``evaluate`` and ``run`` share (``--overwrite`` included)."""
    p.add_argument(
        "--replicas",
        type=positive_int,
        default=replicas,
        help=f"independent replicas of the whole protocol (default {replicas})",
    )
    p.add_argument(
        "--slots",
        type=comma_names,
        default=None,
        help="comma-separated slot names to run, e.g. S1,S6,S11 (default: all)",
    )
    p.add_argument("--seed", type=seed_int, default=0, help="random seed (default 0)")
    p.add_argument(
        "--collision-radius-m",
        type=positive_float,
        default=None,
        help="robot-person centre distance that counts as a collision (default: the robot's radius, "
        "0.275 m, as the paper; 0.475 counts any body contact)",
    )
    p.add_argument(
        "--deadline-per-task",
        action="store_true",
        help="the 45 s deadline bounds the whole task (the paper's wording) instead of each route "
        "hop (the reference code)",
    )
    p.add_argument(
        "--out",
        type=output_folder,
        default=default_out,
        help="output folder"
        + (f" (default {default_out})" if default_out else " (default: evaluation/ next to the tables' folder)"),
    )
    p.add_argument("--no-progress", action="store_true", help="hide the progress bars")
    p.add_argument(
        "--overwrite", action="store_true", help="replace the run in --out whole (only once the new one is complete)"
    )


def _slot_ids(scenario: Scenario, names: list[str] | None) -> list[int] | None:
    if names is None:
        return None
    unknown = [n for n in names if n not in scenario.slot_names]
    if unknown:
        raise ValueError(f"--slots: unknown slot(s) {unknown}; the scenario has {list(scenario.slot_names)}")
    return [scenario.slot_names.index(n) for n in names]


def evaluate_with(scenario: Scenario, tables_file: pathlib.Path, out: pathlib.Path, args: argparse.Namespace) -> int:
    """Run the evaluation with the tables in ``tables_file``; report to ``out``. Exit code."""
    try:
        tables = CausalTables.load(tables_file)  # checked against the scenario by the causal planner
        slots = _slot_ids(scenario, args.slots)
    except (TablesError, ValueError) as e:
        hint = " (run 'socialnav learn' first)" if not tables_file.exists() else ""
        print(f"error: --tables: {e}{hint}", file=sys.stderr)
        return 2
    overwrite = getattr(args, "overwrite", False)
    try:
        runfolder.check_inputs(out, [tables_file, getattr(args, "scenario", None)])
        runfolder.prepare(out, RESULTS, overwrite, marker="summary.json", job=JOB)
    except runfolder.RunFolderError as e:
        print(f"socialnav evaluate: {e}", file=sys.stderr)
        return 2
    backend = getattr(args, "backend", "local")
    size = getattr(args, "shard_replicas", None) or args.replicas
    n_slots = len(slots) if slots is not None else scenario.n_slots
    in_flight = min(size, args.replicas) * n_slots * EXPERIMENT_BYTES
    held = args.replicas * n_slots * TASK_ROWS_BYTES
    available = shortfall(in_flight + held)
    if available is not None:
        print(
            f"socialnav evaluate: --replicas {args.replicas}: about {(in_flight + held) / 1e9:.1f} GB at once "
            f"({min(size, args.replicas) * n_slots:,} experiments in one batch, and every task's row), this machine "
            f"has {available / 1e9:.1f} GB available; lower --replicas, or --shard-replicas for smaller batches",
            file=sys.stderr,
        )
        return 2
    seconds = args.replicas * n_slots * EXPERIMENT_S
    took = f"{seconds / 60:.0f} min" if seconds >= 60 else f"{seconds:.0f} s"
    print(
        f"evaluate: {args.replicas} replica(s) x {n_slots} slot(s) x 2 methods; about {took} on two cores, "
        f"at most {(in_flight + held) / 1e9:.2f} GB at once",
        flush=True,
    )
    settings = {"deadline_per_hop": not args.deadline_per_task}
    if args.collision_radius_m is not None:
        settings["collision_radius_m"] = args.collision_radius_m
    try:
        if backend == "local" and size >= args.replicas:
            result = warehouse.run_evaluation(
                scenario,
                tables,
                replicas=args.replicas,
                slots=slots,
                seed=args.seed,
                cfg=ProtocolConfig.for_params(scenario.params, **settings),
                progress=not args.no_progress,
            )
        else:
            result = evaluate_shards.run_sharded(scenario, tables, tables_file, out, args, slots, settings, size)
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except (backend_lib.BackendError, runfolder.RunFolderError) as e:
        print(f"socialnav evaluate: {e}", file=sys.stderr)
        return 2
    try:
        with runfolder.staged(out, "summary.json", overwrite, job=JOB) as stage:
            files = [out / f.name for f in warehouse.write_report(result, scenario, stage)]
    except runfolder.RunFolderError as e:
        print(f"socialnav evaluate: {e}", file=sys.stderr)
        return 2
    backend_lib.remove_staging(out / evaluate_shards.STAGING)  # the shards live until the report is written
    summary = json.loads((out / "summary.json").read_text())
    print(
        f"\n{args.replicas} replica(s) x {len(result.config['slots'])} slot(s), both methods; wall time "
        + ", ".join(f"{m} {s:.0f} s" for m, s in result.wall_s.items())
    )
    print(warehouse.per_slot_table(result).to_string(index=False, float_format=lambda v: f"{v:.1f}"))
    print(warehouse.format_overall(summary))
    for f in files:
        print(f"wrote {f}")
    return 0


def _out_folder(args) -> pathlib.Path:
    """``--out``, else ``evaluation/`` beside the tables' run folder."""
    return args.out or args.tables.parent.parent / "evaluation"


@locks_folder(_out_folder, "evaluate", reads=lambda args: [("--tables", args.tables.parent)])
def run(args: argparse.Namespace) -> int:
    try:
        scenario = load_scenario(args.scenario or WAREHOUSE_DIR)
    except ScenarioError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return evaluate_with(scenario, args.tables, _out_folder(args), args)
