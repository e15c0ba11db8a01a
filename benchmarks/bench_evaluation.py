"""Time seed 000's whole evaluation protocol: 2 methods x 11 slots (2090 tasks each) x replicas.

    python benchmarks/bench_evaluation.py                     # 32 replicas (the issue's size)
    python benchmarks/bench_evaluation.py --replicas 4 --tables runs/warehouse/causal/engine_tables.npz

Prints the machine, wall time per method (compilation included, reported separately), simulated
time and agent-steps per second, and the headline numbers, so the speed claim and the result
come from the same run. The paper needed about 11 h of Gazebo per method for one replica.
Without ``--tables`` the causal planner uses tables computed from the scenario's schedule
(expected density from the destination probabilities) so the benchmark runs without a learnt
engine; pass a learnt engine's tables for the real comparison.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))

from socialnav.runtime import request_host_devices, request_wide_vectors

request_host_devices()
request_wide_vectors()

import numpy as np  # noqa: E402

from benchmarks.bench_simulator import machine  # noqa: E402
from benchmarks.record import record  # noqa: E402
from socialnav.evaluation import warehouse  # noqa: E402
from socialnav.jaxsim.scenario import load_scenario  # noqa: E402
from socialnav.planners.warehouse.tables import CausalTables  # noqa: E402


def schedule_tables(scenario) -> CausalTables:
    """Stand-in engine tables: density proportional to the schedule's destination probability,
    the battery rate of Eq. (1) at full speed (what a well-learnt engine approaches)."""
    p = scenario.params
    area = np.pi * scenario.waypoint_radius_m**2
    density = scenario.destination_p * p.n_workers * 0.5 / area  # about half the workers at a station
    density[~scenario.slot_working] = 0.0
    rate = -(p.battery_static_pct_per_s + p.battery_dynamic_pct_per_m * p.robot_max_speed_mps)
    return CausalTables.from_arrays(
        {
            "density_ppm2": density,
            "battery_pct_per_s": np.array([[-p.battery_static_pct_per_s, np.nan], [rate, np.nan]]),
            "speed_edges_mps": np.array([0.0, 0.25, p.robot_max_speed_mps]),
        },
        source="schedule-based tables",
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--replicas", type=int, default=32)
    ap.add_argument("--tables", type=pathlib.Path, default=None, help="engine_tables.npz (default: schedule-based)")
    ap.add_argument("--out", type=pathlib.Path, default=None, help="also write the report here")
    args = ap.parse_args()
    scenario = load_scenario()
    tables = CausalTables.load(args.tables) if args.tables else schedule_tables(scenario)
    print(f"machine: {machine()}")
    print(
        f"protocol: 2 methods x {scenario.n_slots} slots x {args.replicas} replicas "
        f"({sum(len(g) for g in scenario.robot_goals)} tasks per method and replica), "
        f"tables: {args.tables or 'schedule-based'}"
    )
    start = time.perf_counter()
    result = warehouse.run_evaluation(scenario, tables, replicas=args.replicas, progress=False)
    total = time.perf_counter() - start
    p = scenario.params
    for m, wall in result.wall_s.items():
        sim_s = float(result.experiment_s[m].sum())
        print(
            f"{m:>9}: {wall:7.1f} s wall; {sim_s / 3600:8.1f} h of experiments simulated "
            f"(longest {result.experiment_s[m].max() / 3600:.2f} h), "
            f"{sim_s / p.dt_s * (p.n_workers + 1) / wall / 1e6:.2f} M useful agent-steps/s"
        )
    print(f"whole protocol: {total:.1f} s ({total / 60:.1f} min; goal < 5 min)")
    steps = sum(float(result.experiment_s[m].sum()) for m in result.wall_s) / p.dt_s * (p.n_workers + 1)
    record("protocol", "useful agent-steps/s (compilation included)", steps / total, "agent-steps/s",
           wall_s=round(total, 1), replicas=args.replicas)  # fmt: skip
    summary = warehouse.overall(result)
    print(warehouse.format_overall(summary))
    if args.out:
        warehouse.write_report(result, scenario, args.out)
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
