"""The dynamic window approach (Fox, Burgard and Thrun 1997) as the robot's rule, people as
moving obstacles.

Each control step samples (v, omega) on a grid over the *dynamic window*, the velocities the base
can reach within one step from its current ones (its acceleration limits) inside its speed and
turn-rate limits; rolls each out as a constant command over ``horizon_steps`` control steps,
integrated as the base integrates (:func:`arcs`); drops the arcs on which the body comes closer
than ``margin_m`` to a wall or a seen person (the people moved on at their estimated velocities:
Fox's static obstacles made moving, as social-jym's DWA and Nav2's DWB with a people layer take
them); and takes the best of the rest by Fox's objective plus one term::

    G(v, omega) = heading_weight * heading + clearance_weight * clearance
                  + velocity_weight * velocity + distance_weight * distance

``heading`` = 1 - |angle from the heading one step ahead to the carrot| / pi (Fox's: at the pose
after the next control interval; at the arc's end a slow arc that would pass the goal scores
worse than standing still, and the base stalls short of it); ``clearance`` = the arc's smallest
body-to-obstacle gap, capped at ``clearance_cap_m`` and divided by it; ``velocity`` = v / v_max;
``distance`` = 1 - (the arc end's distance to the carrot, capped at v_max x the horizon) / that
cap, Nav2 DWB's GoalDist critic. Fox et al. weigh heading most (alpha = 2, beta = gamma = 0.2 in
the paper's experiments), the defaults here. The distance term (weight 1) is ours: with Fox's
three alone, a base limited to 1 rad/s that reaches the goal's side at full speed circles it
(measured: 1 of 8 empty ``snape_walking`` variants looped the flat and timed out), as the heading
term never asks it to slow down and turn tighter. Where no arc is free the base brakes as hard
as it can and turns towards the carrot (Nav2's rotate-in-place recovery, in one step).
"""

from __future__ import annotations

import jax.numpy as jnp
from flax import struct

from socialnav.jaxsim.scenes import world as world_lib
from socialnav.jaxsim.scenes.env import Observation
from socialnav.planners.layers.scene import wrap_angle
from socialnav.planners.reactive import actor as reactive


@struct.dataclass
class DWAParams:
    """Sampling (static ints): v_samples 3 (one control step of the base's 0.5 m/s^2 spans 0.1 m/s:
    its two ends and middle; 7 cost twice the time for the same runs), omega_samples 15,
    horizon_steps 20 (control steps:
    2 s at 0.1 s; Nav2 DWB's sim_time is 1.7 s). Dynamic floats: heading_weight 2.0,
    clearance_weight 0.2, velocity_weight 0.2 (Fox et al.), distance_weight 1.0 (ours, see the
    module), clearance_cap_m 1.0, margin_m 0.02 (an arc is free while its gap stays above this, or
    above the gap now where that is smaller: the arcs are exact, the base's step is Euler)."""

    heading_weight: float = 2.0
    clearance_weight: float = 0.2
    velocity_weight: float = 0.2
    distance_weight: float = 1.0
    clearance_cap_m: float = 1.0
    margin_m: float = 0.02
    v_samples: int = struct.field(pytree_node=False, default=3)
    omega_samples: int = struct.field(pytree_node=False, default=15)
    horizon_steps: int = struct.field(pytree_node=False, default=20)


def window(p: DWAParams, ctx: reactive.ReactiveParams, speed, turn_rate, dt_s: float):
    """The sampled dynamic window: (v (S,), omega (S,)), S = v_samples x omega_samples."""
    r = ctx.robot
    v_lo = jnp.maximum(0.0, speed - r.max_accel_mps2 * dt_s)
    v_hi = jnp.minimum(r.max_speed_mps, speed + r.max_accel_mps2 * dt_s)
    w_lo = jnp.maximum(-r.max_turn_rate_rps, turn_rate - r.max_turn_accel_rps2 * dt_s)
    w_hi = jnp.minimum(r.max_turn_rate_rps, turn_rate + r.max_turn_accel_rps2 * dt_s)
    v = v_lo + (v_hi - v_lo) * jnp.linspace(0.0, 1.0, p.v_samples)
    w = w_lo + (w_hi - w_lo) * jnp.linspace(0.0, 1.0, p.omega_samples)
    vv, ww = jnp.meshgrid(v, w, indexing="ij")
    return vv.reshape(-1), ww.reshape(-1)


