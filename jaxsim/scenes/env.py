"""The social-navigation environment: pure ``reset`` and ``step`` over a scene's people and a robot.

In the style of brax, gymnax and jumanji: :class:`Env` is a pytree whose array leaves (the
scene's walls and occupancy, the crowd's and the robot's parameters, the reward's weights) are
traced, so one compiled program serves every scene of the same padded shapes and every value of
a parameter; its static part (:class:`EnvConfig`, the grid's origin) is the cache key.

One step (``dt_s``, 0.1 s by default):

1. the action ``(v, omega)`` (m/s, rad/s) is applied to the base, whose limits
   (:class:`~jaxsim.scenes.robot.RobotParams`) clip it; once the goal is reached the base is
   commanded to stop (the episode's people go on). An action of another shape is refused when
   the step is traced (``ValueError``, before any work). An action with a NaN or infinite entry
   is never applied: the base is commanded to stop for that step and ``info.invalid_action`` is
   set, so a broken actor's episode stays finite and is marked (the arena counts such steps per
   episode, ``invalid_action_steps``) instead of spreading NaN into the robot, the people who
   avoid it and every metric;
2. the people move by the human model (:mod:`jaxsim.scenes.people`; the social force by
   default), the robot's previous position and velocity an agent they avoid; the base moves and slides along walls;
3. the robot perceives (:mod:`jaxsim.scenes.perception`): people in range and in line of sight,
   their velocities estimated from a window of observed positions (never read from the
   simulator), and the occupancy around it.

:class:`TimeStep` carries the :class:`Observation`, the reward (:class:`RewardParams`, CrowdNav's
sparse reward with a progress term), ``terminated`` (the goal reached), ``truncated`` (the time
limit) and :class:`StepInfo`, the true quantities the metrics need. Everything vmaps over
variants; a variant gives the same bits alone and in any batch (tested).
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from collections.abc import Mapping
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from socialnav.data import WAREHOUSE_DIR
from socialnav.jaxsim import humans, speed_model
from socialnav.jaxsim.grid import Grid, GridSpec
from socialnav.jaxsim.groups import GroupParams
from socialnav.jaxsim.orca import ORCAParams
from socialnav.jaxsim.params import BODY_RADIUS_M, BODY_RADIUS_SOURCE, PERSON_RADIUS_M, SimParams
from socialnav.jaxsim.scenario.loader import load_scenario
from socialnav.jaxsim.scenes import people as people_lib
from socialnav.jaxsim.scenes import perception, routes, specs
from socialnav.jaxsim.scenes import robot as robot_lib
from socialnav.jaxsim.scenes import world as world_lib
from socialnav.jaxsim.scenes.variant import Variant
from socialnav.jaxsim.scenes.world import SceneWorld
from socialnav.jaxsim.walkers import RobotDisc


@dataclasses.dataclass(frozen=True)
class EnvConfig:
    """Static settings (hashable; a change recompiles).

    Attributes:
      dt_s: simulation and control step (0.1 s: 10 Hz, the seeds' local planners).
      max_steps: the time limit in steps (``truncated`` from then on).
      goal_tolerance_m: the goal is reached when the robot's centre is this close.
      person_radius_m: a person's body radius for contacts, the reward and ORCA's people
        (:data:`jaxsim.params.PERSON_RADIUS_M`, 0.25 m).
      sensor_range_m: people farther than this are not seen (8 m: GSCL's window; the seeds'
        RGB-D sensors reach about as far).
      window_cells: the observed occupancy window's side in cells, centred on the robot and
        turned with it (row 0 behind, column 0 to the right; 0: no window).
      window_resolution_m: its cell size.
      human_model: how the people move (:data:`jaxsim.scenes.people.HUMAN_MODELS`): the
        warehouse's social force (default), ORCA (:mod:`jaxsim.orca`) or a velocity model with
        bodies (:mod:`jaxsim.speed_model`; ``docs/humans.md`` measures each against real people).
    """

    dt_s: float = 0.1
    max_steps: int = 600
    goal_tolerance_m: float = 0.3
    person_radius_m: float = PERSON_RADIUS_M
    sensor_range_m: float = perception.RANGE_M
    window_cells: int = 16
    window_resolution_m: float = 0.25
    human_model: str = "social_force"

    def __post_init__(self):
        """Refuse a setting no episode can run with, naming the field (:func:`config_problem`)."""
        problem = config_problem(self)
        if problem is not None:
            raise ValueError(problem)


def config_problem(config: EnvConfig) -> str | None:
    """Why no episode can run with ``config`` (the field, what it must be and what it is), or None:
    an unknown human model; a step, goal tolerance, body radius or window cell that is not a finite
    number > 0 (a step of 0 moves nothing, a NaN one makes every position NaN, a negative
    tolerance is never reached); a person's radius outside a body's range
    (:data:`jaxsim.params.BODY_RADIUS_M`, as the warehouse's workers); a sensor range below 0 or
    NaN (``inf``: everyone is seen); a time limit below one step; a negative window."""
    if config.human_model not in people_lib.HUMAN_MODELS:
        return f"EnvConfig.human_model must be one of {', '.join(people_lib.HUMAN_MODELS)}, got {config.human_model!r}"

    def number(value) -> bool:
        return isinstance(value, numbers.Real) and not isinstance(value, bool) and not math.isnan(value)

    for name in ("dt_s", "goal_tolerance_m", "person_radius_m", "window_resolution_m"):
        value = getattr(config, name)
        if not (number(value) and math.isfinite(value) and value > 0):
            return f"EnvConfig.{name} must be a finite number > 0, got {value!r}"
    low, high = BODY_RADIUS_M["worker_radius_m"]  # a person's body, as the warehouse's workers
    if not low <= config.person_radius_m <= high:
        return (
            f"EnvConfig.person_radius_m must be a body radius in [{low}, {high}] m "
            f"({BODY_RADIUS_SOURCE['worker_radius_m']}), got {config.person_radius_m!r}"
        )
    if not (number(config.sensor_range_m) and config.sensor_range_m >= 0):
        return f"EnvConfig.sensor_range_m must be a number >= 0 (inf: no limit), got {config.sensor_range_m!r}"
    for name, least in (("max_steps", 1), ("window_cells", 0)):
        value = getattr(config, name)
        if not (isinstance(value, numbers.Integral) and not isinstance(value, bool) and value >= least):
            return f"EnvConfig.{name} must be a whole number >= {least}, got {value!r}"
    return None


@struct.dataclass
class RewardParams:
    """The default reward's weights (dynamic floats: a sweep does not recompile).

    CrowdNav's (Chen et al. 2019, also social-jym's ``Reward1``): ``goal_reward`` on the step
    the goal is reached, ``collision_penalty`` on each step in contact with a person,
    ``discomfort_weight * (d - discomfort_distance_m) * dt`` while a person's body is closer than
    ``discomfort_distance_m`` to the robot's; plus ``progress_weight`` per metre gained towards
    the goal (the dense shaping robot_sf uses, 0 for CrowdNav's own), ``wall_penalty`` per step
    in contact with a wall and ``time_penalty`` per step.
    """

    goal_reward: float = 1.0
    collision_penalty: float = -0.25
    discomfort_distance_m: float = 0.2
    discomfort_weight: float = 0.5
    progress_weight: float = 0.1
    wall_penalty: float = -0.05
    time_penalty: float = 0.0


@struct.dataclass
class Observation:
    """What the robot perceives (P people slots; a batch adds leading axes).

    Attributes:
      robot_xy_m (2,), robot_yaw_rad (), robot_speed_mps (), robot_turn_rate_rps (): its own
        pose and velocity (odometry).
      goal_xy_m (2,): where the robot must go.
      people_xy_m (P, 2), people_heading_rad (P,), people_velocity_mps (P, 2): the people as
        sensed (zeros where not seen); the velocity is the estimate from the track window.
      people_visible (P,) bool: in range and in line of sight now.
      occupancy (C, C) float32: the walls around the robot, in its frame (``window_cells``).
      time_s (): the episode's time.
    """

    robot_xy_m: jax.Array
    robot_yaw_rad: jax.Array
    robot_speed_mps: jax.Array
    robot_turn_rate_rps: jax.Array
    goal_xy_m: jax.Array
    people_xy_m: jax.Array
    people_heading_rad: jax.Array
    people_velocity_mps: jax.Array
    people_visible: jax.Array
    occupancy: jax.Array
    time_s: jax.Array


@struct.dataclass
class StepInfo:
    """True quantities for metrics (not for the robot): people_xy_m (P, 2),
    people_heading_rad (P,), people_present (P,) bool, reached () bool (by now),
    person_contact () bool, wall_contact () bool (this step), nearest_person_m () the smallest
    body-to-body distance (inf with nobody present), invalid_action () bool (this step's action
    had a NaN or infinite entry and the base was stopped instead)."""

    people_xy_m: jax.Array
    people_heading_rad: jax.Array
    people_present: jax.Array
    reached: jax.Array
    person_contact: jax.Array
    wall_contact: jax.Array
    nearest_person_m: jax.Array
    invalid_action: jax.Array


@struct.dataclass
class TimeStep:
    """observation; reward () float32; terminated () bool (the goal reached); truncated () bool
    (the time limit, not terminated); info: :class:`StepInfo`."""

    observation: Observation
    reward: jax.Array
    terminated: jax.Array
    truncated: jax.Array
    info: StepInfo

    @property
    def done(self) -> jax.Array:
        return self.terminated | self.truncated


@struct.dataclass
class EnvState:
    """variant (the episode's draw), people, robot, tracks (the perception's window), step ()
    int32, reached () bool, key (the env's own stream; unused by the default sensors), extras
    (what wrappers keep per episode, by name, as brax's ``State.info``; empty for the bare env:
    :mod:`jaxsim.scenes.wrappers`)."""

    variant: Variant
    people: people_lib.PeopleState
    robot: robot_lib.BaseState
    tracks: perception.Tracks
    step: jax.Array
    reached: jax.Array
    key: jax.Array
    extras: dict = struct.field(default_factory=dict)


@struct.dataclass
class Env:
    """A scene as an environment (a pytree: pass it to ``jit`` as an argument).

    Attributes:
      world: the scene's walls (boxes and distance field).
      occupancy: the planner-resolution occupancy as a :class:`~jaxsim.grid.Grid` (H, W).
      crowd: the social force's constants (``dt_s`` is the env's).
      robot: the base's limits.
      reward: the reward's weights.
      orca: ORCA's constants (used with ``config.human_model = "orca"``).
      velocity: a velocity model's constants (:mod:`jaxsim.speed_model`; used with
        ``config.human_model`` one of them), or a fitted power law's; None otherwise (the power
        law's constants then its name's).
      group: the walking groups' terms (:class:`~jaxsim.groups.GroupParams`, Moussaïd's unless
        a fit set them).
      config: static settings.
      walking_groups: static, the scene has walkers who walk together (``walks_with``): the
        crowd step computes the group terms (:mod:`jaxsim.groups`) only then.
      recorded: static, the scene's people are a recorded crowd (:mod:`jaxsim.scenes.people`;
        replayed or reactive as each variant says, so both playbacks of a recording share one
        compiled program).
      routed: static, a walker of the scene (or a queue's served member) may walk round the walls
        by the corners of its way (:func:`jaxsim.scenes.routes.may_route`); without, the people
        step without the corners' bookkeeping.
    """

    world: SceneWorld
    occupancy: Grid
    crowd: SimParams
    robot: robot_lib.RobotParams
    reward: RewardParams
    orca: ORCAParams
    velocity: Any = None
    group: GroupParams = GroupParams()
    config: EnvConfig = struct.field(pytree_node=False, default=EnvConfig())
    walking_groups: bool = struct.field(pytree_node=False, default=False)
    recorded: bool = struct.field(pytree_node=False, default=False)
    routed: bool = struct.field(pytree_node=False, default=False)

    # ------------------------------------------------------------------ API

    def human_params(self) -> humans.HumanParams:
        """The constants the people's model runs with (:func:`people_constants` of this env)."""
        return people_constants(self.config, self.crowd, self.orca, self.velocity, self.group)

    def reset(self, key: jax.Array, variant: Variant) -> tuple[EnvState, TimeStep]:
        """The episode of ``variant`` at time 0 (the variant fixes the people and the crowd's
        random force, so every actor meets the same crowd: common random numbers)."""
        n = variant.valid.shape[-1]
        robot = robot_lib.init_robot(variant.robot_xy, variant.robot_yaw)
        people = people_lib.init_people(variant)
        state = EnvState(
            variant=variant,
            people=people,
            robot=robot,
            tracks=perception.init_tracks(n),
            step=jnp.int32(0),
            reached=jnp.array(False),
            key=key,
        )
        state, observation = perceive(self.world, self.occupancy, self.config, state)
        info = step_info(state, self.robot.radius_m, self.config.person_radius_m, jnp.array(False), jnp.array(False))
        zero = jnp.float32(0.0)
        return state, TimeStep(observation, zero, jnp.array(False), jnp.array(False), info)

    def step(self, state: EnvState, action: jax.Array) -> tuple[EnvState, TimeStep]:
        """Apply ``action`` (2,) = (v m/s, omega rad/s) for one step.

        Raises:
          ValueError: ``action`` is not of shape (2,) (checked when the step is traced; under
            ``vmap`` the shape of one lane).
        """
        cfg = self.config
        action = check_action(action)
        invalid = ~jnp.all(jnp.isfinite(action))
        stop = state.reached | invalid
        v = jnp.where(stop, 0.0, action[0])
        w = jnp.where(stop, 0.0, action[1])
        people = people_lib.step_people(
            cfg.human_model,
            people_constants(cfg, self.crowd, self.orca, self.velocity, self.group),
            self.world,
            state.variant,
            state.people,
            RobotDisc.of(state.robot.xy, state.robot.velocity, felt_robot_radius_m(cfg, self.robot, self.velocity)),
            state.step,
            state.variant.walking_group if self.walking_groups else None,
            self.recorded,
            self.routed,
        )
        robot = robot_lib.step_robot(self.robot, self.world, state.robot, v, w, cfg.dt_s)
        goal = state.variant.goal_xy
        reached_now = jnp.linalg.norm(robot.xy - goal) < cfg.goal_tolerance_m
        new = state.replace(people=people, robot=robot, step=state.step + 1, reached=state.reached | reached_now)
        new, observation = perceive(self.world, self.occupancy, cfg, new)
        wall_contact = robot.wall_contacts > state.robot.wall_contacts
        info = step_info(new, self.robot.radius_m, cfg.person_radius_m, wall_contact, invalid)
        progress_m = jnp.linalg.norm(state.robot.xy - goal) - jnp.linalg.norm(robot.xy - goal)
        reward = step_reward(self.reward, cfg.dt_s, info, ~state.reached & new.reached, progress_m, state.reached)
        terminated = new.reached
        truncated = (new.step >= cfg.max_steps) & ~terminated
        return new, TimeStep(observation, reward, terminated, truncated, info)

    # ------------------------------------------------------------------ specs

    def observation_spec(self, n_people: int) -> Observation:
        """One observation with ``n_people`` slots as an :class:`Observation` of
        :class:`~jaxsim.scenes.specs.Array` specs (``jax.tree.map`` walks it beside an observation)."""
        c = self.config.window_cells
        f32, n = jnp.float32, n_people
        shapes = {
            "robot_xy_m": ((2,), f32),
            "robot_yaw_rad": ((), f32),
            "robot_speed_mps": ((), f32),
            "robot_turn_rate_rps": ((), f32),
            "goal_xy_m": ((2,), f32),
            "people_xy_m": ((n, 2), f32),
            "people_heading_rad": ((n,), f32),
            "people_velocity_mps": ((n, 2), f32),
            "people_visible": ((n,), jnp.bool_),
            "occupancy": ((c, c), f32),
            "time_s": ((), f32),
        }
        return Observation(**{name: specs.Array(shape, dtype, name) for name, (shape, dtype) in shapes.items()})

    def action_spec(self) -> specs.BoundedArray:
        """The action (2,) float32 ``(v m/s, omega rad/s)`` with the bounds the base clips it to."""
        r = self.robot
        return specs.BoundedArray(
            (2,),
            jnp.float32,
            "action",
            minimum=(0.0, -float(r.max_turn_rate_rps)),
            maximum=(float(r.max_speed_mps), float(r.max_turn_rate_rps)),
        )


# ---------------------------------------------------------------------- the step's parts
# Pure functions of the facts they read (the env's step passes them in), so a reader of one
# part needs nothing else of the env.


def people_constants(config: EnvConfig, crowd: SimParams, orca: ORCAParams, velocity, group: GroupParams):
    """The constants the people's model (``config.human_model``) runs with
    (:func:`jaxsim.humans.human_params`): the social force's ``crowd`` with the env's step
    ``config.dt_s``, ORCA's and the velocity model's (or the power law's) as :class:`Env` holds them."""
    return humans.human_params(config.human_model, crowd.replace(dt_s=config.dt_s), orca, velocity, group)


def felt_robot_radius_m(config: EnvConfig, robot: robot_lib.RobotParams, velocity):
    """The robot's radius as the people's model feels it. A velocity model's people keep their
    own fitted body (``velocity.radius_m``, 0.16-0.18 m), narrower than the person the env counts
    contacts with (``config.person_radius_m``, 0.25 m): the robot is widened by the difference, so
    a person keeps off it by the bodies the metrics measure, and "a person walked into the robot"
    is not an artefact of two radii. The other models' people have the env's body (ORCA) or none
    (the social force)."""
    if humans.kind_of(config.human_model) not in speed_model.VELOCITY_MODELS:
        return robot.radius_m
    return robot.radius_m + jnp.maximum(config.person_radius_m - velocity.radius_m, 0.0)


def perceive(world: SceneWorld, occupancy: Grid, config: EnvConfig, state: EnvState) -> tuple[EnvState, Observation]:
    """What the robot senses in ``state``: the people in range and in line of sight past
    ``world``'s walls, their velocities from the tracks (updated in the returned state), and the
    walls around it (:func:`occupancy_window` of ``occupancy``)."""
    people, robot = state.people, state.robot
    seen = perception.visible(world, robot.xy, people.xy, people.present, config.sensor_range_m)
    tracks, velocity = perception.observe(state.tracks, people.xy, seen, config.dt_s)
    observation = Observation(
        robot_xy_m=robot.xy,
        robot_yaw_rad=robot.yaw,
        robot_speed_mps=robot.speed,
        robot_turn_rate_rps=robot.turn_rate,
        goal_xy_m=jnp.asarray(state.variant.goal_xy, jnp.float32),
        people_xy_m=jnp.where(seen[:, None], people.xy, 0.0),
        people_heading_rad=jnp.where(seen, people.heading, 0.0),
        people_velocity_mps=velocity,
        people_visible=seen,
        occupancy=occupancy_window(occupancy, config.window_cells, config.window_resolution_m, robot.xy, robot.yaw),
        time_s=state.step.astype(jnp.float32) * config.dt_s,
    )
    return state.replace(tracks=tracks), observation


def occupancy_window(occupancy: Grid, cells: int, resolution_m: float, xy, yaw):
    """(C, C) = (``cells``, ``cells``) occupancy around ``xy`` (2,) in the frame of heading
    ``yaw`` (rows forward, columns left; nearest cell; off the map: 1)."""
    if cells == 0:
        return jnp.zeros((0, 0), jnp.float32)
    offsets = (jnp.arange(cells, dtype=jnp.float32) - (cells - 1) / 2) * resolution_m
    fwd, left = jnp.meshgrid(offsets, -offsets[::-1], indexing="ij")  # row: forward, col: left
    cos, sin = jnp.cos(yaw), jnp.sin(yaw)
    x = xy[0] + cos * fwd - sin * left
    y = xy[1] + sin * fwd + cos * left
    h, w = occupancy.spec.shape
    row, col = occupancy.nearest_cell(x, y)
    inside = (col >= 0) & (col < w) & (row >= 0) & (row < h)
    return jnp.where(inside, occupancy.lookup(x, y), 1.0)


def step_info(state: EnvState, robot_radius_m, person_radius_m: float, wall_contact, invalid_action) -> StepInfo:
    """The true quantities of ``state`` (:class:`StepInfo`): the people, the smallest gap between
    the robot's body and a present person's (inf with nobody present) and whether it is a contact."""
    people, robot = state.people, state.robot
    gap = jnp.linalg.norm(people.xy - robot.xy, axis=-1) - robot_radius_m - person_radius_m
    nearest = jnp.min(jnp.where(people.present, gap, jnp.inf))
    return StepInfo(
        people_xy_m=people.xy,
        people_heading_rad=people.heading,
        people_present=people.present,
        reached=state.reached,
        person_contact=nearest < 0.0,
        wall_contact=wall_contact,
        nearest_person_m=nearest,
        invalid_action=invalid_action,
    )


def step_reward(reward: RewardParams, dt_s: float, info: StepInfo, arrived, progress_m, was_reached):
    """() float32, one step's reward by ``reward``'s weights: the goal reached this step
    (``arrived``), a person's contact, the discomfort of a person nearer than its distance, the
    ``progress_m`` towards the goal, a wall's contact and the time; 0 once the goal was reached."""
    r = reward
    discomfort = jnp.where(
        (info.nearest_person_m >= 0.0) & (info.nearest_person_m < r.discomfort_distance_m),
        r.discomfort_weight * (info.nearest_person_m - r.discomfort_distance_m) * dt_s,
        0.0,
    )
    total = (
        r.goal_reward * arrived
        + r.collision_penalty * info.person_contact
        + discomfort
        + r.progress_weight * progress_m
        + r.wall_penalty * info.wall_contact
        + r.time_penalty
    )
    return jnp.where(was_reached, 0.0, total).astype(jnp.float32)


def action_problem(shape, dtype) -> str | None:
    """What is wrong with an action of ``shape`` and ``dtype`` (None: a (2,) array of real
    numbers, ``(v m/s, omega rad/s)``)."""
    if tuple(shape) != (2,):
        return (
            f"an action must have shape (2,) = (v m/s, omega rad/s), got shape {tuple(shape)} "
            "(under vmap: the shape of one episode's action)"
        )
    if not (jnp.issubdtype(dtype, jnp.floating) or jnp.issubdtype(dtype, jnp.integer)):
        return f"an action must hold real numbers (v m/s, omega rad/s), got dtype {dtype}"
    return None


def check_action(action) -> jax.Array:
    """``action`` as a (2,) float32 array ``(v m/s, omega rad/s)``; ``ValueError`` naming the
    shape otherwise (:func:`action_problem`). A shape is static under ``jit``, so a wrong one is
    refused when the step is traced, before any episode runs (a (1,) action would otherwise be
    read as speed = turn rate, a (3,) one lose its third entry, a scalar fail deep inside JAX)."""
    if not (hasattr(action, "shape") and hasattr(action, "dtype")):
        try:
            action = jnp.asarray(action)
        except (TypeError, ValueError) as e:
            raise ValueError(f"an action must be an array of shape (2,) = (v m/s, omega rad/s): {e}") from None
    problem = action_problem(action.shape, action.dtype)
    if problem is not None:
        raise ValueError(problem)
    return jnp.asarray(action, jnp.float32)


def _round_up(n: int, multiple: int) -> int:
    return max(multiple, -(-int(n) // multiple) * multiple)


def pad_walls(walls_m, multiple: int = 8):
    """(K', 4) the wall boxes padded to a multiple of ``multiple`` with boxes far outside (never
    nearest, never in sight): scenes of similar size share one compiled program; the padding
    changes no episode (tested bit for bit)."""
    walls = np.asarray(walls_m, np.float32)
    far = np.array([[1e4, 1e4 + 1.0, 1e4, 1e4 + 1.0]], np.float32)
    return np.concatenate([walls, np.repeat(far, _round_up(len(walls), multiple) - len(walls), axis=0)])


def make_env(
    spec,
    config: EnvConfig = EnvConfig(),
    robot: robot_lib.RobotParams = robot_lib.RobotParams(),
    crowd: SimParams | None = None,
    reward: RewardParams = RewardParams(),
    occupancy_resolution_m: float = 0.2,
    orca: ORCAParams | None = None,
    human_values: Mapping[str, float] | None = None,
) -> Env:
    """The environment of a :class:`~jaxsim.scenes.spec.SceneSpec` (host side, once per scene).

    ``crowd`` defaults to the warehouse's social force constants (the arena's people are the
    same walkers); ``orca`` to ORCA's defaults with ``config.person_radius_m`` as its people's
    radius (the body the env counts contacts with). ``human_values`` (``"<part>.<field>"`` ->
    number: a calibration's fit, :func:`jaxsim.humans.with_values`) set the human model's
    constants over its name's own; ``ValueError`` for one the model does not read.
    ``config.max_steps`` is kept as given (see :func:`episode_steps`). Raises ``ValueError`` where
    a step at the robot's top speed is not shorter than its radius
    (:func:`jaxsim.scenes.robot.step_length_problem`: the body could pass through a wall).
    """
    problem = robot_lib.step_length_problem(robot, config.dt_s)
    if problem is not None:
        raise ValueError(problem)
    if orca is None:
        orca = ORCAParams(radius_m=config.person_radius_m)
    if crowd is None:
        crowd = load_scenario(WAREHOUSE_DIR).params
    world = world_lib.build_scene_world(spec.walls_m, spec.bounds_m)
    world = world.replace(walls_m=jnp.asarray(pad_walls(world.walls_m)))
    unturned = None if spec.turned_from is None else (spec.turned_from.walls_m, spec.turned_from.bounds_m)
    occ, (x0, y0) = world_lib.occupancy(spec.walls_m, spec.bounds_m, occupancy_resolution_m, unturned)
    grid = Grid(jnp.asarray(occ), GridSpec(*occ.shape, occupancy_resolution_m, x0, y0))
    kind = humans.kind_of(config.human_model)
    velocity = speed_model.params_of(config.human_model) if kind in speed_model.VELOCITY_MODELS else None
    group = GroupParams()
    if human_values:
        people = humans.human_params(config.human_model, crowd, orca, velocity)
        people = humans.with_values(config.human_model, people, human_values)
        orca, group = people.orca, people.group
        if kind in (*speed_model.VELOCITY_MODELS, "power_law"):
            velocity = getattr(people, humans.PARAMS_OF[kind])
    return Env(
        world=world,
        occupancy=grid,
        crowd=crowd,
        robot=robot,
        reward=reward,
        orca=orca,
        velocity=velocity,
        group=group,
        config=config,
        walking_groups=any(p.get("walks_with") is not None for p in spec.people),
        recorded=spec.recording is not None,
        routed=routes.may_route(spec.people, spec.walls_m),
    )


def episode_steps(timeout_s: float, dt_s: float, period_steps: int = 1) -> int:
    """Steps of an episode of ``timeout_s``, rounded up to whole periods of ``period_steps``."""
    return int(math.ceil(timeout_s / (dt_s * period_steps))) * period_steps
