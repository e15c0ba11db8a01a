"""Exact grid planners in JAX: the potential from the goal (Dijkstra's distances) and the path down it.

The graph: every cell of an (H, W) grid is a node; a move to one of the 8 neighbours (4 with
``connectivity=4``) costs its length in metres times the traversal cost per metre of the cell it
enters (``inf`` for impassable cells, see :func:`planners.layers.costmap.traversal_cost`); a diagonal
move may not cut the corner of an impassable cell. The potential ``phi(a)`` is the cheapest cost
from cell ``a`` to the goal: exactly what ``scipy.sparse.csgraph.dijkstra`` gives on the same
graph (a test holds it to 1e-5 relative on random grids with random walls).

* **NavFn-like** (Nav2's NavFn, the GSCL paper's planner): ``navfn_plan`` = cell cost ``50 + 0.8 c``
  (:func:`planners.layers.costmap.navfn_traversal`), inscribed and lethal cells impassable. NavFn itself
  propagates a 4-connected wave with a quadratic interpolation; here the potential is the exact
  8-connected shortest path (``connectivity=4`` for NavFn's neighbourhood).
* **Weighted-grid Dijkstra** (SNAPE's global planner, seed 004 Sec. 3.3): ``weighted_plan`` = cell
  cost ``1 + c``.

**How it is computed.** Two solvers reach the same float32 fixed point, bit for bit (tested):
on the CPU by default a C++ Dijkstra (``grid_dijkstra.cc``, an XLA FFI call: a ring of buckets,
the path descended in the same call, the grids of a batch over threads; about 8x faster than
scipy per plan at a batch of 64, docs/layers.md "Speed"), and everywhere the JAX
sweeps below (``solver="sweeps"``; no priority queue, which neither vectorises nor batches): Bellman's
equation ``phi(a) = min_b w(a, b) + phi(b)`` relaxed by rounds of four sweeps (down the rows, up,
then along the columns both ways: the fast-sweeping order) until a round changes nothing. A sweep
is a ``lax.scan`` over lines, each line taking its three neighbours in the line before it; a round
settles every optimal path that turns at most a few times, and the loop ends one round after the
last change. The result is the exact fixed point (Bellman-Ford in a Gauss-Seidel order), equal to
Dijkstra's up to the order of float sums. :func:`potentials` runs a batch with the batch axis
innermost; :func:`potential` is one grid.

The path: from the start, step to the neighbour that attains the minimum in Bellman's equation
(Dijkstra's predecessor), so the potential falls strictly at every step and the path never enters
an impassable cell.
"""

from __future__ import annotations

import ctypes
import functools
import math
import os
import pathlib
import warnings

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from socialnav.jaxsim import native
from socialnav.planners.layers.costmap import GridSpec, navfn_traversal, weighted_traversal

DIJKSTRA_SOURCE = pathlib.Path(__file__).with_name("grid_dijkstra.cc")
DIJKSTRA_TARGET = "socialnav_grid_dijkstra"
PLAN_TARGET = "socialnav_grid_plan"
SOLVERS = ("auto", "sweeps", "dijkstra")

MOVES_8 = ((-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1))
MOVES_4 = ((-1, 0), (0, -1), (0, 1), (1, 0))


def moves(connectivity: int):
    if connectivity not in (4, 8):
        raise ValueError(f"connectivity must be 4 or 8, got {connectivity}")
    return MOVES_8 if connectivity == 8 else MOVES_4


def _shift(a, di: int, dj: int, fill):
    """a[i + di, j + dj], ``fill`` where that lies off the grid."""
    h, w = a.shape
    padded = jnp.pad(a, ((1, 1), (1, 1)), constant_values=fill)
    return jax.lax.slice(padded, (1 + di, 1 + dj), (1 + di + h, 1 + dj + w))


