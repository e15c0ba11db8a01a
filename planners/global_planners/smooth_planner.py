"""A differentiable grid planner: the soft-min relaxation of the grid planner's Bellman recursion.

The exact potential (:mod:`planners.global_planners.grid_planner`) solves ``phi(a) = min_b w(a, b) + phi(b)``; its
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

Two gradients: :func:`soft_potential` is differentiated through every Jacobi step (memory grows
with the steps); :func:`soft_potential_implicit` differentiates the fixed point by the implicit
function theorem (an adjoint recursion: the soft policy's expected visits), in memory of one
potential whatever the steps. :mod:`planners.learning.irl` learns costs from demonstrated paths with the
second.
"""

from __future__ import annotations

import functools
import math

import jax
import jax.numpy as jnp

from socialnav.planners.global_planners.grid_planner import move_costs, moves
from socialnav.planners.layers.costmap import INSCRIBED, NAVFN_FACTOR, NAVFN_NEUTRAL, GridSpec

BLOCKED = 1e7  # cost per metre of an impassable cell in the smooth planner


def smooth_traversal(costs, neutral: float = NAVFN_NEUTRAL, factor: float = NAVFN_FACTOR):
    """(H, W) ``neutral + factor c``, and :data:`BLOCKED` for inscribed and lethal cells."""
    costs = _floating(costs)
    return jnp.where(costs >= INSCRIBED, BLOCKED, neutral + factor * costs)


def _floating(a):
    """``a`` as float32, or float64 when it is already (for finite-difference checks under x64)."""
    a = jnp.asarray(a)
    return a.astype(jnp.promote_types(a.dtype, jnp.float32))


def soft_weights(traversal_per_m, resolution_m: float, connectivity: int = 8):
    """(K, H, W) the cost of each move out of each cell (the exact planner's graph: corners not
    cut), impassable moves at :data:`BLOCKED` per metre instead of ``inf``; K = ``connectivity``
    in :func:`planners.global_planners.grid_planner.moves` order."""
    t = _floating(traversal_per_m)
    exact = move_costs(jnp.where(t >= BLOCKED, jnp.inf, t), resolution_m, connectivity)
    return jnp.stack(
        [jnp.where(jnp.isinf(exact[m]), BLOCKED * resolution_m * math.hypot(*m), exact[m]) for m in moves(connectivity)]
    )


def _bellman(weights, phi, is_goal, temperature: float, ceiling, connectivity: int):
    """One Jacobi step of the soft-min Bellman recursion: (H, W) -> (H, W)."""
    h, w_ = phi.shape
    padded = jnp.pad(phi, 1, constant_values=ceiling)
    candidates = weights + jnp.stack(
        [padded[1 + di : 1 + di + h, 1 + dj : 1 + dj + w_] for di, dj in moves(connectivity)]
    )
    soft = -temperature * jax.nn.logsumexp(-candidates / temperature, axis=0)
    return jnp.where(is_goal, 0.0, jnp.minimum(soft, ceiling))


def _goal_mask(shape, goal_ij):
    h, w_ = shape
    goal_ij = jnp.asarray(goal_ij, jnp.int32)
    return (jnp.arange(h)[:, None] == goal_ij[0]) & (jnp.arange(w_)[None, :] == goal_ij[1])


def _iterate(weights, is_goal, temperature, ceiling, connectivity, steps):
    phi0 = jnp.where(is_goal, 0.0, ceiling).astype(weights.dtype)
    phi, _ = jax.lax.scan(
        lambda phi, _: (_bellman(weights, phi, is_goal, temperature, ceiling, connectivity), None),
        phi0,
        None,
        length=steps,
    )
    return phi


def soft_potential(
    traversal_per_m, goal_ij, resolution_m: float, temperature: float, iterations: int = 0, connectivity=8
):
    """(H, W) soft-min potential from the goal after ``iterations`` Jacobi steps (static),
    differentiated through every step (memory grows with ``iterations``; see
    :func:`soft_potential_implicit` for the bounded-memory gradient).

    Args:
      traversal_per_m: (H, W) finite costs per metre (:func:`smooth_traversal`).
      goal_ij: (2,) int goal cell. temperature: in cost units (> 0).
    """
    weights = soft_weights(traversal_per_m, resolution_m, connectivity)
    _, h, w_ = weights.shape
    ceiling = BLOCKED * resolution_m * (h + w_)
    return _iterate(
        weights, _goal_mask((h, w_), goal_ij), temperature, ceiling, connectivity, iterations or 2 * (h + w_)
    )


def soft_potential_implicit(weights, goal_ij, temperature: float, iterations: int, ceiling: float, connectivity=8):
    """(H, W) the soft-min potential of move weights (K, H, W) (:func:`soft_weights`) after
    ``iterations`` Jacobi steps, with the gradient of the *fixed point* by the implicit function
    theorem instead of through the steps.

    The backward pass solves the adjoint equation ``u = g + J^T u`` (``J`` the Bellman step's
    Jacobian in the potential at the fixed point, i.e. the soft-min policy's transition
    probabilities) by ``iterations`` Jacobi steps: ``u`` is the expected number of visits of each
    cell by the soft policy started from the cotangent ``g`` (a one-hot start gives MaxEnt IRL's
    expected state visitation frequencies), and the weights' cotangent is ``u(s) pi(a | s)``.
    Memory is O(K H W) whatever ``iterations`` is (the unrolled gradient of
    :func:`soft_potential` keeps every step: O(iterations K H W)). The gradient is exact when both
    recursions have converged (the forward when ``iterations`` exceeds the longest soft path's
    length; the backward when the soft policy has reached the goal).
    """
    return _implicit(weights, _goal_mask(weights.shape[1:], goal_ij), temperature, iterations, ceiling, connectivity)


@functools.partial(jax.custom_vjp, nondiff_argnums=(2, 3, 4, 5))
def _implicit(weights, is_goal, temperature, iterations, ceiling, connectivity):
    return _iterate(weights, is_goal, temperature, ceiling, connectivity, iterations)


def _implicit_fwd(weights, is_goal, temperature, iterations, ceiling, connectivity):
    phi = _iterate(weights, is_goal, temperature, ceiling, connectivity, iterations)
    return phi, (weights, is_goal, phi)


def _implicit_bwd(temperature, iterations, ceiling, connectivity, residuals, g):
    weights, is_goal, phi = residuals
    _, vjp_phi = jax.vjp(lambda p: _bellman(weights, p, is_goal, temperature, ceiling, connectivity), phi)
    u, _ = jax.lax.scan(lambda u, _: (g + vjp_phi(u)[0], None), g, None, length=iterations)
    _, vjp_w = jax.vjp(lambda w: _bellman(w, phi, is_goal, temperature, ceiling, connectivity), weights)
    return vjp_w(u)[0], None


_implicit.defvjp(_implicit_fwd, _implicit_bwd)


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
