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

Writes ``referee.csv`` (one row per seed and world count, with the run times), ``edges.csv``
(for every edge either graph has or discovery found: in which graphs it is and in how many runs
it was found) and ``referee.md`` (both as tables). A stopped study resumes: a seed's logs and a
learn whose ``report.json`` exists are kept.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys
import time

from socialnav.argtypes import comma_ints, output_folder, positive_float, positive_int
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
    p.add_argument("--no-progress", action="store_true", help="print one line per run only")
    p.set_defaults(handler=run)


def _edge(c: str, e: str, lag: int) -> str:
    return f"{c}(t-{lag})->{e}" if lag else f"{c}->{e}"


@locks_folder(lambda args: args.out, "referee")
def run(args: argparse.Namespace) -> int:
    import pandas as pd

    from causal import discover, simulator_graph
    from causal.extract import LogError
    from causal.learn import learn
    from causal.variables import GROUND_TRUTH
    from common.atomic import write_text_atomic
    from jaxsim import logs
    from jaxsim.route_follower import route_follower
    from jaxsim.scenario import ScenarioError, load_scenario
    from jaxsim.world import build_world
    from planners.routes import shortest_path_plan

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
    driver = route_follower(shortest_path_plan(scenario), build_world(scenario))
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
    edges = _edge_table(
        found_by_run,
        GROUND_TRUTH,
        simulator_graph.pipeline_truth(simulator_graph.sampling_steps(float(table.period_s.iloc[0]))),
    )
    write_text_atomic(out / "edges.csv", edges.to_csv(index=False))
    write_text_atomic(out / "referee.md", _markdown(table) + "\n" + _markdown(edges))
    print(f"wrote {out}/referee.csv, edges.csv, referee.md")
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