def move_costs(traversal_per_m, resolution_m: float, connectivity: int = 8) -> dict:
    """The graph's edge weights: ``{(di, dj): (H, W)}``, the cost of moving from each cell to
    ``(i + di, j + dj)`` (``inf`` off the grid, into an impassable cell, or diagonally past one)."""
    t = jnp.asarray(traversal_per_m)
    t = t.astype(jnp.promote_types(t.dtype, jnp.float32))
    blocked = jnp.isinf(t)
    out = {}
    for di, dj in moves(connectivity):
        length = resolution_m * math.hypot(di, dj)
        w = length * _shift(t, di, dj, jnp.inf)
        if di and dj:
            corner = _shift(blocked, di, 0, True) | _shift(blocked, 0, dj, True)
            w = jnp.where(corner, jnp.inf, w)
        out[(di, dj)] = w
    return out


def _shift_lines(a, d: int):
    """``a[j + d]`` along axis 0 (``inf`` past the end)."""
    pad = jnp.full((1,) + a.shape[1:], jnp.inf, a.dtype)
    return jnp.concatenate([a[1:], pad]) if d == 1 else jnp.concatenate([pad, a[:-1]])


def _sweep(phi, w: dict, direction: int, connectivity: int):
    """One sweep over axis 0 of ``phi`` (H, W, B): ``direction`` +1 takes each line's neighbours
    in the line before it (down the rows), -1 in the line after it (up)."""
    side = (-1, 0, 1) if connectivity == 8 else (0,)
    weights = tuple(w[(-direction, dj)] for dj in side)

    def line_step(prev, xs):
        line, line_weights = xs
        for dj, weight in zip(side, line_weights, strict=True):
            neighbour = prev if dj == 0 else _shift_lines(prev, dj)
            line = jnp.minimum(line, weight + neighbour)
        return line, line

    first = jnp.full(phi.shape[1:], jnp.inf, phi.dtype)
    _, lines = jax.lax.scan(line_step, first, (phi, weights), reverse=direction < 0)
    return lines


def potentials(
    traversal_per_m,
    goal_ij,
    resolution_m: float,
    connectivity: int = 8,
    max_sweeps: int | None = None,
    return_rounds: bool = False,
    solver: str = "auto",
):
    """(B, H, W) float32 exact cost-to-goal of every cell of a batch of grids (``inf`` where the
    goal cannot be reached).

    Args:
      traversal_per_m: (B, H, W) cost per metre of entering each cell, ``inf`` impassable.
      goal_ij: (B, 2) int (row, col) of each goal (its own cost does not matter: nothing leaves
        it); a goal off the grid makes every cell unreachable.
      resolution_m, connectivity: static.
      max_sweeps: a bound on the rounds of four sweeps (default ``H * W``, never reached in
        practice: each round settles at least one more turn of the optimal paths).
      return_rounds: also return the rounds the batch took (static; the benchmark reports it;
        the sweeps only).
      solver: ``"sweeps"`` (the rounds of four sweeps below, any device), ``"dijkstra"`` (the C++
        Dijkstra of ``grid_dijkstra.cc`` on the CPU, one pass with a bucket queue, the grids split over
        threads; the sweeps on other devices), or ``"auto"`` (default): Dijkstra where it is
        built on the CPU (and neither ``max_sweeps`` nor ``return_rounds`` is asked for), else
        the sweeps. Both reach the same float32 fixed point, bit for bit
        (tested). Neither is differentiable (the soft planner, :mod:`planners.global_planners.smooth_planner`, is).

    The batch is the innermost axis inside (arrays (H, W, B)): each sweep step then works on a
    contiguous (W, B) line, which on a CPU measured 2x faster than ``vmap`` over single grids.
    """
    if solver == "auto" and (max_sweeps is not None or return_rounds):
        solver = "sweeps"
    if _solver(solver) == "dijkstra":
        if return_rounds or max_sweeps is not None:
            raise ValueError("max_sweeps and return_rounds belong to the sweeps (solver='sweeps')")
        t = jnp.asarray(traversal_per_m, jnp.float32)
        return _dijkstra_potentials(t, jnp.asarray(goal_ij, jnp.int32), resolution_m, connectivity)
    t = jnp.moveaxis(jnp.asarray(traversal_per_m, jnp.float32), 0, -1)  # (H, W, B)
    h, w_, _ = t.shape
    w = jax.vmap(lambda x: move_costs(x, resolution_m, connectivity), in_axes=2, out_axes=2)(t)
    w_t = {(dj, di): jnp.swapaxes(v, 0, 1) for (di, dj), v in w.items()}  # the moves of the transposed grid
    goal_ij = jnp.asarray(goal_ij, jnp.int32)
    rows = jnp.arange(h)[:, None, None]
    cols = jnp.arange(w_)[None, :, None]
    is_goal = (rows == goal_ij[None, None, :, 0]) & (cols == goal_ij[None, None, :, 1])
    phi0 = jnp.where(is_goal, 0.0, jnp.inf).astype(jnp.float32)
    limit = h * w_ if max_sweeps is None else max_sweeps

    def body(carry):
        phi, _, n = carry
        new = _sweep(_sweep(phi, w, +1, connectivity), w, -1, connectivity)
        new_t = jnp.swapaxes(new, 0, 1)
        new_t = _sweep(_sweep(new_t, w_t, +1, connectivity), w_t, -1, connectivity)
        new = jnp.swapaxes(new_t, 0, 1)
        return new, jnp.any(new < phi), n + 1

    def cond(carry):
        _, changed, n = carry
        return changed & (n < limit)

    phi, _, rounds = jax.lax.while_loop(cond, body, (phi0, jnp.array(True), jnp.array(0)))
    phi = jnp.moveaxis(phi, -1, 0)
    return (phi, rounds) if return_rounds else phi


