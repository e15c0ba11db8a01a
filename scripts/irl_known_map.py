"""Known answer for learning costs through the planner: recover a known cost map from its exact plans.

    python scripts/irl_known_map.py                      # tau 2, 128 maps x 4 paths, 1000 Adam steps
    python scripts/irl_known_map.py --temperature 4 8    # the temperatures compared in the README

A 40 x 40 map at 0.4 m with two walls and five Gaussian cost hills (the known costs, in [0, 1]);
demonstrations: exact plans (planners.global_planners.grid_planner) on it between random free start and goal
cells (``--maps`` random goals, 4 starts each). Learnt: a free cost grid (sigmoid of one
parameter per cell) by maximum-entropy IRL through the soft planner (planners.learning.irl). Printed,
per temperature: the held-out pairs' (64 random pairs no demonstration used) mean and worst
excess of the learnt map's exact plans over the optimum, both costed under the known map; the
same for the all-zero map (plans ignoring every social cost); and the correlation of the learnt
and known costs over the cells the demonstrations visit and over every free cell.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))

import jax
import jax.numpy as jnp
import numpy as np
import optax

from socialnav.models import grid
from socialnav.planners.learning import irl

PATHS_PER_GOAL = 4


def known_map() -> tuple[np.ndarray, np.ndarray]:
    """(input map with two walls, known costs (40, 40) in [0, 1])."""
    n = grid.GRID
    maps = np.zeros((n, n), np.uint8)
    maps[10, 5:30] = grid.WALL
    maps[28, 12:38] = grid.WALL
    yy, xx = np.mgrid[0:n, 0:n]
    costs = np.zeros((n, n), np.float32)
    for cy, cx, r in ((18, 15, 5), (20, 30, 4), (33, 8, 5), (5, 22, 4), (34, 26, 3)):
        costs = np.maximum(costs, np.exp(-((yy - cy) ** 2 + (xx - cx) ** 2) / (2 * r * r)))
    return maps, costs.astype(np.float32)


def run(temperature: float, n_maps: int, steps: int, seed: int = 0) -> dict:
    maps, true = (jnp.asarray(a) for a in known_map())
    demo = jax.jit(jax.vmap(lambda k: irl.planned_demonstration(k, maps, true, PATHS_PER_GOAL)))
    train = demo(jax.random.split(jax.random.key(seed + 1), n_maps))
    test = demo(jax.random.split(jax.random.key(seed + 2), 64))

    def loss(theta):
        costs = jax.nn.sigmoid(theta)
        return jnp.mean(jax.vmap(lambda d: irl.path_nll(costs, maps, d, temperature))(train))

    opt = optax.adam(0.1)
    theta = jnp.full(maps.shape, -2.0)
    state = opt.init(theta)

    @jax.jit
    def step(theta, state):
        value, grad = jax.value_and_grad(loss)(theta)
        updates, state = opt.update(grad, state)
        return optax.apply_updates(theta, updates), state, value

    t0 = time.perf_counter()
    for _ in range(steps):
        theta, state, value = step(theta, state)
    seconds = time.perf_counter() - t0
    learnt = jax.nn.sigmoid(theta)

    def excess(plan_costs):
        def one(d):
            first = jnp.argmax(d.starts.reshape(-1))
            start = jnp.stack([first // grid.GRID, first % grid.GRID])
            return irl.exact_path_cost(true, maps, plan_costs, start, d.goal_ij)

        cost, best = (np.asarray(a) for a in jax.jit(jax.vmap(one))(test))
        ratio = cost / best - 1
        return 100 * float(np.mean(ratio)), 100 * float(np.max(ratio))

    visited = np.asarray(train.moves.sum((0, 1))) > 0
    free = np.asarray(maps) != grid.WALL
    corr = lambda m: float(np.corrcoef(np.asarray(learnt)[m], np.asarray(true)[m])[0, 1])
    return {
        "temperature": temperature,
        "nll_per_path": float(value),
        "excess_pct": excess(learnt),
        "zero_map_excess_pct": excess(jnp.zeros_like(true)),
        "corr_visited": corr(visited),
        "corr_free": corr(free),
        "seconds": seconds,
        "paths": int(np.asarray(train.n_paths).sum()),
    }


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--temperature", type=float, nargs="+", default=[irl.TEMPERATURE])
    ap.add_argument("--maps", type=int, default=128, help="random goals, each with 4 demonstrated starts")
    ap.add_argument("--steps", type=int, default=1000)
    args = ap.parse_args(argv)
    for t in args.temperature:
        r = run(t, args.maps, args.steps)
        print(
            f"tau {t}: {r['paths']} paths, {args.steps} steps in {r['seconds']:.0f} s, NLL {r['nll_per_path']:.3f} "
            f"per path; held-out excess over the optimum {r['excess_pct'][0]:.2f} % (worst {r['excess_pct'][1]:.1f} "
            f"%), all-zero map {r['zero_map_excess_pct'][0]:.2f} % (worst {r['zero_map_excess_pct'][1]:.1f} %); "
            f"correlation with the known map {r['corr_visited']:.3f} where paths go, {r['corr_free']:.3f} on free cells"
        )


if __name__ == "__main__":
    main()
