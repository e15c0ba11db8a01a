"""Where a warehouse step's time goes: by ablation, and optionally per XLA kernel.

    python benchmarks/profile_step.py                   # ablation table, batch 256, both cores
    python benchmarks/profile_step.py --kernels         # + the 25 costliest kernels of one step

Ablation: each variant replaces one part of the step by a no-op (the social force by zeros, the
worker context, the robot's controller, the whole crowd move) or by the dense reference, and
compiles its own program; variants are timed in interleaved rounds and the best round is kept
(this machine's speed drifts by up to 2x between minutes, see README "Speed"). Elementwise XLA
code does the same work whatever the values, so a no-op's saving is the part's cost.

Kernels (``--kernels``): one device, 64 worlds, a JAX profiler trace of 100 steps, summed by
XLA kernel name (numbered copies merged); the profiler adds about 15 %.
"""

from __future__ import annotations

import argparse
import collections
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

from socialnav.runtime import request_host_devices, request_wide_vectors

request_host_devices()
request_wide_vectors()

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

from benchmarks.bench_simulator import machine  # noqa: E402
from benchmarks.xla_trace import kernel_times  # noqa: E402
from socialnav.jaxsim import robot as robot_lib  # noqa: E402
from socialnav.jaxsim import rollout, social_force  # noqa: E402
from socialnav.jaxsim import workers as workers_lib  # noqa: E402
from socialnav.jaxsim.route_follower import route_follower  # noqa: E402
from socialnav.jaxsim.scenario import load_scenario  # noqa: E402
from socialnav.jaxsim.world import build_world  # noqa: E402
from socialnav.planners.warehouse.routes import shortest_path_plan  # noqa: E402

SAMPLES, EVERY = 10, 10  # one call: 100 steps


def _zero_force(params, x, y, vx, vy, weight):
    return jnp.zeros_like(x), jnp.zeros_like(y)


# name -> {attribute path: replacement}; every replacement keeps the shapes of what it replaces.
VARIANTS = {
    "full step": {},
    "social force -> zeros": {"sf": _zero_force},
    "social force -> dense reference": {"sf": social_force.social_force_dense},
    "social force -> JAX version": {"sf": social_force.social_force_xla},
    "worker context -> no-op": {"ctx": lambda params, world, w, *a: w},
    "robot update -> no-op": {"robot": lambda params, world, robot, *a: robot},
    "crowd move -> no-op": {"move": lambda params, world, w, *a: w},
}
_ORIGINAL = {
    "sf": workers_lib.sf.social_force,
    "ctx": workers_lib.update_context,
    "move": workers_lib.move,
    "robot": robot_lib.update_robot,
}


def _install(replace: dict) -> None:
    workers_lib.sf.social_force = replace.get("sf", _ORIGINAL["sf"])
    workers_lib.update_context = replace.get("ctx", _ORIGINAL["ctx"])
    workers_lib.move = replace.get("move", _ORIGINAL["move"])
    robot_lib.update_robot = replace.get("robot", _ORIGINAL["robot"])


def ablation(scenario, batch: int, rounds: int) -> None:
    p = scenario.params
    world = build_world(scenario)
    controller = route_follower(shortest_path_plan(scenario), world)
    keys = rollout.world_keys(0, batch)
    agents = p.n_workers + 1
    n_dev = rollout.devices_for(batch)
    compiled = {}
    for name, replace in VARIANTS.items():
        _install(replace)
        rollout._compiled.cache_clear()  # each variant traces its own program
        t0 = time.perf_counter()
        states = rollout.init_batch(p, world, controller, keys)
        for _ in range(20):  # 200 simulated seconds: the workers have arrived
            states, _ = rollout.run_samples(p, world, controller, states, keys, SAMPLES, EVERY)
        jax.block_until_ready(states)
        fn = rollout._compiled(SAMPLES, EVERY, rollout.DEFAULT_WORLD_CHUNK, n_dev, False)
        compiled[name] = (fn, rollout.place(n_dev, (p, world, controller), (states, keys)))
        print(f"  compiled {name} ({time.perf_counter() - t0:.1f} s with warm-up)", flush=True)
    _install({})
    rollout._compiled.cache_clear()
    best = dict.fromkeys(compiled, float("inf"))
    for _ in range(rounds):
        for name, (fn, (shared, batched)) in compiled.items():
            t0 = time.perf_counter()
            for _ in range(5):
                out = fn(*shared, *batched)
            jax.block_until_ready(out)
            best[name] = min(best[name], (time.perf_counter() - t0) / (5 * SAMPLES * EVERY))
    full = best["full step"]
    cores = os.cpu_count() or 1
    print(f"\nbatch {batch}, {agents} agents, best of {rounds} interleaved rounds of 500 steps")
    print(f"{'variant':34s} {'M agent-steps/s':>16s} {'ns/agent-step/core':>19s} {'saves':>7s}")
    for name, t in best.items():
        ns = t * cores / (agents * batch) * 1e9
        print(f"{name:34s} {agents * batch / t / 1e6:16.2f} {ns:19.1f} {1 - t / full:+7.0%}")


def kernels(scenario, top: int) -> None:
    p = scenario.params
    world = build_world(scenario)
    controller = route_follower(shortest_path_plan(scenario), world)
    keys = rollout.world_keys(0, 64)
    fn = rollout._compiled(1, 10, 64, 1, False)  # one device: one thread's kernels in order
    states = rollout.init_batch(p, world, controller, keys)
    for _ in range(20):
        states, _ = fn(p, world, controller, states, keys)
    jax.block_until_ready(states)

    def run():
        nonlocal states
        for _ in range(10):
            states, _ = fn(p, world, controller, states, keys)
        jax.block_until_ready(states)

    seconds, calls = kernel_times(run, per=100)  # per step (10 calls of 10 steps)
    total = collections.Counter({name: s * 1e6 for name, s in seconds.items()})  # us
    step_us = sum(total.values())
    print(f"\nkernels of one step, 64 worlds on one device (sum {step_us:.0f} us per step)")
    for name, us in total.most_common(top):
        print(f"{us:8.1f} us  {us / step_us:5.1%}  x{calls[name]:5.1f}  {name}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--batch", type=int, default=256)
    ap.add_argument("--rounds", type=int, default=4, help="interleaved timing rounds (best kept)")
    ap.add_argument("--kernels", action="store_true", help="also trace one step's XLA kernels")
    ap.add_argument("--top", type=int, default=25, help="kernels listed with --kernels")
    args = ap.parse_args()
    scenario = load_scenario()
    print(f"machine: {machine()}")
    print(f"XLA_FLAGS: {os.environ.get('XLA_FLAGS', '')}")
    ablation(scenario, args.batch, args.rounds)
    if args.kernels:
        kernels(scenario, args.top)
    return 0


if __name__ == "__main__":
    sys.exit(main())
