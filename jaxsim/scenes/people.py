"""People of a scene: where each behaviour wants them, and one step of the warehouse's social force.

Walkers, stream members and queue members move by the same social force model as the warehouse
crowd (:mod:`jaxsim.social_force`: pedsim's desired, Moussaid and wall forces, the random force;
the warehouse's constants), with the robot as an agent they avoid unless ``ignore_robot``.
Standing people (and group members) stay where they stand, as the seeds' subjects did; a group
member turns to face the group's centre at its ``turn_at_s``.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct

from jaxsim import rng, social_force
from jaxsim.params import SimParams
from jaxsim.scenes.spec import KIND
from jaxsim.scenes.variant import Variant
from jaxsim.scenes.world import SceneWorld

ARRIVED_M = 0.3  # a walker within this distance of its target has arrived
STOP_RAMP_M = 0.5  # a queue member slows down over the last half metre to its place


@struct.dataclass
class PeopleState:
    """(P,) people: xy (P, 2), velocity (P, 2), heading (P,), present (P,) bool (in the scene),
    leg (P,) int32 (a back-and-forth walker: 0 towards its end, 1 back), done (P,) bool (a
    walker that has arrived for good, a stream member or queue member that has left)."""

    xy: jnp.ndarray
    velocity: jnp.ndarray
    heading: jnp.ndarray
    present: jnp.ndarray
    leg: jnp.ndarray
    done: jnp.ndarray


def init_people(v: Variant) -> PeopleState:
    present = v.valid & ((v.kind != KIND["stream"]) | (v.start_s <= 0.0))
    n = v.valid.shape[-1]
    return PeopleState(
        xy=jnp.asarray(v.xy0),
        velocity=jnp.zeros((n, 2), jnp.float32),
        heading=jnp.asarray(v.heading0),
        present=present,
        leg=jnp.zeros(n, jnp.int32),
        done=jnp.zeros(n, bool),
    )


def targets(v: Variant, s: PeopleState, time_s):
    """Where each person is going now: (target (P, 2), desired speed (P,), mobile (P,) bool)."""
    walk = v.kind == KIND["walk"]
    queue = v.kind == KIND["queue"]
    stream = v.kind == KIND["stream"]
    started = time_s >= v.start_s
    # Walkers and stream members: towards the end of their leg (or back, on a return leg).
    leg_target = jnp.where((s.leg == 1)[:, None], v.start_xy, v.end_xy)
    # Queue members: their place, moved up once per interval; past the head, the exit.
    served = jnp.floor(time_s / v.queue_interval_s).astype(jnp.int32)
    place = v.queue_place - served
    queue_target = jnp.where(
        (place >= 0)[:, None], v.queue_head + jnp.maximum(place, 0)[:, None] * v.queue_step, v.exit_xy
    )
    target = jnp.where(queue[:, None], queue_target, jnp.where((walk | stream)[:, None], leg_target, s.xy))
    distance = jnp.linalg.norm(target - s.xy, axis=-1)
    queue_speed = v.speed_mps * jnp.clip(distance / STOP_RAMP_M, 0.0, 1.0)
    speed = jnp.where(queue, jnp.where(place >= 0, queue_speed, v.speed_mps), v.speed_mps)
    mobile = s.present & ~s.done & (((walk | stream) & started) | (queue & (distance > 0.05)))
    return target, speed, mobile


def step_people(
    params: SimParams,
    world: SceneWorld,
    v: Variant,
    s: PeopleState,
    robot_xy,
    robot_velocity,
    step,
) -> PeopleState:
    """One step of ``params.dt_s``: behaviours, then the social force on the mobile people.

    Args:
      robot_xy, robot_velocity: (2,) the robot's previous position and velocity.
      step: () int32 step counter (time and the random force's stream).
    """
    dt = params.dt_s
    time_s = step.astype(jnp.float32) * dt
    target, speed, mobile = targets(v, s, time_s)
    x, y = s.xy[:, 0], s.xy[:, 1]
    vx, vy = s.velocity[:, 0], s.velocity[:, 1]
    ax, ay = social_force.desired_force(params, target[:, 0] - x, target[:, 1] - y, vx, vy, speed)
    weight = s.present.astype(jnp.float32)
    sx, sy = social_force.social_force(params, x, y, vx, vy, weight)
    # The robot as a source, felt by those who do not ignore it.
    rfx, rfy = social_force.pair_force(
        params, robot_xy[0] - x, robot_xy[1] - y, vx - robot_velocity[0], vy - robot_velocity[1]
    )
    sees_robot = (
        (~v.ignore_robot).astype(jnp.float32) * params.worker_robot_force_factor * params.worker_social_force_factor
    )
    field = world.wall_field.lookup(x, y)
    wx, wy = social_force.obstacle_force(params, field[..., 0], field[..., 1], field[..., 2])
    u = rng.hash_uniform16(v.seed_u32, step, (2, x.shape[0]))
    nx_, ny_ = social_force.random_force(params, u[0], u[1])
    ax = ax + sx + sees_robot * rfx + wx + nx_
    ay = ay + sy + sees_robot * rfy + wy + ny_
    new_v = s.velocity + dt * jnp.stack([ax, ay], axis=-1)
    norm = jnp.linalg.norm(new_v, axis=-1, keepdims=True)
    new_v = new_v * jnp.minimum(1.0, speed[:, None] / jnp.maximum(norm, 1e-9))  # pedsim's cap: the desired speed
    new_v = jnp.where(mobile[:, None], new_v, 0.0)
    xy = s.xy + dt * new_v
    # Out of the walls: push back along the normal to a body radius from the surface.
    field = world.wall_field.lookup(xy[:, 0], xy[:, 1])
    depth = jnp.maximum(params.worker_radius_m - field[..., 0], 0.0)
    xy = xy + (depth * mobile)[:, None] * field[..., 1:3]

    moving = jnp.linalg.norm(new_v, axis=-1) > 0.1
    turned = jnp.where(time_s >= v.turn_at_s, v.heading_turned, v.heading0)
    heading = jnp.where(moving, jnp.arctan2(new_v[:, 1], new_v[:, 0]), jnp.where(v.kind == 0, turned, s.heading))

    arrived = jnp.linalg.norm(target - xy, axis=-1) < ARRIVED_M
    walk = v.kind == KIND["walk"]
    stream = v.kind == KIND["stream"]
    queue = v.kind == KIND["queue"]
    place = v.queue_place - jnp.floor(time_s / v.queue_interval_s).astype(jnp.int32)
    flip = mobile & walk & arrived & v.back_and_forth
    leg = jnp.where(flip, 1 - s.leg, s.leg)
    done = s.done | (mobile & arrived & ((walk & ~v.back_and_forth) | stream | (queue & (place < 0))))
    leaves = done & (stream | queue)
    enters = v.valid & stream & (time_s + dt >= v.start_s) & ~done
    present = jnp.where(stream, enters, s.present & ~leaves)
    return PeopleState(xy=xy, velocity=new_v, heading=heading, present=present, leg=leg, done=done)


def stack_people(states: list[PeopleState]) -> PeopleState:
    return jax.tree_util.tree_map(lambda *a: jnp.stack(a), *states)
