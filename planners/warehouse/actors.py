"""Seed 000's causal planner as a warehouse actor (:class:`jaxsim.actor.Actor`): it follows the
causal plan's routes (Eq. 8-9, :func:`planners.warehouse.routes.plan_from_costs`) like the route follower,
and on a task's first step answers ``recharge`` when Eq. (10) refuses the task: the battery left
after the route's predicted cost ``C_L`` would fall below ``B_min``
(:func:`planners.warehouse.waypoint.refuse_task`). The protocol (:mod:`evaluation.protocol`) then resets
the battery before the task, as the paper's robot recharged; the day simulation ignores it.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from socialnav.jaxsim.actor import Actor, Driver
from socialnav.jaxsim.robot import WarehouseObservation
from socialnav.jaxsim.route_follower import RouteParams, RouteState, route_follower_actor, route_params
from socialnav.jaxsim.state import TASK
from socialnav.jaxsim.world import RobotPlan, World
from socialnav.planners.warehouse.waypoint import MIN_BATTERY_PCT, refuse_task


@struct.dataclass
class CausalParams:
    """route: the follower's params (the causal plan); battery_cost_pct: (S, W, W) the predicted
    battery use ``C_L`` of each planned route; min_battery_pct: () ``B_min``."""

    route: RouteParams
    battery_cost_pct: jax.Array
    min_battery_pct: jax.Array


@functools.lru_cache(maxsize=16)
def causal_planner_actor(route_len: int) -> Actor:
    """The causal planner for routes of ``route_len`` entries (params: :class:`CausalParams`)."""
    follower = route_follower_actor(route_len)

    def act(params: CausalParams, state: RouteState, obs: WarehouseObservation, key: jax.Array):
        r = obs.robot
        new_leg = r.legs_started != state.leg
        command, state = follower.act(params.route, state, obs, key)
        cost = params.battery_cost_pct[r.leg_slot, r.leg_start_wp, r.goal_wp]
        refuse = new_leg & (r.mode == TASK) & refuse_task(r.battery_pct, cost, params.min_battery_pct)
        return command.replace(recharge=refuse), state

    return Actor(init=follower.init, act=act, name="causal_planner")


def causal_planner(
    plan: RobotPlan, world: World, battery_cost_pct: np.ndarray, min_battery_pct: float = MIN_BATTERY_PCT
) -> Driver:
    """The causal method's driver: ``plan``'s routes, refusing tasks by Eq. (10).

    Args:
      battery_cost_pct: (S, W, W) ``C_L`` of each route of ``plan``
        (:func:`planners.warehouse.waypoint.battery_cost_table`).
    """
    cost = jnp.asarray(battery_cost_pct, jnp.float32)
    if cost.shape != plan.hops.shape:
        raise ValueError(f"battery cost table shape {cost.shape}, expected {plan.hops.shape}")
    params = CausalParams(
        route=route_params(plan, world), battery_cost_pct=cost, min_battery_pct=jnp.float32(min_battery_pct)
    )
    return Driver(actor=causal_planner_actor(int(plan.routes.shape[-1])), params=params)
