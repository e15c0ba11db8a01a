"""Optimal reciprocal collision avoidance (ORCA, van den Berg et al. 2011) as a human model: one a
run can choose for the arena's people (``EnvConfig.human_model = "orca"``) and the warehouse's
workers (``build_world(scenario, "orca")``), as CrowdNav and social-jym offer beside the social
force (:func:`jaxsim.humans.step_humans`).

Each person takes the velocity closest to its preferred one (towards its target at its desired
speed) inside the intersection of half-planes: one per other person and one for the robot
(each side taking half the avoidance, ``u / 2``: the reciprocal assumption), one for the nearest
wall point (a static obstacle: the whole ``u``), and the disc of its maximum speed. The linear
programs are RVO2's (``linearProgram1/2/3`` of ``Agent.cpp``), written with fixed shapes: the
incremental program runs over all lines with masks, and where the constraints cannot all hold
(a dense crowd) the third program finds the velocity that violates the agents' lines least,
the wall's kept hard. As RVO2, a person feels only its ``max_neighbors`` nearest within
``neighbor_dist`` (:func:`nearest_neighbors`), so its cost does not grow with the crowd; the
third program runs only for the people whose second failed (:func:`_fallback`), so a step of N
people costs O(N^2) (the distances), not the O(N^3-N^4) of solving everything for everyone.

Defaults (:class:`ORCAParams`) are CrowdNav's and social-jym's JORCA's (time horizons 5 s,
neighbour distance 10 m, safety space 0.01 m) and RVO2's (10 neighbours), except the radius:
the toolkit's person (:data:`jaxsim.params.PERSON_RADIUS_M`, 0.25 m, as every other person of
the arena; CrowdNav's 0.3 m made two ORCA people keep 0.62 m between centres, wider than many
pairs walking side by side in ETH/UCY). Walls are also kept by the crowd's hard constraint
(:func:`jaxsim.crowd.wall_constraint`), the same as for the social force.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct

from socialnav.jaxsim.crowd import wall_constraint
from socialnav.jaxsim.grid import Grid
from socialnav.jaxsim.params import PERSON_RADIUS_M
from socialnav.jaxsim.walkers import Aims, RobotDisc, Walkers

_EPS = 1e-5
MAX_NEIGHBORS = 10  # RVO2's default maxNeighbors
FALLBACK_CHUNK = 4  # people whose third program is solved together (:func:`_fallback`)


@struct.dataclass
class ORCAParams:
    """ORCA's constants: dynamic floats (traced, fittable) radius_m (the toolkit's person, 0.25),
    time_horizon_s 5, time_horizon_obst_s 5, neighbor_dist_m 10, safety_space_m 0.01 (CrowdNav's
    ORCA policy; social-jym's JORCA); static ``max_neighbors`` 10 (RVO2's; a change recompiles)."""

    radius_m: float = PERSON_RADIUS_M
    time_horizon_s: float = 5.0
    time_horizon_obst_s: float = 5.0
    neighbor_dist_m: float = 10.0
    safety_space_m: float = 0.01
    max_neighbors: int = struct.field(pytree_node=False, default=MAX_NEIGHBORS)


def _det(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def orca_line(rel_pos, rel_vel, combined_radius, inv_horizon, dt, share):
    """RVO2's half-plane for one neighbour: ``(point (2,), direction (2,))``; the allowed side is
    to the left of ``direction`` through ``point`` (relative to this agent's velocity ``v``:
    the caller adds ``v``). ``share``: 0.5 for a reciprocating neighbour, 1 for a static one."""
    dist_sq = jnp.dot(rel_pos, rel_pos)
    r_sq = combined_radius * combined_radius
    # No collision: the velocity obstacle's cut-off circle or one of its legs.
    w = rel_vel - inv_horizon * rel_pos
    w_len_sq = jnp.dot(w, w)
    dot1 = jnp.dot(w, rel_pos)
    on_circle = (dot1 < 0.0) & (dot1 * dot1 > r_sq * w_len_sq)
    w_len = jnp.sqrt(jnp.maximum(w_len_sq, 1e-12))
    unit_w = w / w_len
    circle_dir = jnp.stack([unit_w[1], -unit_w[0]])
    circle_u = (combined_radius * inv_horizon - w_len) * unit_w
    leg = jnp.sqrt(jnp.maximum(dist_sq - r_sq, 0.0))
    x, y = rel_pos[0], rel_pos[1]
    left = _det(rel_pos, w) > 0.0
    left_dir = jnp.stack([x * leg - y * combined_radius, x * combined_radius + y * leg]) / jnp.maximum(dist_sq, 1e-12)
    right_dir = -jnp.stack([x * leg + y * combined_radius, -x * combined_radius + y * leg]) / jnp.maximum(
        dist_sq, 1e-12
    )
    leg_dir = jnp.where(left, left_dir, right_dir)
    leg_u = jnp.dot(rel_vel, leg_dir) * leg_dir - rel_vel
    free_dir = jnp.where(on_circle, circle_dir, leg_dir)
    free_u = jnp.where(on_circle, circle_u, leg_u)
    # Already overlapping: the cut-off circle of one step.
    inv_dt = 1.0 / dt
    wc = rel_vel - inv_dt * rel_pos
    wc_len = jnp.sqrt(jnp.maximum(jnp.dot(wc, wc), 1e-12))
    unit_wc = wc / wc_len
    hit_dir = jnp.stack([unit_wc[1], -unit_wc[0]])
    hit_u = (combined_radius * inv_dt - wc_len) * unit_wc
    colliding = dist_sq <= r_sq
    direction = jnp.where(colliding, hit_dir, free_dir)
    u = jnp.where(colliding, hit_u, free_u)
    return share * u, direction


def _lp1(px, py, dx, dy, valid, k, radius, ox, oy, direction_opt: bool):
    """RVO2's linearProgram1: the best point on line ``k`` under lines ``j < k`` (valid) and
    the speed disc: ``(ok, x, y)``. Lines as separate coordinate arrays (L,) each (``p`` a
    point on the line, ``d`` its direction): in this layout XLA's CPU code runs the programs
    about 1.7 times faster than on (L, 2) arrays."""
    pkx, pky, dkx, dky = px[k], py[k], dx[k], dy[k]
    dot = pkx * dkx + pky * dky
    disc = dot * dot + radius * radius - (pkx * pkx + pky * pky)
    sq = jnp.sqrt(jnp.maximum(disc, 0.0))
    t_left, t_right = -dot - sq, -dot + sq
    before = (jnp.arange(px.shape[0]) < k) & valid
    denom = dkx * dy - dky * dx  # det(d_k, d_j)
    numer = dx * (pky - py) - dy * (pkx - px)  # det(d_j, p_k - p_j)
    parallel = jnp.abs(denom) <= _EPS
    blocked = jnp.any(before & parallel & (numer < 0.0))
    t = numer / jnp.where(parallel, 1.0, denom)
    use = before & ~parallel
    t_right = jnp.minimum(t_right, jnp.min(jnp.where(use & (denom >= 0.0), t, jnp.inf)))
    t_left = jnp.maximum(t_left, jnp.max(jnp.where(use & (denom < 0.0), t, -jnp.inf)))
    ok = (disc >= 0.0) & ~blocked & (t_left <= t_right)
    if direction_opt:
        t_opt = jnp.where(ox * dkx + oy * dky > 0.0, t_right, t_left)
    else:
        t_opt = jnp.clip(dkx * (ox - pkx) + dky * (oy - pky), t_left, t_right)
    return ok, pkx + t_opt * dkx, pky + t_opt * dky


def _lp2(px, py, dx, dy, valid, radius, ox, oy, direction_opt: bool):
    """RVO2's linearProgram2 over L lines (:func:`_lp1`'s layout): ``(index of the first line
    that failed or L, x, y)``."""
    n = px.shape[0]
    if direction_opt:
        rx, ry = ox * radius, oy * radius
    else:
        norm = jnp.sqrt(ox * ox + oy * oy)
        scale = jnp.where(norm > radius, radius / jnp.maximum(norm, 1e-12), 1.0)
        rx, ry = ox * scale, oy * scale

    def body(k, carry):
        failed, rx, ry = carry
        violated = valid[k] & (dx[k] * (py[k] - ry) - dy[k] * (px[k] - rx) > 0.0) & (failed == n)
        ok, cx, cy = _lp1(px, py, dx, dy, valid, k, radius, ox, oy, direction_opt)
        failed = jnp.where(violated & ~ok, k, failed)
        take = violated & ok
        return failed, jnp.where(take, cx, rx), jnp.where(take, cy, ry)

    return jax.lax.fori_loop(0, n, body, (jnp.int32(n), rx, ry))


def _lp3(px, py, dx, dy, valid, hard, begin, radius, rx, ry):
    """RVO2's linearProgram3: from line ``begin`` on, the velocity ``(x, y)`` that violates the
    soft lines least (``hard`` lines, the walls', stay constraints), starting from ``(rx, ry)``.

    RVO2 re-solves only at the lines the current answer violates by more than the distance so
    far; the loop here jumps from one such line to the next (a ``while_loop``), so a person
    whose answer holds after two re-solves costs two second programs, not L."""
    n = px.shape[0]
    lines = jnp.arange(n)

    def next_worse(i, distance, rx, ry):
        worse = (lines >= i) & valid & ~hard & (dx * (py - ry) - dy * (px - rx) > distance)
        return jnp.where(jnp.any(worse), jnp.argmax(worse), n).astype(jnp.int32)

    def body(carry):
        i, distance, rx, ry = carry
        pix, piy, dix, diy = px[i], py[i], dx[i], dy[i]
        # The lines j < i projected onto line i's boundary (the hard ones kept as they are).
        det_ij = dix * dy - diy * dx
        parallel = jnp.abs(det_ij) <= _EPS
        same = parallel & (dix * dx + diy * dy > 0.0)
        t = (dx * (piy - py) - dy * (pix - px)) / jnp.where(parallel, 1.0, det_ij)
        qx = jnp.where(parallel, 0.5 * (pix + px), pix + t * dix)
        qy = jnp.where(parallel, 0.5 * (piy + py), piy + t * diy)
        ex, ey = dx - dix, dy - diy
        norm = jnp.maximum(jnp.sqrt(ex * ex + ey * ey), 1e-12)
        soft = (lines < i) & valid & ~hard & ~same
        failed, cx, cy = _lp2(
            jnp.where(hard, px, qx), jnp.where(hard, py, qy), jnp.where(hard, dx, ex / norm),
            jnp.where(hard, dy, ey / norm), (hard & valid) | soft, radius, -diy, dix, True,
        )  # fmt: skip
        held = failed < n  # cannot fail in principle (RVO2)
        rx, ry = jnp.where(held, rx, cx), jnp.where(held, ry, cy)
        distance = dix * (piy - ry) - diy * (pix - rx)
        return next_worse(i + 1, distance, rx, ry), distance, rx, ry

    zero = jnp.zeros((), rx.dtype)
    start = (next_worse(begin, zero, rx, ry), zero, rx, ry)
    _, _, rx, ry = jax.lax.while_loop(lambda c: c[0] < n, body, start)
    return rx, ry


def solve(points, dirs, valid, hard, max_speed, pref_velocity):
    """The velocity (2,) closest to ``pref_velocity`` inside the half-planes (L lines: ``points``
    (L, 2) and ``dirs`` (L, 2), the allowed side left of each, ``valid`` (L,) bool) and the disc
    of ``max_speed``; where they cannot all hold, the one that violates the soft lines least,
    the ``hard`` ones (L,) bool kept (RVO2's linearProgram2, then linearProgram3).

    One agent (the robot's ORCA); under ``vmap`` the ``cond`` runs both programs for everyone,
    which is why the crowd's step (:func:`step_orca`) runs the third only for those who need it."""
    line = (points[:, 0], points[:, 1], dirs[:, 0], dirs[:, 1])
    failed, rx, ry = _lp2(*line, valid, max_speed, pref_velocity[0], pref_velocity[1], False)
    n = points.shape[0]
    rx, ry = jax.lax.cond(failed < n, lambda: _lp3(*line, valid, hard, failed, max_speed, rx, ry), lambda: (rx, ry))
    return jnp.stack([rx, ry])


def nearest_neighbors(xy, eligible, k: int, max_dist_m):
    """Each person's ``k`` nearest eligible others closer than ``max_dist_m``: ``(index (N, k)
    int32, valid (N, k) bool)``.

    ``xy`` (N, 2); ``eligible`` (N, N) bool, whether j may be i's neighbour (present, not i).
    RVO2 keeps the ``maxNeighbors`` nearest within ``neighborDist``; here they are then listed by
    index (the order the lines are added in, as before the cap: the program's answer does not
    depend on it where the lines can all hold). Costs O(N^2) per world (the distances)."""
    n = xy.shape[0]
    d2 = jnp.sum((xy[:, None, :] - xy[None, :, :]) ** 2, axis=-1)
    candidate = eligible & (d2 < max_dist_m * max_dist_m)
    d2 = jnp.where(candidate, d2, jnp.inf)
    _, index = jax.lax.top_k(-d2, k)
    valid = jnp.take_along_axis(candidate, index, axis=1)
    key = jnp.sort(jnp.where(valid, index, index + n), axis=1)  # by index, the invalid last
    return (key % n).astype(jnp.int32), key < n


def _fallback(line, valid, hard, failed, max_speed, rx, ry, chunk: int):
    """RVO2's linearProgram3 for the people whose second program failed (``failed`` (N,) < L),
    ``chunk`` of them at a time; everyone else keeps ``(rx, ry)`` (N,) each. ``line``: the lines
    ``(px, py, dx, dy)``, (N, L) each (:func:`_lp1`'s layout).

    Under ``vmap`` a ``cond`` runs both branches for everyone, and the third program costs up to
    L times the second: run for all it made a crowd's step grow as N^3-N^4. Here the failing
    people are gathered to the front and solved ``chunk`` by ``chunk`` in a ``while_loop`` that
    stops after the last of them (batched over worlds, it runs as long as the world with most)."""
    n, lines = failed.shape[0], line[0].shape[1]
    needs = failed < lines
    count = jnp.sum(needs)
    order = jnp.argsort(~needs, stable=True).astype(jnp.int32)  # those who need it first
    lp3 = jax.vmap(_lp3)

    def body(carry):
        start, out_x, out_y = carry
        first = jnp.minimum(start, n - chunk)  # the last chunk overlaps the one before: same answers
        who = jax.lax.dynamic_slice(order, (first,), (chunk,))
        # From the second program's answers (``rx, ry``), never from an earlier chunk's.
        sx, sy = lp3(*(a[who] for a in line), valid[who], hard[who], failed[who], max_speed[who], rx[who], ry[who])
        use = needs[who]
        out_x = out_x.at[who].set(jnp.where(use, sx, out_x[who]))
        out_y = out_y.at[who].set(jnp.where(use, sy, out_y[who]))
        return start + chunk, out_x, out_y

    _, out_x, out_y = jax.lax.while_loop(lambda c: c[0] < count, body, (jnp.int32(0), rx, ry))
    return out_x, out_y


def step_orca(
    params: ORCAParams,
    wall_field: Grid,
    dt: float,
    people: Walkers,
    aims: Aims,
    robot: RobotDisc,
    uniforms: tuple[jax.Array, jax.Array] | None = None,
) -> Walkers:
    """One ORCA step of ``dt`` (s) for N people (the human models' signature,
    :mod:`jaxsim.walkers`; ``aims.max_speed_mps`` and ``uniforms`` are not used): each walks at
    most ``aims.speed_mps``; standing people (not ``people.moving``) are static obstacles to the
    others. Returns the people after the step.

    Each person's lines, in order: the nearest wall point (hard), its ``params.max_neighbors``
    nearest people within ``params.neighbor_dist_m`` (by index), the robot (always, within the
    neighbour distance, unless the person ``ignores_robot``: a person in a crowd does not lose
    sight of a robot). The second program runs for everyone, the third only for those whose
    second failed (:func:`_fallback`). Cost per world: O(N^2) for the neighbours plus O(N K^2)
    and O(F K^3) for the programs (K neighbours, F failing people)."""
    x, y, vx, vy = people.x_m, people.y_m, people.vx_mps, people.vy_mps
    present, moving, ignores_robot = people.present, people.moving, people.ignores_robot
    aim_dx, aim_dy, desired_speed_mps = aims.dx_m, aims.dy_m, aims.speed_mps
    n = x.shape[0]
    k = min(params.max_neighbors, n)
    xy = jnp.stack([x, y], -1)
    v = jnp.stack([vx, vy], -1)
    dist = jnp.sqrt(aim_dx * aim_dx + aim_dy * aim_dy)
    speed = jnp.minimum(desired_speed_mps, dist / dt)  # do not overshoot the target
    pref = jnp.stack([aim_dx, aim_dy], -1) * (speed / jnp.maximum(dist, 1e-9))[:, None]
    rx, ry, rvx, rvy, robot_radius_m = robot.x_m, robot.y_m, robot.vx_mps, robot.vy_mps, robot.radius_m
    ignores = jnp.zeros(n, bool) if ignores_robot is None else ignores_robot
    field = wall_field.lookup(x, y)
    wall_d, nx, ny = field[..., 0], field[..., 1], field[..., 2]
    wall_point = xy - wall_d[:, None] * jnp.stack([nx, ny], -1)
    wall_valid = wall_d < params.neighbor_dist_m
    radius = params.radius_m + params.safety_space_m

    # People: the k nearest present others within reach; standing ones are static (share 1).
    eligible = present[None, :] & ~jnp.eye(n, dtype=bool)
    index, near = nearest_neighbors(xy, eligible, k, params.neighbor_dist_m)
    share = jnp.where(moving, 0.5, 1.0)[index]
    rel_pos = xy[index] - xy[:, None]  # (N, k, 2)
    rel_vel = v[:, None] - v[index]
    lines = jax.vmap(jax.vmap(orca_line, in_axes=(0, 0, None, None, None, 0)), in_axes=(0, 0, None, None, None, 0))
    u, d = lines(rel_pos, rel_vel, radius + params.radius_m, 1.0 / params.time_horizon_s, dt, share)
    # The robot, a reciprocating neighbour, and the wall, a static point obstacle.
    robot_xy, robot_v = jnp.stack([rx, ry]), jnp.stack([rvx, rvy])
    one_line = jax.vmap(orca_line, in_axes=(0, 0, None, None, None, None))
    ru, rd = one_line(robot_xy - xy, v - robot_v, radius + robot_radius_m, 1.0 / params.time_horizon_s, dt, 0.5)
    robot_near = ~ignores & (jnp.linalg.norm(robot_xy - xy, axis=-1) < params.neighbor_dist_m)
    wu, wd = one_line(wall_point - xy, v, radius, 1.0 / params.time_horizon_obst_s, dt, 1.0)
    points = jnp.concatenate([(v + wu)[:, None], v[:, None] + u, (v + ru)[:, None]], axis=1)  # (N, k + 2, 2)
    dirs = jnp.concatenate([wd[:, None], d, rd[:, None]], axis=1)
    line = (points[..., 0], points[..., 1], dirs[..., 0], dirs[..., 1])  # (N, k + 2) each
    valid = jnp.concatenate([wall_valid[:, None], near, robot_near[:, None]], axis=1)
    hard = jnp.zeros_like(valid).at[:, 0].set(True)

    lp2 = jax.vmap(_lp2, in_axes=(0, 0, 0, 0, 0, 0, 0, 0, None))
    failed, new_vx, new_vy = lp2(*line, valid, desired_speed_mps, pref[:, 0], pref[:, 1], False)
    chunk = min(FALLBACK_CHUNK, n)
    new_vx, new_vy = _fallback(line, valid, hard, failed, desired_speed_mps, new_vx, new_vy, chunk)
    nx_, ny_, nvx, nvy = wall_constraint(wall_d, nx, ny, x + dt * new_vx, y + dt * new_vy, new_vx, new_vy, dt)
    zero = jnp.zeros_like(nvx)
    return people.moved(
        jnp.where(moving, nx_, x),
        jnp.where(moving, ny_, y),
        jnp.where(moving, nvx, zero),
        jnp.where(moving, nvy, zero),
    )
