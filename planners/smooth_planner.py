"""A differentiable grid planner: the soft-min relaxation of the grid planner's Bellman recursion.

The exact potential (:mod:`planners.grid_planner`) solves ``phi(a) = min_b w(a, b) + phi(b)``; its
value at the start (the path's cost) is piecewise linear in the cost grid, with a gradient that is
the path's cells and nothing else. Replacing ``min`` with the soft-min at temperature ``tau``,
``softmin(x) = -tau log sum exp(-x / tau)``, gives a potential ``phi_tau`` smooth in every cell's
cost; ``phi_tau <= phi`` and ``phi_tau -> phi`` as ``tau -> 0`` (the gap is at most ``tau ln 8``
per step of the path). Its gradient with respect to the cost grid is the expected number of
visits of each cell by the soft-min policy times the step's length (times the NavFn factor):
a cost layer can be trained through the planner with ``jax.grad``, which none of the seeds'
planners (ROS NavFn, SNAPE's Dijkstra) nor social-jym's JAX Dijkstra allows.

The recursion runs a fixed number of Jacobi iterations (``iterations``, static: reverse-mode
differentiation needs a fixed trip count; the default, ``2 (H + W)``, covers paths with a few
turns); the temperature must stay below ``w_min / ln 8`` (``w_min`` the cheapest move's cost),
where the sum over walks that the soft-min takes converges. Impassable cells cost
:data:`BLOCKED` per metre instead of ``inf`` so that gradients stay finite.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp

from planners.costmap import INSCRIBED, NAVFN_FACTOR, NAVFN_NEUTRAL, GridSpec
from planners.grid_planner import move_costs, moves

BLOCKED = 1e7  # cost per metre of an impassable cell in the smooth planner


def smooth_traversal(costs, neutral: float = NAVFN_NEUTRAL, factor: float = NAVFN_FACTOR):
    """(H, W) ``neutral + factor c``, and :data:`BLOCKED` for inscribed and lethal cells."""
    costs = _floating(costs)
    return jnp.where(costs >= INSCRIBED, BLOCKED, neutral + factor * costs)


def _floating(a):
    """``a`` as float32, or float64 when it is already (for finite-difference checks under x64)."""
    a = jnp.asarray(a)
    return a.astype(jnp.promote_types(a.dtype, jnp.float32))


def soft_potential(
    traversal_per_m, goal_ij, resolution_m: float, temperature: float, iterations: int = 0, connectivity=8
):
    """(H, W) soft-min potential from the goal after ``iterations`` Jacobi steps (static).

    Args:
      traversal_per_m: (H, W) finite costs per metre (:func:`smooth_traversal`).
      goal_ij: (2,) int goal cell. temperature: in cost units (> 0).
    """
    t = _floating(traversal_per_m)
    h, w_ = t.shape
    steps = iterations or 2 * (h + w_)
    goal_ij = jnp.asarray(goal_ij, jnp.int32)
    is_goal = (jnp.arange(h)[:, None] == goal_ij[0]) & (jnp.arange(w_)[None, :] == goal_ij[1])
    big = BLOCKED * resolution_m * (h + w_)
    move_list = moves(connectivity)
    # Cost of each move out of each cell, the exact planner's graph (corners not cut), with the
    # impassable moves at BLOCKED per metre instead of inf: (K, H, W).
    exact = move_costs(jnp.where(t >= BLOCKED, jnp.inf, t), resolution_m, connectivity)
    weights = jnp.stack(
        [jnp.where(jnp.isinf(exact[m]), BLOCKED * resolution_m * math.hypot(*m), exact[m]) for m in move_list]
    )

    def bellman(phi, _):
        padded = jnp.pad(phi, 1, constant_values=big)
        candidates = weights + jnp.stack([padded[1 + di : 1 + di + h, 1 + dj : 1 + dj + w_] for di, dj in move_list])
        soft = -temperature * jax.nn.logsumexp(-candidates / temperature, axis=0)
        return jnp.where(is_goal, 0.0, jnp.minimum(soft, big)), None

    phi0 = jnp.where(is_goal, 0.0, big)
    phi, _ = jax.lax.scan(bellman, phi0, None, length=steps)
    return phi


def soft_path_cost(
    costs, start_xy_m, goal_xy_m, spec: GridSpec, temperature: float = 1.0, iterations: int = 0, connectivity=8
):
    """The smooth path cost ``phi_tau(start)`` of a Nav2-scale cost grid (H, W) under NavFn's cell
    costs: differentiable in ``costs`` (``jax.grad`` of it is the soft path's visits)."""
    start = spec.cell_of(start_xy_m)
    phi = soft_potential(
        smooth_traversal(costs), spec.cell_of(goal_xy_m), spec.resolution_m, temperature, iterations, connectivity
    )
    return phi[start[0], start[1]]
