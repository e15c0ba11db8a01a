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
import pathlib
import sys

from socialnav.cli.argtypes import comma_ints, non_negative_int, output_folder, positive_float, positive_int
from socialnav.locking import locks_folder


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


@locks_folder(lambda args: args.out, "referee")
def run(args: argparse.Namespace) -> int:
    from socialnav import referee_study
    from socialnav.jaxsim.scenario import ScenarioError, load_scenario

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
    say = lambda what: print(what, flush=True)
    try:
        referee_study.run_study(args.out, scenario, args.seeds, args.worlds, duration_s, args.do_worlds,
                                not args.no_progress, say)  # fmt: skip
    except referee_study.StudyError as e:
        print(f"socialnav referee: {e}", file=sys.stderr)
        return 2
    print(f"wrote {args.out}/referee.csv, edges.csv, do.csv, referee.md")
    return 0
