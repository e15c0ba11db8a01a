"""The built-in methods as actors (:class:`jaxsim.scenes.actor.Actor`), and the simplest one.

:func:`stack_actor` turns a :class:`~planners.stack.StackConfig` (a cost layer, a global grid
planner at 1 Hz, a local planner at 10 Hz) into an actor (:func:`stack_parts` gives its pieces):
its ``plan`` draws the social layer from what the robot perceives, adds the seen people as
obstacles inflated with the walls and plans the global path; its ``act`` runs the local planner
on that path and a safety stop; :func:`jaxsim.actor.replanning` runs the plan before every tenth
action. The
map (occupancy, interaction spaces, walls) and every float of the robot and the layers are the
actor's ``params``, traced: another scene of the same shapes, another speed limit or another
GSCL checkpoint reuses the compiled program. The social layer is a
:class:`planners.layers.CostLayer`: the actor holds its function, its params carry the layer's
parameters (``StackParams.layer``).

:func:`go_to_goal` drives straight at the goal (a throughput baseline and the shape of a user's
own actor). :func:`with_stop_and_go` wraps any actor with seed 002's queueing stop-and-go.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from socialnav.jaxsim.params import PERSON_RADIUS_M
from socialnav.jaxsim.scenes import world as world_lib
from socialnav.jaxsim.scenes.actor import Actor, replanning
from socialnav.jaxsim.scenes.env import Observation
from socialnav.jaxsim.scenes.robot import RobotParams
from socialnav.planners import stack
from socialnav.planners.layers import CostLayer, costmap
from socialnav.planners.layers.scene import Scene


@struct.dataclass
class StackMap:
    """What a stack knows of the scene before it starts (M interaction spaces, K wall boxes).

    Attributes:
      occupancy: (H, W) float32 on the planner grid; walls_m: (K, 4) boxes (the band's
      clearance); objects_xy_m (M, 8, 2), objects_cost (M,), objects_valid (M,) bool.
    """

    occupancy: jax.Array
    walls_m: jax.Array
    objects_xy_m: jax.Array
    objects_cost: jax.Array
    objects_valid: jax.Array


# Nav2's default local costmap is a 3 m x 3 m rolling window (nav2_bringup's nav2_params.yaml):
# the people inside it are obstacles the controller avoids, whatever the global costmap holds.
LOCAL_COSTMAP_HALF_M = 1.5


@struct.dataclass
class StackParams:
    """A stack's dynamic inputs: the map, the robot's speed limit (m/s) and body radius used by
    the safety stop (m), the safety margin (m), a person's radius (m), the layers' and local
    planners' parameters (:class:`planners.stack.LayerParams`), ``layer``: the social layer's
    own parameters (``CostLayer.params``: the paper's numbers, the GSCL network's weights, ``()``
    for none) and ``people_are_obstacles`` () bool: whether the global planner
    sees the people as obstacles (a scene's ``people_in_global_plan``, :mod:`jaxsim.scenes.spec`;
    false: only the social layer shapes the path round them, but for the people inside
    ``local_costmap_half_m`` (m) of the robot along x and y, the rolling local costmap that Nav2's
    controller keeps clear of what its sensors see: 1.5 m, Nav2's default 3 m x 3 m window)."""

    map: StackMap
    max_speed_mps: jax.Array
    robot_radius_m: jax.Array
    safety_margin_m: jax.Array
    person_radius_m: jax.Array
    layers: stack.LayerParams
    layer: Any = ()
    people_are_obstacles: jax.Array = True
    local_costmap_half_m: jax.Array = LOCAL_COSTMAP_HALF_M


@struct.dataclass
class StackState:
    """path (L, 2) m, path_len () int32 (0: no plan yet), layer: the social layer's state
    (``CostLayer.init``: CASN's frozen points, ``()`` for the others),
    planner_velocity (P, 2) m/s (the velocity estimate of the previous control step, what the
    1 Hz planner sees), speed_gain () (the social band's factor; 1 otherwise)."""

    path: jax.Array
    path_len: jax.Array
    layer: Any
    planner_velocity: jax.Array
    speed_gain: jax.Array


def stack_map(objects, grid: costmap.GridSpec, occupancy, walls_m) -> StackMap:
    """The map of a scene: occupancy on ``grid``, the (padded) walls, and its interaction spaces
    (``objects``: ``(name, polygon, cost)`` each, :attr:`jaxsim.scenes.spec.SceneSpec.objects`)
    padded to a multiple of 4."""
    m = max(4, -(-len(objects) // 4) * 4)
    verts = np.zeros((m, 8, 2), np.float32)
    cost = np.zeros(m, np.float32)
    valid = np.zeros(m, bool)
    for k, (_, poly, c) in enumerate(objects):
        verts[k, : len(poly)] = poly
        verts[k, len(poly) :] = poly[-1]
        cost[k], valid[k] = c, True
    return StackMap(
        occupancy=jnp.asarray(occupancy, jnp.float32),
        walls_m=jnp.asarray(walls_m),
        objects_xy_m=jnp.asarray(verts),
        objects_cost=jnp.asarray(cost),
        objects_valid=jnp.asarray(valid),
    )


def stack_params(
    robot: RobotParams,
    map_: StackMap,
    safety_margin_m: float = 0.1,
    person_radius_m: float = PERSON_RADIUS_M,
    layer: CostLayer | None = None,
    layers: stack.LayerParams | None = None,
    method: stack.StackConfig | None = None,
    people_are_obstacles: bool = True,
) -> StackParams:
    """A stack's params for a robot of limits ``robot`` (an env's ``robot``) on ``map_``, among
    people of body ``person_radius_m`` (an env's ``config.person_radius_m``); ``layers`` default to
    ``method``'s (:func:`planners.stack.layer_params`); ``layer``: the stack's social layer, whose
    params these carry (default: ``method``'s from ``layers``, :func:`planners.stack.cost_layer`;
    without a method, NavFn's: none)."""
    if layers is None:
        layers = stack.layer_params(method) if method is not None else stack.LayerParams()
    if layer is None:
        layer = stack.cost_layer(method or stack.METHODS["navfn"], layers)
    return StackParams(
        layers=layers,
        map=map_,
        max_speed_mps=jnp.float32(robot.max_speed_mps),
        robot_radius_m=jnp.float32(robot.radius_m),
        safety_margin_m=jnp.float32(safety_margin_m),
        person_radius_m=jnp.float32(person_radius_m),
        layer=layer.params,
        people_are_obstacles=jnp.asarray(people_are_obstacles),
        local_costmap_half_m=jnp.float32(LOCAL_COSTMAP_HALF_M),
    )


def _scene(params: StackParams, obs: Observation, velocity) -> Scene:
    m = params.map
    return Scene(
        people_xy_m=obs.people_xy_m,
        people_heading_rad=obs.people_heading_rad,
        people_velocity_mps=velocity,
        people_valid=obs.people_visible,
        objects_xy_m=m.objects_xy_m,
        objects_cost=m.objects_cost,
        objects_valid=m.objects_valid,
        robot_xy_m=obs.robot_xy_m,
        robot_yaw_rad=obs.robot_yaw_rad,
        goal_xy_m=obs.goal_xy_m,
    )


class StackParts(NamedTuple):
    """A navigation stack's functions before :func:`jaxsim.actor.replanning` joins them:
    ``init(key, obs)``, ``plan(params, state, obs, key)`` (the layer and the global path),
    ``act(params, state, obs, key)`` (the local planner and the safety stop), the planning period
    ``every_steps`` (0: once) and the ``name``."""

    init: Callable
    plan: Callable
    act: Callable
    every_steps: int
    name: str


def stack_parts(
    method: stack.StackConfig,
    grid: costmap.GridSpec,
    robot_radius_m: float,
    replan_every_steps: int = 10,
    max_path_cells: int = 256,
    layer: CostLayer | None = None,
    name: str | None = None,
) -> StackParts:
    """A navigation stack's init, plan and act (:func:`stack_actor` joins them into an actor).

    Args:
      method: the stack (layer, global and local planner, replanning or not).
      grid: the planner grid (static: its shape and origin).
      robot_radius_m: the inscribed radius of the obstacle layer's inflation (static: it sets
        the inflation's kernel).
      replan_every_steps: the global planner's period (10: 1 Hz at 0.1 s); a stack with
        ``replan=False`` plans once.
      max_path_cells: the global path's length bound.
      layer: the social layer (:class:`planners.layers.CostLayer`; its function is the actor's,
        its parameters come with the actor's params, ``StackParams.layer``); default
        ``method``'s (:func:`planners.stack.cost_layer`; the gscl layer needs one given:
        ``layers.gscl(model)``).
    """
    if layer is None:
        if method.layer == "gscl":
            raise ValueError("method 'gscl' needs a trained GSCL model: layer=layers.gscl(model)")
        layer = stack.cost_layer(method)
    if layer.name != stack.layer_kind(method):
        raise ValueError(f"stack_actor: the stack's layer is {method.layer!r}, the layer given is {layer.name!r}")
    x_np, y_np = grid.cell_centres()
    max_len = max_path_cells + 1

    def init(key, obs: Observation) -> StackState:
        del key
        n = obs.people_visible.shape[-1]
        return StackState(
            path=jnp.zeros((max_len, 2), jnp.float32),
            path_len=jnp.int32(0),
            layer=layer.init(n),
            planner_velocity=jnp.zeros((n, 2), jnp.float32),
            speed_gain=jnp.float32(1.0),
        )

    def plan(params: StackParams, st: StackState, obs: Observation, key) -> StackState:
        del key
        x_m, y_m = jnp.asarray(x_np), jnp.asarray(y_np)
        occupancy = params.map.occupancy
        scene = _scene(params, obs, st.planner_velocity)
        social, layer_state = layer.apply(params.layer, scene, grid, st.layer, occupancy)
        # The people the sensors see are obstacles too (Nav2's obstacle layer), inflated with the
        # walls; where the scene leaves them to the social layer (people_are_obstacles false),
        # those inside the local costmap's window still are: the path the robot follows is the
        # one its controller would keep clear of them.
        pxy = obs.people_xy_m
        d = jnp.hypot(x_m[None] - pxy[:, 0, None, None], y_m[None] - pxy[:, 1, None, None])
        local = jnp.max(jnp.abs(pxy - obs.robot_xy_m), axis=-1) <= params.local_costmap_half_m
        seen = obs.people_visible & (params.people_are_obstacles | local)
        bodies = jnp.any((d <= params.person_radius_m) & seen[:, None, None], axis=0)
        # A social layer's lethal cells (the GSCL queue's U) are inflated with the walls, as Nav2's
        # inflation layer grows every lethal cell a layer before it wrote: uninflated, the robot's
        # centre fits between a person in line and the U's side.
        forbidden = social >= costmap.LETHAL
        occupied = jnp.maximum(jnp.maximum(occupancy, bodies), forbidden)
        obstacles = costmap.obstacle_layer(occupied, grid, float(robot_radius_m))
        costs = costmap.combine_max(obstacles, social)
        path, length, found = stack.global_plan(method, costs, obs.robot_xy_m, obs.goal_xy_m, grid, max_path_cells)
        # No path now (a person on the goal, say): keep the previous one; before any, a straight line.
        straight = jnp.linspace(0.0, 1.0, max_len)[:, None] * (obs.goal_xy_m - obs.robot_xy_m) + obs.robot_xy_m
        had = st.path_len > 0
        path = jnp.where(found, path, jnp.where(had, st.path, straight))
        length = jnp.where(found, length, jnp.where(had, st.path_len, max_len))
        return st.replace(path=path, path_len=length, layer=layer_state)

    def act(params: StackParams, st: StackState, obs: Observation, key):
        del key
        scene = _scene(params, obs, obs.people_velocity_mps)
        walls = params.map.walls_m
        person_r = params.person_radius_m

        def clearance(q):
            # Walls, then each seen person's body, one at a time in a fori_loop (elementwise over
            # the band's points, a program that does not grow with the people slots: see
            # world_lib.wall_clearance).
            def body(i, nearest):
                to_body = jnp.linalg.norm(q - obs.people_xy_m[i], axis=-1) - person_r
                return jnp.minimum(nearest, jnp.where(obs.people_visible[i], to_body, jnp.inf))

            return jax.lax.fori_loop(0, obs.people_xy_m.shape[0], body, world_lib.wall_clearance(q, walls))

        v, w, _, gain = stack.local_command(
            method,
            st.path,
            st.path_len,
            obs.robot_xy_m,
            obs.robot_yaw_rad,
            obs.robot_speed_mps,
            params.max_speed_mps,
            scene,
            clearance,
            params.layers.band,
            params.layers.pursuit,
            params.layers.snape,
        )
        v = jnp.where(safety_stop(params, obs), 0.0, v)
        action = jnp.stack([v, w]).astype(jnp.float32)
        return action, st.replace(planner_velocity=obs.people_velocity_mps, speed_gain=gain)

    every = replan_every_steps if method.replan else 0
    return StackParts(init=init, plan=plan, act=act, every_steps=every, name=name or method.layer)


def stack_actor(
    method: stack.StackConfig,
    grid: costmap.GridSpec,
    robot_radius_m: float,
    replan_every_steps: int = 10,
    max_path_cells: int = 256,
    layer: CostLayer | None = None,
    name: str | None = None,
) -> Actor:
    """A navigation stack as an actor: :func:`stack_parts`' ``act`` with its ``plan`` run before
    every ``replan_every_steps``-th action (:func:`jaxsim.actor.replanning`; a stack with
    ``replan=False`` plans before the first only). Arguments as :func:`stack_parts`."""
    parts = stack_parts(method, grid, robot_radius_m, replan_every_steps, max_path_cells, layer, name)
    return replanning(Actor(init=parts.init, act=parts.act, name=parts.name), parts.plan, parts.every_steps)


def safety_stop(params: StackParams, obs: Observation) -> jax.Array:
    """() bool: a visible person in front (within 60 deg of the heading) closer, centre to
    centre, than the bodies plus the safety margin: the base stops."""
    return person_ahead(obs, params.robot_radius_m + params.person_radius_m + params.safety_margin_m, 60.0)


STOP_AND_GO_CONE_DEG = (
    60.0  # "the next person in line": ahead within this angle of the heading (the safety stop's cone)
)


def person_ahead(obs: Observation, gap_m, cone_deg: float = STOP_AND_GO_CONE_DEG) -> jax.Array:
    """() bool: a visible person within ``cone_deg`` of the robot's heading and closer than
    ``gap_m``, centre to centre."""
    offset = obs.people_xy_m - obs.robot_xy_m
    dist = jnp.linalg.norm(offset, axis=-1)
    bearing = jnp.arctan2(offset[:, 1], offset[:, 0]) - obs.robot_yaw_rad
    in_front = jnp.cos(bearing) > np.cos(np.radians(cone_deg))
    return jnp.any(obs.people_visible & in_front & (dist < gap_m))


@functools.lru_cache(maxsize=64)
def with_stop_and_go(actor: Actor, gap_m: float, cone_deg: float = STOP_AND_GO_CONE_DEG) -> Actor:
    """``actor`` with seed 002's queueing stop-and-go (Sec. 4.3: "a simple stop-and-go mechanism
    based on the distance to the next person in line"): its forward speed is held at 0 while a
    seen person is ahead (:func:`person_ahead`) closer than ``gap_m``, and it goes on, as the
    actor commands, once the gap opens. Turning and backing off are left to the actor. Any actor
    (a stack, a reactive baseline, a policy, a user's own) keeps its params, state and plan; the
    wrapper is cached, so the same actor and gap give the same (compiled) actor. Scenes ask for
    it with ``stop_and_go_m`` (:mod:`jaxsim.scenes.spec`), and the arena wraps every method."""

    def act(params, st, obs: Observation, key):
        action, st = actor.act(params, st, obs, key)
        v = jnp.where(person_ahead(obs, gap_m, cone_deg), jnp.minimum(action[0], 0.0), action[0])
        return action.at[0].set(v), st

    return dataclasses.replace(actor, act=act, name=actor.name)


def go_to_goal(gain_turn: float = 2.0, name: str = "go_to_goal") -> Actor:
    """Drive towards the goal at the speed limit, turning at ``gain_turn`` x the heading error
    (rad/s per rad; the base clips both), slower the more it must turn: no planner, no people.
    Its ``params`` are the robot's limits (:class:`~jaxsim.scenes.robot.RobotParams`, the
    default params of an actor)."""

    def init(key, obs):
        del key, obs
        return ()

    def act(robot, st, obs, key):
        del key
        to_goal = obs.goal_xy_m - obs.robot_xy_m
        error = jnp.arctan2(to_goal[1], to_goal[0]) - obs.robot_yaw_rad
        error = jnp.arctan2(jnp.sin(error), jnp.cos(error))
        v = robot.max_speed_mps * jnp.clip(jnp.cos(error), 0.0, 1.0)
        return jnp.stack([v, gain_turn * error]).astype(jnp.float32), st

    return Actor(init=init, act=act, name=name)
