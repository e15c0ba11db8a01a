"""Reactive robot baselines as actors: a velocity rule (ORCA, the social force, DWA) that steers
towards a carrot on a global path.

The field's reactive baselines (CrowdNav's and social-jym's ORCA and social-force robots, DWA)
drive at the goal in open space. The arena's scenes have walls and corners, where a straight line
to the goal ends in a wall; so, as Nav2 feeds its DWB controller, each baseline here follows a
global path and steers towards its lookahead point, the *carrot* (``lookahead_m`` ahead, as pure
pursuit takes it). The path is the ``navfn`` stack's own (NavFn on the inflated walls and the
seen people, no social layer, replanned at 1 Hz: :func:`planners.actors.stack_actor`), so a
baseline differs from ``navfn`` only in what it does between the path and the wheels.
``guide="goal"`` drives at the goal itself, as CrowdNav's do (a choice, not the default: in an
L-shaped hallway it ends against the corner).

A rule is ``command(rule_params, ctx, observation, carrot_xy, dt_s) -> (v, omega)``:
:mod:`planners.reactive.orca_robot` and :mod:`planners.reactive.social_force_robot` find a velocity (2,) and track
it with :func:`track_velocity`; :mod:`planners.reactive.dwa` samples (v, omega) itself.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import jax.numpy as jnp
from flax import struct

from socialnav.jaxsim.scenes.actor import Actor, replanning
from socialnav.jaxsim.scenes.env import Observation
from socialnav.jaxsim.scenes.robot import RobotParams
from socialnav.planners import actors, stack
from socialnav.planners.layers import costmap
from socialnav.planners.layers.scene import wrap_angle
from socialnav.planners.local import pure_pursuit

GUIDES = ("path", "goal")


@struct.dataclass
class ReactiveParams:
    """A reactive baseline's dynamic inputs.

    Attributes:
      guide: the global path's inputs (:class:`planners.actors.StackParams`: the map, the walls
        ``guide.map.walls_m`` (K, 4), the person radius).
      robot: the base's limits (:class:`jaxsim.scenes.robot.RobotParams`: speed, turn rate,
        accelerations, radius).
      rule: the rule's own parameters.
      lookahead_m: the carrot's distance along the path (m).
      turn_gain: omega per radian of heading error when tracking a velocity (1/s; pure
        pursuit's 1.5).
      align_rad: beyond this heading error the base turns on the spot (pure pursuit's 60 deg).
    """

    guide: actors.StackParams
    robot: RobotParams
    rule: Any
    lookahead_m: float = 1.0
    turn_gain: float = 1.5
    align_rad: float = 1.0472


Rule = Callable[[Any, ReactiveParams, Observation, Any, float], tuple[Any, Any]]


def track_velocity(velocity_mps, robot_yaw_rad, ctx: ReactiveParams):
    """``(v, omega)`` of a unicycle following a planar ``velocity_mps`` (2,): turn towards it at
    ``turn_gain`` x the heading error, drive at its speed times the cosine of the error, and not
    at all beyond ``align_rad`` (the holonomic rules' velocities on a differential base, as
    CrowdNav's unicycle robot takes them)."""
    speed = jnp.linalg.norm(velocity_mps)
    error = wrap_angle(jnp.arctan2(velocity_mps[1], velocity_mps[0]) - robot_yaw_rad)
    error = jnp.where(speed > 1e-6, error, 0.0)
    v = speed * jnp.where(jnp.abs(error) < ctx.align_rad, jnp.cos(error), 0.0)
    return v, ctx.turn_gain * error


def preferred_velocity(obs: Observation, carrot_xy, ctx: ReactiveParams):
    """(2,) m/s: towards the carrot at the speed limit. No slowing down onto the goal: the env
    stops the base within the goal tolerance, and a rule that slows (RVO2's examples, pure
    pursuit) lets a standing person's push balance it short of the goal (measured: the social
    force robot stalled 0.4 m short in half of ``snape_static_table_fridge``)."""
    to_carrot = carrot_xy - obs.robot_xy_m
    dist = jnp.linalg.norm(to_carrot)
    return to_carrot / jnp.maximum(dist, 1e-9) * ctx.robot.max_speed_mps


def reactive_actor(
    rule: Rule,
    name: str,
    grid: costmap.GridSpec,
    robot_radius_m: float,
    dt_s: float = 0.1,
    replan_every_steps: int = 10,
    max_path_cells: int = 256,
    guide: str = "path",
) -> Actor:
    """A reactive rule as an actor: the ``navfn`` stack's path (``guide="path"``) or the goal
    (``"goal"``) gives the carrot, ``rule`` the command. Its params are :class:`ReactiveParams`.

    Args:
      rule: ``command(rule_params, ctx, observation, carrot_xy, dt_s) -> (v, omega)``.
      grid, robot_radius_m, replan_every_steps, max_path_cells: the guide's planner (static),
        as :func:`planners.actors.stack_actor`.
      dt_s: the control step the rule predicts with (the env's).
    """
    if guide not in GUIDES:
        raise ValueError(f"guide must be one of {', '.join(GUIDES)}, got {guide!r}")
    path_stack = actors.stack_parts(stack.METHODS["navfn"], grid, robot_radius_m, replan_every_steps, max_path_cells)

    def plan(params: ReactiveParams, st, obs, key):
        return path_stack.plan(params.guide, st, obs, key)

    def act(params: ReactiveParams, st, obs: Observation, key):
        del key
        if guide == "path":
            carrot = pure_pursuit.lookahead_point(st.path, st.path_len, obs.robot_xy_m, params.lookahead_m)
        else:
            carrot = obs.goal_xy_m
        v, w = rule(params.rule, params, obs, carrot, dt_s)
        action = jnp.stack([v, w]).astype(jnp.float32)
        return action, st.replace(planner_velocity=obs.people_velocity_mps)

    if guide == "goal":
        return Actor(init=path_stack.init, act=act, name=name)
    return replanning(Actor(init=path_stack.init, act=act, name=name), plan, path_stack.every_steps)
