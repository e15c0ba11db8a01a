"""The scenario's static arrays on the JAX side: geometry, graph tables, schedule and tasks.

:func:`build_world` turns a validated :class:`~jaxsim.scenario.Scenario` into a :class:`World`
pytree once per scenario; every rollout then takes it as an ordinary (unbatched) argument.
:class:`RobotPlan` is the format of the robot's route table, an input the planners produce
(``planners.warehouse.routes``); the simulator only follows it.
"""

from __future__ import annotations

import dataclasses
import functools

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from socialnav.jaxsim import geometry, graph
from socialnav.jaxsim.grid import Grid
from socialnav.jaxsim.params import SimParams
from socialnav.jaxsim.scenario import Scenario

# Area simulated around the walls: the building plus the open parking lot north of its door.
MARGIN_M = 1.0
WALL_FIELD_RESOLUTION_M = 0.05
WAYPOINT_GRID_RESOLUTION_M = 0.25


@struct.dataclass
class World:
    """Static arrays of one scenario (W waypoints, S slots, T max goals per slot).

    Attributes:
      waypoint_x_m, waypoint_y_m, waypoint_radius_m: (W,) waypoint discs.
      reach_radius_m: (W,) distance at which a walker counts a waypoint as reached.
      is_toilet: (W,) bool, shorter activities.
      human_next_hop: (W, W) int32 next waypoint on the humans' shortest route.
      destination_cdf: (S, W) cumulative destination probabilities per slot.
      slot_working: (S,) bool.
      wall_field: (H, W, 3) grid of the wall distance field: signed distance (m) and the unit
        normal (x, y) away from the nearest wall, packed so one gather reads all three.
      human_waypoint_grid, robot_waypoint_grid: nearest visible waypoint per cell.
      robot_goals: (S, T) int32 goal waypoints per slot (padded by repetition).
      robot_goal_count: (S,) int32 real goals per slot.
      parking_x_m, parking_y_m: worker spawn centre.
      parking: parking waypoint index; charging_station: charger index; robot_start: start index.
      human_model: how the workers move (static: a change recompiles;
        :data:`jaxsim.humans.HUMAN_MODELS`, default the social force).
      human_parts: the constants a calibration's fit set, by part of
        :class:`jaxsim.humans.HumanParams` (``{"speed": {"time_gap_s": 0.42, ...}, ...}``,
        traced: another fit reuses the compiled day; empty: the name's own constants),
        :func:`build_world`'s ``human_values``.
    """

    waypoint_x_m: jax.Array
    waypoint_y_m: jax.Array
    waypoint_radius_m: jax.Array
    reach_radius_m: jax.Array
    is_toilet: jax.Array
    human_next_hop: jax.Array
    destination_cdf: jax.Array
    slot_working: jax.Array
    wall_field: Grid
    human_waypoint_grid: Grid
    robot_waypoint_grid: Grid
    robot_goals: jax.Array
    robot_goal_count: jax.Array
    parking_x_m: jax.Array
    parking_y_m: jax.Array
    parking: int = struct.field(pytree_node=False)
    charging_station: int = struct.field(pytree_node=False)
    robot_start: int = struct.field(pytree_node=False)
    human_model: str = struct.field(pytree_node=False, default="social_force")
    human_parts: dict = dataclasses.field(default_factory=dict)

    @property
    def n_waypoints(self) -> int:
        return self.waypoint_x_m.shape[0]

    @property
    def n_slots(self) -> int:
        return self.destination_cdf.shape[0]


@struct.dataclass
class RobotPlan:
    """The robot's routes: a plain input of the step, computed by a planner outside it.

    Attributes:
      routes: (S, W, W, L) int32; ``routes[s, i, j, :k]`` the waypoints after ``i`` up to ``j``
        in slot ``s``, padded with ``j``.
      hops: (S, W, W) int32 real route length ``k``.
      length_m: (S, W, W) float32 route length in metres (for placing obstacles).
    """

    routes: jax.Array
    hops: jax.Array
    length_m: jax.Array


def world_bounds(scenario: Scenario) -> tuple[float, float, float, float]:
    """(xmin, xmax, ymin, ymax) of the simulated area: walls, waypoints and the parking lot."""
    p = scenario.params
    xs = np.concatenate([scenario.boxes_m[:, :2].ravel(), scenario.waypoint_xy_m[:, 0]])
    ys = np.concatenate([scenario.boxes_m[:, 2:].ravel(), scenario.waypoint_xy_m[:, 1]])
    park = scenario.waypoint_xy_m[scenario.parking]
    xs = np.concatenate([xs, park[:1] + np.array([-1, 1]) * (p.worker_spawn_dx_m / 2 + 1)])
    ys = np.concatenate([ys, park[1:] + np.array([-1, 1]) * (p.worker_spawn_dy_m / 2 + 1)])
    return (
        float(xs.min() - MARGIN_M),
        float(xs.max() + MARGIN_M),
        float(ys.min() - MARGIN_M),
        float(ys.max() + MARGIN_M),
    )