def arcs(xy, yaw, v, w, dt_s: float, steps: int):
    """Poses along constant-command arcs as the base integrates them (the heading turned first,
    then the move along it: :func:`jaxsim.scenes.robot.step_robot`): (xy (S, K, 2), yaw (S, K))
    after each of K steps of ``dt_s``. Predicting with the base's own integrator, not the exact arc, keeps a
    grazing arc's prediction and the base's move the same to float rounding (the exact arc drifts
    a few millimetres per second from the Euler step, enough to touch a door's corner)."""
    k = jnp.arange(1, steps + 1, dtype=jnp.float32)
    yaw_t = yaw + w[:, None] * dt_s * k[None]  # (S, K)
    step = v[:, None, None] * dt_s * jnp.stack([jnp.cos(yaw_t), jnp.sin(yaw_t)], axis=-1)
    return xy + jnp.cumsum(step, axis=1), yaw_t


def scores(p: DWAParams, ctx: reactive.ReactiveParams, obs: Observation, carrot_xy, v, w, dt_s: float):
    """(objective (S,), free (S,) bool, heading (S,)) of the sampled commands."""
    k = p.horizon_steps
    xy, yaw = arcs(obs.robot_xy_m, obs.robot_yaw_rad, v, w, dt_s, k)
    t = dt_s * jnp.arange(1, k + 1, dtype=jnp.float32)
    gap = _gap(ctx, obs, xy, t)
    gap_now = _gap(ctx, obs, obs.robot_xy_m[None, None], jnp.zeros(1, jnp.float32))[0]
    free = gap > jnp.minimum(p.margin_m, gap_now) - 1e-4
    # Fox et al.'s heading: at the pose one control step ahead (at the arc's end a slow arc that
    # would pass the goal scores worse than standing still, and the base stalls short of it).
    to_carrot = carrot_xy - xy[:, 0]
    error = wrap_angle(jnp.arctan2(to_carrot[:, 1], to_carrot[:, 0]) - yaw[:, 0])
    heading = 1.0 - jnp.abs(error) / jnp.pi
    clearance = jnp.clip(gap, 0.0, p.clearance_cap_m) / p.clearance_cap_m
    velocity = v / jnp.maximum(ctx.robot.max_speed_mps, 1e-6)
    reach = jnp.maximum(ctx.robot.max_speed_mps * k * dt_s, 1e-6)
    distance = 1.0 - jnp.minimum(jnp.linalg.norm(carrot_xy - xy[:, -1], axis=-1), reach) / reach
    objective = (
        p.heading_weight * heading
        + p.clearance_weight * clearance
        + p.velocity_weight * velocity
        + p.distance_weight * distance
    )
    return objective, free, heading


def _gap(ctx: reactive.ReactiveParams, obs: Observation, points, t):
    """(S,) the smallest body-to-obstacle gap along each row of ``points`` (S, K, 2) at times ``t``
    (K,): the walls, and the seen people moved on at their estimated velocities."""
    to_walls = world_lib.wall_clearance(points, ctx.guide.map.walls_m, per_box=False) - ctx.robot.radius_m  # (S, K)
    people = obs.people_xy_m[None] + t[:, None, None] * obs.people_velocity_mps[None]  # (K, P, 2)
    d = jnp.linalg.norm(points[:, :, None, :] - people[None], axis=-1)
    d = d - ctx.robot.radius_m - ctx.guide.person_radius_m
    to_people = jnp.min(jnp.where(obs.people_visible[None, None], d, jnp.inf), axis=-1)  # (S, K)
    return jnp.min(jnp.minimum(to_walls, to_people), axis=-1)


def command(p: DWAParams, ctx: reactive.ReactiveParams, obs: Observation, carrot_xy, dt_s: float):
    """(v, omega): the best free arc of the dynamic window; none free: brake and turn."""
    v, w = window(p, ctx, obs.robot_speed_mps, obs.robot_turn_rate_rps, dt_s)
    objective, free, heading = scores(p, ctx, obs, carrot_xy, v, w, dt_s)
    best = jnp.argmax(jnp.where(free, objective, -jnp.inf))
    turn = jnp.argmax(heading)
    any_free = jnp.any(free)
    return jnp.where(any_free, v[best], 0.0), jnp.where(any_free, w[best], w[turn])
