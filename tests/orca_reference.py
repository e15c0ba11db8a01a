"""ORCA's crowd step as it was before issue 66 (every person against every other, both linear
programs run for everyone): the oracle the scaled step (:func:`jaxsim.orca.step_orca`) is tested
equal to, with the neighbour cap above the crowd's size. Kept verbatim, not used by the package;
the half-plane of one neighbour (``orca_line``), which the rewrite left as it was, is the
package's own."""

from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct

from socialnav.jaxsim.crowd import wall_constraint
from socialnav.jaxsim.grid import Grid
from socialnav.jaxsim.orca import _det, orca_line

_EPS = 1e-5


@struct.dataclass
class ORCAParams:
    """ORCA's constants (dynamic floats): radius_m 0.3, time_horizon_s 5, time_horizon_obst_s
    5, neighbor_dist_m 10, safety_space_m 0.01 (CrowdNav's ORCA policy; social-jym's JORCA)."""

    radius_m: float = 0.3
    time_horizon_s: float = 5.0
    time_horizon_obst_s: float = 5.0
    neighbor_dist_m: float = 10.0
    safety_space_m: float = 0.01


def _lp1(points, dirs, valid, k, radius, opt, direction_opt):
    """RVO2's linearProgram1: the best point on line ``k`` under lines ``j < k`` (valid) and
    the speed disc: ``(ok, result)``."""
    p, d = points[k], dirs[k]
    dot = jnp.dot(p, d)
    disc = dot * dot + radius * radius - jnp.dot(p, p)
    sq = jnp.sqrt(jnp.maximum(disc, 0.0))
    t_left, t_right = -dot - sq, -dot + sq
    n = points.shape[0]
    before = (jnp.arange(n) < k) & valid
    denom = _det(d[None], dirs)
    numer = _det(dirs, p[None] - points)
    parallel = jnp.abs(denom) <= _EPS
    blocked = jnp.any(before & parallel & (numer < 0.0))
    t = numer / jnp.where(parallel, 1.0, denom)
    use = before & ~parallel
    t_right = jnp.minimum(t_right, jnp.min(jnp.where(use & (denom >= 0.0), t, jnp.inf)))
    t_left = jnp.maximum(t_left, jnp.max(jnp.where(use & (denom < 0.0), t, -jnp.inf)))
    ok = (disc >= 0.0) & ~blocked & (t_left <= t_right)
    if direction_opt:
        t_opt = jnp.where(jnp.dot(opt, d) > 0.0, t_right, t_left)
    else:
        t_opt = jnp.clip(jnp.dot(d, opt - p), t_left, t_right)
    return ok, p + t_opt * d


def _lp2(points, dirs, valid, radius, opt, direction_opt):
    """RVO2's linearProgram2: ``(index of the first line that failed or n, result)``."""
    n = points.shape[0]
    if direction_opt:
        result = opt * radius
    else:
        norm = jnp.linalg.norm(opt)
        result = jnp.where(norm > radius, opt / jnp.maximum(norm, 1e-12) * radius, opt)

    def body(k, carry):
        failed, result = carry
        violated = valid[k] & (_det(dirs[k], points[k] - result) > 0.0) & (failed == n)
        ok, candidate = _lp1(points, dirs, valid, k, radius, opt, direction_opt)
        failed = jnp.where(violated & ~ok, k, failed)
        result = jnp.where(violated & ok, candidate, result)
        return failed, result

    return jax.lax.fori_loop(0, n, body, (jnp.int32(n), result))


def _lp3(points, dirs, valid, hard, begin, radius, result):
    """RVO2's linearProgram3: from line ``begin`` on, the velocity that violates the soft lines
    least (``hard`` lines, the walls', stay constraints)."""
    n = points.shape[0]

    def body(i, carry):
        distance, result = carry
        worse = (i >= begin) & valid[i] & ~hard[i] & (_det(dirs[i], points[i] - result) > distance)
        # The lines j < i projected onto line i's boundary (the hard ones kept as they are).
        det_ij = _det(dirs[i][None], dirs)
        parallel = jnp.abs(det_ij) <= _EPS
        same = parallel & (jnp.sum(dirs[i][None] * dirs, axis=-1) > 0.0)
        t = _det(dirs, points[i][None] - points) / jnp.where(parallel, 1.0, det_ij)
        proj_point = jnp.where(
            parallel[:, None], 0.5 * (points[i][None] + points), points[i][None] + t[:, None] * dirs[i][None]
        )
        proj_dir = dirs - dirs[i][None]
        proj_dir = proj_dir / jnp.maximum(jnp.linalg.norm(proj_dir, axis=-1, keepdims=True), 1e-12)
        soft = (jnp.arange(n) < i) & valid & ~hard & ~same
        lines_p = jnp.where(hard[:, None], points, proj_point)
        lines_d = jnp.where(hard[:, None], dirs, proj_dir)
        lines_v = (hard & valid) | soft
        opt = jnp.stack([-dirs[i][1], dirs[i][0]])
        failed, candidate = _lp2(lines_p, lines_d, lines_v, radius, opt, True)
        candidate = jnp.where(failed < n, result, candidate)  # cannot fail in principle (RVO2)
        result = jnp.where(worse, candidate, result)
        distance = jnp.where(worse, _det(dirs[i], points[i] - result), distance)
        return distance, result

    return jax.lax.fori_loop(0, n, body, (jnp.zeros((), result.dtype), result))[1]


