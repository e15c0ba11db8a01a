"""The robot driven by the people's own social force (a social-force robot, as CrowdNav's SF
baseline, social-jym's and HuNavSim's): towards the carrot at its speed limit, pushed by every
seen person and by the nearest wall with the same forces and constants that move the crowd.

One step (``dt_s``), with the crowd's :class:`~jaxsim.params.SimParams` (pedsim's desired force,
Moussaid et al. 2009's interaction, pedsim's wall force; :mod:`jaxsim.social_force`)::

    a = (v0 e_carrot - v) / tau + factor * sum_seen F_moussaid(person -> robot) + F_wall
    v' = cap(v + dt a, v_max)

and the base turns towards ``v'`` (:func:`planners.reactive.actor.track_velocity`). Differences from a
person's step, each a choice: the people enter at their *estimated* velocities and only when
seen (the robot has no simulator truth); no random force (the robot is deterministic); the wall
force acts from the robot's body radius instead of a person's. The exact walls (boxes) give the
wall distance, not the crowd's 0.05 m field.
"""

from __future__ import annotations

import jax.numpy as jnp
from flax import struct

from socialnav.jaxsim import social_force as sf
from socialnav.jaxsim.params import SimParams
from socialnav.jaxsim.scenes.env import Observation
from socialnav.jaxsim.scenes.world import wall_distance
from socialnav.planners.reactive import actor as reactive


@struct.dataclass
class SocialForceRobotParams:
    """crowd: the people's social-force constants (the env's ``crowd``; the robot's wall force
    uses its own radius in place of ``worker_radius_m``)."""

    crowd: SimParams


def social_acceleration(crowd: SimParams, xy, velocity, people_xy, people_velocity, people_valid):
    """(2,) m/s^2: the Moussaid interaction of the valid people on an agent at ``xy`` moving at
    ``velocity`` (2,), scaled by ``worker_social_force_factor`` (people (P, 2); valid (P,))."""
    fx, fy = sf.pair_force(
        crowd,
        people_xy[:, 0] - xy[0],
        people_xy[:, 1] - xy[1],
        velocity[0] - people_velocity[:, 0],
        velocity[1] - people_velocity[:, 1],
    )
    w = people_valid.astype(xy.dtype) * crowd.worker_social_force_factor
    return jnp.stack([jnp.sum(w * fx), jnp.sum(w * fy)])


def command(p: SocialForceRobotParams, ctx: reactive.ReactiveParams, obs: Observation, carrot_xy, dt_s: float):
    """(v, omega): one social-force step towards the carrot, tracked by the unicycle."""
    crowd = p.crowd
    heading = jnp.stack([jnp.cos(obs.robot_yaw_rad), jnp.sin(obs.robot_yaw_rad)])
    velocity = obs.robot_speed_mps * heading
    pref = reactive.preferred_velocity(obs, carrot_xy, ctx)
    desired = (pref - velocity) / crowd.worker_relaxation_time_s
    social = social_acceleration(
        crowd, obs.robot_xy_m, velocity, obs.people_xy_m, obs.people_velocity_mps, obs.people_visible
    )
    gap, normal = wall_distance(obs.robot_xy_m, ctx.guide.map.walls_m)
    wx, wy = sf.obstacle_force(crowd.replace(worker_radius_m=ctx.robot.radius_m), gap, normal[0], normal[1])
    new_v = velocity + dt_s * (desired + social + jnp.stack([wx, wy]))
    speed = jnp.linalg.norm(new_v)
    new_v = new_v * jnp.minimum(1.0, ctx.robot.max_speed_mps / jnp.maximum(speed, 1e-6))
    return reactive.track_velocity(new_v, obs.robot_yaw_rad, ctx)
