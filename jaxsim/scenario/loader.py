"""Load and validate a warehouse scenario from a folder of six JSON files (host side, numpy).

One loader per file (this package's modules, each named after its file):

* ``waypoints.json`` (:mod:`.waypoints`), ``walls.json`` (:mod:`.walls`), ``graph.json``
  (:mod:`.graph`), ``schedule.json`` (:mod:`.schedule`), ``tasks.json`` (:mod:`.tasks`),
  ``params.json`` (:meth:`jaxsim.params.SimParams.from_json`).

:func:`load_scenario` checks everything a simulation relies on and raises
:class:`ScenarioError` naming the file and the field at the first problem, before any array
reaches JAX.
"""

from __future__ import annotations

import dataclasses
import pathlib
from typing import Any

import numpy as np

from socialnav.data import DATA_DIR, WAREHOUSE_DIR
from socialnav.jaxsim.params import SimParams
from socialnav.jaxsim.scenario.errors import ScenarioError
from socialnav.jaxsim.scenario.graph import FILE as GRAPH_FILE
from socialnav.jaxsim.scenario.graph import check_connected, load_graph
from socialnav.jaxsim.scenario.schedule import load_schedule
from socialnav.jaxsim.scenario.tasks import load_tasks
from socialnav.jaxsim.scenario.walls import FILE as WALLS_FILE
from socialnav.jaxsim.scenario.walls import load_walls
from socialnav.jaxsim.scenario.waypoints import FILE as WAYPOINTS_FILE
from socialnav.jaxsim.scenario.waypoints import load_waypoints

# The largest map (bounding box of walls and waypoints) a scenario may span: the simulator
# precomputes a wall distance field over it at 5 cm (200 m x 200 m: 16 M cells, 190 MB).
MAX_MAP_SIDE_M = 200.0

DATA_ROOT = DATA_DIR


@dataclasses.dataclass(frozen=True)
class Scenario:
    """A validated scenario as host-side numpy arrays.

    Attributes:
      name: folder name of the scenario.
      waypoint_ids: (W,) waypoint names, index = waypoint id used everywhere else.
      waypoint_xy_m: (W, 2) waypoint centres.
      waypoint_radius_m: (W,) waypoint radii (the density disc of Eq. 3).
      waypoint_kind: (W,) semantic kinds (``work_area``, ``toilet``, ``canteen`` ...).
      edges: (E, 2) int undirected edges.
      human_allowed: (W,) bool, waypoints humans may route through.
      robot_allowed: (W,) bool, waypoints the robot may route through.
      boxes_m: (B, 4) wall boxes as ``xmin, xmax, ymin, ymax``.
      box_kinds: (B,) kinds (wall, shelf, table, tray).
      slot_names: (S,) slot names ``S1``..``S11``.
      slot_clock: (S,) clock labels.
      slot_working: (S,) bool, False for the off slot.
      destination_p: (S, W) destination probabilities per slot (rows sum to 1).
      robot_goals: list of S int arrays, the robot's goal waypoints per slot.
      robot_start: waypoint id where the robot starts.
      charging_station: waypoint id of the charger.
      parking: waypoint id where workers arrive and leave.
      params: numeric parameters.
    """

    name: str
    waypoint_ids: tuple[str, ...]
    waypoint_xy_m: np.ndarray
    waypoint_radius_m: np.ndarray
    waypoint_kind: tuple[str, ...]
    edges: np.ndarray
    human_allowed: np.ndarray
    robot_allowed: np.ndarray
    boxes_m: np.ndarray
    box_kinds: tuple[str, ...]
    slot_names: tuple[str, ...]
    slot_clock: tuple[str, ...]
    slot_working: np.ndarray
    destination_p: np.ndarray
    robot_goals: tuple[np.ndarray, ...]
    robot_start: int
    charging_station: int
    parking: int
    params: SimParams

    @property
    def n_waypoints(self) -> int:
        return len(self.waypoint_ids)

    @property
    def n_slots(self) -> int:
        return len(self.slot_names)

    def waypoint(self, name: str) -> int:
        """Index of the waypoint called ``name``."""
        try:
            return self.waypoint_ids.index(name)
        except ValueError:
            raise KeyError(f"no waypoint {name!r} in scenario {self.name!r}") from None

    def replace_params(self, **changes: Any) -> Scenario:
        """A copy with some :class:`SimParams` fields changed (e.g. ``slot_length_s=60``)."""
        return dataclasses.replace(self, params=self.params.replace(**changes))


