"""The crowd's motion: one social-force step for every simulation of this toolkit.

The warehouse's workers (:mod:`jaxsim.workers`) and the arena's people
(:mod:`jaxsim.scenes.people`) decide *where* each person goes (their behaviours); this module
moves them, with one function and one set of constants (:class:`~jaxsim.params.SimParams`):

  a_i = desired + social (the people and the robot) + wall + random       (pedsim, Moussaid 2009)
  v_i <- cap(v_i + dt a_i),  x_i <- x_i + dt v_i                          (semi-implicit Euler)

then walls as a hard constraint: a person who ends a step closer than :data:`WALL_CLEARANCE_M`
to a wall surface is projected back out and loses the velocity into the wall (the wall force
alone lets a fast walker tunnel through a 0.15 m wall at 0.1 s). The distance after the move is
extrapolated from the one before along the wall's normal (exact for a straight wall; it saves a
second lookup of the distance field).

The arena's copy had drifted from the warehouse's (issue 31): it pushed people out to their body
radius by a second lookup and kept the velocity into the wall, and it added the robot's force
outside the social-force sum. It now calls this function (README, "One crowd model": what
changed in the arena's results).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from socialnav.jaxsim import social_force as sf
from socialnav.jaxsim.grid import Grid
from socialnav.jaxsim.params import SimParams

# Minimum clearance kept from wall surfaces by the hard wall constraint (m).
WALL_CLEARANCE_M = 0.1


def step_crowd(
    params: SimParams,
    wall_field: Grid,
    x: jax.Array,
    y: jax.Array,
    vx: jax.Array,
    vy: jax.Array,
    aim_dx: jax.Array,
    aim_dy: jax.Array,
    desired_speed_mps: jax.Array,
    max_speed_mps: jax.Array,
    present: jax.Array,
    moving: jax.Array,
    robot_xyv: tuple[jax.Array, jax.Array, jax.Array, jax.Array],
    u1: jax.Array,
    u2: jax.Array,
    ignores_robot: jax.Array | None = None,
) -> tuple[jax.Array, jax.Array, jax.Array, jax.Array]:
    """One step of ``params.dt_s`` for N people.

    Args:
      x, y, vx, vy: (N,) positions (m) and velocities (m/s).
      aim_dx, aim_dy: (N,) from each person to where they are going now (m).
      desired_speed_mps: (N,) the desired force's speed (a person settling on a spot slows down).
      max_speed_mps: (N,) the cap on the speed after the step (pedsim's: the desired speed).
      present: (N,) bool: in the scene (a source of social force).
      moving: (N,) bool: moved by the forces; the others keep their place with velocity 0.
      robot_xyv: () each, the robot's position and velocity: an agent everyone avoids, its
        force scaled by ``worker_robot_force_factor`` (it is not moved here).
      u1, u2: (N,) uniforms in (0, 1] for the random force.
      ignores_robot: (N,) bool, people who do not feel the robot (``None``: nobody).

    Returns:
      (x, y, vx, vy) after the step.
    """
    dt = params.dt_s
    ax, ay = sf.desired_force(params, aim_dx, aim_dy, vx, vy, desired_speed_mps)
    rx, ry, rvx, rvy = robot_xyv
    xs = jnp.concatenate([x, rx[None]])
    ys = jnp.concatenate([y, ry[None]])
    vxs = jnp.concatenate([vx, rvx[None]])
    vys = jnp.concatenate([vy, rvy[None]])
    if ignores_robot is None:  # everyone feels the robot: one agent more in the all-pairs sum
        weight = jnp.concatenate([present.astype(x.dtype), jnp.full((1,), params.worker_robot_force_factor, x.dtype)])
        sx, sy = sf.social_force(params, xs, ys, vxs, vys, weight)
        sx, sy = sx[:-1], sy[:-1]
    else:  # the people's sum without the robot, its term added for those who feel it: someone who
        # ignores the robot gets exactly the sum of a world without it (a subtraction left a 1e-7 m
        # rounding that a crowd's dynamics grew; the arena's counterfactual runs rely on this)
        weight = jnp.concatenate([present.astype(x.dtype), jnp.zeros((1,), x.dtype)])
        sx, sy = sf.social_force(params, xs, ys, vxs, vys, weight)
        fx, fy = sf.pair_force(params, rx - x, ry - y, vx - rvx, vy - rvy)
        feels = (~ignores_robot).astype(x.dtype)
        scale = feels * params.worker_robot_force_factor * params.worker_social_force_factor
        sx, sy = sx[:-1] + scale * fx, sy[:-1] + scale * fy
    ax, ay = ax + sx, ay + sy

    field = wall_field.lookup(x, y)
    wall, nx, ny = field[..., 0], field[..., 1], field[..., 2]
    ox, oy = sf.obstacle_force(params, wall, nx, ny)
    qx, qy = sf.random_force(params, u1, u2)
    ax, ay = ax + ox + qx, ay + oy + qy

    new_vx = vx + dt * ax
    new_vy = vy + dt * ay
    speed_now = jnp.sqrt(new_vx * new_vx + new_vy * new_vy)
    cap = jnp.minimum(1.0, max_speed_mps / jnp.maximum(speed_now, 1e-6))
    new_vx, new_vy = new_vx * cap, new_vy * cap
    new_x = x + dt * new_vx
    new_y = y + dt * new_vy

    new_x, new_y, new_vx, new_vy = wall_constraint(wall, nx, ny, new_x, new_y, new_vx, new_vy, dt)
    zero = jnp.zeros_like(new_vx)
    return (
        jnp.where(moving, new_x, x),
        jnp.where(moving, new_y, y),
        jnp.where(moving, new_vx, zero),
        jnp.where(moving, new_vy, zero),
    )


def wall_constraint(wall_m, nx, ny, x, y, vx, vy, dt: float):
    """Walls as a hard constraint after a move: ``(x, y, vx, vy)`` pushed back out to
    :data:`WALL_CLEARANCE_M` from the surface, the velocity into the wall removed.

    ``wall_m, nx, ny``: the distance and outward normal before the move (the distance after it is
    extrapolated along the normal to first order: exact for a straight wall, and it saves a second
    lookup); ``x, y, vx, vy``: after the move.
    """
    v_normal = vx * nx + vy * ny
    wall = wall_m + dt * v_normal
    push = jnp.maximum(WALL_CLEARANCE_M - wall, 0.0)
    x, y = x + push * nx, y + push * ny
    into = jnp.minimum(v_normal, 0.0) * (push > 0)
    return x, y, vx - into * nx, vy - into * ny
