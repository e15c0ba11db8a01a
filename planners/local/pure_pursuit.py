"""A path follower for a unicycle: pure pursuit with a lookahead, turning on the spot first.

Chosen over a DWB-like sampler for the arena's NavFn-based methods because it adds no cost terms
of its own: what the robot does is the global plan's doing, which is what seeds 001 and 002
compare (their own local planners, ROS's default and MPPI, are not described enough to copy).
Like SNAPE's controller (seed 004 Sec. 3.3), the robot first turns towards the point it pursues,
then moves forward with a speed that falls with the heading error.
"""

from __future__ import annotations

import jax.numpy as jnp
from flax import struct

from socialnav.planners.layers.scene import wrap_angle

GOAL_SLOWDOWN_M = 0.5  # the speed falls linearly over the last half metre to the pursued point


@struct.dataclass
class PursuitParams:
    """lookahead 0.6 m; turn gain 1.5 1/s; the speed falls as cos of the heading error, and is
    zero beyond ``align_rad`` (60 deg) of it."""

    lookahead_m: float = 0.6
    turn_gain: float = 1.5
    align_rad: float = 1.0472


def lookahead_point(path_xy, path_len, robot_xy, lookahead_m):
    """The first path point at least ``lookahead_m`` from the robot, after the one nearest to it
    (the last point when none is that far). path_xy: (L, 2); path_len: () valid points."""
    index = jnp.arange(path_xy.shape[0])
    valid = index < path_len
    d = jnp.linalg.norm(path_xy - robot_xy, axis=-1)
    nearest = jnp.argmin(jnp.where(valid, d, jnp.inf))
    far = valid & (index >= nearest) & (d >= lookahead_m)
    first = jnp.argmax(far)
    last = jnp.maximum(path_len - 1, 0)
    return path_xy[jnp.where(jnp.any(far), first, last)]


def pursue(target_xy, robot_xy, robot_yaw, max_speed_mps, p: PursuitParams = PursuitParams()):
    """(v, omega) towards ``target_xy``."""
    delta = target_xy - robot_xy
    error = wrap_angle(jnp.arctan2(delta[1], delta[0]) - robot_yaw)
    v = max_speed_mps * jnp.where(jnp.abs(error) < p.align_rad, jnp.cos(error), 0.0)
    v = jnp.minimum(v, jnp.linalg.norm(delta) / GOAL_SLOWDOWN_M * max_speed_mps)  # slow down onto the goal
    return v, p.turn_gain * error
