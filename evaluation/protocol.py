"""Seed 000's decision-making experiment (Sec. 5.2): a protocol wrapped around the simulator.

The physics is the simulator's: every step calls :func:`jaxsim.step.crowd_step` with the draws
of :func:`jaxsim.rng.step_uniforms`, exactly as the day simulation does, and moves the robot
with :func:`jaxsim.robot.drive` under the command of the method's actor (a
:class:`jaxsim.actor.Driver`, as the day simulation takes: the route follower of a plan, the
causal planner of :mod:`planners.warehouse.actors` with its Eq. 10 refusal, or a user's own);
this module adds only the protocol (tasks, deadlines, battery resets, honouring a refusal) and
its measurements. An experiment runs in the control loop the day and the arena run
(:func:`jaxsim.control.control_loop`): :func:`experiment_step` is its world's step, the method's
actor is given a :class:`ProtocolObservation` and wrapped by :func:`while_running`.

One *experiment* is one time slot played with its context frozen: the workers draw their
destinations from that slot's probabilities for as long as it takes, and the robot runs the
slot's task list once (S1-S10: 200 tasks, S11: the 90-leg cleaning tour). Task ``k`` goes from
the goal of task ``k - 1`` (the robot's start waypoint for ``k = 0``) to goal ``k``, on the
route of the method's plan. The protocol's rules:

* the battery is full when the experiment starts;
* a task that does not reach its next route waypoint within ``robot_leg_deadline_s`` (45 s) is
  a *congestion failure*: the robot is moved to the task's goal, which is the next task's start,
  so every task starts from the same place for every method. The paper says "a 45 seconds
  deadline for task completion"; the reference code (PeopleFlow's plan scripts) passes the
  threshold to every waypoint ``goto`` of the route, so it bounds each hop, and the routes of
  S1-S10 are ~19-21 m long, which at 0.5 m/s leaves no slack for a 45 s whole-task deadline.
  ``ProtocolConfig.deadline_per_hop`` (default True, the reference code) chooses;
* a battery below ``min_battery_pct`` (20 %) during a task is a *battery failure*: the task
  ends there, the robot is moved on and the battery reset to 100 %; a battery below the
  threshold at the moment a task succeeds is reset too, and the task counts as a success;
* a method that may refuse (the causal planner, Eq. 10) checks before each task whether the
  battery left after the route's predicted cost ``C_L`` would fall below the threshold; if so
  its actor answers the task's first step with ``recharge``, the battery is reset to 100 % "as
  if the robot had been at the charging station" and the task goes ahead (the refusal is
  logged);
* the experiment ends when the last task ends; the workers keep moving until every world of the
  batch is done, the finished robot stands still and is no longer measured.

Common random numbers: a world's workers draw from a hash of (world seed, step) and the
obstacle of task ``k`` from a hash of (world seed, ``k``), so two methods run with the same keys
meet the same crowds' randomness and the same obstacles on the same tasks; the planner is the
only difference (the crowds do diverge once the robots have been in different places, since
workers avoid the robot).

Before the first task the workers arrive over ``arrival_spread_s`` and walk for ``warmup_s``
while the robot waits at its start, so the first tasks meet the slot's crowd, not an empty
building (the paper's Gazebo runs started from spawned workers; it does not say how long after).

What is measured per task (:class:`TaskLog`): outcome, refusal, time, stalled time (speed 0),
distance, planned route length, battery used, and collisions, counted once per encounter: a
person whose centre comes within ``collision_radius_m`` of the robot's (default: the robot's
circumscribed radius, 0.275 m, the paper's "a worker enters the robot's circumscribed region",
with people as points as pedsim tracks them) starts an encounter, which ends when they are
``collision_release_m`` further away. Robot-person distances during tasks are histogrammed per
world for Hall's zones.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from socialnav.common import xla
from socialnav.common.pytree import select
from socialnav.evaluation.metrics import collision_encounters
from socialnav.evaluation.outcomes import BATTERY, CONGESTION, NOT_RUN, SUCCESS
from socialnav.jaxsim import control, rollout
from socialnav.jaxsim import robot as robot_lib
from socialnav.jaxsim.actor import Actor, Driver
from socialnav.jaxsim.params import TIAGO_RADIUS_M, SimParams
from socialnav.jaxsim.rng import hash_uniform16, step_uniforms, world_seed_u32
from socialnav.jaxsim.state import SimState
from socialnav.jaxsim.step import actor_keys, crowd_step, init_state
from socialnav.jaxsim.world import World
from socialnav.planners.warehouse.waypoint import MIN_BATTERY_PCT

# Stream constant that separates the per-task obstacle draws from the per-step ones.
_OBSTACLE_STREAM = np.uint32(0x5BD1E995)


@dataclasses.dataclass(frozen=True)
class ProtocolConfig:
    """The experiment's settings (static: hashable, a jit argument).

    Attributes:
      min_battery_pct: B_min, the critical battery level (Sec. 5.2: 20 %).
      reset_battery_pct: battery after a reset (100 %).
      collision_radius_m: centre distance that starts a collision encounter (default set by
        :meth:`for_params`: the robot's radius; robot + person radius counts body contact).
      collision_release_m: extra distance that ends an encounter (hysteresis).
      deadline_per_hop: the deadline bounds each route hop (reference code) rather than the
        whole task (the paper's wording).
      warmup_s: time the workers walk before the first task.
      arrival_spread_s: workers arrive uniformly over this time from the start.
      distance_bin_m, distance_bins: robot-person distance histogram (the last bin holds the rest).
    """

    min_battery_pct: float = MIN_BATTERY_PCT
    reset_battery_pct: float = 100.0
    collision_radius_m: float = TIAGO_RADIUS_M
    collision_release_m: float = 0.05
    deadline_per_hop: bool = True
    warmup_s: float = 300.0
    arrival_spread_s: float = 60.0
    distance_bin_m: float = 0.1
    distance_bins: int = 200

    def __post_init__(self) -> None:
        """Validated on construction: one ValueError naming the field."""
        checks = {
            "min_battery_pct": 0 <= self.min_battery_pct < 100,
            "reset_battery_pct": self.min_battery_pct < self.reset_battery_pct <= 100,
            "collision_radius_m": math.isfinite(self.collision_radius_m) and self.collision_radius_m > 0,
            "collision_release_m": math.isfinite(self.collision_release_m) and self.collision_release_m >= 0,
            "warmup_s": math.isfinite(self.warmup_s) and self.warmup_s >= 0,
            "arrival_spread_s": math.isfinite(self.arrival_spread_s) and self.arrival_spread_s > 0,
            "distance_bin_m": math.isfinite(self.distance_bin_m) and self.distance_bin_m > 0,
            "distance_bins": self.distance_bins >= 1,
        }
        for name, ok in checks.items():
            if not ok:
                raise ValueError(f"ProtocolConfig.{name}: invalid value {getattr(self, name)!r}")

    @classmethod
    def for_params(cls, params: SimParams, **overrides) -> ProtocolConfig:
        """Defaults with the collision radius of ``params``' robot."""
        return cls(**{"collision_radius_m": float(params.robot_radius_m), **overrides})

    def warmup_steps(self, params: SimParams) -> int:
        return int(round(self.warmup_s / params.dt_s))


@struct.dataclass
class TaskLog:
    """Per-task results of one experiment (T = the longest task list; unused entries NOT_RUN).

    Attributes:
      outcome: (T,) int32 NOT_RUN / SUCCESS / CONGESTION / BATTERY.
      refused: (T,) bool, the method refused the task and reset its battery first.
      time_s, stalled_s: (T,) task time and the part of it at speed 0.
      distance_m: (T,) distance driven.
      planned_m: (T,) length of the planned route.
      battery_used_pct: (T,) battery consumed (%).
      collisions: (T,) int32 collision encounters that started during the task.
      start_wp, goal_wp: (T,) int32.
    """

    outcome: jax.Array
    refused: jax.Array
    time_s: jax.Array
    stalled_s: jax.Array
    distance_m: jax.Array
    planned_m: jax.Array
    battery_used_pct: jax.Array
    collisions: jax.Array
    start_wp: jax.Array
    goal_wp: jax.Array


@struct.dataclass
class ExperimentState:
    """One experiment: the simulated world plus the protocol's bookkeeping.

    Attributes:
      sim: workers, robot, the actor's state, step counter.
      slot: () int32 the frozen time slot.
      task: () int32 the current task (== n_tasks when done); n_tasks: () int32.
      leg_open: () bool, the current task's leg has begun.
      leg_begun: () bool, it began at this step (:func:`begin_due_task`, before the step's
        command: a refusal counts on the task's first step).
      hop_elapsed_s: time since the robot last reached a new aim point short of the goal (a
        route waypoint), or began the task; hop_x_m, hop_y_m: that point (NaN: none yet).
      leg_stalled_s, leg_battery_used_pct, leg_collisions: accumulators of the current task.
      in_contact: (N,) bool, person in a collision encounter now.
      log: :class:`TaskLog`.
      distance_hist: (H,) int32 robot-person distances during tasks, one count per present
        person per step.
      end_step: () int32 step at which the last task ended (-1 while running).
    """

    sim: SimState
    slot: jax.Array
    task: jax.Array
    n_tasks: jax.Array
    leg_open: jax.Array
    leg_begun: jax.Array
    hop_elapsed_s: jax.Array
    hop_x_m: jax.Array
    hop_y_m: jax.Array
    leg_stalled_s: jax.Array
    leg_battery_used_pct: jax.Array
    leg_collisions: jax.Array
    in_contact: jax.Array
    log: TaskLog
    distance_hist: jax.Array
    end_step: jax.Array

    @property
    def done(self) -> jax.Array:
        return self.task >= self.n_tasks


@struct.dataclass
class ProtocolObservation:
    """What the method's actor is given at a step: ``seen``, the warehouse's observation
    (:class:`jaxsim.robot.WarehouseObservation`, the slot frozen), and ``running`` () bool, the
    experiment is past its warm-up with tasks left (the actor's state moves only then:
    :func:`while_running`)."""

    seen: robot_lib.WarehouseObservation
    running: jax.Array


def while_running(actor: Actor) -> Actor:
    """``actor`` given the warehouse's observation of a :class:`ProtocolObservation`, its state
    kept as it was on the steps its experiment is not running (the warm-up, after the last task)."""

    def init(key, observation: ProtocolObservation):
        return actor.init(key, observation.seen)

    def act(params, state, observation: ProtocolObservation, key):
        command, new = actor.act(params, state, observation.seen, key)
        return command, select(observation.running, new, state)

    return Actor(init=init, act=act, name=actor.name)


def init_experiment(
    params: SimParams, cfg: ProtocolConfig, world: World, driver: Driver, slot: jax.Array, key: jax.Array
) -> ExperimentState:
    """An experiment of ``slot`` before its warm-up: workers about to arrive, battery full (the
    first task begun already where there is no warm-up, as every step leaves the next one:
    :func:`begin_due_task`)."""
    sim = init_state(params, world, driver, jax.random.fold_in(key, rollout.INIT_FOLD))
    w = sim.workers
    w = w.replace(
        arrive_s=w.arrive_s / params.slot_length_s * cfg.arrival_spread_s, depart_s=jnp.full_like(w.depart_s, jnp.inf)
    )
    r = sim.robot.replace(battery_pct=jnp.float32(cfg.reset_battery_pct), speed_mps=jnp.float32(0.0))
    t = world.robot_goals.shape[1]
    f, i = jnp.zeros(t, jnp.float32), jnp.zeros(t, jnp.int32)
    log = TaskLog(
        outcome=jnp.full(t, NOT_RUN, jnp.int32),
        refused=jnp.zeros(t, bool),
        time_s=f,
        stalled_s=f,
        distance_m=f,
        planned_m=f,
        battery_used_pct=f,
        collisions=i,
        start_wp=i,
        goal_wp=i,
    )
    slot = jnp.asarray(slot, jnp.int32)
    xs = ExperimentState(
        sim=sim.replace(workers=w, robot=r),
        slot=slot,
        task=jnp.int32(0),
        n_tasks=world.robot_goal_count[slot],
        leg_open=jnp.bool_(False),
        leg_begun=jnp.bool_(False),
        hop_elapsed_s=jnp.float32(0.0),
        hop_x_m=jnp.float32(jnp.nan),
        hop_y_m=jnp.float32(jnp.nan),
        leg_stalled_s=jnp.float32(0.0),
        leg_battery_used_pct=jnp.float32(0.0),
        leg_collisions=jnp.int32(0),
        in_contact=jnp.zeros(params.n_workers, bool),
        log=log,
        distance_hist=jnp.zeros(cfg.distance_bins, jnp.int32),
        end_step=jnp.int32(-1),
    )
    return begin_due_task(params, cfg, world, xs, world_seed_u32(key))


def task_endpoints(world: World, slot: jax.Array, k: jax.Array) -> tuple[jax.Array, jax.Array]:
    """(start, goal) waypoints of task ``k`` of ``slot``."""
    goal = world.robot_goals[slot, k]
    start = jnp.where(k > 0, world.robot_goals[slot, jnp.maximum(k - 1, 0)], world.robot_start)
    return start.astype(jnp.int32), goal.astype(jnp.int32)


def _begin_task(params: SimParams, world: World, xs: ExperimentState, seed_u32) -> ExperimentState:
    """Start task ``xs.task``: the robot at its start, the leg with its obstacle draw (the actor
    sees the new leg at this step, plans it and may refuse it)."""
    k, slot, r = xs.task, xs.slot, xs.sim.robot
    start, goal = task_endpoints(world, slot, k)
    r = r.replace(x_m=world.waypoint_x_m[start], y_m=world.waypoint_y_m[start])
    u = hash_uniform16(seed_u32 ^ _OBSTACLE_STREAM, k, (3, 1))[:, 0]
    r = robot_lib.begin_leg(params, r, slot, start, goal, True, u)
    log = xs.log.replace(start_wp=xs.log.start_wp.at[k].set(start), goal_wp=xs.log.goal_wp.at[k].set(goal))
    return xs.replace(
        sim=xs.sim.replace(robot=r),
        log=log,
        leg_open=jnp.bool_(True),
        hop_elapsed_s=jnp.float32(0.0),
        hop_x_m=jnp.float32(jnp.nan),
        hop_y_m=jnp.float32(jnp.nan),
        leg_stalled_s=jnp.float32(0.0),
        leg_battery_used_pct=jnp.float32(0.0),
        leg_collisions=jnp.int32(0),
    )


def _running(params: SimParams, cfg: ProtocolConfig, xs: ExperimentState) -> jax.Array:
    """() bool: past the warm-up, with tasks left."""
    return (xs.sim.step >= cfg.warmup_steps(params)) & ~xs.done


def begin_due_task(
    params: SimParams, cfg: ProtocolConfig, world: World, xs: ExperimentState, seed_u32: jax.Array
) -> ExperimentState:
    """The state as its step starts: the next task begun if it is due (past the warm-up, tasks
    left, no leg open), which ``leg_begun`` records for the step."""
    begin = _running(params, cfg, xs) & ~xs.leg_open
    return select(begin, _begin_task(params, world, xs, seed_u32), xs).replace(leg_begun=begin)


def protocol_observation(params: SimParams, cfg: ProtocolConfig, xs: ExperimentState) -> ProtocolObservation:
    """What the actor sees at the step ``xs`` starts (the task begun: :func:`begin_due_task`)."""
    w = xs.sim.workers
    seen = robot_lib.observe(xs.sim.robot, xs.slot, w.x_m, w.y_m, w.present)
    return ProtocolObservation(seen=seen, running=_running(params, cfg, xs))


def experiment_step(
    params: SimParams,
    cfg: ProtocolConfig,
    world: World,
    xs: ExperimentState,
    command: robot_lib.RobotCommand,
    seed_u32: jax.Array,
) -> tuple[ExperimentState, control.Observed]:
    """Advance one experiment by one step under the method's ``command``: the simulator's crowd
    step with the slot frozen, the robot driven on the current task, the protocol's bookkeeping,
    then the next task begun if due. ``xs.sim.actor`` is carried through untouched (the control
    loop keeps the actor's state: :func:`jaxsim.control.control_loop`). Returns the state and
    the next step's observation (:func:`protocol_observation`)."""
    sim = xs.sim
    time_s = sim.step.astype(jnp.float32) * params.dt_s
    begin, running = xs.leg_begun, _running(params, cfg, xs)
    u_workers, _ = step_uniforms(seed_u32, sim.step, params.n_workers)
    w, r = sim.workers, sim.robot
    present = w.present
    # A refusal (Eq. 10) counts on the task's first step: the battery is reset before it drives.
    refuse = begin & command.recharge
    r = r.replace(battery_pct=jnp.where(refuse, jnp.float32(cfg.reset_battery_pct), r.battery_pct))
    k0 = jnp.minimum(xs.task, xs.log.outcome.shape[0] - 1)
    xs = xs.replace(
        log=xs.log.replace(
            refused=xs.log.refused.at[k0].set(jnp.where(begin, refuse, xs.log.refused[k0])),
            planned_m=xs.log.planned_m.at[k0].set(jnp.where(begin, command.planned_length_m, xs.log.planned_m[k0])),
        )
    )
    w = crowd_step(params, world, w, r, time_s, xs.slot, u_workers)
    driven, arrived = robot_lib.drive(params, world, r, command, sim.workers.x_m, sim.workers.y_m, present)
    # The hop deadline restarts when the robot reaches a new aim point short of the goal (the
    # route's next waypoint; an actor that aims where it stands gains no time by it).
    new_hop = driven.reached & ~arrived & ((command.aim_x_m != xs.hop_x_m) | (command.aim_y_m != xs.hop_y_m))
    hop_elapsed = jnp.where(new_hop, 0.0, xs.hop_elapsed_s + params.dt_s)
    hop_x = jnp.where(running & new_hop, command.aim_x_m, xs.hop_x_m)
    hop_y = jnp.where(running & new_hop, command.aim_y_m, xs.hop_y_m)
    r = select(running, driven, r)
    arrived = running & arrived
    elapsed = hop_elapsed if cfg.deadline_per_hop else r.leg_elapsed_s

    # Measurements of this step (new positions).
    present = w.present
    dist = jnp.sqrt((w.x_m - r.x_m) ** 2 + (w.y_m - r.y_m) ** 2)
    in_contact, new_encounters = collision_encounters(
        xs.in_contact, dist, present, cfg.collision_radius_m, cfg.collision_release_m
    )
    bins = jnp.clip((dist / cfg.distance_bin_m).astype(jnp.int32), 0, cfg.distance_bins - 1)
    hist = xs.distance_hist.at[bins].add((present & running).astype(jnp.int32))
    leg_collisions = xs.leg_collisions + jnp.where(running, new_encounters, 0)
    leg_stalled = xs.leg_stalled_s + jnp.where(running & (r.speed_mps <= 0), params.dt_s, 0.0)
    leg_battery = xs.leg_battery_used_pct + jnp.where(running, jnp.maximum(-r.battery_change_pct, 0.0), 0.0)

    # Task end: success, battery failure, congestion failure.
    battery_low = r.battery_pct < cfg.min_battery_pct
    battery_fail = running & ~arrived & battery_low
    congestion = running & ~arrived & ~battery_fail & (elapsed >= params.robot_leg_deadline_s)
    failed = battery_fail | congestion
    ended = arrived | failed
    outcome = jnp.where(arrived, SUCCESS, jnp.where(battery_fail, BATTERY, CONGESTION))
    k = jnp.minimum(xs.task, xs.log.outcome.shape[0] - 1)
    log = xs.log

    def put(column, value):
        return column.at[k].set(jnp.where(ended, value, column[k]))

    log = log.replace(
        outcome=put(log.outcome, outcome),
        time_s=put(log.time_s, r.leg_elapsed_s),
        stalled_s=put(log.stalled_s, leg_stalled),
        distance_m=put(log.distance_m, r.leg_dist_m),
        battery_used_pct=put(log.battery_used_pct, leg_battery),
        collisions=put(log.collisions, leg_collisions),
    )
    goal_x, goal_y = world.waypoint_x_m[r.goal_wp], world.waypoint_y_m[r.goal_wp]
    r = r.replace(
        x_m=jnp.where(failed, goal_x, r.x_m),
        y_m=jnp.where(failed, goal_y, r.y_m),
        speed_mps=jnp.where(ended, 0.0, r.speed_mps),
        battery_pct=jnp.where(ended & battery_low, jnp.float32(cfg.reset_battery_pct), r.battery_pct),
    )
    task = xs.task + ended.astype(jnp.int32)
    end_step = jnp.where(ended & (task >= xs.n_tasks), sim.step + 1, xs.end_step)
    xs = xs.replace(
        sim=sim.replace(workers=w, robot=r, step=sim.step + 1),
        task=task,
        leg_open=xs.leg_open & ~ended,
        hop_elapsed_s=jnp.where(running, hop_elapsed, xs.hop_elapsed_s),
        hop_x_m=hop_x,
        hop_y_m=hop_y,
        leg_stalled_s=leg_stalled,
        leg_battery_used_pct=leg_battery,
        leg_collisions=leg_collisions,
        in_contact=in_contact,
        log=log,
        distance_hist=hist,
        end_step=end_step,
    )
    xs = begin_due_task(params, cfg, world, xs, seed_u32)
    return xs, control.Observed(observation=protocol_observation(params, cfg, xs))


def _advance_one(params, cfg, world, driver, xs, key, n_steps):
    """``n_steps`` steps of one experiment: the control loop both worlds run, the actor's state
    kept apart from the experiment's and put back after."""
    seed = world_seed_u32(key)
    world_step = lambda s, command: experiment_step(params, cfg, world, s, command, seed)
    observe = lambda s: protocol_observation(params, cfg, s)
    keys = actor_keys(seed, xs.sim.step, n_steps)
    actor = while_running(driver.actor)
    start = xs.replace(sim=xs.sim.replace(actor=()))
    (xs, _, actor_state), _ = control.control_loop(
        world_step, actor, driver.params, start, None, xs.sim.actor, keys, observe=observe
    )
    return xs.replace(sim=xs.sim.replace(actor=actor_state))


@functools.lru_cache(maxsize=8)
def _compiled_advance(cfg: ProtocolConfig, n_steps: int, world_chunk: int, n_dev: int) -> Callable:
    def fn(params, world, driver, states, keys):
        run = functools.partial(_advance_one, params, cfg, world, driver, n_steps=n_steps)
        return rollout.map_worlds(run, (states, keys), world_chunk)

    return rollout.shard_worlds(fn, 3, 2, n_dev)


@functools.lru_cache(maxsize=8)
def _compiled_init(cfg: ProtocolConfig) -> Callable:
    init = lambda p, w, m, s, k: init_experiment(p, cfg, w, m, s, k)
    # Run once per batch and mostly random draws: compiled for speed of compiling (common.xla).
    return jax.jit(jax.vmap(init, in_axes=(None, None, None, 0, 0)), compiler_options=xla.ONCE_PER_RUN)


def experiment_keys(seed: int, slots: np.ndarray, replicas: np.ndarray) -> jax.Array:
    """Keys for (slot, replica) pairs: ``fold_in(fold_in(key(seed), replica), slot)``.

    Methods run with the same keys share their random numbers (common random numbers).
    """
    base = jax.random.key(seed)
    return jax.vmap(lambda s, r: jax.random.fold_in(jax.random.fold_in(base, r), s))(
        jnp.asarray(slots, jnp.int32), jnp.asarray(replicas, jnp.int32)
    )


def run_experiments(
    params: SimParams,
    world: World,
    driver: Driver,
    slots: np.ndarray,
    keys: jax.Array,
    cfg: ProtocolConfig | None = None,
    segment_s: float = 600.0,
    world_chunk: int = rollout.DEFAULT_WORLD_CHUNK,
    shrink_at: float = 0.5,
    progress=None,
) -> ExperimentState:
    """Run a batch of experiments until every one has ended all its tasks.

    Experiments end at different times (S11 after ~15 min, a crowded slot after hours). After
    each segment, once the unfinished ones are at most ``shrink_at`` of the batch, the finished
    ones are retired and the rest continue in a smaller batch (rounded up to a multiple of 8 per
    device, padded with copies whose results are dropped); each new size compiles once. Results
    do not depend on this: an experiment's steps are the same whichever batch it is in (to float
    rounding, see :mod:`jaxsim.rollout`).

    Args:
      driver: the method: its actor and params (replicated over the batch), e.g.
        :func:`jaxsim.route_follower.route_follower` of a plan.
      slots: (B,) slot of each experiment.
      keys: (B,) keys (:func:`experiment_keys`); the same keys for two methods = common random numbers.
      cfg: protocol settings (default :meth:`ProtocolConfig.for_params`).
      segment_s: simulated time per compiled call; between calls the host checks which
        experiments are done and updates ``progress``.
      shrink_at: share of unfinished experiments below which the batch is compacted (0: never).
      progress: optional callable ``(tasks_done, tasks_total)``.

    Returns:
      the final batched :class:`ExperimentState` (host numpy arrays), in the order of ``slots``.
    """
    cfg = ProtocolConfig.for_params(params) if cfg is None else cfg
    slots = np.asarray(slots, np.int32)
    if slots.ndim != 1 or len(slots) != keys.shape[0]:
        raise ValueError(f"need one slot per key: slots {slots.shape}, keys {keys.shape}")
    if len(slots) == 0:
        raise ValueError("no experiments to run")
    if slots.min() < 0 or slots.max() >= world.n_slots:
        raise ValueError(f"slots must be in [0, {world.n_slots - 1}], got {sorted(set(slots.tolist()))}")
    states = _compiled_init(cfg)(params, world, driver, jnp.asarray(slots), keys)
    n_tasks = np.asarray(states.n_tasks)
    n_steps = max(1, int(round(segment_s / params.dt_s)))
    # Every hop ends within the deadline, so this many segments always suffice (a route has at
    # most one hop per waypoint).
    hops = world.n_waypoints if cfg.deadline_per_hop else 1
    limit_s = cfg.warmup_s + float(n_tasks.max()) * hops * (float(params.robot_leg_deadline_s) + params.dt_s)
    return rollout.run_until_done(
        lambda n_dev: _compiled_advance(cfg, n_steps, world_chunk, n_dev),
        (params, world, driver),
        states,
        keys,
        is_done=lambda s: np.asarray(s.task) >= np.asarray(s.n_tasks),
        max_segments=int(np.ceil(limit_s / segment_s)) + 1,
        work_done=lambda s: np.asarray(s.task),
        progress=progress,
        total_work=int(n_tasks.sum()),
        shrink_at=shrink_at,
    )
