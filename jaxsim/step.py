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


def _fmix32(h):
    """murmur3's 32-bit finaliser: a bijective avalanche mix of uint32 words."""
    h = h ^ (h >> 16)
    h = h * jnp.uint32(0x85EBCA6B)
    h = h ^ (h >> 13)
    h = h * jnp.uint32(0xC2B2AE35)
    return h ^ (h >> 16)


def hash_uniform16(seed_u32, step, shape):
    """Counter-based uniform draws in (0, 1), 16-bit resolution, two per 32-bit hash.

    ``u[r, i] = fmix32(fmix32(seed ^ step * K1) ^ (r * A + i) * K2)``: a stateless hash of
    (world seed, step, stream, agent), so like ``fold_in`` it does not depend on how time or
    worlds are chunked. About ten integer operations per word against threefry's hundred;
    threefry was 40% of a step. Statistical quality is ample for noise and discrete choices
    (the test checks moments and independence of neighbours); not for cryptography.

    Args:
      seed_u32: () uint32 world seed.
      step: () int32 step counter.
      shape: (R, A) draws wanted.
    """
    rows, cols = shape
    half = (rows + 1) // 2
    base = _fmix32(seed_u32 ^ (step.astype(jnp.uint32) * jnp.uint32(0x9E3779B9)))
    counter = jnp.arange(half * cols, dtype=jnp.uint32).reshape(half, cols)
    bits = _fmix32(base ^ (counter * jnp.uint32(0x632BE5AB) + jnp.uint32(0x7F4A7C15)))
    words = jnp.concatenate([bits >> 16, bits & 0xFFFF])[:rows]
    return (words.astype(jnp.float32) + 0.5) * (1.0 / 65536.0)


def world_seed_u32(key) -> jnp.ndarray:
    """A uint32 seed from a JAX key (for :func:`hash_uniform16`)."""
    return jax.random.bits(key, (), jnp.uint32)


def current_slot(params: SimParams, world: World, step):
    """Slot index of ``step`` (the last slot goes on after the day's end)."""
    return jnp.minimum(step // params.steps_per_slot, world.n_slots - 1).astype(jnp.int32)


def init_state(params: SimParams, world: World, plan: RobotPlan, key) -> SimState:
    """A world at time 0: workers waiting to arrive, the robot starting slot 0's first task."""
    kw, kr = jax.random.split(key)
    workers = workers_lib.init_workers(params, world, jax.random.uniform(kw, (5, params.n_workers)))
    robot = robot_lib.init_robot(params, world, plan, jax.random.uniform(kr, (3,)))
    return SimState(workers=workers, robot=robot, step=jnp.int32(0))


def step(params: SimParams, world: World, plan: RobotPlan, state: SimState, seed_u32) -> SimState:
    """Advance one world by one step. Workers and robot see each other's previous pose.

    ``seed_u32``: the world's uint32 seed (:func:`world_seed_u32`); the step's random draws
    are hashed from it and the step counter.
    """
    time_s = state.step.astype(jnp.float32) * params.dt_s
    slot = current_slot(params, world, state.step)
    n = params.n_workers
    u = hash_uniform16(seed_u32, state.step, (6, n + 1))
    w, r = state.workers, state.robot
    present = w.present
    w = workers_lib.update_context(params, world, w, time_s, slot, u[:, :n])
    w = workers_lib.move(params, world, w, r.x_m, r.y_m, r.speed_mps * r.heading_x,
                         r.speed_mps * r.heading_y, u[4, :n], u[5, :n])
    r = robot_lib.update_robot(params, world, plan, r, slot, state.workers.x_m, state.workers.y_m,
                               present, u[:3, n])
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
