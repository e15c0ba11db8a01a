"""Walking groups: the group terms of Moussaïd, Perozo, Garnier, Helbing & Theraulaz (2010),
"The walking behaviour of pedestrian social groups and its impact on crowd dynamics", PLoS ONE
5(4): e10047, on top of any human model.

Moussaïd et al. add to a member ``i`` of a walking group the acceleration

  f_i = -b_gaze a_i v_i  +  q_A b_att u_i  -  sum_k q_R b_rep w_ik

- *gaze*: ``a_i`` is the angle (rad) by which ``i`` must turn its head from its walking
  direction to see the centre of mass of the other members within its vision field of half-angle
  ``phi`` (90 degrees); someone ahead of their group slows down (``v_i`` their velocity);
- *attraction*: ``u_i`` the unit vector from ``i`` to the group's centre of mass, ``q_A`` 1 when
  ``i`` is farther from it than ``(N - 1) / 2`` m (N the group's size), else 0;
- *repulsion*: ``w_ik`` the unit vector from ``i`` to member ``k``, ``q_R`` 1 when the two are
  closer than ``repulsion_distance_m``.

The paper's strengths are ``b_gaze`` 4, ``b_att`` 3, ``b_rep`` 1 (m/s^2, per radian and per
m/s for the gaze), added to its social force with relaxation time ``tau`` 0.5 s. Here every
human model receives them the same way, as a change of each member's *desired velocity*: the
velocity at which the social force's driving term ``(v0 e - v) / tau`` balances the group terms,

  w_i = (v0_i e_i + tau (q_A b_att u_i - sum_k q_R b_rep w_ik)) / (1 + tau b_gaze a_i)

(the gaze term is linear in the velocity, so it divides), the aim along ``w_i`` and the desired
speed ``|w_i|`` capped at the person's speed cap. The social force then relaxes towards the
velocity Moussaïd's force would settle at, and the first-order models (:mod:`jaxsim.speed_model`,
ORCA), which walk their target velocity at once, walk it directly (adding ``tau f`` with ``f``
at the current velocity would make them overshoot: a leader whose partner is behind would turn
back). Choices the paper leaves open, made here:
the walking direction of the gaze term is the person's aim (the desired direction, as in
pedsim and PySocialForce), and two members repel when closer than 0.6 m (their bodies, 0.25 m
each, plus a hand's breadth; the paper: "when they overlap").

Groups are given by ``group_id`` (N,) int32: people with the same non-negative id walk together,
-1 walks alone. The terms cost O(N^2) a step, as the crowd's pair terms do.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
from flax import struct

from socialnav.jaxsim.walkers import Aims, Walkers

_EPS = 1e-6
ALONE = -1


@struct.dataclass
class GroupParams:
    """Moussaïd et al. 2010's group terms (dynamic floats: traced, fittable); see the module."""

    gaze_per_rad: float = 4.0  # b_gaze: 1/s per radian of head turn (times the velocity)
    attraction_mps2: float = 3.0  # b_att
    repulsion_mps2: float = 1.0  # b_rep, per member too close
    vision_half_angle_rad: float = math.pi / 2
    repulsion_distance_m: float = 0.6
    relaxation_s: float = 0.5  # acceleration -> desired-velocity change


def same_group(group_id: jax.Array, present: jax.Array) -> jax.Array:
    """(N, N) bool: ``i`` and ``j`` (not ``i`` itself) walk in one group, both present."""
    n = group_id.shape[0]
    both = present[:, None] & present[None, :] & ~jnp.eye(n, dtype=bool)
    return (group_id[:, None] == group_id[None, :]) & (group_id[:, None] >= 0) & both


