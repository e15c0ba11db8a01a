"""The social-navigation arena: a scene's people and a robot with a navigation stack, in closed loop,
as batched JAX episodes.

One episode step: the people move (:mod:`jaxsim.scenes.people`, the robot as an agent they see),
the robot perceives them (range, line of sight, velocities from a window of positions), the
local planner commands the base, the base moves (:mod:`jaxsim.scenes.robot`). The global planner
replans every ``replan_every_steps`` (1 Hz at the default 0.1 s step; a stack with ``replan=False``
plans once, at the start, as SNAPE does: its band adapts the path from then on): an outer
``lax.scan`` over replanning periods, an inner one over control steps, so no branch runs the
planner every step under ``vmap``. :func:`episode_function` vmaps episodes over a scene's variants;
the methods are a Python loop (each is another program). The physics knows nothing of stacks or
metrics: the stack (:mod:`planners.stack`) is passed in.

Compilation is shared across scenes: a scene's arrays (occupancy, walls, wall field, objects) are
arguments of the episode program, not constants in it, and are padded to sizes that depend on the
scene alone (walls to a multiple of 8 with boxes far outside, objects to a multiple of 4, people
slots to a power of two: :func:`jaxsim.scenes.variant.padded_slots`). Scenes with the same grid,
timeout and padded sizes (seed 001's four, seed 004's five) run one compiled program per method.
Padding walls and objects changes no episode (tested bit for bit); padding one person to two slots
changes episodes to float rounding only (XLA reduces over a one-long axis in another order; d_min
agrees to 1e-7 m). The sizes depend on the scene alone, so a scene gives the same episodes
whichever other scenes run beside it.
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

from data import WAREHOUSE_DIR
from jaxsim.params import SimParams
from jaxsim.scenario.loader import load_scenario
from jaxsim.scenes import people as people_lib
from jaxsim.scenes import perception
from jaxsim.scenes import robot as robot_lib
from jaxsim.scenes import world as world_lib
from jaxsim.scenes.spec import SceneSpec
from jaxsim.scenes.variant import Variant, padded_slots
from planners import casn, costmap, gscl_layer, stack
from planners.scene import Scene


@dataclasses.dataclass(frozen=True)
class ArenaConfig:
    """Static settings of the episodes.

    Attributes:
      dt_s: simulation and control step (0.1 s: 10 Hz control, as the seeds' local planners).
      replan_every_steps: global replanning period in steps (10: 1 Hz, seed 002's behaviour tree).
      grid_resolution_m: the global planner's cell size.
      goal_tolerance_m: reached when the robot's centre is this close to the goal.
      safety_margin_m: the base stops when a visible person in front (within 60 deg) is closer
        than robot radius + person radius + this margin.
      person_radius_m: a person's body radius (the warehouse's workers').
      max_path_cells: the global path's length bound in cells.
    """

    dt_s: float = 0.1
    replan_every_steps: int = 10
    grid_resolution_m: float = 0.2
    goal_tolerance_m: float = 0.3
    safety_margin_m: float = 0.1
    person_radius_m: float = 0.25
    max_path_cells: int = 256


@struct.dataclass
class Trajectory:
    """One episode's record, T steps (a batch adds a leading axis).

    Attributes:
      robot_xy (T, 2), robot_yaw (T,), robot_speed (T,); people_xy (T, P, 2), people_heading (T, P),
      people_present (T, P), people_visible (T, P); reached (T,) bool (the goal has been reached by
      then); speed_gain (T,) the local planner's speed factor (1 without one); predicted_distance_m
      (T,) nearest person's predicted distance to the robot 2 s ahead; wall_contacts () int32.
    """

    robot_xy: jnp.ndarray
    robot_yaw: jnp.ndarray
    robot_speed: jnp.ndarray
    people_xy: jnp.ndarray
    people_heading: jnp.ndarray
    people_present: jnp.ndarray
    people_visible: jnp.ndarray
    reached: jnp.ndarray
    speed_gain: jnp.ndarray
    predicted_distance_m: jnp.ndarray
    wall_contacts: jnp.ndarray


@struct.dataclass
class SceneArrays:
    """A scene's arrays as the episode program's argument (padded; :func:`setup_scene`).

    Attributes:
      occupancy: (H, W) float32 planner grid; world: walls (K, 4) and wall field;
      objects_xy_m (M, 8, 2), objects_cost (M,), objects_valid (M,): interaction spaces.
    """

    occupancy: jnp.ndarray
    world: world_lib.SceneWorld
    objects_xy_m: jnp.ndarray
    objects_cost: jnp.ndarray
    objects_valid: jnp.ndarray


@dataclasses.dataclass(frozen=True)
class SceneSetup:
    """What an episode needs of a scene, built once on the host (:func:`setup_scene`).

    Attributes:
      spec: the scene; grid: the planner grid (static); arrays: the padded arrays the program
      takes; obstacle_costs: (H, W) the walls' inflated layer (profiling); n_periods: replanning
      periods per episode; n_slots: people slots the variants are padded to.
    """

    spec: SceneSpec
    grid: costmap.GridSpec
    arrays: SceneArrays
    obstacle_costs: np.ndarray
    n_periods: int
    n_slots: int

    @property
    def world(self) -> world_lib.SceneWorld:
        return self.arrays.world

    @property
    def occupancy(self) -> np.ndarray:
        return np.asarray(self.arrays.occupancy)


def _round_up(n: int, multiple: int) -> int:
    return max(multiple, -(-int(n) // multiple) * multiple)


def crowd_params() -> SimParams:
    """The warehouse's social force constants (the arena's people are the same walkers)."""
    return load_scenario(WAREHOUSE_DIR).params


def setup_scene(
    spec: SceneSpec, config: ArenaConfig = ArenaConfig(), robot: robot_lib.RobotParams = robot_lib.RobotParams()
) -> SceneSetup:
    occ, origin = world_lib.occupancy(spec, config.grid_resolution_m)
    grid = costmap.GridSpec(occ.shape[0], occ.shape[1], config.grid_resolution_m, origin[0], origin[1])
    obstacles = np.asarray(costmap.obstacle_layer(occ, grid, float(robot.radius_m)))
    m = _round_up(len(spec.objects), 4)
    verts = np.zeros((m, 8, 2), np.float32)
    cost = np.zeros(m, np.float32)
    valid = np.zeros(m, bool)
    for k, (_, poly, c) in enumerate(spec.objects):
        verts[k, : len(poly)] = poly
        verts[k, len(poly) :] = poly[-1]
        cost[k], valid[k] = c, True
    world = world_lib.build_scene_world(spec)
    walls = np.asarray(world.walls_m)
    far = np.array([[1e4, 1e4 + 1.0, 1e4, 1e4 + 1.0]], np.float32)  # never nearest, never in sight
    walls = np.concatenate([walls, np.repeat(far, _round_up(len(walls), 8) - len(walls), axis=0)])
    period_s = config.dt_s * config.replan_every_steps
    arrays = SceneArrays(
        occupancy=jnp.asarray(occ),
        world=world.replace(walls_m=jnp.asarray(walls)),
        objects_xy_m=jnp.asarray(verts),
        objects_cost=jnp.asarray(cost),
        objects_valid=jnp.asarray(valid),
    )
    return SceneSetup(
        spec=spec,
        grid=grid,
        arrays=arrays,
        obstacle_costs=obstacles,
        n_periods=int(math.ceil(spec.timeout_s / period_s)),
        n_slots=padded_slots(spec.n_people_slots),
    )


def _perceived_scene(arrays: SceneArrays, people, visible, velocity, robot, goal_xy) -> Scene:
    return Scene(
        people_xy_m=people.xy,
        people_heading_rad=people.heading,
        people_velocity_mps=velocity,
        people_valid=visible,
        objects_xy_m=arrays.objects_xy_m,
        objects_cost=arrays.objects_cost,
        objects_valid=arrays.objects_valid,
        robot_xy_m=robot.xy,
        robot_yaw_rad=robot.yaw,
        goal_xy_m=goal_xy,
    )


def run_episode(
    grid: costmap.GridSpec,
    n_periods: int,
    arrays: SceneArrays,
    method: stack.StackConfig,
    variant: Variant,
    crowd: SimParams,
    robot_params: robot_lib.RobotParams = robot_lib.RobotParams(),
    config: ArenaConfig = ArenaConfig(),
    gscl_predict: Callable | None = None,
) -> Trajectory:
    """One episode of one variant on a scene's ``arrays`` (``grid``, ``n_periods``, ``method``,
    ``robot_params``, ``config`` and ``gscl_predict`` static; vmap it over variants)."""
    crowd = crowd.replace(dt_s=config.dt_s) if crowd.dt_s != config.dt_s else crowd
    x_m, y_m = grid.cell_centres()
    occupancy = arrays.occupancy
    world = arrays.world
    goal = jnp.asarray(variant.goal_xy)
    gscl_fn = None
    if method.layer == "gscl":
        if gscl_predict is None:
            raise ValueError("method 'gscl' needs a trained GSCL model")
        gscl_fn = lambda scene: gscl_layer.gscl_layer(gscl_predict, occupancy, grid, scene)
    n_people = variant.valid.shape[-1]
    radius_sum = robot_params.radius_m + config.person_radius_m

    def clearance_fn(people_xy, visible):
        def fn(q):
            walls = world_lib.wall_distance(q, world.walls_m)[0]
            d = jnp.linalg.norm(q[:, None, :] - people_xy[None], axis=-1) - config.person_radius_m
            return jnp.minimum(walls, jnp.min(jnp.where(visible[None], d, jnp.inf), axis=1))

        return fn

    def control_step(carry, _):
        people, robot, tracks, path, path_len, reached, step = carry
        seen = perception.visible(world, robot.xy, people.xy, people.present)
        tracks, velocity = perception.observe(tracks, people.xy, seen, config.dt_s)
        scene = _perceived_scene(arrays, people, seen, velocity, robot, goal)
        v, w, _, gain = stack.local_command(
            method,
            path,
            path_len,
            robot.xy,
            robot.yaw,
            robot.speed,
            robot_params.max_speed_mps,
            scene,
            clearance_fn(people.xy, seen),
        )
        # The local planner's speed factor and the predicted distance (for the pictures).
        predicted = people.xy + 2.0 * velocity
        ahead = robot.xy + 2.0 * robot.velocity
        pred_d = jnp.min(jnp.where(seen, jnp.linalg.norm(predicted - ahead, axis=-1), jnp.inf))
        # Safety stop: a visible person in front, closer than the bodies plus a margin.
        offset = people.xy - robot.xy
        dist = jnp.linalg.norm(offset, axis=-1)
        bearing = jnp.arctan2(offset[:, 1], offset[:, 0]) - robot.yaw
        in_front = jnp.cos(bearing) > 0.5
        stop = jnp.any(seen & in_front & (dist < radius_sum + config.safety_margin_m))
        v = jnp.where(stop | reached, 0.0, v)
        w = jnp.where(reached, 0.0, w)
        new_people = people_lib.step_people(crowd, world, variant, people, robot.xy, robot.velocity, step)
        robot = robot_lib.step_robot(robot_params, world, robot, v, w, config.dt_s)
        reached = reached | (jnp.linalg.norm(robot.xy - goal) < config.goal_tolerance_m)
        record = (
            robot.xy,
            robot.yaw,
            robot.speed,
            new_people.xy,
            new_people.heading,
            new_people.present,
            seen,
            reached,
            gain,
            pred_d,
        )
        return (new_people, robot, tracks, path, path_len, reached, step + 1), record

    def plan_now(people, robot, tracks, casn_state):
        """The global plan from the robot's perception now: (path, length, found, CASN state)."""
        seen = perception.visible(world, robot.xy, people.xy, people.present)
        velocity = perception.velocity(tracks, config.dt_s)
        scene = _perceived_scene(arrays, people, seen, velocity, robot, goal)
        social, casn_state = stack.social_layer(method, scene, x_m, y_m, casn_state, gscl_fn)
        # The people the sensors see are obstacles too (Nav2's obstacle layer), inflated with the walls.
        d = jnp.hypot(x_m[None] - people.xy[:, 0, None, None], y_m[None] - people.xy[:, 1, None, None])
        bodies = jnp.any((d <= config.person_radius_m) & seen[:, None, None], axis=0)
        obstacles = costmap.obstacle_layer(jnp.maximum(occupancy, bodies), grid, float(robot_params.radius_m))
        costs = costmap.combine_max(obstacles, social)
        path, length, found = stack.global_plan(method, costs, robot.xy, goal, grid, config.max_path_cells)
        return path, length, found, casn_state

    def period(carry, _):
        people, robot, tracks, casn_state, path, path_len, reached, step = carry
        if method.replan:
            new_path, new_len, found, casn_state = plan_now(people, robot, tracks, casn_state)
            # Keep the previous path when no path is found now (a person on the goal, say).
            path = jnp.where(found, new_path, path)
            path_len = jnp.where(found, new_len, path_len)
        inner = (people, robot, tracks, path, path_len, reached, step)
        inner, records = jax.lax.scan(control_step, inner, None, length=config.replan_every_steps)
        people, robot, tracks, path, path_len, reached, step = inner
        return (people, robot, tracks, casn_state, path, path_len, reached, step), records

    robot = robot_lib.init_robot(variant.robot_xy, variant.robot_yaw)
    people = people_lib.init_people(variant)
    tracks = perception.init_tracks(n_people)
    max_len = config.max_path_cells + 1
    straight = jnp.linspace(0.0, 1.0, max_len)[:, None] * (goal - robot.xy) + robot.xy
    path, path_len, found, casn_state = plan_now(people, robot, tracks, casn.initial_state(n_people))
    path = jnp.where(found, path, straight)
    path_len = jnp.where(found, path_len, max_len)
    carry = (people, robot, tracks, casn_state, path, path_len, jnp.array(False), jnp.int32(0))
    carry, records = jax.lax.scan(period, carry, None, length=n_periods)
    flat = jax.tree_util.tree_map(lambda a: a.reshape((-1,) + a.shape[2:]), records)
    robot_xy, yaw, speed, pxy, pheading, present, seen, reached, gain, pred_d = flat
    return Trajectory(
        robot_xy=robot_xy,
        robot_yaw=yaw,
        robot_speed=speed,
        people_xy=pxy,
        people_heading=pheading,
        people_present=present,
        people_visible=seen,
        reached=reached,
        speed_gain=gain,
        predicted_distance_m=pred_d,
        wall_contacts=carry[1].wall_contacts,
    )


@functools.lru_cache(maxsize=64)
def _episode_program(
    grid: costmap.GridSpec,
    n_periods: int,
    method: stack.StackConfig,
    robot_params: robot_lib.RobotParams,
    config: ArenaConfig,
    gscl_predict: Callable | None,
):
    """``(arrays, crowd, variants) -> Trajectory``, jitted, vmapped over variants; one per static
    key, so scenes of equal padded shapes share its compilations."""

    def batch(arrays, crowd, variants):
        def one(variant):
            return run_episode(grid, n_periods, arrays, method, variant, crowd, robot_params, config, gscl_predict)

        return jax.vmap(one)(variants)

    return jax.jit(batch)


def episode_function(
    setup: SceneSetup,
    method: stack.StackConfig,
    crowd: SimParams,
    robot_params: robot_lib.RobotParams = robot_lib.RobotParams(),
    config: ArenaConfig = ArenaConfig(),
    gscl_predict: Callable | None = None,
):
    """``variants (batched Variant, padded to ``setup.n_slots``) -> Trajectory (batched)``."""
    program = _episode_program(setup.grid, setup.n_periods, method, robot_params, config, gscl_predict)
    return functools.partial(program, setup.arrays, crowd)
