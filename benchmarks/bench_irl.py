"""Training costs through the planner (planners.learning.irl): gradient steps per second and memory.

Two measurements, each at the batch sizes given (default 32 and 256), on the U-Net of the
default GSCL recipe:

* **the whole training step of the "paths" objective** (``models.steps.make_train_step`` with
  ``planners.learning.irl.PathObjective``: planning the batch's demonstrations on its target maps, the
  U-Net forward and backward, the soft planner's implicit gradient, Adam), beside the "maps"
  objective's step (seed 002's regression) on the same batch;
* **the soft planner's gradient alone** (the path likelihood of random costs, ``jax.grad``),
  implicit (``soft_potential_implicit``: the adjoint recursion) against unrolled (reverse mode
  through every Jacobi step).

Memory is XLA's own figure for the compiled program (``compiled.memory_analysis()``: the
temporary buffers at their peak plus arguments and outputs), not the process's RSS.

    python benchmarks/bench_irl.py [--batches 32 256] [--seconds 10]
"""

from __future__ import annotations

import argparse
import functools
import pathlib
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from socialnav.runtime import request_host_devices, request_wide_vectors  # noqa: E402

request_host_devices()
request_wide_vectors()

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

from benchmarks.bench_simulator import machine  # noqa: E402
from benchmarks.record import record  # noqa: E402
from socialnav.models import dataset, grid  # noqa: E402
from socialnav.models.config import TrainConfig  # noqa: E402
from socialnav.models.steps import batch_sharding, compiled, initial_state  # noqa: E402
from socialnav.planners.global_planners import smooth_planner  # noqa: E402
from socialnav.planners.learning import irl  # noqa: E402


def _rate(fn, args, seconds: float) -> tuple[float, float]:
    """(calls per second after the first, compile + first call seconds)."""
    t0 = time.perf_counter()
    jax.block_until_ready(fn(*args))
    first = time.perf_counter() - t0
    n, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        jax.block_until_ready(fn(*args))
        n += 1
    return n / (time.perf_counter() - t0), first


def _memory_mb(fn, args) -> float:
    m = jax.jit(fn).lower(*args).compile().memory_analysis()
    if m is None:
        return float("nan")
    return (m.temp_size_in_bytes + m.argument_size_in_bytes + m.output_size_in_bytes) / 2**20


def _unrolled_nll(costs, maps, demo, temperature, iterations):
    weights = smooth_planner.soft_weights(irl.traversal_per_m(maps, costs), grid.CELL_M)
    phi = smooth_planner._iterate(
        weights, smooth_planner._goal_mask(costs.shape, demo.goal_ij), temperature, irl.CEILING, 8, iterations
    )
    nll = (jnp.sum(demo.moves * weights) - jnp.sum(demo.starts * phi)) / temperature
    return jnp.where(demo.n_paths > 0, nll / jnp.maximum(demo.n_paths, 1.0), 0.0)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--batches", type=int, nargs="+", default=[32, 256])
    ap.add_argument("--seconds", type=float, default=10.0)
    args = ap.parse_args(argv)
    print(machine())
    data = dataset.generate(0, {f: 64 for f in dataset.FAMILIES})
    objective = irl.PathObjective()
    print(
        f"paths objective: tau {objective.temperature}, {objective.paths_per_map} paths per map, "
        f"{objective.iterations} Jacobi steps forward and in the adjoint"
    )
    for b in args.batches:
        idx = np.arange(b) % len(data["inputs"])
        inputs, targets = jnp.asarray(data["inputs"][idx]), jnp.asarray(data["targets"][idx])
        family = jnp.asarray(data["family"][idx].astype(np.int32))
        key = jax.random.key(0)
        data_sharding, replicated = batch_sharding(b)
        if data_sharding is not None:  # as training runs it: the batch split over the host devices
            inputs, targets, family = jax.device_put((inputs, targets, family), data_sharding)
        print(f"\nbatch {b}")
        for name, obj in (("maps (seed 002's regression)", None), ("paths (IRL through the planner)", objective)):
            config = TrainConfig(batch_size=b, objective="maps" if obj is None else "paths")
            state = initial_state(config)
            if replicated is not None:
                state = jax.device_put(state, replicated)
            step = compiled(config, obj)[2]
            rate, first = _rate(step, (state, inputs, targets, family, None, key), args.seconds)
            print(
                f"  whole training step, {name}: {rate:.2f} steps/s ({rate * b:.0f} maps/s), first call {first:.1f} s"
            )
            record("irl", f"maps/s ({name.split(' ')[0]} objective)", rate * b, "maps/s", compile_s=first, batch=b)
        demos = jax.jit(objective.prepare)(key, inputs, targets)
        costs = jnp.clip(targets + 0.05, 0.0, 1.0)
        for name, nll in (("implicit", _implicit_mean_nll), ("unrolled", _unrolled_mean_nll)):
            grad = jax.grad(functools.partial(nll, objective=objective))
            rate, _ = _rate(jax.jit(grad), (costs, inputs, demos), args.seconds / 2)
            mem = _memory_mb(grad, (costs, inputs, demos))
            print(f"  soft planner's gradient alone, {name}: {rate * b:.0f} maps/s, XLA memory {mem:.0f} MiB")


def _implicit_mean_nll(costs, maps, demos, objective):
    return jnp.mean(irl.batch_nll(costs, maps, demos, objective.temperature, objective.iterations))


def _unrolled_mean_nll(costs, maps, demos, objective):
    def one(c, m, d):
        return _unrolled_nll(c, m, d, objective.temperature, objective.iterations)

    return jnp.mean(jax.vmap(one)(costs, maps, demos))


if __name__ == "__main__":
    main()