def group_terms(
    params: GroupParams,
    x: jax.Array,
    y: jax.Array,
    aim_dx: jax.Array,
    aim_dy: jax.Array,
    group_id: jax.Array,
    present: jax.Array,
) -> tuple[jax.Array, jax.Array, jax.Array, jax.Array]:
    """``(turn_rad, ax, ay, in_group)`` (N,) each: the gaze's head turn ``a_i`` (rad), the
    attraction plus repulsion (m/s^2), and whether ``i`` has a group mate present; 0 alone.

    Args:
      x, y: (N,) positions (m).
      aim_dx, aim_dy: (N,) towards each person's target (their walking direction).
      group_id: (N,) int32, -1 alone; present: (N,) bool.
    """
    w = same_group(group_id, present).astype(x.dtype)
    # one pass over the pairs: relative positions serve the centres of mass and the repulsion
    dx = x[None, :] - x[:, None]  # (N, N) from i to j
    dy = y[None, :] - y[:, None]
    d = jnp.sqrt(dx * dx + dy * dy + _EPS * _EPS)
    close = w * (d < params.repulsion_distance_m) / d
    others = jnp.sum(w, axis=1)
    to_x, to_y = jnp.sum(w * dx, axis=1), jnp.sum(w * dy, axis=1)  # sums of (x_j - x_i) over mates
    push_x, push_y = jnp.sum(close * dx, axis=1), jnp.sum(close * dy, axis=1)
    in_group = others > 0
    size = others + 1.0
    # gaze: the angle to the other members' centre of mass beyond the vision field
    ox, oy = to_x / jnp.maximum(others, 1.0), to_y / jnp.maximum(others, 1.0)
    cross, dot = aim_dx * oy - aim_dy * ox, aim_dx * ox + aim_dy * oy
    # the angle in [0, pi]; arctan2's gradient is NaN at (0, 0) (someone alone, no aim): kept off it
    alone_here = (cross == 0.0) & (dot == 0.0)
    angle = jnp.arctan2(jnp.abs(cross), jnp.where(alone_here, 1.0, dot))
    turn_rad = jnp.maximum(angle - params.vision_half_angle_rad, 0.0)
    # attraction: towards the whole group's centre of mass (i included), beyond (N - 1) / 2 m of it
    cx, cy = to_x / size, to_y / size
    c_norm = jnp.sqrt(cx * cx + cy * cy + _EPS * _EPS)
    far = (c_norm > (size - 1.0) / 2.0).astype(x.dtype)
    ax = far * params.attraction_mps2 * cx / c_norm - params.repulsion_mps2 * push_x
    ay = far * params.attraction_mps2 * cy / c_norm - params.repulsion_mps2 * push_y
    keep = in_group.astype(x.dtype)
    return keep * turn_rad, keep * ax, keep * ay, in_group


def group_aim(params: GroupParams, people: Walkers, aims: Aims, group_id: jax.Array) -> Aims:
    """``aims`` with the group terms folded into each member's desired velocity ``w_i`` (see the
    module); unchanged for someone alone. ``group_id`` (N,) int32: people walking together share a
    non-negative id (-1: alone); only ``people.present`` mates count. The new aim keeps the old
    aim's length (a target's distance, for the models that slow down near it; at least 1 m); the
    speed is capped at ``aims.max_speed_mps``."""
    x, y, present = people.x_m, people.y_m, people.present
    aim_dx, aim_dy, speed_mps, max_speed_mps = aims.dx_m, aims.dy_m, aims.speed_mps, aims.max_speed_mps
    turn, ax, ay, in_group = group_terms(params, x, y, aim_dx, aim_dy, group_id, present)
    aim_norm = jnp.sqrt(aim_dx * aim_dx + aim_dy * aim_dy + _EPS * _EPS)
    ex, ey = aim_dx / (aim_norm + _EPS), aim_dy / (aim_norm + _EPS)
    slow = 1.0 + params.relaxation_s * params.gaze_per_rad * turn
    wx = (speed_mps * ex + params.relaxation_s * ax) / slow
    wy = (speed_mps * ey + params.relaxation_s * ay) / slow
    w_norm = jnp.sqrt(wx * wx + wy * wy + _EPS * _EPS)
    scale = jnp.maximum(aim_norm, 1.0) / (w_norm + _EPS)
    new_dx = jnp.where(in_group, wx * scale, aim_dx)
    new_dy = jnp.where(in_group, wy * scale, aim_dy)
    new_speed = jnp.where(in_group, jnp.minimum(w_norm, max_speed_mps), speed_mps)
    return aims.replace(dx_m=new_dx, dy_m=new_dy, speed_mps=new_speed)
