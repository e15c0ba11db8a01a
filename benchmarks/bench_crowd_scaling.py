"""Each human model's crowd step at 8-512 people per world and a batch of 1-1024 worlds, beside
the social force: the cost of a model as the crowd grows.

    python benchmarks/bench_crowd_scaling.py                                  # the default grid
    python benchmarks/bench_crowd_scaling.py --people 8,32,128 --worlds 1     # one world (issue 66's table)
    SOCIALNAV_NATIVE_MARCH=x86-64-v3 XLA_FLAGS=--xla_cpu_max_isa=AVX2 python benchmarks/bench_crowd_scaling.py

The crowd: N people at 1 person/m² in an open square (side sqrt(N) m, no walls), each walking
to the point mirrored through the square's centre at 1.0-1.4 m/s (everyone crosses everyone:
the dense middle is where ORCA's first program fails and its fallback runs), a robot standing
at the centre that they avoid. ``steps`` steps are scanned inside one ``jit`` and ``vmap``-ed
over worlds. Prints, per model and size, the wall time of one step of the whole batch and
people-steps/s (compilation apart, best of ``--repeats``), the ratio to the social force's step
time at the same size, and the machine.
"""

from __future__ import annotations

import argparse
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

from benchmarks.bench_human_models import _timed  # noqa: E402
from benchmarks.bench_simulator import machine  # noqa: E402
from socialnav.evaluation.humans import calibration as hc  # noqa: E402
from socialnav.evaluation.humans import validation as hv  # noqa: E402
from socialnav.jaxsim.walkers import Aims, Walkers  # noqa: E402

MODELS = (
    "social_force",
    "orca",
    "collision_free_speed_calibrated",
    "anticipation_calibrated",
    "steering_speed_calibrated",
)


def crowd(n: int, worlds: int, seed: int = 0):
    """``(xy0 (W, N, 2), goal (W, N, 2), speed (W, N))``: N people at 1 /m² in a square."""
    side = float(np.sqrt(n))
    cells = int(np.ceil(np.sqrt(n)))
    rng = np.random.default_rng(seed)
    xy, goal, speed = [], [], []
    for _ in range(worlds):
        grid = np.stack(np.meshgrid(np.arange(cells), np.arange(cells)), -1).reshape(-1, 2)
        pick = grid[rng.permutation(len(grid))[:n]]
        p = (pick + 0.5 + rng.uniform(-0.2, 0.2, pick.shape)) * side / cells - side / 2
        xy.append(p)
        goal.append(-p)
        speed.append(rng.uniform(1.0, 1.4, n))
    return tuple(jnp.asarray(np.stack(a), jnp.float32) for a in (xy, goal, speed))


def program(model: hv.HumanModel, n: int, worlds: int, steps: int):
    """``(run, args)``: ``run(*args)`` steps ``worlds`` crowds of ``n`` people ``steps`` times."""
    field = hv._open_field()
    present = jnp.ones(n, bool)

    def one(params, xy, goal, speed, key):
        def step(carry, k):
            xy, v = carry
            u = jax.random.uniform(k, (2, n), minval=1e-6, maxval=1.0)
            aim = goal - xy
            people = Walkers.of(xy, v, present, present)
            after = hv.model_step(
                model.name, params, field, people, Aims(aim[:, 0], aim[:, 1], speed, speed), (u[0], u[1])
            )
            return (after.xy_m, after.velocity_mps), None

        (xy, _), _ = jax.lax.scan(step, (xy, jnp.zeros_like(xy)), jax.random.split(key, steps))
        return xy

    run = jax.jit(jax.vmap(one, in_axes=(None, 0, 0, 0, 0)))
    xy0, goal, speed = crowd(n, worlds)
    return run, (model.params, xy0, goal, speed, jax.random.split(jax.random.key(0), worlds))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--people", default="8,32,128,512", help="people per world (default 8,32,128,512)")
    ap.add_argument("--worlds", default="1,64,1024", help="batch sizes (default 1,64,1024)")
    ap.add_argument("--models", default=",".join(MODELS))
    ap.add_argument("--steps", type=int, default=20, help="steps scanned per call (default 20)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument(
        "--max-people-steps",
        type=float,
        default=2e7,
        help="skip a size whose batch x people x steps exceeds this (default 2e7)",
    )
    args = ap.parse_args()
    print(machine())
    print(f"{'model':32s} {'N':>4s} {'worlds':>6s} {'ms/step':>10s} {'people-steps/s':>15s} {'x social force':>15s}"
          f" {'compile s':>9s}")  # fmt: skip
    for worlds in (int(w) for w in args.worlds.split(",")):
        for n in (int(v) for v in args.people.split(",")):
            if worlds * n * args.steps > args.max_people_steps:
                print(f"{'(all)':32s} {n:4d} {worlds:6d} skipped (over --max-people-steps)")
                continue
            base = None
            for name in args.models.split(","):
                run, run_args = program(hc.named_model(name), n, worlds, args.steps)
                compile_s = _timed(run, run_args)
                best = min(_timed(run, run_args) for _ in range(args.repeats))
                step_s = best / args.steps
                base = step_s if name == "social_force" else base
                ratio = f"{step_s / base:15.1f}" if base else f"{'':15s}"
                print(f"{name:32s} {n:4d} {worlds:6d} {step_s * 1e3:10.3f} {worlds * n / step_s / 1e6:13.2f} M"
                      f" {ratio} {compile_s:9.1f}", flush=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
