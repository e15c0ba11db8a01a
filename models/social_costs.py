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
  "at least one metre from the corner");
* **queue**: with the goal at the line's head, a U round the line (its sides and a bar across its
  front, open at the tail) at :data:`FORBIDDEN`, so that the robot joins at the tail.

Two ranges (this project's choice; the paper draws the U as one more graded cost): every graded
shape peaks at :data:`GRADED_TOP` (0.7), and the U is drawn at :data:`FORBIDDEN` (1). The GSCL
layer (:mod:`planners.layers.gscl_layer`) reads network costs from :data:`FORBIDDEN_FROM` (0.85, halfway)
up as lethal and scales the graded ones back to Nav2's full graded range, so the planner sees the
graded shapes as it did when they peaked at 1. Why: in closed loop a graded U, even at the top of
the graded range, is crossed by every plan, since the way round a line is metres longer than the
way through it (``scripts/gscl_queue_oracle.py``: 0 % social success with the generator's own
graded map, about 90 % with the U read as lethal). Nav2 has the same split: a keepout zone is
lethal, a social cost is graded.

Costs combine by cell-wise max, as Nav2 layers do.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from socialnav.models.grid import CELL_X_M, CELL_Y_M

GRADED_TOP = 0.7  # the peak of every graded shape (a person's own cell)
FORBIDDEN = 1.0  # the queue's U: read as lethal by the GSCL layer
FORBIDDEN_FROM = 0.5 * (GRADED_TOP + FORBIDDEN)  # network costs from here up are lethal

PROXEMIC_SIGMA_M = 0.5
FRONT_STRETCH_PER_MPS = 2.0
PASSING_AMPLITUDE = 0.6
INTERACTION_COST = 0.8 * GRADED_TOP
CORNER_SIGMA_M = 1.0


def _wrap(a):
    return (a + jnp.pi) % (2 * jnp.pi) - jnp.pi


def proxemic_cost(x_m, y_m, heading_rad, speed_mps, sigma_m: float = PROXEMIC_SIGMA_M):
    """(GRID, GRID) proxemic + passing cost of one person, peak :data:`GRADED_TOP` at the person."""
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
    return GRADED_TOP * jnp.maximum(body, passing)


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
    """Gaussian around a corner point, peak :data:`GRADED_TOP`, on the cells where ``free_side``
    (GRID, GRID) is True."""
    d2 = (CELL_X_M - cx_m) ** 2 + (CELL_Y_M - cy_m) ** 2
    return jnp.where(free_side, GRADED_TOP * jnp.exp(-d2 / (2 * sigma_m**2)), 0.0)


HALLWAY_LEFT_COST = 0.6 * GRADED_TOP
QUEUE_U_INNER_M = 0.6  # the U's sides: this far from the line's axis ...
QUEUE_U_OUTER_M = 1.4  # ... to this far
QUEUE_U_BEHIND_TAIL_M = 0.6  # the sides start this far behind the tail
QUEUE_U_FRONT_M = (1.4, 2.2)  # the bar across the front: this far ahead of the head
QUEUE_U_EDGE_M = 0.06  # the U's edges: steep, but continuous in the line's position


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
    """(GRID, GRID) the U round a queue whose goal is at its head, at :data:`FORBIDDEN`: both sides
    (:data:`QUEUE_U_INNER_M`-:data:`QUEUE_U_OUTER_M` from the line's axis, from
    :data:`QUEUE_U_BEHIND_TAIL_M` behind the tail to the front bar's far edge) and a bar across
    the front (:data:`QUEUE_U_FRONT_M` ahead of the head), open at the tail. Its edges are
    sigmoids :data:`QUEUE_U_EDGE_M` wide: at the 0.4 m cells' centres the U is 0 or 1 but for a
    cell whose centre lies within about 0.1 m of an edge.

    Args:
      head_x_m, head_y_m: the head's position; heading_rad: the way the queue faces (its line
        runs from the head along ``heading + pi``); tail_m: the tail's distance behind the head.
    """
    c, s = jnp.cos(heading_rad), jnp.sin(heading_rad)
    dx, dy = CELL_X_M - head_x_m, CELL_Y_M - head_y_m
    lx, ly = dx * c + dy * s, jnp.abs(-dx * s + dy * c)  # +x ahead of the head, the queue along -x
    near, far = QUEUE_U_FRONT_M
    e = QUEUE_U_EDGE_M
    along = soft_band(lx, -tail_m - QUEUE_U_BEHIND_TAIL_M, far, 1.0, edge_m=e)
    sides = along * soft_band(ly, QUEUE_U_INNER_M, QUEUE_U_OUTER_M, FORBIDDEN, edge_m=e)
    front = soft_band(ly, -1.0, QUEUE_U_OUTER_M, 1.0, edge_m=e) * soft_band(lx, near, far, FORBIDDEN, edge_m=e)
    return jnp.maximum(sides, front)


def drawn_line(x_m, y_m, heading_rad, valid):
    """``(head x, head y, heading, tail)`` of a queue as its input map shows it: ``x_m``, ``y_m``
    (P,) its people at their cells' centres, head first, ``heading_rad`` (P,) their drawn
    (8-direction) headings, ``valid`` (P,) (at least one). The line runs from the last valid
    person to the head; a line of one faces the head's drawn heading. Drawing the U from these and
    not from the sampled line makes the target a function of the input (the sampled line differs
    by up to a cell's half-diagonal at each end)."""
    last = jnp.max(jnp.where(valid, jnp.arange(x_m.shape[0]), 0))
    tx, ty = x_m[last], y_m[last]
    hx, hy = x_m[0], y_m[0]
    along = jnp.arctan2(hy - ty, hx - tx)
    return hx, hy, jnp.where(last > 0, along, heading_rad[0]), jnp.hypot(hx - tx, hy - ty)


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
