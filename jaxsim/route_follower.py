"""The paper's robot as an actor: it follows a :class:`~jaxsim.world.RobotPlan`'s route for each
leg, waypoint by waypoint (the day simulation's default actor, and seed 000's shortest-path and
causal methods with their plans).

Its params are the plan and the waypoints' coordinates (traced: another plan of the same shape
reuses the compiled program); its state the current leg's route and the waypoint aimed at. On a
new leg (``robot.legs_started`` changed) it looks up ``plan.routes[leg_slot, start, goal]``; when
the robot reached its aim in the last step it aims at the route's next waypoint; it tells the
robot the route's length, where the leg's obstacle is placed.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
from flax import struct

from socialnav.jaxsim.actor import Actor, Driver
from socialnav.jaxsim.robot import RobotCommand, WarehouseObservation
from socialnav.jaxsim.world import RobotPlan, World


@struct.dataclass
class RouteParams:
    """plan: the routes per slot; waypoint_x_m, waypoint_y_m: (W,) the waypoints' coordinates."""

    plan: RobotPlan
    waypoint_x_m: jax.Array
    waypoint_y_m: jax.Array


@struct.dataclass
class RouteState:
    """route: (L,) int32 the waypoints of the current leg after its start (padded with its goal);
    route_pos: () the index aimed at; route_hops: () its real length; leg: () the
    ``robot.legs_started`` it was planned for."""

    route: jax.Array
    route_pos: jax.Array
    route_hops: jax.Array
    leg: jax.Array


def init_route(params: RouteParams, obs: WarehouseObservation) -> RouteState:
    """The route of the robot's current leg, its first waypoint aimed at."""
    r = obs.robot
    return RouteState(
        route=params.plan.routes[r.leg_slot, r.leg_start_wp, r.goal_wp],
        route_pos=jnp.int32(0),
        route_hops=params.plan.hops[r.leg_slot, r.leg_start_wp, r.goal_wp],
        leg=r.legs_started,
    )


def follow_route(params: RouteParams, state: RouteState, obs: WarehouseObservation) -> tuple[RobotCommand, RouteState]:
    """Replan on a new leg; else step to the next waypoint once the last aim was reached (not past
    the last one). The command aims at the route's waypoint."""
    r = obs.robot
    fresh = init_route(params, obs)
    last = state.route_pos + 1 >= jnp.maximum(state.route_hops, 1)
    advanced = state.replace(route_pos=jnp.where(r.reached & ~last, state.route_pos + 1, state.route_pos))
    state = jax.tree.map(lambda a, b: jnp.where(r.legs_started != state.leg, a, b), fresh, advanced)
    aim = state.route[state.route_pos]
    command = RobotCommand(
        aim_x_m=params.waypoint_x_m[aim],
        aim_y_m=params.waypoint_y_m[aim],
        speed_mps=jnp.float32(jnp.inf),
        planned_length_m=params.plan.length_m[r.leg_slot, r.leg_start_wp, r.goal_wp],
        recharge=jnp.bool_(False),
    )
    return command, state


@functools.lru_cache(maxsize=16)
def route_follower_actor(route_len: int) -> Actor:
    """The route follower as an :class:`~jaxsim.actor.Actor` for routes of ``route_len`` entries
    (params: :class:`RouteParams`; one actor per length, so its programs are reused).

    ``init`` has no params, so it cannot look up the plan: it gives an empty route of leg -1, and
    the first ``act`` sees a new leg and plans it."""

    def init(key, obs: WarehouseObservation) -> RouteState:
        del key
        return RouteState(
            route=jnp.zeros(route_len, jnp.int32),
            route_pos=jnp.int32(0),
            route_hops=jnp.int32(0),
            leg=jnp.full_like(obs.robot.legs_started, -1),
        )

    def act(params: RouteParams, state: RouteState, obs: WarehouseObservation, key: jax.Array):
        del key
        return follow_route(params, state, obs)

    return Actor(init=init, act=act, name="route_follower")


def route_params(plan: RobotPlan, world: World) -> RouteParams:
    """The follower's params: ``plan`` and the world's waypoint coordinates."""
    return RouteParams(plan=plan, waypoint_x_m=world.waypoint_x_m, waypoint_y_m=world.waypoint_y_m)


def route_follower(plan: RobotPlan, world: World) -> Driver:
    """The driver of the day simulation and seed 000's methods: ``plan``'s routes, followed."""
    return Driver(actor=route_follower_actor(int(plan.routes.shape[-1])), params=route_params(plan, world))
