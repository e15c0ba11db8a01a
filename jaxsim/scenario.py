"""Load and validate a warehouse scenario from ``data/<name>/*.json`` (host side, numpy).

A scenario folder holds six files:

* ``waypoints.json``: ``waypoints`` list of ``{id, x_m, y_m, radius_m, kind, human_destination}``.
* ``graph.json``: undirected ``edges`` as ``[u, v]`` waypoint-id pairs, and the ids excluded for
  humans (``humans_exclude``) and for the robot (``robot_exclude``).
* ``walls.json``: axis-aligned ``boxes`` ``{kind, name, xmin_m, xmax_m, ymin_m, ymax_m}``.
* ``schedule.json``: ordered ``slots`` ``{name, clock, working, destinations: {waypoint: p}}``.
* ``tasks.json``: the robot's ``goals`` per slot, its start and the charging station.
* ``params.json``: every numeric parameter (see :mod:`jaxsim.params`).

Loading checks everything a simulation relies on and raises :class:`ScenarioError` naming the
file and the field at the first problem, before any array reaches JAX.
"""

from __future__ import annotations

import dataclasses
import json
import pathlib
from typing import Any

import numpy as np

from jaxsim.params import SimParams

DATA_ROOT = pathlib.Path(__file__).resolve().parents[1] / "data"
WAREHOUSE_DIR = DATA_ROOT / "warehouse"

PROBABILITY_TOLERANCE = 1e-6


class ScenarioError(ValueError):
    """A scenario file is missing, malformed or inconsistent.

    Attributes:
      file: the file at fault.
      field: the JSON field at fault (dotted path).
    """

    def __init__(self, file: pathlib.Path | str, field: str, message: str):
        self.file = pathlib.Path(file)
        self.field = field
        super().__init__(f"{self.file}: field '{field}': {message}")


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

    def replace_params(self, **changes: Any) -> "Scenario":
        """A copy with some :class:`SimParams` fields changed (e.g. ``slot_length_s=60``)."""
        return dataclasses.replace(self, params=dataclasses.replace(self.params, **changes))


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

    wp_file = folder / "waypoints.json"
    waypoints = _list_field(_read_json(wp_file), wp_file, "waypoints")
    ids: list[str] = []
    xy, radius, kinds, human_dest = [], [], [], []
    for i, wp in enumerate(waypoints):
        where = f"waypoints[{i}]"
        name = _field(wp, wp_file, where, "id", str)
        if name in ids:
            raise ScenarioError(wp_file, f"{where}.id", f"duplicate waypoint id {name!r}")
        ids.append(name)
        xy.append((_number(wp, wp_file, where, "x_m"), _number(wp, wp_file, where, "y_m")))
        r = _number(wp, wp_file, where, "radius_m")
        if r <= 0:
            raise ScenarioError(wp_file, f"{where}.radius_m", f"must be > 0, got {r}")
        radius.append(r)
        kinds.append(_field(wp, wp_file, where, "kind", str))
        human_dest.append(_field(wp, wp_file, where, "human_destination", bool))
    index = {name: i for i, name in enumerate(ids)}
    waypoint_xy = np.asarray(xy, np.float64)

    walls_file = folder / "walls.json"
    boxes_raw = _list_field(_read_json(walls_file), walls_file, "boxes")
    boxes, box_kinds = [], []
    for i, b in enumerate(boxes_raw):
        where = f"boxes[{i}]"
        box = [_number(b, walls_file, where, k) for k in ("xmin_m", "xmax_m", "ymin_m", "ymax_m")]
        if box[0] >= box[1] or box[2] >= box[3]:
            raise ScenarioError(walls_file, where, f"empty box {box} (need xmin < xmax, ymin < ymax)")
        boxes.append(box)
        box_kinds.append(_field(b, walls_file, where, "kind", str))
    boxes_m = np.asarray(boxes, np.float64).reshape(-1, 4)
    for i, (x, y) in enumerate(waypoint_xy):
        inside = (boxes_m[:, 0] < x) & (x < boxes_m[:, 1]) & (boxes_m[:, 2] < y) & (y < boxes_m[:, 3])
        if inside.any():
            j = int(np.argmax(inside))
            raise ScenarioError(wp_file, f"waypoints[{i}]",
                                f"waypoint {ids[i]!r} at ({x}, {y}) lies inside wall box {j} "
                                f"({boxes_raw[j].get('name', '?')}) of {walls_file.name}")

    graph_file = folder / "graph.json"
    graph = _read_json(graph_file)
    edges = []
    for i, e in enumerate(_list_field(graph, graph_file, "edges")):
        if not (isinstance(e, list) and len(e) == 2):
            raise ScenarioError(graph_file, f"edges[{i}]", f"expected [u, v], got {e!r}")
        for end in e:
            if end not in index:
                raise ScenarioError(graph_file, f"edges[{i}]", f"edge to unknown waypoint {end!r}")
        if e[0] == e[1]:
            raise ScenarioError(graph_file, f"edges[{i}]", f"self loop at {e[0]!r}")
        edges.append((index[e[0]], index[e[1]]))
    human_allowed = _exclusion_mask(graph, graph_file, "humans_exclude", index)
    robot_allowed = _exclusion_mask(graph, graph_file, "robot_exclude", index)

    sched_file = folder / "schedule.json"
    slots = _list_field(_read_json(sched_file), sched_file, "slots")
    if not slots:
        raise ScenarioError(sched_file, "slots", "no slots")
    slot_names, slot_clock, slot_working, dest_p = [], [], [], []
    for s, slot in enumerate(slots):
        where = f"slots[{s}]"
        slot_names.append(_field(slot, sched_file, where, "name", str))
        slot_clock.append(_field(slot, sched_file, where, "clock", str))
        slot_working.append(_field(slot, sched_file, where, "working", bool))
        dests = _field(slot, sched_file, where, "destinations", dict)
        row = np.zeros(len(ids))
        for name, p in dests.items():
            if name not in index:
                raise ScenarioError(sched_file, f"{where}.destinations.{name}", "unknown waypoint")
            if not isinstance(p, (int, float)) or isinstance(p, bool) or not 0 <= p <= 1:
                raise ScenarioError(sched_file, f"{where}.destinations.{name}", f"not a probability: {p!r}")
            if not human_allowed[index[name]]:
                raise ScenarioError(sched_file, f"{where}.destinations.{name}", "waypoint excluded for humans")
            row[index[name]] = p
        if abs(row.sum() - 1.0) > PROBABILITY_TOLERANCE:
            raise ScenarioError(sched_file, f"{where}.destinations",
                                f"probabilities sum to {row.sum():.6f}, expected 1")
        dest_p.append(row)

    tasks_file = folder / "tasks.json"
    tasks = _read_json(tasks_file)
    task_slots = _list_field(tasks, tasks_file, "slots")
    if [t.get("name") for t in task_slots] != slot_names:
        raise ScenarioError(tasks_file, "slots", f"slot names must match schedule.json: {slot_names}")
    robot_goals = []
    for s, t in enumerate(task_slots):
        goals = _field(t, tasks_file, f"slots[{s}]", "goals", list)
        if not goals:
            raise ScenarioError(tasks_file, f"slots[{s}].goals", "empty goal list")
        for g, name in enumerate(goals):
            if name not in index or not robot_allowed[index.get(name, 0)]:
                raise ScenarioError(tasks_file, f"slots[{s}].goals[{g}]",
                                    f"unknown or robot-excluded waypoint {name!r}")
        robot_goals.append(np.asarray([index[n] for n in goals], np.int32))
    robot_start = _waypoint_field(tasks, tasks_file, "robot_start", index)
    charging = _waypoint_field(tasks, tasks_file, "charging_station", index)
    if "parking" not in index:
        raise ScenarioError(wp_file, "waypoints", "needs a 'parking' waypoint where workers arrive and leave")

    params = SimParams.from_json(folder / "params.json", ScenarioError)
    if param_overrides:
        params = dataclasses.replace(params, **param_overrides)
    params.validate(ScenarioError)

    return Scenario(
        name=folder.name,
        waypoint_ids=tuple(ids),
        waypoint_xy_m=waypoint_xy,
        waypoint_radius_m=np.asarray(radius, np.float64),
        waypoint_kind=tuple(kinds),
        edges=np.asarray(edges, np.int32).reshape(-1, 2),
        human_allowed=human_allowed,
        robot_allowed=robot_allowed,
        boxes_m=boxes_m,
        box_kinds=tuple(box_kinds),
        slot_names=tuple(slot_names),
        slot_clock=tuple(slot_clock),
        slot_working=np.asarray(slot_working, bool),
        destination_p=np.asarray(dest_p, np.float64),
        robot_goals=tuple(robot_goals),
        robot_start=robot_start,
        charging_station=charging,
        parking=index["parking"],
        params=params,
    )


