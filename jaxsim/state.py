"""Dynamic state of one simulated world: fixed shapes, absent agents masked (not removed).

Batching adds leading axes to every leaf; nothing here knows about batches.
"""

from __future__ import annotations

from typing import Any

import jax
from flax import struct

# Worker status codes.
WAITING, WALKING, ACTIVITY, LEFT = 0, 1, 2, 3
# Robot mode codes.
TASK, TO_CHARGER, CHARGING = 0, 1, 2


@struct.dataclass
class WorkerState:
    """N workers; x and y are separate arrays (10x faster pairwise forces than (N, 2)).

    Attributes:
      x_m, y_m, vx_mps, vy_mps: (N,) position and velocity.
      desired_speed_mps: (N,) pedsim's v0, drawn once per worker.
      status: (N,) int32 WAITING / WALKING / ACTIVITY / LEFT.
      leaving: (N,) bool, heading out for the day.
      target_wp: (N,) int32 waypoint walked to now.
      dest_wp: (N,) int32 destination (activity station).
      spot_dx_m, spot_dy_m: (N,) where in the destination disc the worker stands.
      activity_end_s, arrive_s, depart_s: (N,) times.
      best_dist_m: (N,) closest distance to ``target_wp`` so far (stuck detection).
      stuck_s: (N,) time without progress towards ``target_wp``.
    """

    x_m: jax.Array
    y_m: jax.Array
    vx_mps: jax.Array
    vy_mps: jax.Array
    desired_speed_mps: jax.Array
    status: jax.Array
    leaving: jax.Array
    target_wp: jax.Array
    dest_wp: jax.Array
    spot_dx_m: jax.Array
    spot_dy_m: jax.Array
    activity_end_s: jax.Array
    arrive_s: jax.Array
    depart_s: jax.Array
    best_dist_m: jax.Array
    stuck_s: jax.Array

    @property
    def present(self) -> jax.Array:
        """(N,) bool, inside the simulated area (arrived and not left)."""
        return (self.status == WALKING) | (self.status == ACTIVITY)


@struct.dataclass
class RobotState:
    """The robot's body and its working day (all scalars); how it gets there is its actor's
    (:mod:`jaxsim.actor`).

    Attributes:
      x_m, y_m, heading_x, heading_y: pose (unit heading).
      speed_mps: V.
      battery_pct: B in [0, 100].
      battery_change_pct: L of the last step (Eq. 1).
      mode: TASK / TO_CHARGER / CHARGING.
      charging: C.
      obstacle: O, maneuvering around a static obstacle now.
      reached: the point the actor aimed at was reached in the last step (within
        ``robot_goal_tolerance_m``).
      leg_start_wp, goal_wp: the current leg's start and goal; ``leg_slot`` the slot when it
        began (whose routes apply); ``legs_started`` counts legs (an actor sees a new leg by it).
      task_idx, task_slot: position in the slot's goal list, and the slot it belongs to.
      leg_elapsed_s, leg_dist_m: time and distance on the current leg.
      obstacle_at_share: where on the planned path the obstacle is met, as a share of the
        path's length (the actor's ``planned_length_m``); inf: none on this leg.
      obstacle_left_m: maneuver distance still to go once met.
      obstacle_speed_factor: share of the speed kept while maneuvering around this leg's obstacle.
      tasks_started, tasks_succeeded, tasks_failed: counters.
      stalled_s: total time the robot stood still while it had somewhere to go.
    """

    x_m: jax.Array
    y_m: jax.Array
    heading_x: jax.Array
    heading_y: jax.Array
    speed_mps: jax.Array
    battery_pct: jax.Array
    battery_change_pct: jax.Array
    mode: jax.Array
    charging: jax.Array
    obstacle: jax.Array
    reached: jax.Array
    leg_start_wp: jax.Array
    goal_wp: jax.Array
    leg_slot: jax.Array
    legs_started: jax.Array
    task_idx: jax.Array
    task_slot: jax.Array
    leg_elapsed_s: jax.Array
    leg_dist_m: jax.Array
    obstacle_at_share: jax.Array
    obstacle_left_m: jax.Array
    obstacle_speed_factor: jax.Array
    tasks_started: jax.Array
    tasks_succeeded: jax.Array
    tasks_failed: jax.Array
    stalled_s: jax.Array


@struct.dataclass
class SimState:
    """One world: workers, robot, its actor's state and the step counter (time = step * dt)."""

    workers: WorkerState
    robot: RobotState
    step: jax.Array  # () int32
    actor: Any = ()  # the actor's own state (any pytree of fixed shapes)


@struct.dataclass
class Record:
    """What is logged at a sampling instant (W waypoints, N workers).

    Attributes:
      time_s, slot: clock.
      robot_x_m, robot_y_m, robot_speed_mps, battery_pct, battery_change_pct: robot signals.
      charging, obstacle: the contexts C and O.
      robot_mode, robot_waypoint, goal_wp, leg_elapsed_s: where the robot is in its work.
      tasks_started, tasks_succeeded, tasks_failed, stalled_s: counters.
      n_present: workers inside.
      density_ppm2: (W,) people per m^2 in each waypoint disc (Eq. 3).
      worker_dist_m: (N,) robot-worker centre distance, NaN for absent workers.
      worker_x_m, worker_y_m, worker_status: (N,) positions and status.
    """

    time_s: jax.Array
    slot: jax.Array
    robot_x_m: jax.Array
    robot_y_m: jax.Array
    robot_speed_mps: jax.Array
    battery_pct: jax.Array
    battery_change_pct: jax.Array
    charging: jax.Array
    obstacle: jax.Array
    robot_mode: jax.Array
    robot_waypoint: jax.Array
    goal_wp: jax.Array
    leg_elapsed_s: jax.Array
    tasks_started: jax.Array
    tasks_succeeded: jax.Array
    tasks_failed: jax.Array
    stalled_s: jax.Array
    n_present: jax.Array
    density_ppm2: jax.Array
    worker_dist_m: jax.Array
    worker_x_m: jax.Array
    worker_y_m: jax.Array
    worker_status: jax.Array
