"""Grid planners and cost layers on this machine, beside scipy's Dijkstra on the same grids.

    python benchmarks/bench_planners.py                 # 100x100 and 320x320, batches 1, 64, 1024
    python benchmarks/bench_planners.py --quick         # batches 1 and 64 only

Milliseconds per plan of the exact planner (NavFn-like cells; SNAPE's weighted grid is the same
solver on other cell costs) for batches of grids with random costs and 10 % random lethal cells,
each with its own goal, by both solvers (the JAX sweeps; the C++ Dijkstra, plans with their
paths and the potential alone); scipy's ``dijkstra`` from the same goal on the same graph in the
same run (its graph built beforehand, not timed: the comparison favours scipy). Each JAX figure
is the second call (the first compiles; the sweeps' compile time is printed apart). Then layer evaluations per second
for 1000 scenes of 10 people on a 100x100 grid.
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
import scipy.sparse as sp  # noqa: E402
from scipy.sparse.csgraph import dijkstra  # noqa: E402

from benchmarks.bench_simulator import machine  # noqa: E402
from socialnav.planners.global_planners import grid_planner  # noqa: E402
from socialnav.planners.layers import casn_layer as casn  # noqa: E402
from socialnav.planners.layers import costmap  # noqa: E402
from socialnav.planners.layers import snape_layer as snape  # noqa: E402
from socialnav.planners.layers import snl_layer as snl  # noqa: E402
from socialnav.planners.layers.scene import make_scene  # noqa: E402

RESOLUTION_M = 0.05


def random_costs(rng, batch: int, n: int) -> np.ndarray:
    costs = rng.uniform(0, 100, (batch, n, n)).astype(np.float32)
    costs[rng.uniform(size=(batch, n, n)) < 0.1] = costmap.LETHAL
    return costs


def scipy_graph(traversal: np.ndarray):
    """The planner's graph, reversed (Dijkstra from the goal gives the cost to reach it)."""
    h, w = traversal.shape
    index = np.arange(h * w).reshape(h, w)
    blocked = np.isinf(traversal)
    rows, cols, vals = [], [], []
    for di, dj in grid_planner.MOVES_8:
        i0, i1, j0, j1 = max(0, -di), min(h, h - di), max(0, -dj), min(w, w - dj)
        src, dst = index[i0:i1, j0:j1], index[i0 + di : i1 + di, j0 + dj : j1 + dj]
        weight = RESOLUTION_M * np.hypot(di, dj) * traversal[i0 + di : i1 + di, j0 + dj : j1 + dj]
        ok = np.isfinite(weight)
        if di and dj:
            ok &= ~blocked[i0 + di : i1 + di, j0:j1] & ~blocked[i0:i1, j0 + dj : j1 + dj]
        rows.append(dst[ok])
        cols.append(src[ok])
        vals.append(weight[ok])
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(h * w, h * w))


def _timed(fn, *args) -> tuple[float, float]:
    """(first call s, second call s) of a jitted function (the first compiles)."""
    t0 = time.perf_counter()
    jax.block_until_ready(fn(*args))
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    jax.block_until_ready(fn(*args))
    return first, time.perf_counter() - t0


