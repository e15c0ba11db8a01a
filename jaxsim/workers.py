"""Workers: the PeopleFlow context (arrivals, destinations by time slot, activities, routes,
replanning, departures) and their social-force motion. Pure JAX over (N,) arrays.

Rules (seed 000 Sec. 4.2.3 and the issue; the parameters are in :class:`~jaxsim.params.SimParams`):

* A worker arrives at ``arrive_s`` (uniform over the first slot) at the parking lot, draws a
  destination from the current slot's probabilities and walks the humans' shortest waypoint
  route to it (``next_hop`` lookups). An intermediate waypoint counts as reached within
  ``max(radius, worker_min_reach_radius_m)``.
* At the destination the worker walks to a personal spot inside the waypoint disc and stays for
  the activity duration, uniform in ``[activity_min_s, activity_max_s]`` (toilets
  ``[toilet_activity_min_s, toilet_activity_max_s]``), then draws the next destination with the
  probabilities of the slot current at that time.
* A walker that has not got closer to its target for ``worker_stuck_time_s`` replans from the
  nearest waypoint in line of sight (a precomputed grid).
* At ``depart_s`` (during the last working slot) the worker walks back to the parking lot and
  leaves. Anyone still inside when a non-working slot starts is removed: nobody is in during
  the off slot.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import jax.scipy.special as jss

from socialnav.jaxsim import humans
from socialnav.jaxsim import social_force as sf
from socialnav.jaxsim.params import SimParams
from socialnav.jaxsim.state import ACTIVITY, LEFT, WAITING, WALKING, WorkerState
from socialnav.jaxsim.walkers import Aims, RobotDisc, Walkers
from socialnav.jaxsim.world import World, worker_params

# Share of the destination disc's radius within which a worker's activity spot is drawn.
SPOT_RADIUS_FRACTION = 0.7
# Distance to the spot under which a worker doing an activity slows down (m).
SETTLE_DISTANCE_M = 1.0
# Required gain in distance to the target to count as progress (m).
PROGRESS_M = 0.25


def draw_destination(world: World, slot: jax.Array, u: jax.Array) -> jax.Array:
    """Waypoint drawn from the slot's destination probabilities by inverse CDF (u in [0, 1))."""
    idx = jnp.searchsorted(world.destination_cdf[slot], u, side="right")
    return jnp.minimum(idx, world.n_waypoints - 1).astype(jnp.int32)


def activity_duration_s(params: SimParams, world: World, dest: jax.Array, u: jax.Array) -> jax.Array:
    """Activity duration at ``dest``: uniform, shorter for toilets."""
    lo = jnp.where(world.is_toilet[dest], params.worker_toilet_activity_min_s, params.worker_activity_min_s)
    hi = jnp.where(world.is_toilet[dest], params.worker_toilet_activity_max_s, params.worker_activity_max_s)
    return lo + u * (hi - lo)


