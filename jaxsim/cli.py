"""``peopleflow``: the project's command line. One command, one subcommand per job.

    peopleflow simulate --worlds 8 --out runs/warehouse          # a full day, 8 worlds
    peopleflow simulate --slots 2 --slot-length-s 600 --out runs/quick

    peopleflow learn --logs runs/warehouse                          # causal graph + engine
    peopleflow evaluate --tables runs/warehouse/causal/engine_tables.npz --replicas 32
    peopleflow run --out runs/warehouse                             # all three, end to end
"""

from __future__ import annotations

import argparse
import pathlib
import sys

from jaxsim.devices import request_host_devices


def _positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {value}")
    return value


def _positive_float(text: str) -> float:
    value = float(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {value}")
    return value


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="peopleflow", description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    sim = sub.add_parser("simulate", help="simulate the warehouse; write Parquet logs and pictures",
                         description="Simulate worlds of the warehouse in parallel and write logs.parquet, "
                                     "run.json, snapshot.png and density_by_slot.png to --out.")
    sim.add_argument("--scenario", type=pathlib.Path, default=None,
                     help="scenario folder (default: the built-in warehouse, data/warehouse)")
    sim.add_argument("--worlds", type=_positive_int, default=8, help="worlds simulated in parallel (default 8)")
    length = sim.add_mutually_exclusive_group()
    length.add_argument("--slots", type=_positive_int, default=None,
                        help="simulated time slots from 08:00 (default: the whole day, 11 slots)")
    length.add_argument("--hours", type=_positive_float, default=None,
                        help="simulated hours from 08:00 (alternative to --slots)")
    sim.add_argument("--slot-length-s", type=_positive_float, default=None,
                     help="length of a time slot in s (default from params.json: 3600)")
    sim.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    sim.add_argument("--out", type=pathlib.Path, default=pathlib.Path("runs/warehouse"),
                     help="output folder (default runs/warehouse)")
    sim.add_argument("--sample-interval-s", type=_positive_float, default=1.0,
                     help="logging interval in s, a multiple of dt (default 1.0)")
    sim.add_argument("--obstacle-probability", type=float, default=None,
                     help="probability of a static obstacle on a robot leg (default 0.25)")
    sim.add_argument("--snapshot-time-s", type=float, default=None,
                     help="time of the snapshot picture (default: the middle of the lunch slot S6, or of the run)")
    sim.add_argument("--log-positions", action="store_true", help="also log every worker's position and status")
    sim.add_argument("--no-progress", action="store_true", help="hide the progress bar")

    lrn = sub.add_parser("learn", help="learn the causal graph and inference engine from simulator logs",
                         description="J-PCMCI+ discovery and a pyAgrum inference engine from the logs of "
                                     "'peopleflow simulate'; writes the graph, the engine, its tables and a report.")
    lrn.add_argument("--logs", type=pathlib.Path, default=pathlib.Path("runs/warehouse"),
                     help="folder written by 'peopleflow simulate' (default runs/warehouse)")
    lrn.add_argument("--out", type=pathlib.Path, default=None, help="output folder (default: LOGS/causal)")
    lrn.add_argument("--test", choices=["parcorr", "regression"], default="parcorr",
                     help="conditional independence test: parcorr (fast) or regression (RegressionCI, mixed data)")
    lrn.add_argument("--alpha", type=float, default=0.01, help="significance level (default 0.01)")
    lrn.add_argument("--step", type=_positive_int, default=None,
                     help="subsampling step in logged samples (default: the Nyquist rule)")
    lrn.add_argument("--max-samples", type=_positive_int, default=200_000,
                     help="discovery's sample budget over all datasets (default 200000); coarsens the step")
    lrn.add_argument("--worlds", type=lambda s: [int(w) for w in s.split(",")], default=None,
                     help="comma-separated world ids to learn from (default: all)")
    lrn.add_argument("--waypoints", type=lambda s: s.split(","), default=None,
                     help="comma-separated waypoints to learn (default: every non-empty one)")
    lrn.add_argument("--compare-subsampling", action="store_true",
                     help="also run discovery at the Nyquist step (no sample budget) and report both")
    lrn.add_argument("--no-progress", action="store_true", help="print nothing but errors")

    abl = sub.add_parser("ablation", help="causal vs Bayesian battery estimates (seed 000 Sec. 6)",
                         description="The simplified scenario (no workers, obstacles with probability p) for "
                                     "each p and seed; E[L | V] against E[L | do(V)] for 60 m at 0.5 m/s; writes "
                                     "ablation.csv, ablation.json and the bar chart ablation.png.")
    abl.add_argument("--out", type=pathlib.Path, default=pathlib.Path("runs/ablation"), help="output folder")
    abl.add_argument("--seeds", type=_positive_int, default=8, help="seeds (worlds) per probability (default 8)")
    abl.add_argument("--probabilities", type=lambda s: [float(v) for v in s.split(",")],
                     default=[0.1, 0.2, 0.3, 0.4, 0.5], help="obstacle probabilities (default 0.1,...,0.5)")
    abl.add_argument("--seed", type=int, default=0, help="base random seed (default 0)")
    abl.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    ev = sub.add_parser("evaluate", help="causal planner vs shortest-path baseline (seed 000 Sec. 5.2-5.4)",
                        description="Every slot's experiment (200 tasks, S11 the 90-leg tour) with both methods "
                                    "and common random numbers, for --replicas independent replicas; writes "
                                    "tasks.parquet, per_slot.csv, summary.json and Fig. 9-11 to --out.")
    ev.add_argument("--tables", type=pathlib.Path, default=pathlib.Path("runs/warehouse/causal/engine_tables.npz"),
                    help="the causal engine's tables, written by 'peopleflow learn' "
                         "(default runs/warehouse/causal/engine_tables.npz)")
    _evaluation_options(ev, default_out=None)
    ev.add_argument("--scenario", type=pathlib.Path, default=None, help="scenario folder (default: the warehouse)")

    run = sub.add_parser("run", help="the whole pipeline: simulate a day, learn the engine, evaluate the planners",
                         description="simulate -> learn -> evaluate on the built-in warehouse, into one folder: "
                                     "logs and pictures, causal/ (graph, engine), evaluation/ (tables, figures).")
    run.add_argument("--worlds", type=_positive_int, default=4, help="worlds simulated for learning (default 4)")
    run.add_argument("--learn-worlds", type=lambda s: [int(w) for w in s.split(",")], default=[0],
                     help="comma-separated worlds the engine learns from (default 0)")
    _evaluation_options(run, default_out=pathlib.Path("runs/warehouse"), replicas=4)
    return parser


def _evaluation_options(p: argparse.ArgumentParser, default_out, replicas: int = 32) -> None:
    p.add_argument("--replicas", type=_positive_int, default=replicas,
                   help=f"independent replicas of the whole protocol (default {replicas})")
    p.add_argument("--slots", type=lambda s: s.split(","), default=None,
                   help="comma-separated slot names to run, e.g. S1,S6,S11 (default: all)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--collision-radius-m", type=_positive_float, default=None,
                   help="robot-person centre distance that counts as a collision (default: the robot's radius, "
                        "0.275 m, as the paper; 0.475 counts any body contact)")
    p.add_argument("--deadline-per-task", action="store_true",
                   help="the 45 s deadline bounds the whole task (the paper's wording) instead of each route "
                        "hop (the reference code)")
    p.add_argument("--out", type=pathlib.Path, default=default_out,
                   help="output folder" + (f" (default {default_out})" if default_out else
                                           " (default: evaluation/ next to the tables' folder)"))
    p.add_argument("--no-progress", action="store_true", help="hide the progress bars")


def _slot_ids(scenario, names):
    if names is None:
        return None
    unknown = [n for n in names if n not in scenario.slot_names]
    if unknown:
        raise ValueError(f"unknown slot(s) {unknown}; the scenario has {list(scenario.slot_names)}")
    return [scenario.slot_names.index(n) for n in names]


def _evaluate(scenario, tables_file: pathlib.Path, out: pathlib.Path, args: argparse.Namespace) -> int:
    import json

    import numpy as np

    from planners import evaluation

    if not tables_file.is_file():
        print(f"error: {tables_file} not found: run 'peopleflow learn' first (it writes engine_tables.npz)",
              file=sys.stderr)
        return 2
    with np.load(tables_file) as f:
        tables = dict(f)
    missing = {"density_ppm2", "battery_pct_per_s", "speed_edges_mps"} - set(tables)
    if missing:
        print(f"error: {tables_file} lacks {sorted(missing)}", file=sys.stderr)
        return 2
    from jaxsim.experiment import ProtocolConfig

    settings = {"deadline_per_hop": not args.deadline_per_task}
    if args.collision_radius_m is not None:
        settings["collision_radius_m"] = args.collision_radius_m
    try:
        result = evaluation.run_evaluation(scenario, tables, replicas=args.replicas,
                                           slots=_slot_ids(scenario, args.slots), seed=args.seed,
                                           cfg=ProtocolConfig.for_params(scenario.params, **settings),
                                           progress=not args.no_progress)
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    files = evaluation.write_report(result, scenario, out)
    summary = json.loads((out / "summary.json").read_text())
    print(f"\n{args.replicas} replica(s) x {len(result.config['slots'])} slot(s), both methods; wall time "
          + ", ".join(f"{m} {s:.0f} s" for m, s in result.wall_s.items()))
    print(evaluation.per_slot_table(result).to_string(index=False, float_format=lambda v: f"{v:.1f}"))
    print(evaluation.format_overall(summary))
    for f in files:
        print(f"wrote {f}")
    return 0


def evaluate(args: argparse.Namespace) -> int:
    from jaxsim.scenario import WAREHOUSE_DIR, ScenarioError, load_scenario

    try:
        scenario = load_scenario(args.scenario or WAREHOUSE_DIR)
    except ScenarioError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return _evaluate(scenario, args.tables, args.out or args.tables.parent.parent / "evaluation", args)


def run_pipeline(args: argparse.Namespace) -> int:
    """simulate -> learn -> evaluate, each step's output the next one's input."""
    from jaxsim.scenario import load_scenario

    out = args.out
    steps = [("simulate", ["simulate", "--worlds", str(args.worlds), "--seed", str(args.seed), "--out", str(out)]),
             ("learn", ["learn", "--logs", str(out), "--worlds", ",".join(map(str, args.learn_worlds))])]
    quiet = ["--no-progress"] if args.no_progress else []
    for i, (name, argv) in enumerate(steps, 1):
        print(f"\n=== [{i}/3] {name} ===", flush=True)
        code = main(argv + quiet)
        if code:
            return code
    print("\n=== [3/3] evaluate ===", flush=True)
    return _evaluate(load_scenario(), out / "causal" / "engine_tables.npz", out / "evaluation", args)


def ablation(args: argparse.Namespace) -> int:
    import json

    from causal import ablation as abl

    if any(not 0 < p <= 1 for p in args.probabilities):
        print("error: probabilities must be in (0, 1]", file=sys.stderr)
        return 2
    abl.run(args.out, args.probabilities, args.seeds, args.seed, progress=not args.no_progress)
    summary = json.loads((args.out / "ablation.json").read_text())
    print(f"structure found by J-PCMCI+ at p = 0.3: {summary['structure_at_p_0.3']}")
    print(f"{'p':>5} {'L_ref':>8} {'L_BN':>8} {'L_CM':>8} {'MAE BN':>14} {'MAE CM':>14}"
          "   (battery % for 60 m at 0.5 m/s)")
    for r in summary["summary"]:
        print(f"{r['p']:>5.1f} {r['reference']:>8.3f} {r['bayesian']:>8.3f} {r['causal']:>8.3f} "
              f"{r['mae_bayesian']:>7.3f}+-{r['sd_bayesian']:.3f} {r['mae_causal']:>7.3f}+-{r['sd_causal']:.3f}")
    print(f"wrote {args.out}/ablation.csv, ablation.json, ablation.png")
    return 0


def learn(args: argparse.Namespace) -> int:
    from causal.extract import LogError
    from causal.learn import learn as run_learn

    try:
        run_learn(args.logs, args.out or args.logs / "causal", test=args.test, alpha=args.alpha, step=args.step,
                  max_samples=args.max_samples, worlds=args.worlds, waypoints=args.waypoints,
                  compare_subsampling=args.compare_subsampling, progress=not args.no_progress)
    except (LogError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


def simulate(args: argparse.Namespace) -> int:
    from jaxsim import logs, viz
    from jaxsim.scenario import WAREHOUSE_DIR, ScenarioError, load_scenario

    overrides = {}
    if args.slot_length_s is not None:
        overrides["slot_length_s"] = args.slot_length_s
    if args.obstacle_probability is not None:
        overrides["robot_obstacle_probability"] = args.obstacle_probability
    try:
        scenario = load_scenario(args.scenario or WAREHOUSE_DIR, **overrides)
    except (ScenarioError, TypeError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    p = scenario.params
    if args.hours is not None:
        duration_s = args.hours * 3600.0
    else:
        duration_s = (args.slots or scenario.n_slots) * p.slot_length_s
    if args.snapshot_time_s is not None:
        snap_t = args.snapshot_time_s
    elif duration_s >= 6 * p.slot_length_s:
        snap_t = 5.5 * p.slot_length_s
    else:
        snap_t = duration_s / 2
    snap_t = round(snap_t / args.sample_interval_s) * args.sample_interval_s
    try:
        run = logs.simulate_to_parquet(scenario, args.out, n_worlds=args.worlds, duration_s=duration_s,
                                       seed=args.seed, sample_interval_s=args.sample_interval_s,
                                       log_positions=args.log_positions, snapshot_time_s=snap_t,
                                       progress=not args.no_progress)
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    pictures = []
    if run.snapshot is not None:
        pictures.append(viz.snapshot_png(scenario, run.snapshot, args.out / "snapshot.png"))
    pictures.append(viz.density_by_slot_png(scenario, run.mean_density_by_slot, args.out / "density_by_slot.png"))

    f = run.final
    n = len(f["tasks_started"])
    mean = lambda k: sum(f[k]) / n  # noqa: E731
    print(f"\nsimulated {args.worlds} world(s) x {duration_s:.0f} s ({duration_s / p.slot_length_s:.2f} slots of "
          f"{p.slot_length_s:.0f} s), {p.n_workers} workers + robot, seed {args.seed}")
    print(f"wall time {run.wall_s:.1f} s (until the first chunk, compile included: {run.compile_s:.1f} s), "
          f"{run.agent_steps_per_s / 1e6:.2f} M agent-steps/s")
    print(f"robot per world: {mean('tasks_succeeded'):.1f} tasks succeeded, {mean('tasks_failed'):.1f} failed, "
          f"stalled {mean('stalled_s'):.0f} s, final battery {mean('battery_pct'):.1f} %")
    for k in range(scenario.n_slots):
        if run.slot_samples[k]:
            d = run.mean_density_by_slot[k]
            top = [scenario.waypoint_ids[i] for i in d.argsort()[::-1][:2] if d[i] > 0]
            print(f"  {scenario.slot_names[k]:>3} {scenario.slot_clock[k]:>11}: most crowded {', '.join(top) or '-'}")
    print(f"wrote {run.log_file} ({run.rows} rows), {run.meta_file}")
    for pic in pictures:
        print(f"wrote {pic}")
    return 0


def main(argv: list[str] | None = None) -> int:
    request_host_devices()
    args = build_parser().parse_args(argv)
    if args.command == "simulate":
        return simulate(args)
    if args.command == "learn":
        return learn(args)
    if args.command == "ablation":
        return ablation(args)
    if args.command == "evaluate":
        return evaluate(args)
    if args.command == "run":
        return run_pipeline(args)
    return 2  # pragma: no cover - argparse rejects unknown commands


if __name__ == "__main__":
    sys.exit(main())