def solver_variable_problem() -> str | None:
    """Why ``$SOCIALNAV_GRID_SOLVER`` names no solver, in one line naming it; None where it is unset
    or names one."""
    value = os.environ.get("SOCIALNAV_GRID_SOLVER")
    if not value or value in SOLVERS:
        return None
    return f"SOCIALNAV_GRID_SOLVER={value}: not a solver (one of {', '.join(SOLVERS)}; unset: auto)"


def _solver(solver: str) -> str:
    """The solver that runs: ``"auto"`` is ``$SOCIALNAV_GRID_SOLVER`` when set (``sweeps`` or
    ``dijkstra``), else Dijkstra where it is built and JAX's default backend is the CPU;
    ``"dijkstra"`` without a build runs the sweeps (with the build's warning)."""
    if solver == "auto" and os.environ.get("SOCIALNAV_GRID_SOLVER"):
        problem = solver_variable_problem()
        if problem:
            raise ValueError(problem)
        solver = os.environ["SOCIALNAV_GRID_SOLVER"]
    if solver not in SOLVERS:
        raise ValueError(f"solver must be one of {', '.join(SOLVERS)}, got {solver!r}")
    if solver == "sweeps" or (solver == "auto" and jax.default_backend() != "cpu"):
        return "sweeps"
    return "dijkstra" if dijkstra_available() else "sweeps"


@functools.cache
def dijkstra_available() -> bool:
    """Whether the C++ Dijkstra (``grid_dijkstra.cc``) is built and registered with XLA for the CPU
    (built as :mod:`socialnav.jaxsim.native` builds its kernels; False with ``SOCIALNAV_NATIVE=off``,
    or with a warning naming the reason when it cannot be built)."""
    if native.disabled():
        return False
    try:
        library = ctypes.cdll.LoadLibrary(str(native.build(DIJKSTRA_SOURCE)))
        jax.ffi.register_ffi_target(DIJKSTRA_TARGET, jax.ffi.pycapsule(library.GridDijkstra), platform="cpu")
        jax.ffi.register_ffi_target(PLAN_TARGET, jax.ffi.pycapsule(library.GridPlan), platform="cpu")
    except (RuntimeError, OSError) as e:
        warnings.warn(
            f"socialnav.planners.global_planners.grid_planner: plans run on the sweeps, not Dijkstra ({e})",
            stacklevel=2,
        )
        return False
    return True


def _lengths(resolution_m: float, connectivity: int) -> dict:
    """The kernels' attributes: the moves' lengths rounded to float32 as JAX rounds them."""
    moves(connectivity)  # the same error for a bad connectivity
    return dict(
        straight_m=np.float32(resolution_m),
        diagonal_m=np.float32(resolution_m * math.sqrt(2.0)),
        connectivity=np.int32(connectivity),
    )


