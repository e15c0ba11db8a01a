"""Throughput of the full warehouse step, against JuPedSim and pysocialforce in the same run.

    python benchmarks/bench_simulator.py                 # batches 1..4096, both peers
    python benchmarks/bench_simulator.py --batches 1 64 256 --seconds 3
    SOCIALNAV_NATIVE=off python benchmarks/bench_simulator.py   # the social force in JAX throughout

Agent-steps per second = (workers + robot) x worlds x steps / wall time, compile excluded
(reported separately). The jaxsim step is everything switched on: the worker context
(schedule, routes, activities, replanning), pedsim's social force with the robot as an agent,
walls, random force, the robot with its blocking rule, obstacles, deadline, battery and
charging, and the Eq. (3) densities and robot-worker distances measured every 1 s. The social
force runs in the C++ kernel of :mod:`jaxsim.native` where it builds; the same step with the
social force in JAX (the reference, every pair exact as well) is measured after it in a child
process with ``SOCIALNAV_NATIVE=off`` (``--no-reference`` skips it).

The peers run the same crowd: the warehouse's walls and furniture, 50 walkers cycling between
the human destination waypoints. JuPedSim (C++, single-threaded) uses its SocialForceModel at
its default dt = 0.01 s; pysocialforce (numpy) its default extended social force model with the
walls as obstacle segments. A step is a step whatever its dt: the ratios compare work per
agent-step, not simulated seconds per second.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import platform
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

from socialnav.runtime import request_host_devices, request_wide_vectors

request_host_devices()
request_wide_vectors()

import jax  # noqa: E402
import numpy as np  # noqa: E402

from benchmarks.record import record  # noqa: E402
from socialnav.common.machine import cpu_model, usable_cores  # noqa: E402
from socialnav.jaxsim import native  # noqa: E402
from socialnav.jaxsim.rollout import init_batch, run_samples, world_keys  # noqa: E402
from socialnav.jaxsim.route_follower import route_follower  # noqa: E402
from socialnav.jaxsim.scenario import load_scenario  # noqa: E402
from socialnav.jaxsim.world import build_world  # noqa: E402
from socialnav.planners.warehouse.routes import shortest_path_plan  # noqa: E402

WARMUP_S = 200.0  # simulated seconds before timing: the workers have arrived


def machine() -> str:
    cpu = cpu_model()
    force = native.describe()
    return (
        f"{cpu}, {usable_cores()} of {os.cpu_count()} cores usable, Python {platform.python_version()}, "
        f"jax {jax.__version__}, "
        f"{jax.local_device_count()} host device(s); social force on the CPU: {force}"
    )


def bench_jaxsim(scenario, batches, seconds):
    p = scenario.params
    world = build_world(scenario)
    controller = route_follower(shortest_path_plan(scenario), world)
    agents = p.n_workers + 1
    every = int(round(1.0 / p.dt_s))
    rows = []
    for b in batches:
        keys = world_keys(0, b)
        states = init_batch(p, world, controller, keys)
        chunk = 10  # samples per call: every call has the same shape, so only the first compiles
        t0 = time.perf_counter()
        for _ in range(int(WARMUP_S / (chunk * every * p.dt_s))):
            states, _ = run_samples(p, world, controller, states, keys, chunk, every)
        jax.block_until_ready(states)
        compile_s = time.perf_counter() - t0
        calls, t0 = 0, time.perf_counter()
        while time.perf_counter() - t0 < seconds:
            states, rec = run_samples(p, world, controller, states, keys, chunk, every)
            jax.block_until_ready((states, rec))
            calls += 1
        wall = time.perf_counter() - t0
        steps = calls * chunk * every
        rate = agents * b * steps / wall
        rows.append((b, rate, compile_s))
        record("warehouse", "agent-steps/s", rate, "agent-steps/s", compile_s=compile_s, batch=b,
               note=f"compile_s includes {WARMUP_S:.0f} simulated s of warm-up")  # fmt: skip
        print(
            f"  jaxsim  batch {b:5d}: {rate / 1e6:7.2f} M agent-steps/s  "
            f"({steps} steps, {wall:.1f} s; compile + {WARMUP_S:.0f} s warm-up {compile_s:.1f} s)",
            flush=True,
        )
    return rows


def peer_geometry(scenario):
    """The warehouse interior minus walls and furniture, as a shapely polygon."""
    from shapely.geometry import box
    from shapely.ops import unary_union

    boxes = scenario.boxes_m
    outer = box(-19.93, -9.93, 9.93, 9.93)
    obstacles = unary_union([box(x0, y0, x1, y1) for x0, x1, y0, y1 in boxes])
    area = outer.difference(obstacles)
    if area.geom_type == "MultiPolygon":
        area = max(area.geoms, key=lambda g: g.area)
    return area


def cycle_waypoints(scenario, area):
    from shapely.geometry import Point

    names = [
        n
        for n, k, h in zip(scenario.waypoint_ids, scenario.waypoint_kind, scenario.human_allowed)
        if h and k in ("work_area", "office", "toilet", "canteen")
    ]
    pts = [tuple(scenario.waypoint_xy_m[scenario.waypoint(n)]) for n in names]
    return [pt for pt in pts if area.contains(Point(pt).buffer(0.5))]


def bench_jupedsim(scenario, n_agents, seconds):
    import jupedsim as jps

    area = peer_geometry(scenario)
    pts = cycle_waypoints(scenario, area)
    sim = jps.Simulation(model=jps.SocialForceModel(), geometry=area, dt=0.01)
    stages = [sim.add_waypoint_stage(pt, 0.5) for pt in pts]
    journey = jps.JourneyDescription(stages)
    for i, s in enumerate(stages):
        journey.set_transition_for_stage(s, jps.Transition.create_fixed_transition(stages[(i + 1) % len(stages)]))
    jid = sim.add_journey(journey)
    rng = np.random.default_rng(0)
    placed = 0
    while placed < n_agents:
        k = int(rng.integers(len(pts)))
        pos = (pts[k][0] + rng.uniform(-1, 1), pts[k][1] + rng.uniform(-1, 1))
        try:
            sim.add_agent(
                jps.SocialForceModelAgentParameters(
                    position=pos,
                    orientation=(1.0, 0.0),
                    journey_id=jid,
                    stage_id=stages[(k + 1) % len(stages)],
                    desired_speed=1.34,
                    radius=0.2,
                )
            )
            placed += 1
        except Exception:
            continue
    for _ in range(100):
        sim.iterate()
    steps, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        sim.iterate(100)
        steps += 100
    wall = time.perf_counter() - t0
    rate = sim.agent_count() * steps / wall
    print(
        f"  JuPedSim SocialForceModel: {rate / 1e6:7.3f} M agent-steps/s ({sim.agent_count()} agents, "
        f"{steps} steps, {wall:.1f} s)",
        flush=True,
    )
    return rate


def bench_pysocialforce(scenario, n_agents, seconds):
    import logging

    import pysocialforce as psf

    logging.disable(logging.CRITICAL)  # pysocialforce logs every step at DEBUG level
    area = peer_geometry(scenario)
    pts = np.array(cycle_waypoints(scenario, area))
    rng = np.random.default_rng(0)
    start = rng.integers(len(pts), size=n_agents)
    goal = (start + 1) % len(pts)
    state = np.zeros((n_agents, 6))
    state[:, :2] = pts[start] + rng.uniform(-0.8, 0.8, (n_agents, 2))
    state[:, 4:6] = pts[goal]
    obstacles = []
    for x0, x1, y0, y1 in scenario.boxes_m:
        obstacles += [(x0, x1, y0, y0), (x0, x1, y1, y1), (x0, x0, y0, y1), (x1, x1, y0, y1)]
    sim = psf.Simulator(state, obstacles=obstacles)
    sim.step(2)  # numba compiles on the first step
    steps, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        sim.step(1)
        st = sim.peds.state
        reached = np.hypot(*(st[:, :2] - st[:, 4:6]).T) < 0.5
        if reached.any():  # cycle on to the next waypoint
            goal[reached] = (goal[reached] + 1) % len(pts)
            st[reached, 4:6] = pts[goal[reached]]
        steps += 1
    wall = time.perf_counter() - t0
    rate = n_agents * steps / wall
    print(
        f"  pysocialforce: {rate / 1e3:9.2f} k agent-steps/s ({n_agents} agents, {steps} steps, {wall:.1f} s)",
        flush=True,
    )
    return rate


def reference_rate(batches, seconds) -> float:
    """Best rate of the same step with the social force in JAX (``SOCIALNAV_NATIVE=off``), measured
    in a child process (the switch is read once per process); its lines are printed as they come."""
    env = {**os.environ, "SOCIALNAV_NATIVE": "off"}
    command = [sys.executable, __file__, "--no-peers", "--no-reference", "--seconds", str(seconds), "--batches"]
    done = subprocess.run(command + [str(b) for b in batches], env=env, capture_output=True, text=True, check=True)
    best = 0.0
    for line in done.stdout.splitlines():
        if line.startswith("  jaxsim  batch"):
            print("  (JAX social force)" + line[len("  jaxsim") :], flush=True)
        if line.startswith("best:"):
            best = float(line.split()[1]) * 1e6
    return best


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--batches", type=int, nargs="+", default=[1, 4, 16, 64, 256, 1024, 4096])
    ap.add_argument("--seconds", type=float, default=5.0, help="timed wall seconds per measurement")
    ap.add_argument("--no-peers", action="store_true", help="skip JuPedSim and pysocialforce")
    ap.add_argument(
        "--no-reference",
        action="store_true",
        help="skip the same step with the JAX social force (SOCIALNAV_NATIVE=off, in a child process)",
    )
    args = ap.parse_args()
    scenario = load_scenario()
    print(f"machine: {machine()}")
    print(f"scenario: {scenario.name}, {scenario.params.n_workers} workers + robot, dt {scenario.params.dt_s} s")
    rows = bench_jaxsim(scenario, args.batches, args.seconds)
    best_b, best, _ = max(rows, key=lambda r: r[1])
    print(f"\n{'batch':>6} {'M agent-steps/s':>16} {'compile+warm-up s':>18}")
    for b, rate, comp in rows:
        print(f"{b:>6} {rate / 1e6:>16.2f} {comp:>18.1f}")
    print(f"best: {best / 1e6:.2f} M agent-steps/s at batch {best_b}")
    if not args.no_reference and not native.disabled():
        reference = reference_rate([best_b], args.seconds)  # the same batch: a like-for-like ratio
        print(f"the same step with the JAX social force (the reference), batch {best_b}: {reference / 1e6:.2f} M")
        print(f"ratio C++ kernel / JAX social force at batch {best_b}: {best / reference:.2f}x")
    if args.no_peers:
        return 0
    missing = [name for name in ("jupedsim", "pysocialforce") if importlib.util.find_spec(name) is None]
    if missing:
        print(f"peers skipped: {', '.join(missing)} not installed (pip install -e '.[bench]')")
        return 0
    n = scenario.params.n_workers
    jps_rate = bench_jupedsim(scenario, n, args.seconds)
    psf_rate = bench_pysocialforce(scenario, n, args.seconds)
    print(f"ratio jaxsim best / JuPedSim SFM:   {best / jps_rate:8.1f}x")
    print(f"ratio jaxsim best / pysocialforce:  {best / psf_rate:8.0f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
