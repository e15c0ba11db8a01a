"""Target cost shapes of the GSCL dataset, on the grid of :mod:`models.grid`, values in [0, 1].

The paper (seed 002 Sec. 4.1) describes the shapes but not their formulas; these are this
project's rules:

* **proxemics** (one person): the ROS social_navigation_layers proxemic Gaussian (sigma 0.5 m;
  in the front half-plane stretched along the heading by ``1 + factor * speed``) combined with
  the passing layer (a Gaussian on the person's right, stretched along the motion, so that the
  robot passes on their left) into one layer by cell-wise max, as the paper does. In the
  dataset every person gets this shape at one speed, :data:`PERSON_SPEED_MPS`: the paper's input
  encodes a person's cell and heading, not their speed, so a target that depended on the speed
  could not be learnt from the input (measured: with speeds of 0-1.5 m/s the proxemics family's
  test error stalled at 0.37-0.48 of the trivial predictor's while every other family improved);
* **interaction zone** of a group: a plateau over the disc the group faces, soft-edged;
* **blind corner**: a Gaussian around the corner point on the free side, sigma 1 m (the paper's
  "at least one metre from the corner").

Costs combine by cell-wise max, as Nav2 layers do.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from socialnav.models.grid import CELL_X_M, CELL_Y_M

PROXEMIC_SIGMA_M = 0.5
FRONT_STRETCH_PER_MPS = 2.0
PASSING_AMPLITUDE = 0.6
INTERACTION_COST = 0.8
CORNER_SIGMA_M = 1.0


def _wrap(a):
    return (a + jnp.pi) % (2 * jnp.pi) - jnp.pi


def proxemic_cost(x_m, y_m, heading_rad, speed_mps, sigma_m: float = PROXEMIC_SIGMA_M):
    """(GRID, GRID) proxemic + passing cost of one person, peak 1 at the person."""
    dx, dy = CELL_X_M - x_m, CELL_Y_M - y_m
    c, s = jnp.cos(heading_rad), jnp.sin(heading_rad)
    along, left = dx * c + dy * s, -dx * s + dy * c
    stretch = 1.0 + FRONT_STRETCH_PER_MPS * speed_mps
    var_along = jnp.where(along > 0, (sigma_m * stretch) ** 2, sigma_m**2)
    body = jnp.exp(-(along**2 / (2 * var_along) + left**2 / (2 * sigma_m**2)))
    # Passing layer: the robot should keep to the person's left, so cost on their right.
    right = -left
    passing = PASSING_AMPLITUDE * jnp.exp(
        -(
            (along - 0.5 * stretch * sigma_m) ** 2 / (2 * (stretch * sigma_m) ** 2)
            + (right - 2 * sigma_m) ** 2 / (2 * sigma_m**2)
        )
    )
    passing = jnp.where((right > 0) & (speed_mps > 0), passing, 0.0)
    return jnp.maximum(body, passing)


PERSON_SPEED_MPS = 0.5  # every person's cost is drawn for this speed (front stretch 2, passing layer on)


def people_cost(x_m, y_m, heading_rad, valid, speed_mps: float = PERSON_SPEED_MPS):
    """Max of :func:`proxemic_cost` over the valid people ((P,) arrays), all at ``speed_mps``."""
    costs = jax.vmap(proxemic_cost, in_axes=(0, 0, 0, None))(x_m, y_m, heading_rad, speed_mps)  # (P, GRID, GRID)
    return jnp.max(jnp.where(valid[:, None, None], costs, 0.0), axis=0)


def disc_plateau(cx_m, cy_m, radius_m, level: float = INTERACTION_COST, edge_m: float = 0.25):
    """A soft-edged plateau of ``level`` over the disc."""
    d = jnp.sqrt((CELL_X_M - cx_m) ** 2 + (CELL_Y_M - cy_m) ** 2)
    return level / (1.0 + jnp.exp((d - radius_m) / edge_m))


def corner_cost(cx_m, cy_m, free_side, sigma_m: float = CORNER_SIGMA_M):
    """Gaussian around a corner point, on the cells where ``free_side`` (GRID, GRID) is True."""
    d2 = (CELL_X_M - cx_m) ** 2 + (CELL_Y_M - cy_m) ** 2
    return jnp.where(free_side, jnp.exp(-d2 / (2 * sigma_m**2)), 0.0)


HALLWAY_LEFT_COST = 0.6
QUEUE_U_COST = 0.7


def smoothstep(t):
    """0 below 0, 1 above 1, ``3 t^2 - 2 t^3`` between (continuous slope)."""
    t = jnp.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def soft_band(distance_m, inner_m, outer_m, level: float, edge_m: float = 0.15):
    """``level`` where ``inner <= distance <= outer``, soft-edged on both sides."""
    rise = 1.0 / (1.0 + jnp.exp(-(distance_m - inner_m) / edge_m))
    fall = 1.0 / (1.0 + jnp.exp((distance_m - outer_m) / edge_m))
    return level * rise * fall


def queue_u_cost(head_x_m, head_y_m, heading_rad, tail_m):
    """(GRID, GRID) the U around a queue whose goal is at its head: :data:`QUEUE_U_COST` along
    both sides (0.6-1.4 m from the queue's line, from the tail to 1.6 m ahead of the head) and
    across the front (1.4-2.2 m ahead), open at the tail.

    Args:
      head_x_m, head_y_m: the head's position; heading_rad: the way the queue faces (its line
        runs from the head along ``heading + pi``); tail_m: the tail's distance behind the head.
    """
    c, s = jnp.cos(heading_rad), jnp.sin(heading_rad)
    dx, dy = CELL_X_M - head_x_m, CELL_Y_M - head_y_m
    lx, ly = dx * c + dy * s, -dx * s + dy * c  # +x ahead of the head, the queue along -x
    along = soft_band(lx, -tail_m, 1.6, 1.0, edge_m=0.3)  # from the tail to the front bar
    sides = along * soft_band(jnp.abs(ly), 0.6, 1.4, QUEUE_U_COST)
    front = soft_band(jnp.abs(ly), -1.0, 1.4, 1.0) * soft_band(lx, 1.4, 2.2, QUEUE_U_COST)
    return jnp.maximum(sides, front)


def left_of_path(lx_m, ly_m, turn_at_m: float | jax.Array, turns_left):
    """Distance (m) of cells to the left of an L-shaped way, 0 on its right.

    The way runs along +x (local frame) up to ``x = turn_at_m`` and then along +y
    (``turns_left``) or along -y; ``ly_m`` is given mirrored for a right turn (so the turn is
    always towards +y, as :func:`models.families` draws the L). Before the turn the left is +y
    for a left turn and -y for a right one; after it, -x for a left turn and +x for a right one;
    round the turn's vertex on the outer side the distance is to the vertex.
    """
    a = turn_at_m
    inner = jnp.where((lx_m < a) & (ly_m > 0), jnp.minimum(ly_m, a - lx_m), 0.0)
    before = (lx_m <= a) & (ly_m < 0)
    after = (lx_m > a) & (ly_m >= 0)
    round_vertex = (lx_m > a) & (ly_m < 0)
    outer = jnp.where(
        before, -ly_m, jnp.where(after, lx_m - a, jnp.where(round_vertex, jnp.hypot(lx_m - a, ly_m), 0.0))
    )
    return jnp.where(turns_left, inner, outer)
