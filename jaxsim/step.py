"""One simulation step and one measurement, pure functions of a single world.

* :func:`crowd_step` moves the workers one step given the robot's previous pose: the one crowd
  step the day simulation and every protocol (``evaluation.protocol``) call.
* :func:`env_step` is the day's transition under a command: the crowd step, then the robot
  driven by the command (:class:`jaxsim.robot.RobotCommand`); workers and robot see each other's
  previous pose. It returns the next :func:`observe` (:class:`jaxsim.robot.WarehouseObservation`,
  the robot and the workers' positions), so the day runs in the control loop both worlds share
  (:func:`jaxsim.control.control_loop`, with the robot's actor passed in as waymax passes its
  actor: :func:`jaxsim.route_follower.route_follower` follows a plan). :func:`step` is one such
  step with the actor, for code that steps a world by hand.
* :func:`measure` computes what is logged; the rollout (:mod:`jaxsim.rollout`) calls it only at
  sampling instants, so the per-step cost is the dynamics alone.

Batching is the caller's business (``vmap`` over ``state`` and the seed).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from socialnav.jaxsim import rng
from socialnav.jaxsim import robot as robot_lib
from socialnav.jaxsim import workers as workers_lib
from socialnav.jaxsim.actor import Driver
from socialnav.jaxsim.control import Observed
from socialnav.jaxsim.params import SimParams
from socialnav.jaxsim.state import Record, RobotState, SimState, WorkerState
from socialnav.jaxsim.world import World

# Stream constant of the actors' keys (apart from the uniforms of jaxsim.rng).
ACTOR_STREAM = 0x61637472


def actor_key(seed_u32: jax.Array, step: jax.Array) -> jax.Array:
    """The key the actor gets at ``step`` of the world with ``seed_u32`` (unused keys cost nothing:
    XLA drops what no actor reads)."""
    return jax.random.fold_in(jax.random.fold_in(jax.random.key(seed_u32), ACTOR_STREAM), step)


def actor_keys(seed_u32: jax.Array, first_step: jax.Array, n_steps: int) -> jax.Array:
    """(n_steps,) the actor's keys at steps ``first_step ..`` (:func:`actor_key` of each)."""
    return jax.vmap(lambda i: actor_key(seed_u32, first_step + i))(jnp.arange(n_steps, dtype=jnp.int32))


