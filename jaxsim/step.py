"""One simulation step and one measurement, pure functions of a single world.

``step(params, world, plan, state, key) -> state`` advances time by ``params.dt_s``;
``measure(params, world, state) -> Record`` computes what is logged. The rollout
(:mod:`jaxsim.rollout`) calls ``measure`` only at sampling instants, so the per-step cost is the
dynamics alone. Batching is the caller's business (``vmap`` over ``state`` and ``key``).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxsim import robot as robot_lib
from jaxsim import workers as workers_lib
from jaxsim.params import SimParams
from jaxsim.state import Record, SimState
from jaxsim.world import RobotPlan, World


def uniform16(key, shape):
    """Uniform draws in (0, 1) with 16-bit resolution, two per 32-bit random word.

    Half the threefry work of ``jax.random.uniform`` (which was 40% of a step); 16 bits
    resolve the schedule's 0.01 probabilities and give Gaussian tails to 4.7 sigma.
    """
    half = (shape[0] + 1) // 2
    bits = jax.random.bits(key, (half, *shape[1:]), jnp.uint32)
    words = jnp.concatenate([bits >> 16, bits & 0xFFFF])[: shape[0]]
    return (words.astype(jnp.float32) + 0.5) * (1.0 / 65536.0)


def current_slot(params: SimParams, world: World, step):
    """Slot index of ``step`` (the last slot goes on after the day's end)."""
    return jnp.minimum(step // params.steps_per_slot, world.n_slots - 1).astype(jnp.int32)


def init_state(params: SimParams, world: World, plan: RobotPlan, key) -> SimState:
    """A world at time 0: workers waiting to arrive, the robot starting slot 0's first task."""
    kw, kr = jax.random.split(key)
    workers = workers_lib.init_workers(params, world, jax.random.uniform(kw, (5, params.n_workers)))
    robot = robot_lib.init_robot(params, world, plan, jax.random.uniform(kr, (2,)))
    return SimState(workers=workers, robot=robot, step=jnp.int32(0))


def step(params: SimParams, world: World, plan: RobotPlan, state: SimState, key) -> SimState:
    """Advance one world by one step. Workers and robot see each other's previous pose."""
    time_s = state.step.astype(jnp.float32) * params.dt_s
    slot = current_slot(params, world, state.step)
    n = params.n_workers
    u = uniform16(key, (6, n + 1))
    w, r = state.workers, state.robot
    present = w.present
    w = workers_lib.update_context(params, world, w, time_s, slot, u[:, :n])
    w = workers_lib.move(params, world, w, r.x_m, r.y_m, r.speed_mps * r.heading_x,
                         r.speed_mps * r.heading_y, u[4, :n], u[5, :n])
    r = robot_lib.update_robot(params, world, plan, r, slot, state.workers.x_m, state.workers.y_m,
                               present, u[:2, n])
    return SimState(workers=w, robot=r, step=state.step + 1)


def measure(params: SimParams, world: World, state: SimState) -> Record:
    """The logged sample of one world: robot signals, Eq. (3) densities, robot-worker distances."""
    w, r = state.workers, state.robot
    present = w.present
    dx = w.x_m[:, None] - world.waypoint_x_m[None, :]
    dy = w.y_m[:, None] - world.waypoint_y_m[None, :]
    inside = present[:, None] & (dx * dx + dy * dy < world.waypoint_radius_m[None, :] ** 2)
    area = jnp.pi * world.waypoint_radius_m ** 2
    density = jnp.sum(inside, axis=0).astype(jnp.float32) / area
    dist = jnp.sqrt((w.x_m - r.x_m) ** 2 + (w.y_m - r.y_m) ** 2)
    return Record(
        time_s=state.step.astype(jnp.float32) * params.dt_s,
        slot=current_slot(params, world, jnp.maximum(state.step - 1, 0)),
        robot_x_m=r.x_m, robot_y_m=r.y_m, robot_speed_mps=r.speed_mps, battery_pct=r.battery_pct,
        battery_change_pct=r.battery_change_pct, charging=r.charging, obstacle=r.obstacle,
        robot_mode=r.mode, robot_waypoint=world.robot_waypoint_grid.lookup(r.x_m, r.y_m),
        goal_wp=r.goal_wp, leg_elapsed_s=r.leg_elapsed_s, tasks_started=r.tasks_started,
        tasks_succeeded=r.tasks_succeeded, tasks_failed=r.tasks_failed, stalled_s=r.stalled_s,
        n_present=jnp.sum(present).astype(jnp.int32), density_ppm2=density,
        worker_dist_m=jnp.where(present, dist, jnp.nan), worker_x_m=w.x_m, worker_y_m=w.y_m,
        worker_status=w.status)