def load_scenario(path: str | pathlib.Path = WAREHOUSE_DIR, **param_overrides: Any) -> Scenario:
    """Load and validate the scenario in folder ``path`` (default: the built-in warehouse).

    Args:
      path: folder with the six scenario files.
      **param_overrides: :class:`SimParams` fields to override after loading.

    Raises:
      ScenarioError: naming the file and field of the first problem found.
    """
    folder = pathlib.Path(path)
    if not folder.is_dir():
        raise ScenarioError(folder, "<folder>", "scenario folder does not exist")
    waypoints = load_waypoints(folder)
    index = waypoints.index
    boxes_m, box_kinds = load_walls(folder, waypoints)
    edges, human_allowed, robot_allowed = load_graph(folder, index)
    schedule = load_schedule(folder, index, human_allowed)
    tasks = load_tasks(folder, index, robot_allowed, schedule.names)
    _check_extent(folder, waypoints, boxes_m)
    _check_waypoint_discs(folder, waypoints, boxes_m)
    _check_routes(folder, waypoints.ids, edges, human_allowed, robot_allowed, schedule, tasks, index["parking"])
    params_file = folder / "params.json"
    params = SimParams.from_json(params_file, ScenarioError)
    params.validate(ScenarioError, params_file)
    _check_clearance(folder, waypoints, boxes_m, params.robot_radius_m)
    if param_overrides:
        unknown = sorted(set(param_overrides) - {f.name for f in dataclasses.fields(SimParams)})
        if unknown:
            raise ScenarioError(params_file, unknown[0], "unknown parameter (override)")
        params = params.replace(**param_overrides)
        changed = ", ".join(f"{k}={v!r}" for k, v in param_overrides.items())
        params.validate(ScenarioError, f"{params_file} with {changed}")
    return Scenario(
        name=folder.name,
        waypoint_ids=waypoints.ids,
        waypoint_xy_m=waypoints.xy_m,
        waypoint_radius_m=waypoints.radius_m,
        waypoint_kind=waypoints.kinds,
        edges=edges,
        human_allowed=human_allowed,
        robot_allowed=robot_allowed,
        boxes_m=boxes_m,
        box_kinds=box_kinds,
        slot_names=schedule.names,
        slot_clock=schedule.clock,
        slot_working=schedule.working,
        destination_p=schedule.destination_p,
        robot_goals=tasks.goals,
        robot_start=tasks.robot_start,
        charging_station=tasks.charging_station,
        parking=index["parking"],
        params=params,
    )


def _check_extent(folder: pathlib.Path, waypoints, boxes_m: np.ndarray) -> None:
    """Refuse a map wider than :data:`MAX_MAP_SIDE_M`, naming the waypoint farthest out."""
    xs = np.concatenate([boxes_m[:, :2].ravel(), waypoints.xy_m[:, 0]])
    ys = np.concatenate([boxes_m[:, 2:].ravel(), waypoints.xy_m[:, 1]])
    width, height = xs.max() - xs.min(), ys.max() - ys.min()
    if max(width, height) <= MAX_MAP_SIDE_M:
        return
    centre = np.median(waypoints.xy_m, axis=0)
    far = int(np.argmax(np.abs(waypoints.xy_m - centre).max(axis=1)))
    x, y = waypoints.xy_m[far]
    raise ScenarioError(
        folder / WAYPOINTS_FILE,
        f"waypoints[{far}]",
        f"the map spans {width:.0f} m x {height:.0f} m, more than the {MAX_MAP_SIDE_M:.0f} m supported "
        f"(its wall distance field would need about {width * height * 400 * 12 / 1e9:.1f} GB); "
        f"waypoint {waypoints.ids[far]!r} at ({x:g}, {y:g}) lies farthest from the others",
    )


def _check_waypoint_discs(folder: pathlib.Path, waypoints, boxes_m: np.ndarray) -> None:
    """A waypoint's disc (the area whose people Eq. 3 counts) fits in the map: its radius is at
    most half the walls' extent (the warehouse's largest, the parking lot's, is 3 m of 30 m)."""
    extent = max(boxes_m[:, 1].max() - boxes_m[:, 0].min(), boxes_m[:, 3].max() - boxes_m[:, 2].min())
    for i, r in enumerate(waypoints.radius_m):
        if r > extent / 2:
            raise ScenarioError(
                folder / WAYPOINTS_FILE,
                f"waypoints[{i}].radius_m",
                f"waypoint {waypoints.ids[i]!r} has a {r:g} m disc, more than half the map's {extent:.1f} m extent: "
                "its density (people per m^2 in the disc, Eq. 3) would count the whole map",
            )


def _check_clearance(folder: pathlib.Path, waypoints, boxes_m: np.ndarray, robot_radius_m: float) -> None:
    """Every waypoint's centre lies at least the robot's radius from every wall: the robot and the
    workers stand there (the warehouse's closest, corridor-1, is 0.325 m from a wall)."""
    x, y = waypoints.xy_m[:, :1], waypoints.xy_m[:, 1:]
    dx = np.maximum(np.maximum(boxes_m[None, :, 0] - x, x - boxes_m[None, :, 1]), 0.0)
    dy = np.maximum(np.maximum(boxes_m[None, :, 2] - y, y - boxes_m[None, :, 3]), 0.0)
    gap = np.hypot(dx, dy)  # (W, B): 0 inside or on a box
    for i in np.flatnonzero(gap.min(axis=1) < robot_radius_m):
        j = int(np.argmin(gap[i]))
        raise ScenarioError(
            folder / WAYPOINTS_FILE,
            f"waypoints[{i}]",
            f"waypoint {waypoints.ids[i]!r} at ({waypoints.xy_m[i, 0]:g}, {waypoints.xy_m[i, 1]:g}) is "
            f"{gap[i, j]:.3f} m from wall box {j} of {WALLS_FILE}: closer than the robot's radius "
            f"({robot_radius_m:g} m, params.json robot.radius_m), so the robot could not stand on it",
        )


def _check_routes(folder, ids, edges, human_allowed, robot_allowed, schedule, tasks, parking: int) -> None:
    """Every destination a worker may draw is reachable from the parking lot, and every goal of
    the robot and its charger from its start, along the graph."""
    destinations = {int(w): "destination" for w in np.flatnonzero(schedule.destination_p.max(axis=0) > 0)}
    check_connected(folder / GRAPH_FILE, ids, edges, human_allowed, parking, destinations, "workers")
    needed = {int(g): "task goal" for goals in tasks.goals for g in goals}
    needed[tasks.charging_station] = "charging station"
    check_connected(folder / GRAPH_FILE, ids, edges, robot_allowed, tasks.robot_start, needed, "the robot")