def _read_json(file: pathlib.Path) -> dict:
    if not file.is_file():
        raise ScenarioError(file, "<file>", "file is missing")
    try:
        obj = json.loads(file.read_text())
    except json.JSONDecodeError as e:
        raise ScenarioError(file, "<file>", f"invalid JSON: {e}") from None
    if not isinstance(obj, dict):
        raise ScenarioError(file, "<file>", "top level must be a JSON object")
    return obj


def _field(obj: Any, file: pathlib.Path, where: str, key: str, kind: type) -> Any:
    if not isinstance(obj, dict) or key not in obj:
        raise ScenarioError(file, f"{where}.{key}" if where else key, "missing field")
    value = obj[key]
    if not isinstance(value, kind) or (kind is not bool and isinstance(value, bool)):
        raise ScenarioError(file, f"{where}.{key}" if where else key,
                            f"expected {kind.__name__}, got {type(value).__name__}")
    return value


def _number(obj: Any, file: pathlib.Path, where: str, key: str) -> float:
    if not isinstance(obj, dict) or key not in obj:
        raise ScenarioError(file, f"{where}.{key}", "missing field")
    value = obj[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
        raise ScenarioError(file, f"{where}.{key}", f"expected a finite number, got {value!r}")
    return float(value)


def _list_field(obj: dict, file: pathlib.Path, key: str) -> list:
    return _field(obj, file, "", key, list)


def _exclusion_mask(graph: dict, file: pathlib.Path, key: str, index: dict[str, int]) -> np.ndarray:
    allowed = np.ones(len(index), bool)
    for name in _list_field(graph, file, key):
        if name not in index:
            raise ScenarioError(file, key, f"unknown waypoint {name!r}")
        allowed[index[name]] = False
    return allowed


def _waypoint_field(obj: dict, file: pathlib.Path, key: str, index: dict[str, int]) -> int:
    name = _field(obj, file, "", key, str)
    if name not in index:
        raise ScenarioError(file, key, f"unknown waypoint {name!r}")
    return index[name]
