"""What each human model costs: one crowd step of N people, every model on the same crowd.

    python benchmarks/bench_human_models.py                  # N = 16, 64, 256 in a batch of 64 worlds
    python benchmarks/bench_human_models.py --pairs          # and each model with everyone in pairs
    XLA_FLAGS=--xla_cpu_max_isa=AVX2 python benchmarks/bench_human_models.py   # AVX2 only

The crowd is a periodic corridor's (:mod:`evaluation.humans.validation`: 1.8 m wide, 2 persons/m²,
ghosts either side, so 3N bodies are felt), ``vmap``-ed over worlds as the arena and the
validation batch them. Prints people-steps per second (worlds x N x steps over the wall time,
compilation apart and printed, best of ``--repeats``) for each model, the ratio to the social
force, and the machine; with ``--pairs``, each model again with everyone walking in pairs
(:mod:`jaxsim.groups`: what the group terms cost). ``benchmarks/bench_crowd_scaling.py`` takes each model from 8 to 512
people and from 1 to 1,024 worlds.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

from benchmarks.bench_simulator import machine  # noqa: E402
from benchmarks.record import record  # noqa: E402
from socialnav.evaluation.humans import calibration as hc  # noqa: E402
from socialnav.evaluation.humans import validation as hv  # noqa: E402

MODELS = (
    "social_force",
    "collision_free_speed_calibrated",
    "anticipation_calibrated",
    "steering_speed_calibrated",
    "orca",
    "power_law",
)


def program(model: hv.HumanModel, n: int, worlds: int, steps: int, seed: int = 0, pairs: bool = False):
    """``(run, args)``: ``run(*args)`` steps ``worlds`` corridors of ``n`` people ``steps`` times
    (``pairs``: person 2k walks with 2k + 1)."""
    width, length = 1.8, n / (2.0 * 1.8)
    rng = np.random.default_rng(seed)
    xy0 = np.stack([hv._starts(n, width, length, model.radius_m, rng) for _ in range(worlds)])
    speed = np.stack([hv.desired_speeds(model.crowd, n, rng) for _ in range(worlds)])
    field = hv.corridor_field(width, length)

    def one(params, xy, s, key):
        direction = jnp.ones(n, jnp.float32)
        group_id = jnp.arange(n, dtype=jnp.int32) // 2 if pairs else None
        step = hv.periodic_step(model.name, params, field, direction, s, length, group_id)
        carry, _ = jax.lax.scan(lambda c, k: (step(c, k), None), hv.periodic_start(direction, s, xy),
                                jax.random.split(key, steps))  # fmt: skip
        return carry[0]

    run = jax.jit(jax.vmap(one, in_axes=(None, 0, 0, 0)))
    args = (model.params, jnp.asarray(xy0, jnp.float32), jnp.asarray(speed, jnp.float32),
            jax.random.split(jax.random.key(seed), worlds))  # fmt: skip
    return run, args


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--people", default="16,64,256", help="crowd sizes (default 16,64,256)")
    ap.add_argument("--worlds", type=int, default=64)
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--pairs", action="store_true", help="each model again with everyone walking in pairs")
    args = ap.parse_args()
    print(machine())
    for n in (int(v) for v in args.people.split(",")):
        base = None
        for name, pairs in [(m, p) for m in MODELS for p in ((False, True) if args.pairs else (False,))]:
            run, run_args = program(hc.named_model(name), n, args.worlds, args.steps, pairs=pairs)
            t0 = time.perf_counter()
            jax.block_until_ready(run(*run_args))
            compile_s = time.perf_counter() - t0
            best = min(_timed(run, run_args) for _ in range(args.repeats))
            rate = args.worlds * n * args.steps / best
            base = rate if name == "social_force" and not pairs else base
            label = f"{name}{' in pairs' if pairs else ''}"
            print(f"N={n:4d} {label:41s} {rate / 1e6:8.2f} M people-steps/s  (x{rate / base:.2f} of the social "
                  f"force; compile and first run {compile_s:.1f} s)", flush=True)  # fmt: skip
            record("human_models", f"people-steps/s ({label})", rate, "people-steps/s", compile_s=compile_s - best,
                   people=n, worlds=args.worlds)  # fmt: skip
    return 0


def _timed(run, args) -> float:
    t0 = time.perf_counter()
    jax.block_until_ready(run(*args))
    return time.perf_counter() - t0


if __name__ == "__main__":
    sys.exit(main())
