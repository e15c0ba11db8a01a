"""``socialnav referee``: seed 000's discovery scored against the simulator's own graph, over seeds
and world counts, beside the score against the paper's Fig. 8.

socialnav referee --out runs/referee                           # seeds 0-4 x 1 and 2 worlds, a whole day
socialnav referee --out runs/referee-small --seeds 0,1 --worlds 1 --slots 3

For each seed the warehouse is simulated once with the largest world count (the route
follower, the command's defaults, :func:`jaxsim.logs.simulate_to_parquet`), then ``socialnav
learn``'s pipeline (:func:`causal.learn.learn`: extraction, J-PCMCI+, the engine) runs on its
first ``n`` worlds for every ``n`` of ``--worlds``. Each discovery is scored (precision,
recall, SHD; :func:`causal.discover.score`) against Fig. 8 (:data:`causal.variables.GROUND_TRUTH`),
against the simulator's graph sampled at the run's period
(:func:`causal.simulator_graph.pipeline_truth`) and against the part of it J-PCMCI+ can return
with the pipeline's context declarations (:func:`causal.simulator_graph.findable`).

The engine's do()-queries are refereed too: for every speed bin of each seed's engine learned
from the fewest worlds, ``E[L | do(V = v), C = 0]`` (:meth:`causal.engine.CausalEngine.expected_battery_do`,
``v`` the bin's mean speed) against the mean of L in ``--do-worlds`` simulated worlds (2 h from
08:00) whose robot is forced to drive at exactly ``v`` (:attr:`jaxsim.robot.RobotCommand.force_speed`,
on the route follower's routes), at the engine's sampling period, over the samples with C = 0,
with a 95 % t-interval over the worlds. Beside it: the engine's plain conditional ``E[L | V = v]``,
its one-step do(Vt) and pyAgrum's ``causalImpact`` (the query before the sustained, seen-cells
one), the share of the parent configurations the data cover, how often an obstacle is present
(the engine's P(O = 1 | C = 0) against the forced robot's share of periods), and both sides
without obstacles (the engine given O = 0, the simulator's periods with no obstacle).

Writes ``referee.csv`` (one row per seed and world count, with the run times), ``edges.csv``
(for every edge either graph has or discovery found: in which graphs it is and in how many runs
it was found), ``do.csv`` (the do()-queries against the simulator's interventions) and
``referee.md`` (the three as tables). A stopped study resumes: a seed's logs and a learn whose
``report.json`` exists are kept.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys
import time

from socialnav.cli.argtypes import comma_ints, non_negative_int, output_folder, positive_float, positive_int
from socialnav.locking import locks_folder

JOB = "socialnav referee"


def add_parser(sub) -> None:
    p = sub.add_parser(
        "referee",
        help="seed 000's discovery scored against the simulator's own causal graph, over seeds and world counts",
        description="Seed 000's discovery (simulate a day per seed, socialnav learn on its first N worlds) scored "
        "against the paper's Fig. 8 and against the simulator's own causal graph (causal/simulator_graph.py); "
        "writes referee.csv, edges.csv and referee.md to --out, and resumes a stopped study.",
    )
    p.add_argument(
        "--out", type=output_folder, default=pathlib.Path("runs/referee"), help="output folder (default runs/referee)"
    )
    p.add_argument("--seeds", type=comma_ints, default=[0, 1, 2, 3, 4], help="simulation seeds (default 0,1,2,3,4)")
    p.add_argument("--worlds", type=comma_ints, default=[1, 2], help="world counts learned from (default 1,2)")
    p.add_argument("--slots", type=positive_int, default=None, help="simulated slots from 08:00 (default: the day)")
    p.add_argument("--slot-length-s", type=positive_float, default=None, help="slot length (default 3600)")
    p.add_argument(
        "--battery-initial-pct",
        type=positive_float,
        default=None,
        help="the robot's battery at 08:00 (default from params.json; a short day needs a low one to charge at all)",
    )
    p.add_argument(
        "--do-worlds", type=non_negative_int, default=8, help="simulated worlds per forced speed (default 8; 0: skip)"
    )
    p.add_argument("--no-progress", action="store_true", help="print one line per run only")
    p.set_defaults(handler=run)


def _edge(c: str, e: str, lag: int) -> str:
    return f"{c}(t-{lag})->{e}" if lag else f"{c}->{e}"


@locks_folder(lambda args: args.out, "referee")
def run(args: argparse.Namespace) -> int:
    import pandas as pd

    from socialnav.causal import discover, simulator_graph
    from socialnav.causal.extract import LogError
    from socialnav.causal.learn import learn
    from socialnav.causal.variables import GROUND_TRUTH
    from socialnav.common.atomic import write_text_atomic
    from socialnav.jaxsim import logs
    from socialnav.jaxsim.route_follower import route_follower
    from socialnav.jaxsim.scenario import ScenarioError, load_scenario
    from socialnav.jaxsim.world import build_world
    from socialnav.planners.warehouse.routes import shortest_path_plan

    if any(n < 1 for n in args.worlds) or any(s < 0 for s in args.seeds):
        print("socialnav referee: --worlds must be >= 1 and --seeds >= 0", file=sys.stderr)
        return 2
    overrides = {
        k: v
        for k, v in (("slot_length_s", args.slot_length_s), ("battery_initial_pct", args.battery_initial_pct))
        if v is not None
    }
    try:
        scenario = load_scenario(**overrides)
    except ScenarioError as e:
        print(f"socialnav referee: {e}", file=sys.stderr)
        return 2
    if args.slots is not None and args.slots > scenario.n_slots:
        print(f"socialnav referee: --slots {args.slots}: the scenario has {scenario.n_slots} slots", file=sys.stderr)
        return 2
    duration_s = (args.slots or scenario.n_slots) * scenario.params.slot_length_s
    n_worlds = max(args.worlds)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    world = build_world(scenario)
    driver = route_follower(shortest_path_plan(scenario), world)
    rows, found_by_run = [], []
    for seed in args.seeds:
        logs_dir = out / f"seed{seed}"
        t0 = time.perf_counter()
        if not (logs_dir / "run.json").is_file():
            logs.simulate_to_parquet(
                scenario,
                logs_dir,
                driver,
                n_worlds=n_worlds,
                duration_s=duration_s,
                seed=seed,
                progress=not args.no_progress,
            )
            simulate_s = time.perf_counter() - t0
        else:
            simulate_s = float("nan")  # simulated by an earlier call
        for n in sorted(set(args.worlds)):
            learned = logs_dir / f"learn_w{n}"
            if not (learned / "report.json").is_file():
                try:
                    learn(logs_dir, learned, worlds=list(range(n)), progress=False)
                except LogError as e:
                    print(f"socialnav referee: seed {seed}, {n} world(s): {e}", file=sys.stderr)
                    return 2
            report = json.loads((learned / "report.json").read_text())
            found = discover.Discovery.load(learned / "discovery.json")
            sampled = simulator_graph.pipeline_truth(simulator_graph.sampling_steps(report["period_s"]))
            scores = {
                "fig8": discover.score(found.links, GROUND_TRUTH),
                "simulator": discover.score(found.links, sampled),
                "findable": discover.score(found.links, simulator_graph.findable(sampled)),
            }
            row = {
                "seed": seed,
                "worlds": n,
                "samples": report["samples"],
                "period_s": report["period_s"],
                "simulate_s": round(simulate_s, 1),
                "discover_s": round(report["timings"]["discover_s"], 1),
                "learn_s": round(report["timings"]["total_s"], 1),
            }
            for name, s in scores.items():
                row |= {f"{name}_precision": s["precision"], f"{name}_recall": s["recall"], f"{name}_shd": s["shd"]}
            rows.append(row)
            found_by_run.append({(k.cause, k.effect, k.lag) for k in found.links if k.oriented})
            found_by_run[-1] |= {
                ("~" + "".join(sorted((k.cause, k.effect))), "", 0) for k in found.links if not k.oriented
            }
            said = "; ".join(
                f"{name} P {sc['precision']:.2f} R {sc['recall']:.2f} SHD {sc['shd']}" for name, sc in scores.items()
            )
            print(f"seed {seed}, {n} world(s): {said}; discovery {row['discover_s']:.0f} s", flush=True)
    table = pd.DataFrame(rows)
    write_text_atomic(out / "referee.csv", table.to_csv(index=False))
    do_rows = []
    if args.do_worlds:
        from socialnav.causal.engine import CausalEngine

        fewest = min(args.worlds)
        for seed in args.seeds:
            engine = CausalEngine.load(out / f"seed{seed}" / f"learn_w{fewest}")
            do_rows += _do_check(engine, scenario.params, world, driver, args.do_worlds, seed, fewest)
            print(f"seed {seed}: the engine's do()-queries against forced speeds in the simulator", flush=True)
    do_table = pd.DataFrame(do_rows)
    write_text_atomic(out / "do.csv", do_table.to_csv(index=False))
    edges = _edge_table(
        found_by_run,
        GROUND_TRUTH,
        simulator_graph.pipeline_truth(simulator_graph.sampling_steps(float(table.period_s.iloc[0]))),
    )
    write_text_atomic(out / "edges.csv", edges.to_csv(index=False))
    markdown = _markdown(table) + "\n" + _markdown(edges) + ("\n" + _markdown(do_table) if do_rows else "")
    write_text_atomic(out / "referee.md", markdown)
    print(f"wrote {out}/referee.csv, edges.csv, do.csv, referee.md")
    return 0


def _edge_table(found_by_run: list[set], fig8, simulator):
    """Every edge in either graph or found in any run, in which graph it is, how often found."""
    import pandas as pd

    candidates = set(fig8) | set(simulator)
    for found in found_by_run:
        candidates |= {t for t in found if t[1]}
    rows = []
    for c, e, lag in sorted(candidates):
        oriented = sum((c, e, lag) in found for found in found_by_run)
        unoriented = sum(lag == 0 and ("~" + "".join(sorted((c, e))), "", 0) in found for found in found_by_run)
        rows.append(
            {
                "edge": _edge(c, e, lag),
                "fig8": (c, e, lag) in fig8,
                "simulator": (c, e, lag) in simulator,
                "found_oriented": oriented,
                "found_unoriented": unoriented,
                "runs": len(found_by_run),
            }
        )
    return pd.DataFrame(rows)


def _markdown(frame) -> str:
    """A GitHub table (no tabulate needed)."""
    cells = [[f"{v:.2f}" if isinstance(v, float) else str(v) for v in row] for row in frame.itertuples(index=False)]
    lines = ["| " + " | ".join(frame.columns) + " |", "|" + "---|" * len(frame.columns)]
    return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in cells]) + "\n"


DO_HOURS = 2.0  # simulated per forced speed, from 08:00


def forced_speed_driver(driver):
    """``driver`` (the route follower) with its command's speed forced: params ``(driver's params,
    v)``, v () m/s, traced (one compiled program for every speed)."""
    import jax.numpy as jnp

    from socialnav.jaxsim.actor import Actor, Driver

    inner = driver.actor

    def act(params, state, obs, key):
        command, state = inner.act(params[0], state, obs, key)
        return command.replace(speed_mps=params[1], force_speed=jnp.array(True)), state

    actor = Actor(init=inner.init, act=act, name="forced")
    return lambda v: Driver(actor=actor, params=(driver.params, jnp.float32(v)))


def _mean_interval(values, mask) -> tuple[float, float]:
    """Mean over worlds of each world's mean of ``values[mask]`` (worlds, periods), with the
    half-width of its 95 % t-interval."""
    import numpy as np
    from scipy import stats

    per_world = np.array([values[w][mask[w]].mean() for w in range(len(values)) if mask[w].any()])
    if len(per_world) < 2:
        return (float(per_world.mean()) if len(per_world) else float("nan")), float("nan")
    half = stats.t.ppf(0.975, len(per_world) - 1) * per_world.std(ddof=1) / np.sqrt(len(per_world))
    return float(per_world.mean()), float(half)


def _do_check(engine, params, world, driver, n_worlds: int, seed: int, worlds: int) -> list[dict]:
    """One row per speed bin: the engine's do() and conditional answers and the simulator's
    interventional mean of L (per sampling period, C = 0) with its 95 % interval over worlds."""
    import numpy as np

    from socialnav.jaxsim import rollout

    period_steps = max(1, round(engine.period_s / params.dt_s))
    n_steps = int(DO_HOURS * 3600 / params.dt_s) // period_steps * period_steps
    forced = forced_speed_driver(driver)
    rows = []
    for k, v in enumerate(engine.bins["V"].means):
        _, rec = rollout.rollout(params, world, forced(float(v)), 10_000 + seed, n_worlds, n_steps, period_steps)
        battery = np.asarray(rec.battery_pct, np.float64)
        charging = np.asarray(rec.charging, bool)
        obstacle = np.asarray(rec.obstacle, bool)
        change = np.diff(battery, axis=1)  # L_t = B_t - B_{t-1} over one period
        keep = ~charging[:, 1:]
        clear = keep & ~obstacle[:, 1:] & ~obstacle[:, :-1]
        mean, half = _mean_interval(change, keep)
        mean_clear, half_clear = _mean_interval(change, clear)
        sustained = engine.battery_do(k, 0)
        engine_do = sustained.value
        rows.append(
            {
                "seed": seed,
                "worlds": worlds,
                "speed_bin": k,
                "v_mps": round(float(v), 3),
                "engine_do": engine_do,
                "engine_do_one_step": engine.battery_do(k, 0, sustained=False).value,
                "engine_do_pyagrum": engine.expected_battery_do_pyagrum(k, 0),
                "seen_share": sustained.seen_share,
                "engine_given": engine.expected_battery_given(k),
                "simulated_do": mean,
                "simulated_lo": mean - half,
                "simulated_hi": mean + half,
                "inside": abs(engine_do - mean) <= half,
                "obstacle_share_engine": engine.obstacle_share(0),
                "obstacle_share_simulated": float(obstacle[:, 1:][keep].mean()),
                "engine_do_no_obstacle": engine.battery_do(k, 0, obstacle=0).value,
                "simulated_no_obstacle": mean_clear,
                "simulated_no_obstacle_half": half_clear,
            }
        )
    return rows
