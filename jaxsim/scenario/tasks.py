"""``tasks.json``: the robot's ``goals`` per slot (slot names as in ``schedule.json``), its
``robot_start`` and the ``charging_station``."""

from __future__ import annotations

import dataclasses
import pathlib

import numpy as np

from socialnav.jaxsim.scenario.errors import ScenarioError
from socialnav.jaxsim.scenario.jsonio import field, list_field, only_fields, read_json, waypoint_field

FILE = "tasks.json"


@dataclasses.dataclass(frozen=True)
class Tasks:
    """goals: S int32 arrays of goal waypoints; robot_start, charging_station: waypoint indices."""

    goals: tuple[np.ndarray, ...]
    robot_start: int
    charging_station: int


def load_tasks(
    folder: pathlib.Path, index: dict[str, int], robot_allowed: np.ndarray, slot_names: tuple[str, ...]
) -> Tasks:
    file = folder / FILE
    tasks = read_json(file)
    only_fields(tasks, file, "", ("slots", "robot_start", "charging_station"))
    task_slots = list_field(tasks, file, "slots")
    for s, t in enumerate(task_slots):
        only_fields(t, file, f"slots[{s}]", ("name", "goals"))
        field(t, file, f"slots[{s}]", "name", str)
    if [t.get("name") if isinstance(t, dict) else None for t in task_slots] != list(slot_names):
        raise ScenarioError(file, "slots", f"slot names must match schedule.json: {list(slot_names)}")
    goals = []
    for s, t in enumerate(task_slots):
        names = field(t, file, f"slots[{s}]", "goals", list)
        if not names:
            raise ScenarioError(file, f"slots[{s}].goals", "empty goal list")
        for g, name in enumerate(names):
            if not isinstance(name, str) or name not in index or not robot_allowed[index[name]]:
                raise ScenarioError(file, f"slots[{s}].goals[{g}]", f"unknown or robot-excluded waypoint {name!r}")
        goals.append(np.asarray([index[n] for n in names], np.int32))
    return Tasks(
        tuple(goals),
        waypoint_field(tasks, file, "robot_start", index),
        waypoint_field(tasks, file, "charging_station", index),
    )