def bench_planner(rng, n: int, batch: int) -> dict:
    """Per plan (s): the sweeps' plans (potential and path) and the C++ Dijkstra's, the Dijkstra
    potential alone (what scipy computes), scipy's; the sweeps' compile time and their rounds."""
    costs = random_costs(rng, batch, n)
    goals = rng.integers(0, n, (batch, 2))
    starts = rng.integers(0, n, (batch, 2))
    costs[np.arange(batch), goals[:, 0], goals[:, 1]] = 0.0
    traversal = costmap.navfn_traversal(costs)
    out = {}
    for solver in ("sweeps", "dijkstra"):
        fn = jax.jit(lambda t, s, g, solver=solver: grid_planner.plans(t, s, g, RESOLUTION_M, solver=solver))
        first, run = _timed(fn, traversal, starts, goals)
        out[solver] = run / batch
        out[f"{solver} compile"] = first - run
    potential = jax.jit(lambda t, g: grid_planner.potentials(t, g, RESOLUTION_M, solver="dijkstra"))
    out["dijkstra potential"] = _timed(potential, traversal, goals)[1] / batch
    sweeps = jax.jit(lambda t, g: grid_planner.potentials(t, g, RESOLUTION_M, return_rounds=True, solver="sweeps"))
    out["rounds"] = int(sweeps(traversal, goals)[1])

    t_np = np.asarray(traversal)
    sample = min(batch, 16)
    graphs = [scipy_graph(t_np[k]) for k in range(sample)]
    t0 = time.perf_counter()
    for k in range(sample):
        dijkstra(graphs[k], directed=True, indices=int(goals[k, 0] * n + goals[k, 1]))
    out["scipy"] = (time.perf_counter() - t0) / sample
    return out


def bench_layers(rng, scenes: int = 1000, people: int = 10, n: int = 100) -> dict[str, float]:
    """Layer evaluations per second (one jitted vmap over the scenes)."""
    spec = costmap.GridSpec(n, n, 0.1, origin_x_m=-n * 0.05, origin_y_m=-n * 0.05)
    x, y = spec.cell_centres()
    batch = [
        make_scene(
            rng.uniform(-4, 4, (people, 2)),
            rng.uniform(-np.pi, np.pi, people),
            rng.uniform(-1, 1, (people, 2)) * (rng.uniform(size=(people, 1)) < 0.5),
        )
        for _ in range(scenes)
    ]
    stacked = jax.tree_util.tree_map(lambda *a: jnp.stack(a), *batch)
    layers = {
        "SNL (proxemic + passing)": lambda s: snl.snl_layer(s, x, y),
        "CASN (with group detection)": lambda s: casn.casn_layer(s, x, y)[0],
        "SNAPE social map": lambda s: snape.snape_layer(s, x, y),
    }
    out = {}
    for name, fn in layers.items():
        f = jax.jit(jax.vmap(fn))
        jax.block_until_ready(f(stacked))
        t0 = time.perf_counter()
        jax.block_until_ready(f(stacked))
        out[name] = scenes / (time.perf_counter() - t0)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="batches 1 and 64 only")
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    print(f"machine: {machine()}")
    print(f"grid planner: {grid_planner.DIJKSTRA_TARGET} built: {grid_planner.dijkstra_available()}")
    print("grid planner (exact, 8-connected), ms per plan; scipy.sparse.csgraph.dijkstra on the same graphs")
    header = f"{'grid':>9} {'batch':>6} {'sweeps':>8} {'(rounds)':>8} {'Dijkstra':>9} {'potential':>10} {'scipy':>8}"
    print(f"{header} {'sweeps/scipy':>13} {'Dijkstra/scipy':>15} {'potential/scipy':>16} {'compile s':>10}")
    batches = (1, 64) if args.quick else (1, 64, 1024)
    for n in (100, 320):
        for batch in batches:
            r = bench_planner(rng, n, batch)
            print(
                f"{n:>4}x{n:<4} {batch:>6} {r['sweeps'] * 1e3:>8.2f} {r['rounds']:>8} {r['dijkstra'] * 1e3:>9.3f} "
                f"{r['dijkstra potential'] * 1e3:>10.3f} {r['scipy'] * 1e3:>8.2f} {r['sweeps'] / r['scipy']:>13.2f} "
                f"{r['dijkstra'] / r['scipy']:>15.3f} {r['dijkstra potential'] / r['scipy']:>16.3f} "
                f"{r['sweeps compile']:>10.2f}",
                flush=True,
            )
    print("cost layers, 1000 scenes of 10 people on 100x100 cells (0.1 m), scenes per second")
    for name, rate in bench_layers(rng).items():
        print(f"  {name:<30} {rate:>10.0f}")


if __name__ == "__main__":
    main()