def draw_spot(world: World, dest: jax.Array, u_radius: jax.Array, u_angle: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Offset of a point drawn uniformly in the inner part of the destination disc."""
    r = SPOT_RADIUS_FRACTION * world.waypoint_radius_m[dest] * jnp.sqrt(u_radius)
    cos, sin = sf.cos_sin_turns(u_angle)  # of the angle 2 pi u_angle, by polynomials (6e-7)
    return r * cos, r * sin


def update_context(
    params: SimParams, world: World, w: WorkerState, time_s: jax.Array, slot: jax.Array, u: jax.Array
) -> WorkerState:
    """Arrivals, departures, waypoint progress, activities and replanning for one step.

    Args:
      time_s: () current time.
      slot: () int32 current slot.
      u: (6, N) uniform draws: destination, duration, spot radius, spot angle, 2 spare.

    Returns:
      the workers with updated status, targets and destinations (positions untouched).
    """
    u_dest, u_dur, u_r, u_a = u[0], u[1], u[2], u[3]
    new_dest = draw_destination(world, slot, u_dest)
    new_dur = activity_duration_s(params, world, new_dest, u_dur)
    spot_dx, spot_dy = draw_spot(world, new_dest, u_r, u_a)
    here = world.human_waypoint_grid.lookup(w.x_m, w.y_m)
    inf = jnp.full_like(w.best_dist_m, jnp.inf)

    status, leaving = w.status, w.leaving
    target, dest = w.target_wp, w.dest_wp
    sdx, sdy = w.spot_dx_m, w.spot_dy_m
    activity_end, best, stuck = w.activity_end_s, w.best_dist_m, w.stuck_s
    next_hop = world.human_next_hop

    # Arrival at the parking lot: first destination of the day.
    arrive = (status == WAITING) & (time_s >= w.arrive_s)
    status = jnp.where(arrive, WALKING, status)
    dest = jnp.where(arrive, new_dest, dest)
    target = jnp.where(arrive, next_hop[world.parking, new_dest], target)
    sdx, sdy = jnp.where(arrive, spot_dx, sdx), jnp.where(arrive, spot_dy, sdy)
    best = jnp.where(arrive, inf, best)

    # Departure: route back to the parking lot from the nearest visible waypoint.
    present = (status == WALKING) | (status == ACTIVITY)
    depart = present & ~leaving & (time_s >= w.depart_s)
    leaving = leaving | depart
    status = jnp.where(depart, WALKING, status)
    dest = jnp.where(depart, world.parking, dest)
    target = jnp.where(depart, here, target)
    sdx, sdy = jnp.where(depart, 0.0, sdx), jnp.where(depart, 0.0, sdy)
    best = jnp.where(depart, inf, best)

    # Waypoint reached.
    dx = world.waypoint_x_m[target] - w.x_m
    dy = world.waypoint_y_m[target] - w.y_m
    dist = jnp.sqrt(dx * dx + dy * dy)
    reached = (status == WALKING) & (dist < world.reach_radius_m[target])
    at_dest = reached & (target == dest)
    via = reached & (target != dest)
    target = jnp.where(via, next_hop[target, dest], target)
    best = jnp.where(via, inf, best)
    status = jnp.where(at_dest, jnp.where(leaving, LEFT, ACTIVITY), status)
    activity_end = jnp.where(at_dest, time_s + activity_duration_s(params, world, dest, u_dur), activity_end)

    # Activity over: next destination with the current slot's probabilities.
    done = (status == ACTIVITY) & (time_s >= activity_end) & ~leaving
    same = done & (new_dest == dest)
    move = done & ~same
    activity_end = jnp.where(same, time_s + new_dur, activity_end)
    status = jnp.where(move, WALKING, status)
    target = jnp.where(move, next_hop[dest, new_dest], target)
    dest = jnp.where(move, new_dest, dest)
    sdx, sdy = jnp.where(move, spot_dx, sdx), jnp.where(move, spot_dy, sdy)
    best = jnp.where(move, inf, best)

    # Stuck: no progress towards the target for a while -> replan from the nearest visible one.
    dx = world.waypoint_x_m[target] - w.x_m
    dy = world.waypoint_y_m[target] - w.y_m
    dist = jnp.sqrt(dx * dx + dy * dy)
    walking = status == WALKING
    progress = dist < best - PROGRESS_M
    best = jnp.where(walking & progress, dist, best)
    stuck = jnp.where(walking & ~progress, stuck + params.dt_s, 0.0)
    replan = walking & (stuck > params.worker_stuck_time_s)
    onward = jnp.where(target == dest, dest, next_hop[target, dest])
    target = jnp.where(replan, jnp.where(here == target, onward, here), target)
    best = jnp.where(replan, inf, best)
    stuck = jnp.where(replan, 0.0, stuck)

    # The building closes in non-working slots.
    present = (status == WALKING) | (status == ACTIVITY)
    status = jnp.where(present & ~world.slot_working[slot], LEFT, status)

    return w.replace(
        status=status,
        leaving=leaving,
        target_wp=target.astype(jnp.int32),
        dest_wp=dest.astype(jnp.int32),
        spot_dx_m=sdx,
        spot_dy_m=sdy,
        activity_end_s=activity_end,
        best_dist_m=best,
        stuck_s=stuck,
    )


def move(
    params: SimParams,
    world: World,
    w: WorkerState,
    robot_x: jax.Array,
    robot_y: jax.Array,
    robot_vx: jax.Array,
    robot_vy: jax.Array,
    u1: jax.Array,
    u2: jax.Array,
) -> WorkerState:
    """One step of every present worker by the world's human model (``world.human_model``,
    :func:`jaxsim.humans.step_humans`, the crowd function the arena's people share; by default
    the social force, :func:`jaxsim.crowd.step_crowd`), towards the current waypoint or, at the destination,
    the worker's spot there (slowing down within ``SETTLE_DISTANCE_M``; the speed cap stays the
    worker's desired speed). The robot is an agent the workers avoid; it is not moved here.
    ``u1, u2``: (N,) uniforms for the random force."""
    present = w.present
    on_spot = w.target_wp == w.dest_wp
    aim_x = world.waypoint_x_m[w.target_wp] + jnp.where(on_spot, w.spot_dx_m, 0.0)
    aim_y = world.waypoint_y_m[w.target_wp] + jnp.where(on_spot, w.spot_dy_m, 0.0)
    dx, dy = aim_x - w.x_m, aim_y - w.y_m
    settle = jnp.minimum(1.0, jnp.sqrt(dx * dx + dy * dy) / SETTLE_DISTANCE_M)
    speed = jnp.where(w.status == ACTIVITY, w.desired_speed_mps * settle, w.desired_speed_mps)
    people = Walkers(w.x_m, w.y_m, w.vx_mps, w.vy_mps, present, present)
    aims = Aims(dx, dy, speed, w.desired_speed_mps)
    robot = RobotDisc(robot_x, robot_y, robot_vx, robot_vy, params.robot_radius_m)
    model = world.human_model
    bundle = worker_params(model, params)
    for part, fields in world.human_parts.items():  # a calibration's fit, if any (build_world checked it)
        bundle = bundle.replace(**{part: getattr(bundle, part).replace(**fields)})
    people = humans.step_humans(model, bundle, world.wall_field, people, aims, robot, (u1, u2))
    return w.replace(x_m=people.x_m, y_m=people.y_m, vx_mps=people.vx_mps, vy_mps=people.vy_mps)


def init_workers(params: SimParams, world: World, u: jax.Array) -> WorkerState:
    """Workers waiting to arrive. ``u``: (5, N) uniforms (speed, arrival, departure, spawn x, y)."""
    n = params.n_workers
    # Desired speed ~ N(mean, std) clipped, by inverse CDF of the uniform draw.
    z = jnp.sqrt(2.0) * jss.erfinv(2.0 * jnp.clip(u[0], 1e-6, 1 - 1e-6) - 1.0)
    v0 = jnp.clip(
        params.worker_desired_speed_mean_mps + params.worker_desired_speed_std_mps * z,
        params.worker_desired_speed_min_mps,
        params.worker_max_speed_mps,
    )
    slot = params.slot_length_s
    last_working = world.n_slots - 1 - jnp.argmax(world.slot_working[::-1])
    margin = jnp.minimum(params.worker_exit_margin_s, 0.5 * slot)
    arrive = u[1] * slot
    depart = last_working * slot + u[2] * (slot - margin)
    x = world.parking_x_m + (u[3] - 0.5) * params.worker_spawn_dx_m
    y = world.parking_y_m + (u[4] - 0.5) * params.worker_spawn_dy_m
    zeros = jnp.zeros(n, jnp.float32)
    park = jnp.full(n, world.parking, jnp.int32)
    return WorkerState(
        x_m=x.astype(jnp.float32),
        y_m=y.astype(jnp.float32),
        vx_mps=zeros,
        vy_mps=zeros,
        desired_speed_mps=v0.astype(jnp.float32),
        status=jnp.full(n, WAITING, jnp.int32),
        leaving=jnp.zeros(n, bool),
        target_wp=park,
        dest_wp=park,
        spot_dx_m=zeros,
        spot_dy_m=zeros,
        activity_end_s=zeros,
        arrive_s=arrive.astype(jnp.float32),
        depart_s=depart.astype(jnp.float32),
        best_dist_m=jnp.full(n, jnp.inf, jnp.float32),
        stuck_s=zeros,
    )