def _dijkstra_potentials(t, goal_ij, resolution_m: float, connectivity: int):
    """:func:`potentials` by the C++ Dijkstra on the CPU (the sweeps elsewhere): the same float32
    sums, so the same bits (tested)."""
    attributes = _lengths(resolution_m, connectivity)

    def on_cpu(t, goal_ij):
        out = jax.ShapeDtypeStruct(t.shape, jnp.float32)
        return jax.ffi.ffi_call(DIJKSTRA_TARGET, out, vmap_method="broadcast_all")(t, goal_ij, **attributes)

    def elsewhere(t, goal_ij):
        return potentials(t, goal_ij, resolution_m, connectivity, solver="sweeps")

    return jax.lax.platform_dependent(t, goal_ij, cpu=on_cpu, default=elsewhere)


def _dijkstra_plans(t, start_ij, goal_ij, resolution_m: float, connectivity: int, steps: int):
    """Potentials and paths (:func:`descend`'s, the same moves and ties) in one C++ call on the CPU."""
    attributes = _lengths(resolution_m, connectivity)
    batch = t.shape[:-2]

    def on_cpu(t, start_ij, goal_ij):
        out = (
            jax.ShapeDtypeStruct(t.shape, jnp.float32),
            jax.ShapeDtypeStruct((*batch, steps + 1, 2), jnp.int32),
            jax.ShapeDtypeStruct(batch, jnp.int32),
        )
        call = jax.ffi.ffi_call(PLAN_TARGET, out, vmap_method="broadcast_all")
        return tuple(call(t, start_ij, goal_ij, steps=np.int32(steps), **attributes))

    def elsewhere(t, start_ij, goal_ij):
        phi = potentials(t, goal_ij, resolution_m, connectivity, solver="sweeps")
        path, length, _ = jax.vmap(lambda p, tt, s, g: descend(p, tt, s, g, resolution_m, connectivity, steps))(
            phi, t, start_ij, goal_ij
        )
        return phi, path, length

    return jax.lax.platform_dependent(t, start_ij, goal_ij, cpu=on_cpu, default=elsewhere)


def potential(traversal_per_m, goal_ij, resolution_m: float, connectivity: int = 8, max_sweeps: int | None = None):
    """(H, W) exact cost-to-goal of one grid (:func:`potentials` on a batch of one)."""
    t = jnp.asarray(traversal_per_m, jnp.float32)[None]
    goal = jnp.asarray(goal_ij, jnp.int32)[None]
    return potentials(t, goal, resolution_m, connectivity, max_sweeps)[0]


@struct.dataclass
class GridPlan:
    """A plan on the grid.

    Attributes:
      potential: (H, W) cost-to-goal.
      path_ij: (L, 2) int32 cells from the start; after the goal (or a dead end) the last cell repeats.
      path_length: () int32 number of distinct cells on the path (start and goal included).
      reached: () bool, the path ends at the goal.
      cost: () float32, the potential at the start (the path's cost; ``inf`` when unreachable).
    """

    potential: jnp.ndarray
    path_ij: jnp.ndarray
    path_length: jnp.ndarray
    reached: jnp.ndarray
    cost: jnp.ndarray


def descend(phi, traversal_per_m, start_ij, goal_ij, resolution_m: float, connectivity: int = 8, max_steps: int = 0):
    """The path from ``start_ij`` down the potential: (max_steps + 1, 2) cells, its length, reached.

    ``max_steps`` (static) defaults to ``2 (H + W)``; a path needing more is cut (``reached``
    False).
    """
    h, w_ = phi.shape
    steps = max_steps or 2 * (h + w_)
    w = move_costs(traversal_per_m, resolution_m, connectivity)
    offsets = jnp.array(moves(connectivity), jnp.int32)
    weights = jnp.stack([w[m] for m in moves(connectivity)])  # (K, H, W)
    phi_pad = jnp.pad(phi, 1, constant_values=jnp.inf)
    goal_ij = jnp.asarray(goal_ij, jnp.int32)

    def step(cell, _):
        at_goal = jnp.all(cell == goal_ij)
        nbr = cell[None, :] + offsets
        value = weights[:, cell[0], cell[1]] + phi_pad[nbr[:, 0] + 1, nbr[:, 1] + 1]
        k = jnp.argmin(value)
        move = ~at_goal & jnp.isfinite(value[k])
        nxt = jnp.where(move, nbr[k], cell)
        return nxt, nxt

    start = jnp.asarray(start_ij, jnp.int32)
    _, rest = jax.lax.scan(step, start, None, length=steps)
    path = jnp.concatenate([start[None], rest], axis=0)
    moved = jnp.any(path[1:] != path[:-1], axis=-1)
    length = 1 + jnp.sum(moved).astype(jnp.int32)
    reached = jnp.all(path[-1] == goal_ij)
    return path, length, reached


