"""The arena's robot: a unicycle with speed, turn-rate and acceleration limits and a body radius.

Commands ``(v, omega)`` come from the navigation stack passed into the episode; the base clips
them to its limits. A move that would put its body into a wall keeps only its component along
the wall and is backed out to the body's clearance (the base slides, as a bumper-guided base
would; the contact is counted), so the body never enters a wall whatever the local planner
commands, provided a step at top speed is shorter than the body's radius
(:func:`step_length_problem`, which the environment checks): the base looks at where a move
ends, not at the way there, and a longer step can end past a thin wall.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
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


def step_length_problem(p: RobotParams, dt_s: float) -> str | None:
    """Why a step of ``dt_s`` at ``p``'s top speed could carry the body through a wall, or None.

    :func:`step_robot` checks where a move ends. From a start at least one radius clear of a wall,
    a move shorter than the radius cannot end past the wall's middle, whatever its thickness, so
    the base backs out on the near side; a move of one radius can reach the far side of a wall of
    no thickness, and longer moves cross thicker walls (measured with ``step_robot``: a 0.275 m
    body driven at a long wall at 0.9, 0.95, 0.99 and 0.999 radii a step never ended past walls 0,
    0.01 or 0.2 m thick, from 47 starts and 5 headings; at one radius it crossed the wall of no
    thickness once, at 1.2 radii the 0 and 0.01 m walls, at 3 radii the 0.2 m wall too;
    ``tests/test_scene_body.py`` keeps a smaller sweep)."""
    step_m = np.asarray(p.max_speed_mps, np.float64) * dt_s
    radius_m = np.asarray(p.radius_m, np.float64)
    if np.all(step_m < radius_m):
        return None
    return (
        f"RobotParams.max_speed_mps {np.max(p.max_speed_mps):g} m/s for a step of EnvConfig.dt_s {dt_s:g} s moves "
        f"{np.max(step_m):.3g} m, not less than the robot's radius_m {np.min(p.radius_m):g} m: a step could carry "
        "the body through a wall (the base checks where a move ends, not the way there); "
        f"a top speed below {np.min(radius_m) / dt_s:.3g} m/s at this step"
    )


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
