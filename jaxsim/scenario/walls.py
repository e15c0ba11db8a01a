"""``walls.json``: axis-aligned ``boxes`` ``{kind, name, xmin_m, xmax_m, ymin_m, ymax_m}``."""

from __future__ import annotations

import pathlib

import numpy as np

from socialnav.jaxsim.scenario.errors import ScenarioError
from socialnav.jaxsim.scenario.jsonio import field, list_field, number, only_fields, read_json
from socialnav.jaxsim.scenario.waypoints import FILE as WAYPOINTS_FILE
from socialnav.jaxsim.scenario.waypoints import Waypoints

FILE = "walls.json"


def load_walls(folder: pathlib.Path, waypoints: Waypoints) -> tuple[np.ndarray, tuple[str, ...]]:
    """(B, 4) boxes as ``xmin, xmax, ymin, ymax`` and their kinds; no waypoint may lie inside one."""
    file = folder / FILE
    top = read_json(file)
    only_fields(top, file, "", ("boxes",))
    raw = list_field(top, file, "boxes")
    if not raw:
        raise ScenarioError(file, "boxes", "is empty: the map needs its walls (at least its outline) as boxes")
    boxes, kinds = [], []
    for i, b in enumerate(raw):
        where = f"boxes[{i}]"
        only_fields(b, file, where, ("kind", "name", "xmin_m", "xmax_m", "ymin_m", "ymax_m"))
        box = [number(b, file, where, k) for k in ("xmin_m", "xmax_m", "ymin_m", "ymax_m")]
        if box[0] >= box[1] or box[2] >= box[3]:
            raise ScenarioError(file, where, f"empty box {box} (need xmin < xmax, ymin < ymax)")
        boxes.append(box)
        kinds.append(field(b, file, where, "kind", str))
    boxes_m = np.asarray(boxes, np.float64).reshape(-1, 4)
    for i, (x, y) in enumerate(waypoints.xy_m):
        inside = (boxes_m[:, 0] < x) & (x < boxes_m[:, 1]) & (boxes_m[:, 2] < y) & (y < boxes_m[:, 3])
        if inside.any():
            j = int(np.argmax(inside))
            raise ScenarioError(
                folder / WAYPOINTS_FILE,
                f"waypoints[{i}]",
                f"waypoint {waypoints.ids[i]!r} at ({x}, {y}) lies inside wall box {j} "
                f"({raw[j].get('name', '?')}) of {FILE}",
            )
    return boxes_m, tuple(kinds)
