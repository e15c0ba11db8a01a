"""The robot of the day simulation: its body (motion, blocking rule, obstacles, battery) and its
working day (the slot's task list, deadlines, recharging). Pure JAX. Where it drives is its
actor's choice (:mod:`jaxsim.actor`): each step the actor sees a :class:`WarehouseObservation`
and answers a :class:`RobotCommand` (where to aim, how long its planned path is, whether to
recharge first); :func:`jaxsim.route_follower.route_follower` follows a
:class:`~jaxsim.world.RobotPlan`'s routes, as the paper's robot did. Protocols
(:mod:`evaluation.protocol`) reuse :func:`drive` and :func:`begin_leg` with task logic of their own.

* Motion: straight towards the actor's aim point (the next route waypoint) at up to
  ``robot_max_speed_mps``, speeding up at ``robot_accel_mps2`` (braking is immediate). The
  aim is reached within ``robot_goal_tolerance_m``.
* Crowds (the blocking rule): a person is *in the lane* when ahead of the robot with a lateral
  offset below ``robot_radius + worker_radius + block_lane_margin``. With ``gap`` the free
  distance to the nearest person in the lane, the speed is scaled by
  ``clip((gap - stop_gap) / (slow_gap - stop_gap), 0, 1)``: the robot slows, then stalls until
  the person moves (the workers' social force makes them step aside). Crowds cost time, as
  the paper's navigation stack did.
* Obstacles: when a task leg starts, with ``robot_obstacle_probability`` a static obstacle lies
  at a uniform point of the planned path (a share of the actor's ``planned_length_m``). Once
  the robot reaches it, it maneuvers for ``robot_obstacle_length_m`` at a share of its speed
  drawn per obstacle uniformly in ``[robot_obstacle_speed_factor_min, 1]``, with ``O = 1`` (and
  ``K_o`` times the consumption).
* Tasks: goals come from the slot's list in order (the list restarts when a slot begins, and
  wraps around). A leg is finished when the robot reaches the leg's goal waypoint as the point
  it aimed at. A leg not finished within ``robot_leg_deadline_s`` fails; with
  ``robot_teleport_on_failure`` the robot is put at the leg's goal, which is the next task's
  start (the paper's protocol). After a leg, if the battery is below
  ``battery_recharge_below_pct`` the robot drives to the charging station and charges
  (``C = 1``, ``V = 0``) up to ``battery_charged_pct``.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct

from socialnav.common.pytree import select
from socialnav.jaxsim import battery
from socialnav.jaxsim.params import SimParams
from socialnav.jaxsim.state import CHARGING, TASK, TO_CHARGER, RobotState
from socialnav.jaxsim.world import World


@struct.dataclass
class RobotCommand:
    """A warehouse actor's action for one step (all scalars).

    Attributes:
      aim_x_m, aim_y_m: the point to drive straight towards now (the route's next waypoint).
      speed_mps: the speed asked for, capped at ``robot_max_speed_mps`` (the blocking rule,
        obstacles and acceleration apply on top); inf (the route follower's) asks for the cap.
      planned_length_m: length of the path the actor plans for the current leg: the leg's
        obstacle, if any, lies at its drawn share of this distance.
      recharge: bool, refuse the task that begins now and recharge first (Eq. 10). The protocol
        (:mod:`evaluation.protocol`) honours it on a task's first step; the day simulation
        recharges by its own rule and ignores it.
      force_speed: bool, an experimenter's do(V = speed_mps): the robot moves at exactly
        ``speed_mps`` (capped at ``robot_max_speed_mps``), whatever the crowd, the obstacle or
        the acceleration limit (a charging robot or an empty battery still stands). The
        referee of the causal engine's do()-queries uses it (``socialnav referee``).
    """

    aim_x_m: jax.Array
    aim_y_m: jax.Array
    speed_mps: jax.Array
    planned_length_m: jax.Array
    recharge: jax.Array = False
    force_speed: jax.Array = False


@struct.dataclass
class WarehouseObservation:
    """What a warehouse actor sees at a step (the simulator's state, exactly: no sensor model).

    Attributes:
      robot: the robot (pose, speed, battery, mode, the current leg: ``leg_start_wp``,
        ``goal_wp``, ``leg_slot``, ``legs_started``, and ``reached``: its last aim reached).
      slot: () int32 the current time slot.
      workers_x_m, workers_y_m: (N,) the workers' positions before this step; workers_present (N,) bool.
    """

    robot: RobotState
    slot: jax.Array
    workers_x_m: jax.Array
    workers_y_m: jax.Array
    workers_present: jax.Array


def observe(
    robot: RobotState, slot: jax.Array, workers_x_m: jax.Array, workers_y_m: jax.Array, present: jax.Array
) -> WarehouseObservation:
    """The observation of a step (the workers' positions before it, as the robot's physics uses)."""
    return WarehouseObservation(
        robot=robot, slot=slot, workers_x_m=workers_x_m, workers_y_m=workers_y_m, workers_present=present
    )


def begin_leg(
    params: SimParams,
    r: RobotState,
    slot: jax.Array,
    start_wp: jax.Array,
    goal_wp: jax.Array,
    is_task: jax.Array | bool,
    u: jax.Array,
) -> RobotState:
    """Begin the leg ``start_wp -> goal_wp`` in ``slot`` (leg counters reset; the actor sees the
    new leg by ``legs_started`` and plans its path).

    ``is_task``: a task leg (obstacles may appear; mode TASK) rather than the way to the charger.
    ``u``: (3,) uniforms: obstacle or not, where on the path, how much it slows the robot.
    """
    u_obs, u_at, u_speed = u[0], u[1], u[2]
    has_obstacle = is_task & (u_obs < params.robot_obstacle_probability)
    return r.replace(
        mode=jnp.where(is_task, TASK, TO_CHARGER).astype(jnp.int32),
        leg_start_wp=jnp.asarray(start_wp, jnp.int32),
        goal_wp=jnp.asarray(goal_wp, jnp.int32),
        leg_slot=jnp.asarray(slot, jnp.int32),
        legs_started=r.legs_started + 1,
        leg_elapsed_s=jnp.float32(0.0),
        leg_dist_m=jnp.float32(0.0),
        obstacle_at_share=jnp.where(has_obstacle, u_at, jnp.inf).astype(jnp.float32),
        obstacle_left_m=jnp.float32(params.robot_obstacle_length_m),
        obstacle_speed_factor=(
            params.robot_obstacle_speed_factor_min + u_speed * (1.0 - params.robot_obstacle_speed_factor_min)
        ).astype(jnp.float32),
        tasks_started=r.tasks_started + jnp.where(is_task, 1, 0).astype(jnp.int32),
    )


def start_leg(
    params: SimParams,
    world: World,
    r: RobotState,
    slot: jax.Array,
    start_wp: jax.Array,
    to_charger: jax.Array | bool,
    u: jax.Array,
) -> RobotState:
    """Begin the next leg from ``start_wp``: the next task of ``slot``, or the way to the charger.

    ``u``: (3,) uniforms: obstacle or not, where on the path, how much it slows the robot.
    """
    idx = jnp.where(r.task_slot == slot, r.task_idx + 1, 0) % world.robot_goal_count[slot]
    goal = jnp.where(to_charger, world.charging_station, world.robot_goals[slot, idx])
    r = begin_leg(params, r, slot, start_wp, goal, ~jnp.asarray(to_charger), u)
    return r.replace(
        task_idx=jnp.where(to_charger, r.task_idx, idx).astype(jnp.int32),
        task_slot=jnp.where(to_charger, r.task_slot, slot).astype(jnp.int32),
    )


def crowd_speed_factor(
    params: SimParams, r: RobotState, hx: jax.Array, hy: jax.Array, wx: jax.Array, wy: jax.Array, present: jax.Array
) -> jax.Array:
    """The blocking rule: speed factor in [0, 1] from the people in the robot's lane."""
    rel_x, rel_y = wx - r.x_m, wy - r.y_m
    along = rel_x * hx + rel_y * hy
    lateral = jnp.abs(rel_x * hy - rel_y * hx)
    contact = params.robot_radius_m + params.worker_radius_m
    in_lane = present & (along > 0) & (lateral < contact + params.robot_block_lane_margin_m)
    gap = jnp.min(jnp.where(in_lane, along - contact, jnp.inf), initial=jnp.inf)
    stop, slow = params.robot_block_stop_gap_m, params.robot_block_slow_gap_m
    return jnp.clip((gap - stop) / (slow - stop), 0.0, 1.0)


def keep_body_clear(params: SimParams, world: World, x_m: jax.Array, y_m: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Push the robot's centre out to ``robot_radius_m`` from the nearest wall surface.

    Its routes are straight lines between waypoints, and a few of the warehouse's edges pass a
    thin wall's end closer than the robot's radius (1.2 % of a day's samples had the body in a
    wall, 10 of 26,400 the centre itself); the robot now slides round the wall's end instead.
    The distance at ``(x, y)`` is the wall field's value at the nearest grid point carried to the
    point along its normal (exact beside a straight wall, within the field's 5 cm cell at a
    corner). No robot waypoint lies within ``robot_radius_m`` of a wall (checked by
    ``tests/test_physics.py``), so the push never keeps the robot from a goal.
    """
    field = world.wall_field
    row, col = field.index(x_m, y_m)
    d, nx, ny = field.values[row, col, 0], field.values[row, col, 1], field.values[row, col, 2]
    x0, y0 = field.first_centre_m
    gx = x0 + col.astype(x_m.dtype) * field.spec.resolution_m
    gy = y0 + row.astype(y_m.dtype) * field.spec.resolution_m
    d = d + nx * (x_m - gx) + ny * (y_m - gy)
    push = jnp.maximum(params.robot_radius_m - d, 0.0)
    return x_m + push * nx, y_m + push * ny


def obstacle_at_m(r: RobotState, cmd: RobotCommand) -> jax.Array:
    """The leg distance at which the obstacle is met (inf: none on this leg)."""
    return jnp.where(jnp.isfinite(r.obstacle_at_share), r.obstacle_at_share * cmd.planned_length_m, jnp.inf)


def drive(
    params: SimParams,
    world: World,
    r: RobotState,
    cmd: RobotCommand,
    wx: jax.Array,
    wy: jax.Array,
    present: jax.Array,
) -> tuple[RobotState, jax.Array]:
    """One step of motion towards the command's aim point: crowds, obstacle, battery.

    ``wx, wy, present``: (N,) workers. Returns the moved robot (``reached``: the aim point
    reached this step, while not charging) and ``arrived``: reached, and the aim point is the
    leg's goal waypoint. Task bookkeeping is the caller's.
    """
    moving = r.mode != CHARGING
    dx, dy = cmd.aim_x_m - r.x_m, cmd.aim_y_m - r.y_m
    dist = jnp.sqrt(dx * dx + dy * dy)
    hx = jnp.where(dist > 1e-6, dx / jnp.maximum(dist, 1e-6), r.heading_x)
    hy = jnp.where(dist > 1e-6, dy / jnp.maximum(dist, 1e-6), r.heading_y)

    in_obstacle = (r.mode == TASK) & (r.leg_dist_m >= obstacle_at_m(r, cmd)) & (r.obstacle_left_m > 0)
    v_max = jnp.minimum(params.robot_max_speed_mps, jnp.maximum(cmd.speed_mps, 0.0))
    v_des = v_max * crowd_speed_factor(params, r, hx, hy, wx, wy, present)
    v_des = jnp.where(in_obstacle, v_des * r.obstacle_speed_factor, v_des)
    v_des = jnp.where(moving & (r.battery_pct > 0), v_des, 0.0)
    speed = jnp.minimum(v_des, r.speed_mps + params.robot_accel_mps2 * params.dt_s)
    speed = jnp.where(cmd.force_speed & moving & (r.battery_pct > 0), v_max, speed)  # do(V = v)
    travel = jnp.minimum(speed * params.dt_s, dist)

    charging = r.mode == CHARGING
    change = battery.battery_change_pct(params, speed, charging, in_obstacle)
    x_m, y_m = keep_body_clear(params, world, r.x_m + travel * hx, r.y_m + travel * hy)
    reached = moving & (dist - travel <= params.robot_goal_tolerance_m)
    new = r.replace(
        x_m=x_m,
        y_m=y_m,
        heading_x=hx,
        heading_y=hy,
        speed_mps=speed,
        battery_pct=battery.next_battery_pct(r.battery_pct, change),
        battery_change_pct=change,
        charging=charging,
        obstacle=in_obstacle,
        reached=reached,
        leg_elapsed_s=r.leg_elapsed_s + params.dt_s,
        leg_dist_m=r.leg_dist_m + travel,
        obstacle_left_m=jnp.where(in_obstacle, r.obstacle_left_m - travel, r.obstacle_left_m),
        stalled_s=r.stalled_s + jnp.where(moving & (speed <= 0), params.dt_s, 0.0),
    )
    at_goal = (cmd.aim_x_m == world.waypoint_x_m[r.goal_wp]) & (cmd.aim_y_m == world.waypoint_y_m[r.goal_wp])
    return new, reached & at_goal


def update_robot(
    params: SimParams,
    world: World,
    r: RobotState,
    cmd: RobotCommand,
    slot: jax.Array,
    wx: jax.Array,
    wy: jax.Array,
    present: jax.Array,
    u: jax.Array,
) -> RobotState:
    """One step of the robot's working day under the actor's command ``cmd``.

    ``wx, wy, present``: (N,) workers; ``u``: (3,) uniforms. ``cmd.recharge`` is not used: the
    day's robot recharges by its battery rule.
    """
    new, arrived = drive(params, world, r, cmd, wx, wy, present)
    task_mode = r.mode == TASK
    success = task_mode & arrived
    failure = task_mode & ~arrived & (new.leg_elapsed_s >= params.robot_leg_deadline_s)
    at_charger = (r.mode == TO_CHARGER) & arrived
    full = (r.mode == CHARGING) & (new.battery_pct >= params.battery_charged_pct)

    new = new.replace(tasks_succeeded=r.tasks_succeeded + success, tasks_failed=r.tasks_failed + failure)
    teleport = failure & params.robot_teleport_on_failure
    goal_x, goal_y = world.waypoint_x_m[r.goal_wp], world.waypoint_y_m[r.goal_wp]
    new = new.replace(
        x_m=jnp.where(teleport, goal_x, new.x_m),
        y_m=jnp.where(teleport, goal_y, new.y_m),
        speed_mps=jnp.where(failure | at_charger, 0.0, new.speed_mps),
    )
    new = new.replace(mode=jnp.where(at_charger, CHARGING, new.mode).astype(jnp.int32))

    leg_over = success | failure
    need_charge = leg_over & (new.battery_pct < params.battery_recharge_below_pct)
    next_leg = start_leg(params, world, new, slot, r.goal_wp, need_charge, u)
    resume = start_leg(params, world, new, slot, jnp.int32(world.charging_station), False, u)
    new = select(leg_over, next_leg, new)
    return select(full, resume, new)


def init_robot(params: SimParams, world: World, u: jax.Array) -> RobotState:
    """The robot at its start waypoint with a full battery, starting slot 0's first task."""
    f = jnp.float32
    i = jnp.int32
    start = world.robot_start
    r = RobotState(
        x_m=world.waypoint_x_m[start],
        y_m=world.waypoint_y_m[start],
        heading_x=f(1.0),
        heading_y=f(0.0),
        speed_mps=f(0.0),
        battery_pct=f(params.battery_initial_pct),
        battery_change_pct=f(0.0),
        mode=i(TASK),
        charging=jnp.bool_(False),
        obstacle=jnp.bool_(False),
        reached=jnp.bool_(False),
        leg_start_wp=i(start),
        goal_wp=i(start),
        leg_slot=i(0),
        legs_started=i(0),
        task_idx=i(-1),
        task_slot=i(0),
        leg_elapsed_s=f(0.0),
        leg_dist_m=f(0.0),
        obstacle_at_share=f(jnp.inf),
        obstacle_left_m=f(0.0),
        obstacle_speed_factor=f(1.0),
        tasks_started=i(0),
        tasks_succeeded=i(0),
        tasks_failed=i(0),
        stalled_s=f(0.0),
    )
    return start_leg(params, world, r, jnp.int32(0), jnp.int32(start), False, u)