def orca_velocity(
    params: ORCAParams, xy, velocity, pref_velocity, max_speed, others_xy, others_velocity, others_radius, others_valid,
    others_share, wall_point, wall_valid, dt,
):  # fmt: skip
    """One agent's ORCA velocity (2,).

    Args:
      xy, velocity, pref_velocity: (2,) this agent; max_speed: ().
      others_*: (M,) neighbours (people and the robot): positions, velocities, radii, valid,
        their share of the avoidance (0.5 reciprocal, 1 static).
      wall_point: (2,) the nearest wall point; wall_valid: () bool (within reach).
    """
    radius = params.radius_m + params.safety_space_m
    rel_pos = others_xy - xy
    near = others_valid & (jnp.linalg.norm(rel_pos, axis=-1) < params.neighbor_dist_m)
    u, d = jax.vmap(orca_line, in_axes=(0, 0, 0, None, None, 0))(
        rel_pos, velocity - others_velocity, radius + others_radius, 1.0 / params.time_horizon_s, dt, others_share
    )
    # The wall: a static point obstacle, its line first and hard.
    wu, wd = orca_line(wall_point - xy, velocity, radius, 1.0 / params.time_horizon_obst_s, dt, 1.0)
    points = jnp.concatenate([(velocity + wu)[None], velocity + u])
    dirs = jnp.concatenate([wd[None], d])
    valid = jnp.concatenate([wall_valid[None], near])
    hard = jnp.zeros_like(valid).at[0].set(True)
    return solve(points, dirs, valid, hard, max_speed, pref_velocity)


def solve(points, dirs, valid, hard, max_speed, pref_velocity):
    """The velocity (2,) closest to ``pref_velocity`` inside the half-planes (L lines: ``points``
    (L, 2) and ``dirs`` (L, 2), the allowed side left of each, ``valid`` (L,) bool) and the disc
    of ``max_speed``; where they cannot all hold, the one that violates the soft lines least,
    the ``hard`` ones (L,) bool kept (RVO2's linearProgram2, then linearProgram3)."""
    failed, result = _lp2(points, dirs, valid, max_speed, pref_velocity, False)
    n = points.shape[0]
    return jax.lax.cond(failed < n, lambda: _lp3(points, dirs, valid, hard, failed, max_speed, result), lambda: result)


def step_orca(
    params: ORCAParams,
    wall_field: Grid,
    dt: float,
    x: jax.Array,
    y: jax.Array,
    vx: jax.Array,
    vy: jax.Array,
    aim_dx: jax.Array,
    aim_dy: jax.Array,
    desired_speed_mps: jax.Array,
    present: jax.Array,
    moving: jax.Array,
    robot_xyv: tuple[jax.Array, jax.Array, jax.Array, jax.Array],
    robot_radius_m: float,
    ignores_robot: jax.Array | None = None,
):
    """One ORCA step of N people (the arguments of :func:`jaxsim.crowd.step_crowd`; standing
    people are static obstacles to the others). Returns (x, y, vx, vy)."""
    n = x.shape[0]
    xy = jnp.stack([x, y], -1)
    v = jnp.stack([vx, vy], -1)
    dist = jnp.sqrt(aim_dx * aim_dx + aim_dy * aim_dy)
    speed = jnp.minimum(desired_speed_mps, dist / dt)  # do not overshoot the target
    pref = jnp.stack([aim_dx, aim_dy], -1) * (speed / jnp.maximum(dist, 1e-9))[:, None]
    rx, ry, rvx, rvy = robot_xyv
    ignores = jnp.zeros(n, bool) if ignores_robot is None else ignores_robot
    field = wall_field.lookup(x, y)
    wall_d, nx, ny = field[..., 0], field[..., 1], field[..., 2]
    wall_point = xy - wall_d[:, None] * jnp.stack([nx, ny], -1)
    wall_valid = wall_d < params.neighbor_dist_m

    # Everyone's neighbours: the people, then the robot (the same for every agent).
    others_xy = jnp.concatenate([xy, jnp.stack([rx, ry])[None]])
    others_v = jnp.concatenate([v, jnp.stack([rvx, rvy])[None]])
    radius = jnp.concatenate([jnp.full(n, params.radius_m), jnp.full(1, robot_radius_m)])
    share = jnp.concatenate([jnp.where(moving, 0.5, 1.0), jnp.full(1, 0.5)])

    def one(i):
        me = jnp.arange(n + 1) == i
        valid = jnp.concatenate([present, ~ignores[i][None]]) & ~me
        return orca_velocity(
            params, xy[i], v[i], pref[i], desired_speed_mps[i], others_xy, others_v, radius, valid, share,
            wall_point[i], wall_valid[i], dt,
        )  # fmt: skip

    new_v = jax.vmap(one)(jnp.arange(n))
    new_xy = xy + dt * new_v
    nx_, ny_, nvx, nvy = wall_constraint(wall_d, nx, ny, new_xy[:, 0], new_xy[:, 1], new_v[:, 0], new_v[:, 1], dt)
    zero = jnp.zeros_like(nvx)
    return (
        jnp.where(moving, nx_, x),
        jnp.where(moving, ny_, y),
        jnp.where(moving, nvx, zero),
        jnp.where(moving, nvy, zero),
    )