@functools.lru_cache(maxsize=4)
def _geometry(
    boxes_key: bytes, wp_key: bytes, human_key: bytes, robot_key: bytes, bounds: tuple[float, float, float, float]
):
    boxes = np.frombuffer(boxes_key).reshape(-1, 4)
    wp = np.frombuffer(wp_key).reshape(-1, 2)
    human = np.frombuffer(human_key, bool)
    robot = np.frombuffer(robot_key, bool)
    field = geometry.build_distance_field(boxes, bounds, WALL_FIELD_RESOLUTION_M)
    hgrid = geometry.build_waypoint_grid(wp, human, boxes, bounds, WAYPOINT_GRID_RESOLUTION_M)
    rgrid = geometry.build_waypoint_grid(wp, robot, boxes, bounds, WAYPOINT_GRID_RESOLUTION_M)
    return field, hgrid, rgrid


def build_world(scenario: Scenario, human_model: str = "social_force", human_values=()) -> World:
    """Precompute the static arrays of ``scenario`` (distance field, routes, schedule); its
    workers move by ``human_model`` (:data:`jaxsim.humans.HUMAN_MODELS`), its constants set by
    ``human_values`` (``("<part>.<field>", value)`` pairs or a mapping; ``ValueError`` for one the
    model does not read)."""
    from socialnav.jaxsim import humans  # humans -> orca -> world: imported here

    humans.check_model(human_model)
    human_values = dict(human_values)
    problem = humans.values_problem(human_model, human_values)
    if problem is not None:
        raise ValueError(problem)
    human_parts = humans.by_part({path: jnp.float32(value) for path, value in sorted(human_values.items())})
    p = scenario.params
    bounds = world_bounds(scenario)
    field, hgrid, rgrid = _geometry(
        scenario.boxes_m.tobytes(),
        scenario.waypoint_xy_m.tobytes(),
        scenario.human_allowed.tobytes(),
        scenario.robot_allowed.tobytes(),
        bounds,
    )
    lengths = graph.edge_lengths_m(scenario.waypoint_xy_m, scenario.edges)
    _, next_hop = graph.all_pairs_shortest(scenario.n_waypoints, scenario.edges, lengths, scenario.human_allowed)
    cdf = np.cumsum(scenario.destination_p, axis=1)
    cdf[:, -1] = 1.0 + 1e-6  # a draw of u < 1 always lands on a waypoint with p > 0
    max_goals = max(len(g) for g in scenario.robot_goals)
    goals = np.stack([np.resize(g, max_goals) for g in scenario.robot_goals]).astype(np.int32)

    def grid(values, g):
        return Grid.of_samples(jnp.asarray(values), float(g.origin_m[0]), float(g.origin_m[1]), float(g.resolution_m))

    park = scenario.waypoint_xy_m[scenario.parking]
    return World(
        waypoint_x_m=jnp.asarray(scenario.waypoint_xy_m[:, 0], jnp.float32),
        waypoint_y_m=jnp.asarray(scenario.waypoint_xy_m[:, 1], jnp.float32),
        waypoint_radius_m=jnp.asarray(scenario.waypoint_radius_m, jnp.float32),
        reach_radius_m=jnp.asarray(np.maximum(scenario.waypoint_radius_m, p.worker_min_reach_radius_m), jnp.float32),
        is_toilet=jnp.asarray([k == "toilet" for k in scenario.waypoint_kind]),
        human_next_hop=jnp.asarray(next_hop),
        destination_cdf=jnp.asarray(cdf, jnp.float32),
        slot_working=jnp.asarray(scenario.slot_working),
        wall_field=grid(np.stack([field.sdf_m, field.normal_x, field.normal_y], axis=-1), field),
        human_waypoint_grid=grid(hgrid.nearest, hgrid),
        robot_waypoint_grid=grid(rgrid.nearest, rgrid),
        robot_goals=jnp.asarray(goals),
        robot_goal_count=jnp.asarray([len(g) for g in scenario.robot_goals], jnp.int32),
        parking_x_m=jnp.float32(park[0]),
        parking_y_m=jnp.float32(park[1]),
        parking=scenario.parking,
        charging_station=scenario.charging_station,
        robot_start=scenario.robot_start,
        human_model=human_model,
        human_parts=human_parts,
    )


def worker_params(human_model: str, params: SimParams):
    """The constants the warehouse's workers walk by (:class:`jaxsim.humans.HumanParams`): the
    run's social force, and ORCA's people with the workers' bodies; a velocity model keeps its
    own (fitted) radius."""
    from socialnav.jaxsim import humans, orca  # humans -> orca -> world: imported here

    return humans.human_params(human_model, params, orca.ORCAParams(radius_m=params.worker_radius_m))
