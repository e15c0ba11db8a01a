"""The reactive baselines by name: ``orca``, ``social_force``, ``dwa`` (:mod:`planners.reactive.actor`).

:data:`BASELINES` maps a name to its rule and its default parameters, which depend on the
environment (the social-force robot takes the env's crowd constants). :func:`baseline_actor` makes
the actor, :func:`baseline_params` its :class:`~planners.reactive.actor.ReactiveParams`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

from socialnav.jaxsim.scenes.env import Env
from socialnav.planners import actors
from socialnav.planners.layers import costmap
from socialnav.planners.reactive import actor as reactive
from socialnav.planners.reactive import dwa, orca_robot, social_force_robot


@dataclasses.dataclass(frozen=True)
class Baseline:
    """A reactive rule and its default parameters ``(env) -> rule params``; ``source`` says
    where the defaults come from."""

    rule: reactive.Rule
    default_params: Callable[[Env], Any]
    source: str


BASELINES: dict[str, Baseline] = {
    "orca": Baseline(
        orca_robot.command,
        lambda env: orca_robot.ORCARobotParams(),
        "van den Berg et al. 2011; defaults of CrowdNav's ORCA policy",
    ),
    "social_force": Baseline(
        social_force_robot.command,
        lambda env: social_force_robot.SocialForceRobotParams(crowd=env.crowd),
        "the people's own social force (pedsim, Moussaid et al. 2009; the warehouse's constants)",
    ),
    "dwa": Baseline(dwa.command, lambda env: dwa.DWAParams(), "Fox, Burgard and Thrun 1997"),
}


def baseline_actor(
    name: str,
    grid: costmap.GridSpec,
    robot_radius_m: float,
    dt_s: float = 0.1,
    replan_every_steps: int = 10,
    max_path_cells: int = 256,
    guide: str = "path",
):
    """The actor of baseline ``name`` (:func:`planners.reactive.actor.reactive_actor`)."""
    if name not in BASELINES:
        raise ValueError(f"unknown baseline {name!r} (known: {', '.join(BASELINES)})")
    rule = BASELINES[name].rule
    return reactive.reactive_actor(rule, name, grid, robot_radius_m, dt_s, replan_every_steps, max_path_cells, guide)


def baseline_params(
    name: str,
    env: Env,
    map_: actors.StackMap,
    rule_params=None,
    safety_margin_m: float = 0.1,
    people_are_obstacles: bool = True,
) -> reactive.ReactiveParams:
    """A baseline's params in ``env`` on ``map_`` (``rule_params`` default: the baseline's);
    ``people_are_obstacles``: whether its guiding path plans round the seen people."""
    rule_params = BASELINES[name].default_params(env) if rule_params is None else rule_params
    guide = actors.stack_params(
        env.robot, map_, safety_margin_m, env.config.person_radius_m, people_are_obstacles=people_are_obstacles
    )
    return reactive.ReactiveParams(guide=guide, robot=env.robot, rule=rule_params)
