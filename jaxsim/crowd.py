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
from socialnav.jaxsim.walkers import Aims, RobotDisc, Walkers

# Minimum clearance kept from wall surfaces by the hard wall constraint (m).
WALL_CLEARANCE_M = 0.1


def step_crowd(
    params: SimParams,
    wall_field: Grid,
    dt: float,
    people: Walkers,
    aims: Aims,
    robot: RobotDisc,
    uniforms: tuple[jax.Array, jax.Array],
) -> Walkers:
    """One step of ``dt`` (s) for N people (the human models' signature, :mod:`jaxsim.walkers`).

    ``people`` are pushed by the desired force towards ``aims`` (``aims.speed_mps`` the desired
    force's speed, ``aims.max_speed_mps`` the cap on the speed after the step, pedsim's: the
    desired speed), the social force of the present others and of the robot (an agent everyone but
    ``people.ignores_robot`` avoids, its force scaled by ``worker_robot_force_factor``; its radius
    is not used), the walls and a random force from ``uniforms`` (two (N,) draws in (0, 1]). Who
    is not ``people.moving`` keeps their place with velocity 0. Returns the people after the step.
    """
    x, y, vx, vy = people.x_m, people.y_m, people.vx_mps, people.vy_mps
    present, moving, ignores_robot = people.present, people.moving, people.ignores_robot
    aim_dx, aim_dy, desired_speed_mps, max_speed_mps = aims.dx_m, aims.dy_m, aims.speed_mps, aims.max_speed_mps
    u1, u2 = uniforms
    ax, ay = sf.desired_force(params, aim_dx, aim_dy, vx, vy, desired_speed_mps)
    rx, ry, rvx, rvy = robot.x_m, robot.y_m, robot.vx_mps, robot.vy_mps
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
    return people.moved(
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
