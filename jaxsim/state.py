"""Dynamic state of one simulated world: fixed shapes, absent agents masked (not removed).

Batching adds leading axes to every leaf; nothing here knows about batches.
"""

from __future__ import annotations

import jax.numpy as jnp
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

    x_m: jnp.ndarray
    y_m: jnp.ndarray
    vx_mps: jnp.ndarray
    vy_mps: jnp.ndarray
    desired_speed_mps: jnp.ndarray
    status: jnp.ndarray
    leaving: jnp.ndarray
    target_wp: jnp.ndarray
    dest_wp: jnp.ndarray
    spot_dx_m: jnp.ndarray
    spot_dy_m: jnp.ndarray
    activity_end_s: jnp.ndarray
    arrive_s: jnp.ndarray
    depart_s: jnp.ndarray
    best_dist_m: jnp.ndarray
    stuck_s: jnp.ndarray

    @property
    def present(self) -> jnp.ndarray:
        """(N,) bool, inside the simulated area (arrived and not left)."""
        return (self.status == WALKING) | (self.status == ACTIVITY)


@struct.dataclass
class RobotState:
    """The robot (all scalars but ``route``).

    Attributes:
      x_m, y_m, heading_x, heading_y: pose (unit heading).
      speed_mps: V.
      battery_pct: B in [0, 100].
      battery_change_pct: L of the last step (Eq. 1).
      mode: TASK / TO_CHARGER / CHARGING.
      charging: C.
      obstacle: O, maneuvering around a static obstacle now.
      route: (L,) int32 waypoints of the current leg; ``route_pos`` the index aimed at now;
        ``route_hops`` its real length.
      leg_start_wp, goal_wp: the current leg's start and goal.
      task_idx, task_slot: position in the slot's goal list, and the slot it belongs to.
      leg_elapsed_s, leg_dist_m: time and distance on the current leg.
      obstacle_at_m: leg distance at which the obstacle is met (inf: none on this leg).
      obstacle_left_m: maneuver distance still to go once met.
      obstacle_speed_factor: share of the speed kept while maneuvering around this leg's obstacle.
      tasks_started, tasks_succeeded, tasks_failed: counters.
      stalled_s: total time the robot stood still while it had somewhere to go.
    """

    x_m: jnp.ndarray
    y_m: jnp.ndarray
    heading_x: jnp.ndarray
    heading_y: jnp.ndarray
    speed_mps: jnp.ndarray
    battery_pct: jnp.ndarray
    battery_change_pct: jnp.ndarray
    mode: jnp.ndarray
    charging: jnp.ndarray
    obstacle: jnp.ndarray
    route: jnp.ndarray
    route_pos: jnp.ndarray
    route_hops: jnp.ndarray
    leg_start_wp: jnp.ndarray
    goal_wp: jnp.ndarray
    task_idx: jnp.ndarray
    task_slot: jnp.ndarray
    leg_elapsed_s: jnp.ndarray
    leg_dist_m: jnp.ndarray
    obstacle_at_m: jnp.ndarray
    obstacle_left_m: jnp.ndarray
    obstacle_speed_factor: jnp.ndarray
    tasks_started: jnp.ndarray
    tasks_succeeded: jnp.ndarray
    tasks_failed: jnp.ndarray
    stalled_s: jnp.ndarray


@struct.dataclass
class SimState:
    """One world: workers, robot and the step counter (time = step * dt)."""

    workers: WorkerState
    robot: RobotState
    step: jnp.ndarray  # () int32


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

    time_s: jnp.ndarray
    slot: jnp.ndarray
    robot_x_m: jnp.ndarray
    robot_y_m: jnp.ndarray
    robot_speed_mps: jnp.ndarray
    battery_pct: jnp.ndarray
    battery_change_pct: jnp.ndarray
    charging: jnp.ndarray
    obstacle: jnp.ndarray
    robot_mode: jnp.ndarray
    robot_waypoint: jnp.ndarray
    goal_wp: jnp.ndarray
    leg_elapsed_s: jnp.ndarray
    tasks_started: jnp.ndarray
    tasks_succeeded: jnp.ndarray
    tasks_failed: jnp.ndarray
    stalled_s: jnp.ndarray
    n_present: jnp.ndarray
    density_ppm2: jnp.ndarray
    worker_dist_m: jnp.ndarray
    worker_x_m: jnp.ndarray
    worker_y_m: jnp.ndarray
    worker_status: jnp.ndarray