def current_slot(params: SimParams, world: World, step: jax.Array) -> jax.Array:
    """Slot index of ``step`` (the last slot goes on after the day's end)."""
    return jnp.minimum(step // params.steps_per_slot, world.n_slots - 1).astype(jnp.int32)


def init_state(params: SimParams, world: World, driver: Driver, key: jax.Array) -> SimState:
    """A world at time 0: workers waiting to arrive, the robot at its start on slot 0's first
    task, the actor's state from its ``init``."""
    kw, kr = jax.random.split(key)
    workers = workers_lib.init_workers(params, world, jax.random.uniform(kw, (5, params.n_workers)))
    robot = robot_lib.init_robot(params, world, jax.random.uniform(kr, (3,)))
    state = SimState(workers=workers, robot=robot, step=jnp.int32(0))
    actor_state = driver.actor.init(jax.random.fold_in(key, ACTOR_STREAM), observe(params, world, state))
    return state.replace(actor=actor_state)


def observe(params: SimParams, world: World, state: SimState) -> robot_lib.WarehouseObservation:
    """What the actor sees before the step ``state.step``: the robot, the slot, the workers'
    positions (those the robot's physics uses in that step)."""
    w = state.workers
    return robot_lib.observe(state.robot, current_slot(params, world, state.step), w.x_m, w.y_m, w.present)


def crowd_step(
    params: SimParams,
    world: World,
    workers: WorkerState,
    robot: RobotState,
    time_s: jax.Array,
    slot: jax.Array,
    u: jax.Array,
) -> WorkerState:
    """Advance the workers one step: their context (arrivals, routes, activities), then the
    social force with the robot as an agent they avoid.

    Args:
      workers: (N,) workers before the step.
      robot: the robot's previous pose and speed (it is not moved here).
      time_s, slot: () the clock and the slot whose destination probabilities apply.
      u: (6, N) uniforms (:func:`jaxsim.rng.step_uniforms`).
    """
    w = workers_lib.update_context(params, world, workers, time_s, slot, u)
    return workers_lib.move(
        params,
        world,
        w,
        robot.x_m,
        robot.y_m,
        robot.speed_mps * robot.heading_x,
        robot.speed_mps * robot.heading_y,
        u[4],
        u[5],
    )


def env_step(
    params: SimParams, world: World, state: SimState, command: robot_lib.RobotCommand, seed_u32: jax.Array
) -> tuple[SimState, Observed]:
    """Advance one world by one step under the robot's ``command`` (the crowd, then the robot).

    ``seed_u32``: the world's uint32 seed (:func:`jaxsim.rng.world_seed_u32`); the step's random
    draws are hashed from it and the step counter. ``state.actor`` is carried through untouched
    (the control loop keeps the actor's state apart). Returns the state after the step and its
    observation.
    """
    time_s = state.step.astype(jnp.float32) * params.dt_s
    slot = current_slot(params, world, state.step)
    u_workers, u_robot = rng.step_uniforms(seed_u32, state.step, params.n_workers)
    w, r = state.workers, state.robot
    workers = crowd_step(params, world, w, r, time_s, slot, u_workers)
    robot = robot_lib.update_robot(params, world, r, command, slot, w.x_m, w.y_m, w.present, u_robot)
    new = state.replace(workers=workers, robot=robot, step=state.step + 1)
    return new, Observed(observation=observe(params, world, new))


def step(params: SimParams, world: World, driver: Driver, state: SimState, seed_u32: jax.Array) -> SimState:
    """One step of the day by hand: the actor's command on :func:`observe`, then :func:`env_step`
    (what one turn of :func:`jaxsim.control.control_loop` in the rollout does)."""
    seen = observe(params, world, state)
    command, actor_state = driver.actor.act(driver.params, state.actor, seen, actor_key(seed_u32, state.step))
    new, _ = env_step(params, world, state, command, seed_u32)
    return new.replace(actor=actor_state)


def measure(params: SimParams, world: World, state: SimState) -> Record:
    """The logged sample of one world: robot signals, Eq. (3) densities, robot-worker distances."""
    w, r = state.workers, state.robot
    present = w.present
    dx = w.x_m[:, None] - world.waypoint_x_m[None, :]
    dy = w.y_m[:, None] - world.waypoint_y_m[None, :]
    inside = present[:, None] & (dx * dx + dy * dy < world.waypoint_radius_m[None, :] ** 2)
    area = jnp.pi * world.waypoint_radius_m**2
    density = jnp.sum(inside, axis=0).astype(jnp.float32) / area
    dist = jnp.sqrt((w.x_m - r.x_m) ** 2 + (w.y_m - r.y_m) ** 2)
    return Record(
        time_s=state.step.astype(jnp.float32) * params.dt_s,
        slot=current_slot(params, world, jnp.maximum(state.step - 1, 0)),
        robot_x_m=r.x_m,
        robot_y_m=r.y_m,
        robot_speed_mps=r.speed_mps,
        battery_pct=r.battery_pct,
        battery_change_pct=r.battery_change_pct,
        charging=r.charging,
        obstacle=r.obstacle,
        robot_mode=r.mode,
        robot_waypoint=world.robot_waypoint_grid.lookup(r.x_m, r.y_m),
        goal_wp=r.goal_wp,
        leg_elapsed_s=r.leg_elapsed_s,
        tasks_started=r.tasks_started,
        tasks_succeeded=r.tasks_succeeded,
        tasks_failed=r.tasks_failed,
        stalled_s=r.stalled_s,
        n_present=jnp.sum(present).astype(jnp.int32),
        density_ppm2=density,
        worker_dist_m=jnp.where(present, dist, jnp.nan),
        worker_x_m=w.x_m,
        worker_y_m=w.y_m,
        worker_status=w.status,
    )