def plans(
    traversal_per_m,
    start_ij,
    goal_ij,
    resolution_m: float,
    connectivity: int = 8,
    max_steps: int = 0,
    solver: str = "auto",
) -> GridPlan:
    """Potentials and paths of a batch: traversal (B, H, W), start and goal (B, 2) cells; every
    field of the returned :class:`GridPlan` has the leading batch axis (``solver``: as
    :func:`potentials`)."""
    t = jnp.asarray(traversal_per_m, jnp.float32)
    start_ij = jnp.asarray(start_ij, jnp.int32)
    goal_ij = jnp.asarray(goal_ij, jnp.int32)
    h, w_ = t.shape[1:]
    if _solver(solver) == "dijkstra":
        steps = max_steps or 2 * (h + w_)
        phi, path, length = _dijkstra_plans(t, start_ij, goal_ij, resolution_m, connectivity, steps)
        reached = jnp.all(path[:, -1] == goal_ij, axis=-1)
    else:
        phi = potentials(t, goal_ij, resolution_m, connectivity, solver="sweeps")
        path, length, reached = jax.vmap(
            lambda p, tt, s, g: descend(p, tt, s, g, resolution_m, connectivity, max_steps)
        )(phi, t, start_ij, goal_ij)
    on = (start_ij[:, 0] >= 0) & (start_ij[:, 0] < h) & (start_ij[:, 1] >= 0) & (start_ij[:, 1] < w_)
    clipped = jnp.clip(start_ij, 0, jnp.array([h - 1, w_ - 1]))
    cost = jnp.where(on, phi[jnp.arange(len(phi)), clipped[:, 0], clipped[:, 1]], jnp.inf)
    return GridPlan(phi, path, length, reached & on, cost)


def plan(
    traversal_per_m, start_ij, goal_ij, resolution_m: float, connectivity: int = 8, max_steps: int = 0
) -> GridPlan:
    """Potential from the goal and the path down it, for one grid (:func:`plans` for a batch)."""
    batch = plans(
        jnp.asarray(traversal_per_m, jnp.float32)[None],
        jnp.asarray(start_ij, jnp.int32)[None],
        jnp.asarray(goal_ij, jnp.int32)[None],
        resolution_m,
        connectivity,
        max_steps,
    )
    return jax.tree_util.tree_map(lambda a: a[0], batch)


def navfn_plans(costs, start_xy_m, goal_xy_m, spec: GridSpec, connectivity: int = 8, max_steps: int = 0) -> GridPlan:
    """NavFn-like plans on a batch of Nav2-scale cost grids (B, H, W) between world points (B, 2)."""
    return plans(
        navfn_traversal(costs),
        spec.cell_of(start_xy_m),
        spec.cell_of(goal_xy_m),
        spec.resolution_m,
        connectivity,
        max_steps,
    )


def weighted_plans(costs, start_xy_m, goal_xy_m, spec: GridSpec, connectivity: int = 8, max_steps: int = 0) -> GridPlan:
    """SNAPE's weighted-grid Dijkstra (cell cost ``1 + c``) on a batch (B, H, W) between world
    points (B, 2)."""
    return plans(
        weighted_traversal(costs),
        spec.cell_of(start_xy_m),
        spec.cell_of(goal_xy_m),
        spec.resolution_m,
        connectivity,
        max_steps,
    )


def path_xy_m(grid_plan: GridPlan, spec: GridSpec):
    """(..., L, 2) world positions of a plan's path cells (centres)."""
    return spec.centre_of(grid_plan.path_ij)
