"""The social-navigation arena: a scene's people and a robot driven by an actor, in closed loop,
as batched JAX episodes.

An episode is :func:`jaxsim.scenes.actor.rollout`: the environment (:mod:`jaxsim.scenes.env`:
the people's social force, the robot's base, its perception) stepped by an actor's actions. The
built-in methods are actors made from their stacks (:func:`planners.actors.stack_actor`: the
social layer and global planner at 1 Hz, the local planner at 10 Hz); a user's own actor runs
the same way (:func:`actor_function`). The physics knows nothing of stacks or metrics.
:func:`episode_function` vmaps episodes over a scene's variants; the methods are separate
programs, run at the same time on the host devices, one per core (:func:`run_spread`).

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
from collections.abc import Callable, Iterator, Mapping
from concurrent.futures import ThreadPoolExecutor

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from socialnav.data import WAREHOUSE_DIR
from socialnav.jaxsim.actor import inner_state
from socialnav.jaxsim.params import SimParams
from socialnav.jaxsim.scenario.loader import load_scenario
from socialnav.jaxsim.scenes import env as env_lib
from socialnav.jaxsim.scenes import robot as robot_lib
from socialnav.jaxsim.scenes import world as world_lib
from socialnav.jaxsim.scenes.actor import Actor, rollout
from socialnav.jaxsim.scenes.reachable import refuse_unfinishable
from socialnav.jaxsim.scenes.spec import SceneSpec
from socialnav.jaxsim.scenes.variant import Variant, padded_slots
from socialnav.planners import actors, stack
from socialnav.planners.layers import CostLayer, costmap
from socialnav.planners.layers.scene import Scene
from socialnav.planners.learning import policy_social
from socialnav.planners.reactive import baselines


@dataclasses.dataclass(frozen=True)
class ArenaConfig:
    """Static settings of the episodes: the environment's own (``env``) and the arena's.

    Each quantity has one home: the step, the goal tolerance, a person's body and the human model
    are the environment's (:class:`jaxsim.scenes.env.EnvConfig`, read here as ``config.env.dt_s``
    and so on); what only the arena's stacks use is here.

    Attributes:
      env: the environment's settings; its ``max_steps`` is set per scene from the scene's
        timeout (whole replanning periods), whatever it holds here.
      replan_every_steps: global replanning period in steps (10: 1 Hz, seed 002's behaviour tree).
      grid_resolution_m: the global planner's cell size.
      safety_margin_m: the base stops when a visible person in front (within 60 deg) is closer
        than robot radius + person radius + this margin.
      max_path_cells: the global path's length bound in cells.
    """

    env: env_lib.EnvConfig = env_lib.EnvConfig()
    replan_every_steps: int = 10
    grid_resolution_m: float = 0.2
    safety_margin_m: float = 0.1
    max_path_cells: int = 256

    @classmethod
    def of(cls, human_model: str = "social_force", **arena) -> ArenaConfig:
        """The default settings with the people moved by ``human_model``
        (:data:`jaxsim.scenes.people.HUMAN_MODELS`) and ``arena`` the arena's own fields."""
        return cls(env=env_lib.EnvConfig(human_model=human_model), **arena)


# The look-ahead of the trajectory's predicted distance to the nearest seen person (the pictures'
# and the social band's horizon, seed 004 Sec. 3.3).
PREDICTION_HORIZON_S = 2.0


@struct.dataclass
class Trajectory:
    """One episode's record, T steps (a batch adds a leading axis).

    Attributes:
      robot_xy_m (T, 2), robot_yaw_rad (T,), robot_speed_mps (T,); people_xy_m (T, P, 2),
      people_heading_rad (T, P),
      people_present (T, P), people_visible (T, P); reached (T,) bool (the goal has been reached by
      then); speed_gain (T,) the local planner's speed factor (1 without one); predicted_distance_m
      (T,) nearest person's predicted distance to the robot 2 s ahead; wall_contacts () int32;
      invalid_actions () int32 the steps whose action had a NaN or infinite entry (the base was
      stopped instead: :meth:`jaxsim.scenes.env.Env.step`).
    """

    robot_xy_m: jnp.ndarray
    robot_yaw_rad: jnp.ndarray
    robot_speed_mps: jnp.ndarray
    people_xy_m: jnp.ndarray
    people_heading_rad: jnp.ndarray
    people_present: jnp.ndarray
    people_visible: jnp.ndarray
    reached: jnp.ndarray
    speed_gain: jnp.ndarray
    predicted_distance_m: jnp.ndarray
    wall_contacts: jnp.ndarray
    invalid_actions: jnp.ndarray


@dataclasses.dataclass(frozen=True)
class SceneSetup:
    """What an episode needs of a scene, built once on the host (:func:`setup_scene`).

    Attributes:
      spec: the scene.
      grid: the planner grid (static).
      env: the scene as an environment (:class:`socialnav.jaxsim.scenes.env.Env`, its walls padded).
      map: what a stack knows of it (:class:`socialnav.planners.actors.StackMap`).
      obstacle_costs: (H, W) the walls' inflated layer on ``grid``.
      n_periods: replanning periods per episode.
      n_slots: people slots the variants are padded to.
      program_key: what picks the scene's compiled programs: its grid, its env's structure and
        array shapes, its people slots and episode length (a scene and its held-out mirror, or a
        recording's replayed and reactive scenes, share one; :func:`release_programs_if_crowded`).
    """

    spec: SceneSpec
    grid: costmap.GridSpec
    env: env_lib.Env
    map: actors.StackMap
    obstacle_costs: np.ndarray
    n_periods: int
    n_slots: int
    program_key: tuple

    @property
    def world(self) -> world_lib.SceneWorld:
        return self.env.world

    @property
    def occupancy(self) -> np.ndarray:
        return np.asarray(self.map.occupancy)


def crowd_params() -> SimParams:
    """The warehouse's social force constants (the arena's people are the same walkers)."""
    return load_scenario(WAREHOUSE_DIR).params


def setup_scene(
    spec: SceneSpec,
    config: ArenaConfig = ArenaConfig(),
    robot: robot_lib.RobotParams = robot_lib.RobotParams(),
    crowd: SimParams | None = None,
    reward: env_lib.RewardParams = env_lib.RewardParams(),
    human_values: Mapping[str, float] | None = None,
) -> SceneSetup:
    """Everything a scene's episodes share, with ``robot``, its people's constants set by
    ``human_values`` (a calibration's fit, :func:`jaxsim.scenes.env.make_env`). Raises
    :class:`~jaxsim.scenario.errors.ScenarioError` for a scene no method can finish with that
    robot (:func:`jaxsim.scenes.reachable.scene_problem`)."""
    refuse_unfinishable(spec, robot, config.env.goal_tolerance_m)
    period_s = config.env.dt_s * config.replan_every_steps
    n_periods = int(math.ceil(spec.timeout_s / period_s))
    env_config = dataclasses.replace(config.env, max_steps=n_periods * config.replan_every_steps)
    crowd = crowd_params() if crowd is None else crowd
    env = env_lib.make_env(spec, env_config, robot, crowd, reward, config.grid_resolution_m, human_values=human_values)
    occ = np.asarray(env.occupancy.values)
    grid = env.occupancy.spec
    obstacles = np.asarray(costmap.obstacle_layer(occ, grid, float(robot.radius_m)))
    n_slots = padded_slots(spec.n_people_slots)
    leaves, structure = jax.tree_util.tree_flatten(env)
    return SceneSetup(
        spec=spec,
        grid=grid,
        env=env,
        map=actors.stack_map(spec.objects, grid, occ, env.world.walls_m),
        obstacle_costs=obstacles,
        n_periods=n_periods,
        n_slots=n_slots,
        program_key=(grid, n_slots, n_periods, structure, tuple(np.shape(leaf) for leaf in leaves)),
    )


def planner_scene(setup: SceneSetup, variant: Variant, time_s: float = 0.0, perceived: bool = False) -> Scene:
    """The planner's :class:`~socialnav.planners.layers.scene.Scene` of one variant of a scene at
    ``time_s`` (the people walked by the crowd model with the robot standing at its start).

    ``perceived=False`` gives the truth: every person present, with their true velocity and
    heading. ``perceived=True`` gives what the robot's sensors report (people in range and in
    line of sight, velocities estimated from their tracks: zero at time 0), as the stacks see it.
    The scene's objects (SNAPE's interaction spaces) come from the scene file either way.
    ``variant``: one draw (:func:`socialnav.jaxsim.scenes.variant.sample_variant`, padded to
    ``setup.n_slots`` people or not)."""
    env = setup.env
    variant = jax.tree_util.tree_map(jnp.asarray, variant)
    state, timestep = env.reset(episode_key(variant), variant)
    steps = int(round(time_s / env.config.dt_s))
    if steps:  # the robot stands (action 0) while the crowd walks: one scan, not a Python loop
        stand = lambda carry, _: (env.step(carry[0], jnp.zeros(2, jnp.float32)), None)
        state, timestep = jax.jit(lambda c: jax.lax.scan(stand, c, None, length=steps)[0])((state, timestep))
    objects = dict(
        objects_xy_m=setup.map.objects_xy_m, objects_cost=setup.map.objects_cost, objects_valid=setup.map.objects_valid
    )
    if perceived:
        return policy_social.perceived_scene(timestep.observation).replace(**objects)
    return Scene(
        people_xy_m=state.people.xy,
        people_heading_rad=state.people.heading,
        people_velocity_mps=state.people.velocity,
        people_valid=state.people.present,
        robot_xy_m=state.robot.xy,
        robot_yaw_rad=state.robot.yaw,
        goal_xy_m=variant.goal_xy,
        **objects,
    )


def scene_from_file(
    file, variant: int = 0, seed: int = 0, time_s: float = 0.0, perceived: bool = False, held_out: bool = False
) -> tuple[Scene, SceneSetup]:
    """A scene file's variant ``variant`` (drawn under ``seed``, as ``socialnav arena --seed`` draws
    it) as the planner's :class:`~socialnav.planners.layers.scene.Scene`, with the scene's
    :class:`SceneSetup` (its planner ``grid``, ``occupancy`` and environment). ``time_s``,
    ``perceived``: as :func:`planner_scene`; ``held_out``: the arena's held-out row (the scene
    mirrored, the variant drawn just outside the file's ranges). Raises ``ValueError`` naming the
    file and field for a bad file, and for a negative variant or time."""
    from socialnav.jaxsim.scenes.spec import load_scene, mirror
    from socialnav.jaxsim.scenes.variant import sample_variant

    if int(variant) != variant or variant < 0 or not time_s >= 0:
        raise ValueError(f"scene_from_file: variant must be an integer >= 0 and time_s >= 0, got {variant}, {time_s}")
    spec = load_scene(file)
    spec = mirror(spec) if held_out else spec
    setup = setup_scene(spec)
    draw = sample_variant(spec, seed, variant, held_out=held_out, n_slots=setup.n_slots)
    return planner_scene(setup, draw, time_s, perceived), setup


def _record(seen: env_lib.Observation, action, actor_state, timestep: env_lib.TimeStep):
    """One step of a :class:`Trajectory` (before stacking)."""
    o, info = timestep.observation, timestep.info
    # The nearest seen person's predicted distance PREDICTION_HORIZON_S ahead, from what the actor saw.
    heading = jnp.stack([jnp.cos(seen.robot_yaw_rad), jnp.sin(seen.robot_yaw_rad)])
    ahead = seen.robot_xy_m + PREDICTION_HORIZON_S * seen.robot_speed_mps * heading
    predicted = seen.people_xy_m + PREDICTION_HORIZON_S * seen.people_velocity_mps
    pred_d = jnp.min(jnp.where(seen.people_visible, jnp.linalg.norm(predicted - ahead, axis=-1), jnp.inf))
    gain = getattr(inner_state(actor_state), "speed_gain", jnp.float32(1.0))
    return (
        o.robot_xy_m,
        o.robot_yaw_rad,
        o.robot_speed_mps,
        info.people_xy_m,
        info.people_heading_rad,
        info.people_present,
        seen.people_visible,
        info.reached,
        jnp.asarray(gain, jnp.float32),
        pred_d,
        info.invalid_action,
    )


def episode_key(variant: Variant) -> jax.Array:
    """The actor's and the env's key of a variant: from its own seed, so a variant's episode is
    the same alone and in any batch, and the same for every method (common random numbers)."""
    return jax.random.fold_in(jax.random.key(0), variant.seed_u32)


def trajectory_of(records: tuple, wall_contacts) -> Trajectory:
    """One episode's :class:`Trajectory` from its rollout's stacked records (:func:`_record`'s)
    and the base's count of wall contacts at its end."""
    robot_xy, yaw, speed, pxy, pheading, present, seen, reached, gain, pred_d, invalid = records
    return Trajectory(
        robot_xy_m=robot_xy,
        robot_yaw_rad=yaw,
        robot_speed_mps=speed,
        people_xy_m=pxy,
        people_heading_rad=pheading,
        people_present=present,
        people_visible=seen,
        reached=reached,
        speed_gain=gain,
        predicted_distance_m=pred_d,
        wall_contacts=wall_contacts,
        invalid_actions=jnp.sum(invalid, dtype=jnp.int32),
    )


# Episodes run in batches of a multiple of this many (see _episode_program).
LANES = 8


@functools.lru_cache(maxsize=64)
def _episode_program(actor: Actor):
    """``(env, params, variants) -> Trajectory``, jitted, vmapped over variants (each episode
    :func:`jaxsim.scenes.actor.rollout` with the arena's record, :func:`trajectory_of`); one per actor
    (the env's and the params' arrays are arguments: scenes of equal padded shapes and every
    value of a parameter share its compilations)."""

    def batch(env, params, variants):
        # The batch is padded to a multiple of LANES with copies of its last variant (their
        # episodes dropped): XLA vectorises a vmap differently at different sizes, and unpadded a
        # variant's people drifted by float rounding between batches of 1, 4 and 8 (a one-element
        # vmap is even compiled as the unbatched program). Padded, a variant has the same bits
        # alone and in batches of 1-100 for the go-to-goal actor, NavFn and DWA (tested; measured
        # on AVX2), but not for every method: ORCA, SNL and SNAPE's bands differ by rounding
        # between batches of 104 and 56 lanes, which the closed loop grows (casn_head_on, 100
        # variants: SNL matched in 3 of them by up to 0.25 m, the social band in 99 by up to
        # 4 cm). Every episode in a lax.map of 8-lane chunks gives the same bits for every
        # method in any batch, but costs 28-90 % more time (gscl_group, 100 variants; the band
        # alone no dearer), so it is not done.
        n = jax.tree_util.tree_leaves(variants)[0].shape[0]
        padded = -(-n // LANES) * LANES
        grown = jax.tree_util.tree_map(lambda a: jnp.concatenate([a, jnp.repeat(a[-1:], padded - n, 0)]), variants)

        def episode(variant):  # under the variant's own key (episode_key): the same in any batch
            (state, _), records = rollout(env, actor, params, variant, episode_key(variant), record=_record)
            return trajectory_of(records, state.robot.wall_contacts)

        out = jax.vmap(episode)(grown)
        return jax.tree_util.tree_map(lambda a: a[:n], out)

    return jax.jit(batch)


def _call_on(function: Callable, variants: Variant, device, home):
    """``function(variants)`` run on ``device``, waited for and on ``home``; on ``home`` itself
    the inputs stay uncommitted (the default device, as a call without threads)."""
    if device == home:
        return jax.block_until_ready(function(variants))
    return jax.device_put(jax.block_until_ready(function(jax.device_put(variants, device))), home)


def run_spread(functions: list[Callable], variants: Variant, n_devices: int | None = None) -> Iterator:
    """``function(variants)`` for each of ``functions`` (``variants -> Trajectory``, as
    :func:`actor_function` gives), yielded in order, the functions spread over ``n_devices`` host
    devices (default: every local one; ``socialnav`` asks XLA for one per core,
    :func:`socialnav.runtime.request_host_devices`) that run at the same time, one thread each.

    The functions' programs (an :func:`actor_function`'s jitted episode program; any other
    function is its own) are dealt to the devices in turn, in order of first appearance, and a
    function runs on its program's device: a method keeps its device from scene to scene, and
    methods sharing a program (the SNL variants, :func:`planners.stack.program_config`) compile
    it once. An episode program runs mostly on one core; two
    methods on two cores, one compiling while the other runs, took the full table (28,000
    episodes, 2 cores) from 14.4 to 12.6 min, the same episodes bit for bit. A program gives
    the same bits on every device (the same compiled code; tested). Every result is on the first
    device. With one device the functions run one after the other in the calling thread."""
    devices = jax.local_devices()[: max(1, n_devices or jax.local_device_count())]
    if len(devices) == 1:
        for function in functions:
            yield function(variants)
        return
    pools = [ThreadPoolExecutor(1, thread_name_prefix=f"arena-device-{d.id}") for d in devices]
    try:
        futures = []
        dealt = {}  # program -> device index
        for function in functions:
            k = dealt.setdefault(getattr(function, "func", function), len(dealt) % len(devices))
            futures.append(pools[k].submit(_call_on, function, variants, devices[k], devices[0]))
        for future in futures:
            yield future.result()
    finally:
        for pool in pools:
            pool.shutdown(wait=True, cancel_futures=True)


def method_actor(
    method: stack.StackConfig,
    grid: costmap.GridSpec,
    robot_radius_m: float,
    config: ArenaConfig = ArenaConfig(),
    layer: CostLayer | None = None,
) -> Actor:
    """A built-in stack as an actor with its social ``layer`` (default: the method's,
    :func:`planners.stack.cost_layer`), cached: the same stack with the same kind of layer on the
    same grid is the same actor, so its compiled program is reused (the layer's parameters come
    with the actor's params, not with the actor)."""
    layer = stack.cost_layer(method) if layer is None else layer
    return _method_actor(method, grid, robot_radius_m, config, layer.replace(()))


@functools.lru_cache(maxsize=64)
def _method_actor(method, grid, robot_radius_m, config, layer) -> Actor:
    return actors.stack_actor(
        method, grid, robot_radius_m, config.replan_every_steps, config.max_path_cells, layer, name=method.layer
    )


def _replaced(crowd: SimParams | None, robot_params: robot_lib.RobotParams | None) -> dict:
    """The env fields a caller gives instead of the scene's own (None: the scene's)."""
    return {name: value for name, value in (("crowd", crowd), ("robot", robot_params)) if value is not None}


def actor_function(setup: SceneSetup, actor: Actor, params, env: env_lib.Env | None = None):
    """``variants (batched Variant, padded to ``setup.n_slots``) -> Trajectory (batched)`` for
    any actor with its ``params``. In a scene with ``stop_and_go_m`` (the queue) the actor runs
    with the stop-and-go (:func:`planners.actors.with_stop_and_go`), whatever it is, so every
    method of the scene has it."""
    if setup.spec.stop_and_go_m is not None:
        actor = actors.with_stop_and_go(actor, float(setup.spec.stop_and_go_m))
    program = _episode_program(actor)
    return functools.partial(program, setup.env if env is None else env, params)


def episode_function(
    setup: SceneSetup,
    method: stack.StackConfig,
    crowd: SimParams | None = None,
    robot_params: robot_lib.RobotParams | None = None,
    config: ArenaConfig = ArenaConfig(),
    gscl_model=None,
    layers: stack.LayerParams | None = None,
):
    """``variants -> Trajectory`` of a built-in stack. ``gscl_model``: the gscl layer's network
    (:func:`planners.layers.gscl`: a :class:`~socialnav.models.inference.SocialCostModel`, whose
    weights enter the program traced, so another checkpoint reuses it; or a function of the maps,
    closing over its weights). ``layers``: the layers' and local planners' parameters (default:
    the method's, :func:`planners.stack.layer_params`), traced: a sweep reuses the program.
    ``crowd`` and ``robot_params``: the people's constants and the robot's limits (default: the
    scene's env's, :func:`setup_scene`)."""
    env = setup.env.replace(**_replaced(crowd, robot_params))
    robot_params = env.robot
    layer = stack.cost_layer(method, layers, gscl_model)  # both default to the method's layers
    actor = method_actor(stack.program_config(method), setup.grid, float(robot_params.radius_m), config, layer)
    params = actors.stack_params(
        robot_params,
        setup.map,
        config.safety_margin_m,
        config.env.person_radius_m,
        layer,
        layers,
        method,
        people_are_obstacles=setup.spec.people_in_global_plan,
    )
    return actor_function(setup, actor, params, env)


# Each compiled episode program holds 400-950 of the process's memory maps (XLA's CPU backend
# maps its code sections one by one; measured on hotel_replayed: NavFn 535, SNAPE's social band
# 937), and Linux gives a process at most vm.max_map_count of them (65,530 by default): past it
# LLVM aborts the process ("Unable to allocate section memory"). The recorded-crowd table (14
# scenes of 13 programs each, as it then was) hit it after 10 minutes. Before a scene the arena drops
# every compiled program once the process holds more than this share of its limit
# (:func:`release_programs_if_crowded`); a dropped program compiles again to the same code.
MAP_SHARE_BEFORE_RELEASE = 0.5


def memory_maps() -> tuple[int, int] | None:
    """``(maps held, the limit)`` of this process on Linux; None elsewhere."""
    try:
        with open("/proc/self/maps", "rb") as maps:
            held = sum(1 for _ in maps)
        with open("/proc/sys/vm/max_map_count") as limit:
            return held, int(limit.read())
    except (OSError, ValueError):
        return None


_previous_key: list = [None]  # the program key of the scene run last (release_programs_if_crowded)


def release_programs_if_crowded(share: float = MAP_SHARE_BEFORE_RELEASE, caches=(), key=None) -> bool:
    """Drop every compiled program (JAX's caches, the arena's actor and program caches and the
    ``functools.lru_cache`` caches in ``caches``) when the process holds more than ``share`` of its
    memory-map limit (:func:`memory_maps`); True if it did. A ``key`` (:attr:`SceneSetup.program_key`) equal
    to the previous call's keeps them: the next scene runs the same programs. The programs compile
    again when next called, to the same code (tested bit for bit)."""
    previous, _previous_key[0] = _previous_key[0], key
    if key is not None and key == previous:
        return False
    maps = memory_maps()
    if maps is None or maps[0] <= share * maps[1]:
        return False
    jax.clear_caches()
    for cache in (_episode_program, _method_actor, baseline_actor, actors.with_stop_and_go, *caches):
        cache.cache_clear()
    return True


@functools.lru_cache(maxsize=64)
def baseline_actor(name: str, grid: costmap.GridSpec, robot_radius_m: float, config: ArenaConfig = ArenaConfig()):
    """A reactive baseline (:data:`planners.reactive.baselines.BASELINES`) as an actor (cached as
    :func:`method_actor`)."""
    return baselines.baseline_actor(
        name, grid, robot_radius_m, config.env.dt_s, config.replan_every_steps, config.max_path_cells
    )


def baseline_function(
    setup: SceneSetup,
    name: str,
    crowd: SimParams | None = None,
    robot_params: robot_lib.RobotParams | None = None,
    config: ArenaConfig = ArenaConfig(),
    rule_params=None,
):
    """``variants -> Trajectory`` of a reactive baseline (``orca``, ``social_force``, ``dwa``);
    ``rule_params`` (default: the baseline's) are traced. ``crowd`` and ``robot_params``: the
    people's constants and the robot's limits (default: the scene's env's, :func:`setup_scene`)."""
    env = setup.env.replace(**_replaced(crowd, robot_params))
    robot_params = env.robot
    actor = baseline_actor(name, setup.grid, float(robot_params.radius_m), config)
    params = baselines.baseline_params(
        name, env, setup.map, rule_params, config.safety_margin_m, setup.spec.people_in_global_plan
    )
    return actor_function(setup, actor, params, env)


def _stand_init(key, observation):
    del key, observation
    return ()


def _stand_act(params, state, observation, key):
    del params, observation, key
    return jnp.zeros(2, jnp.float32), state


# The robot of the counterfactual run: it stands where it starts, far away (:func:`without_robot`).
STAND_STILL = Actor(init=_stand_init, act=_stand_act, name="stand_still")


# Where the counterfactual's robot stands: so far that its social force is exactly 0 in float32
# (exp(-d / B) underflows) and it is nobody's ORCA neighbour.
FAR_AWAY_M = 1.0e4


def without_robot(variants: Variant) -> Variant:
    """The same variants with the robot standing :data:`FAR_AWAY_M` away: the crowd as it would
    move without it (the same draws and random-force stream: common random numbers). Not by
    ``ignore_robot``: that takes the robot's force out by a subtraction, whose rounding (1e-7 m)
    a crowd's chaotic dynamics grew to 3 cm of mean deviation in every method's rows alike; a
    robot whose force is exactly 0 adds nothing, bit for bit (tested)."""
    far = jnp.full_like(variants.robot_xy, FAR_AWAY_M)
    return variants.replace(robot_xy=far)


def counterfactual_function(setup: SceneSetup, crowd: SimParams | None = None):
    """``variants -> Trajectory`` of the people without the robot (:func:`without_robot`)."""
    run = actor_function(setup, STAND_STILL, (), setup.env.replace(**_replaced(crowd, None)))
    return lambda variants: run(without_robot(variants))
