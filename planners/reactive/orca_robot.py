"""ORCA as the robot's rule (van den Berg et al. 2011): the velocity closest to the preferred one
that keeps out of every seen person's and every wall's velocity obstacle.

The people are the seen ones, at their estimated velocities, each taking half the avoidance
(``reciprocity`` 0.5: ORCA's reciprocal assumption, as CrowdNav's and social-jym's ORCA robots
assume of everyone). Each wall box is the half-plane of its face at its nearest point to the
robot: the velocity towards it at most the gap over ``time_horizon_obst_s``, a straight wall's
truncated velocity obstacle (RVO2 builds the same from obstacle segments; as one point obstacle
a wall forbade only heading at that point, and the robot slanted into it). The walls' lines are
hard: where the people's lines cannot all hold, RVO2's third program relaxes theirs, never a
wall's. The linear programs are :mod:`jaxsim.orca`'s (the people's ORCA), so the robot and an
ORCA crowd solve the same problem.

Defaults (:class:`ORCARobotParams`) are CrowdNav's ORCA policy's (``crowd_sim/envs/policy/orca.py``):
time horizons 5 s for agents and obstacles, neighbour distance 10 m, radius the robot's plus
0.01 m. The robot is a unicycle: ORCA's velocity is tracked by turning towards it
(:func:`planners.reactive.actor.track_velocity`), as CrowdNav drives its unicycle robot.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct

from socialnav.jaxsim import orca
from socialnav.jaxsim.scenes.env import Observation
from socialnav.planners.reactive import actor as reactive


@struct.dataclass
class ORCARobotParams:
    """time_horizon_s 5, time_horizon_obst_s 5, neighbor_dist_m 10, safety_space_m 0.01 (added to
    the robot's radius), reciprocity 0.5 (the robot's share of the avoidance of a person)."""

    time_horizon_s: float = 5.0
    time_horizon_obst_s: float = 5.0
    neighbor_dist_m: float = 10.0
    safety_space_m: float = 0.01
    reciprocity: float = 0.5


def orca_robot_velocity(
    p: ORCARobotParams, xy, velocity, pref_velocity, max_speed, radius_m, people_xy, people_velocity, people_radius_m,
    people_valid, walls_m, dt_s,
):  # fmt: skip
    """(2,) the robot's ORCA velocity.

    Args:
      xy, velocity, pref_velocity (2,); max_speed, radius_m ().
      people_xy, people_velocity (P, 2); people_radius_m (); people_valid (P,) bool.
      walls_m (K, 4) wall boxes (xmin, xmax, ymin, ymax).
    """
    radius = radius_m + p.safety_space_m
    rel_pos = people_xy - xy
    near = people_valid & (jnp.linalg.norm(rel_pos, axis=-1) < p.neighbor_dist_m)
    n = people_xy.shape[0]
    u, d = jax.vmap(orca.orca_line, in_axes=(0, 0, None, None, None, None))(
        rel_pos, velocity - people_velocity, radius + people_radius_m, 1.0 / p.time_horizon_s, dt_s, p.reciprocity
    )
    # Each wall box: the half-plane of its face at the nearest point, n.v >= -(d - r) / tau (n away
    # from the wall).
    wall_point = jnp.stack(
        [jnp.clip(xy[0], walls_m[:, 0], walls_m[:, 1]), jnp.clip(xy[1], walls_m[:, 2], walls_m[:, 3])], axis=-1
    )  # (K, 2)
    away = xy - wall_point
    wall_d = jnp.linalg.norm(away, axis=-1)
    normal = away / jnp.maximum(wall_d, 1e-9)[:, None]
    wu = -normal * ((wall_d - radius) / p.time_horizon_obst_s)[:, None]  # the line's point
    wd = jnp.stack([normal[:, 1], -normal[:, 0]], axis=-1)  # allowed side on its left
    walls_near = wall_d < p.neighbor_dist_m
    points = jnp.concatenate([wu, velocity + u])
    dirs = jnp.concatenate([wd, d])
    valid = jnp.concatenate([walls_near, near])
    hard = jnp.concatenate([jnp.ones(walls_m.shape[0], bool), jnp.zeros(n, bool)])
    return orca.solve(points, dirs, valid, hard, max_speed, pref_velocity)


def command(p: ORCARobotParams, ctx: reactive.ReactiveParams, obs: Observation, carrot_xy, dt_s: float):
    """(v, omega): ORCA's velocity towards the carrot, tracked by the unicycle."""
    heading = jnp.stack([jnp.cos(obs.robot_yaw_rad), jnp.sin(obs.robot_yaw_rad)])
    velocity = obs.robot_speed_mps * heading
    pref = reactive.preferred_velocity(obs, carrot_xy, ctx)
    new_v = orca_robot_velocity(
        p, obs.robot_xy_m, velocity, pref, ctx.robot.max_speed_mps, ctx.robot.radius_m, obs.people_xy_m,
        obs.people_velocity_mps, ctx.guide.person_radius_m, obs.people_visible, ctx.guide.map.walls_m, dt_s,
    )  # fmt: skip
    return reactive.track_velocity(new_v, obs.robot_yaw_rad, ctx)
