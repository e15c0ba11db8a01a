"""The arena's robot: a unicycle with speed, turn-rate and acceleration limits and a body radius.

Commands ``(v, omega)`` come from the navigation stack passed into the episode; the base clips
them to its limits. A move that would put its body into a wall keeps only its component along
the wall and is backed out to the body's clearance (the base slides, as a bumper-guided base
would; the contact is counted), so the body never enters a wall whatever the local planner
commands.
"""

from __future__ import annotations

import jax.numpy as jnp
from flax import struct

from socialnav.jaxsim.params import TIAGO_RADIUS_M
from socialnav.jaxsim.scenes.world import SceneWorld, wall_distance


@struct.dataclass
class RobotParams:
    """Limits (dynamic floats): v_max 0.5 m/s (seed 004 used 0.8), turn rate 1.0 rad/s,
    acceleration 0.5 m/s^2 and 2 rad/s^2 (eband_local_planner's defaults), radius 0.275 m
    (the warehouse's TIAGo-like base)."""

    max_speed_mps: float = 0.5
    max_turn_rate_rps: float = 1.0
    max_accel_mps2: float = 0.5
    max_turn_accel_rps2: float = 2.0
    radius_m: float = TIAGO_RADIUS_M


@struct.dataclass
class BaseState:
    """The arena's differential-drive base (the warehouse's robot is :class:`jaxsim.state.RobotState`):
    xy (2,) m, yaw () rad, speed () m/s, turn_rate () rad/s, wall_contacts () int32."""

    xy: jnp.ndarray
    yaw: jnp.ndarray
    speed: jnp.ndarray
    turn_rate: jnp.ndarray
    wall_contacts: jnp.ndarray

    @property
    def velocity(self):
        return self.speed * jnp.stack([jnp.cos(self.yaw), jnp.sin(self.yaw)])


def init_robot(xy, yaw) -> BaseState:
    return BaseState(
        xy=jnp.asarray(xy, jnp.float32),
        yaw=jnp.asarray(yaw, jnp.float32),
        speed=jnp.float32(0.0),
        turn_rate=jnp.float32(0.0),
        wall_contacts=jnp.int32(0),
    )


def step_robot(p: RobotParams, world: SceneWorld, s: BaseState, v_cmd, omega_cmd, dt_s: float) -> BaseState:
    """Apply a command for one step: limits, then the move unless it ends in a wall."""
    v_target = jnp.clip(v_cmd, 0.0, p.max_speed_mps)
    w_target = jnp.clip(omega_cmd, -p.max_turn_rate_rps, p.max_turn_rate_rps)
    speed = s.speed + jnp.clip(v_target - s.speed, -p.max_accel_mps2 * dt_s, p.max_accel_mps2 * dt_s)
    turn = s.turn_rate + jnp.clip(w_target - s.turn_rate, -p.max_turn_accel_rps2 * dt_s, p.max_turn_accel_rps2 * dt_s)
    yaw = s.yaw + turn * dt_s
    move = speed * dt_s * jnp.stack([jnp.cos(yaw), jnp.sin(yaw)])
    now, _ = wall_distance(s.xy, world.walls_m)
    allowed = jnp.minimum(p.radius_m, now)  # never closer than the body, nor closer than now
    after, normal = wall_distance(s.xy + move, world.walls_m)
    hits = after < allowed
    slide = move - jnp.minimum(jnp.dot(move, normal), 0.0) * normal
    slid = s.xy + slide
    gap, slid_normal = wall_distance(slid, world.walls_m)
    slid = slid + jnp.maximum(allowed - gap, 0.0) * slid_normal  # back out to the allowed clearance
    still_in = wall_distance(slid, world.walls_m)[0] < allowed - 1e-4
    xy = jnp.where(hits, jnp.where(still_in, s.xy, slid), s.xy + move)
    return BaseState(
        xy=xy,
        yaw=yaw,
        speed=jnp.where(hits, jnp.linalg.norm(xy - s.xy) / dt_s, speed),
        turn_rate=turn,
        wall_contacts=s.wall_contacts + hits.astype(jnp.int32),
    )
