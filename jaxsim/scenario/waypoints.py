"""``waypoints.json``: ``waypoints`` list of ``{id, x_m, y_m, radius_m, kind, human_destination}``."""

from __future__ import annotations

import dataclasses
import pathlib

import numpy as np

from socialnav.common.names import SAFE_NAME_RULE, is_safe_name, name_problem
from socialnav.jaxsim.scenario.errors import ScenarioError
from socialnav.jaxsim.scenario.jsonio import field, list_field, number, only_fields, read_json

FILE = "waypoints.json"


@dataclasses.dataclass(frozen=True)
class Waypoints:
    """ids (W,), xy_m (W, 2), radius_m (W,), kinds (W,), human_destination (W,) bool."""

    ids: tuple[str, ...]
    xy_m: np.ndarray
    radius_m: np.ndarray
    kinds: tuple[str, ...]
    human_destination: np.ndarray

    @property
    def index(self) -> dict[str, int]:
        return {name: i for i, name in enumerate(self.ids)}


def load_waypoints(folder: pathlib.Path) -> Waypoints:
    file = folder / FILE
    ids: list[str] = []
    xy, radius, kinds, human_dest = [], [], [], []
    top = read_json(file)
    only_fields(top, file, "", ("waypoints",))
    for i, wp in enumerate(list_field(top, file, "waypoints")):
        where = f"waypoints[{i}]"
        only_fields(wp, file, where, ("id", "x_m", "y_m", "radius_m", "kind", "human_destination"))
        name = field(wp, file, where, "id", str)
        if not is_safe_name(name):  # it names a log column, density_<id>, and the pictures' labels
            raise ScenarioError(
                file, f"{where}.id", f"{name!r} cannot name a log column ({name_problem(name)}): use {SAFE_NAME_RULE}"
            )
        if name in ids:
            raise ScenarioError(file, f"{where}.id", f"duplicate waypoint id {name!r}")
        ids.append(name)
        xy.append((number(wp, file, where, "x_m"), number(wp, file, where, "y_m")))
        r = number(wp, file, where, "radius_m")
        if r <= 0:
            raise ScenarioError(file, f"{where}.radius_m", f"must be > 0, got {r}")
        radius.append(r)
        kinds.append(field(wp, file, where, "kind", str))
        human_dest.append(field(wp, file, where, "human_destination", bool))
    if "parking" not in ids:
        raise ScenarioError(file, "waypoints", "needs a 'parking' waypoint where workers arrive and leave")
    return Waypoints(
        tuple(ids),
        np.asarray(xy, np.float64).reshape(-1, 2),
        np.asarray(radius, np.float64),
        tuple(kinds),
        np.asarray(human_dest, bool),
    )
