"""A recorded-crowd scene written from a recording by fixed rules (``socialnav arena-scene``,
``scripts/build_recorded_scenes.py``): nothing in it is chosen after seeing a result.

* bounds: the recording's extent, one metre wider on every side, rounded out to whole metres
  (a corridor with a known geometry: its walkable area); walls: the corridor's, or those of a map
  of the place (an occupancy grid, ``socialnav arena-scene --map``: its occupied cells inside the
  bounds, merged into boxes, :func:`walls_from_occupancy`); without either, none (the planners see
  open ground);
* the robot crosses the crowd's main flow: the flow is the principal axis of the people's
  velocities (sign ignored); the robot's start and goal lie on the perpendicular through the
  people's median position, at the 15th and 85th percentiles of their positions along it (a
  corridor: half a metre from each wall), each drawn within 0.5 m of that point;
* timeout: 10 s and 3 s per metre between start and goal (the robot's 0.5 m/s top speed covers
  a metre in 2 s), rounded up to 5 s;
* windows: evaluated and training windows lie in the first two thirds of the recording; held-out
  windows in the last third;
* rule: never within 0.45 m of anyone, centre to centre, as in the seed scenes.
"""

from __future__ import annotations

import math

import numpy as np

START_SPREAD_M = 0.5  # how far a start or goal is drawn from its point, along x and y
ROBOT_WALL_CLEAR_M = 0.5  # a corridor's start and goal: this far from its walls
EVALUATED_SHARE = 2 / 3  # the recording's first part, where evaluated and training windows lie
MOVING_MPS = 0.2  # the speed above which a sample counts towards the flow's direction
RULE = {"type": "min_distance", "distance_m": 0.45}
PLAYBACKS = ("replayed", "reactive")


def _r(x: float) -> float:
    return round(float(x), 2)


def flow_axis(rows) -> np.ndarray:
    """The principal axis of the people's velocities (unit (2,), sign as the first eigenvector's)
    from ``person, t_s, x_m, y_m`` rows; raises ``ValueError`` if nobody walks faster than
    :data:`MOVING_MPS`."""
    rows = rows.sort_values(["person", "t_s"])
    d = rows.groupby("person")[["x_m", "y_m", "t_s"]].diff().dropna()
    v = d[["x_m", "y_m"]].to_numpy() / d[["t_s"]].to_numpy()
    moving = np.linalg.norm(v, axis=1) > MOVING_MPS
    if not moving.any():
        raise ValueError(
            f"nobody walks faster than {MOVING_MPS} m/s: no flow for the robot to cross "
            "(are the positions in metres and the times in seconds?)"
        )
    _, vectors = np.linalg.eigh(v[moving].T @ v[moving])
    return vectors[:, -1]


def open_ground_bounds(rows) -> list[float]:
    """``[xmin, xmax, ymin, ymax]`` (m) of a recording without a geometry: its people's extent, one
    metre wider on every side, rounded out to whole metres."""
    xy = rows[["x_m", "y_m"]].to_numpy()
    lo, hi = np.floor(xy.min(0) - 1.0), np.ceil(xy.max(0) + 1.0)
    return [float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1])]


def walls_from_occupancy(occupied, resolution_m: float, origin_xy_m, bounds_m) -> list[list[float]]:
    """The occupied cells of an occupancy grid (``occupied`` (H, W), truthy where a wall is; row 0
    at ``origin_xy_m``'s y, the bottom, as a ROS map's OccupancyGrid) that overlap ``bounds_m``,
    as scene walls ``[xmin, xmax, ymin, ymax]`` (m): each row's runs of occupied cells, a run
    continued by the same run in the rows above merged into one box (exactly the cells, fewer
    boxes than cells), clipped to the bounds."""
    occupied = np.asarray(occupied) > 0
    x0, y0 = float(origin_xy_m[0]), float(origin_xy_m[1])
    xmin, xmax, ymin, ymax = (float(b) for b in bounds_m)
    cols = slice(max(0, int(np.floor((xmin - x0) / resolution_m))), max(0, int(np.ceil((xmax - x0) / resolution_m))))
    rows = slice(max(0, int(np.floor((ymin - y0) / resolution_m))), max(0, int(np.ceil((ymax - y0) / resolution_m))))
    part = occupied[rows, cols]
    c_off, r_off = cols.start, rows.start
    boxes, open_runs = [], {}  # (first column, end column) -> first row of the box growing upward
    for r in range(part.shape[0] + 1):
        line = part[r] if r < part.shape[0] else np.zeros(part.shape[1], bool)
        edges = np.flatnonzero(np.diff(np.concatenate([[False], line, [False]]).astype(np.int8)))
        runs = set(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))
        for run in [k for k in open_runs if k not in runs]:
            first = open_runs.pop(run)
            boxes.append((run[0], run[1], first, r))
        for run in runs:
            open_runs.setdefault(run, r)
    walls = []
    for c0, c1, r0, r1 in sorted(boxes, key=lambda b: (b[2], b[0])):
        box = [
            max(xmin, x0 + (c_off + c0) * resolution_m),
            min(xmax, x0 + (c_off + c1) * resolution_m),
            max(ymin, y0 + (r_off + r0) * resolution_m),
            min(ymax, y0 + (r_off + r1) * resolution_m),
        ]
        if box[0] < box[1] and box[2] < box[3]:
            walls.append([round(v, 4) for v in box])
    return walls


def recorded_scene(
    rows,
    name: str,
    playback: str,
    recording: dict,
    duration_s: float,
    source: str,
    geometry: dict | None = None,
    walls: list | None = None,
) -> dict:
    """The scene (a dict in the scene format, :func:`jaxsim.scenes.spec.load_scene`) of the
    recording whose ``person, t_s, x_m, y_m`` ``rows`` last ``duration_s`` seconds once
    resampled, named ``<name>_<playback>``.

    Args:
      recording: the scene's ``recording`` block without ``playback`` and ``window_within_s``:
        ``{"run": ...}`` or ``{"file": ...}``.
      source: the scene's ``source`` text (where the recording comes from, how it was written).
      geometry: a corridor's (:func:`socialnav.data.recorded.run_info`'s ``geometry``: the
        walkable polygon, obstacles, measurement area and width, the corridor along x from y = 0),
        or None for open ground.
      walls: without a geometry, the scene's walls (boxes inside :func:`open_ground_bounds`, from
        a map: :func:`walls_from_occupancy`); None or ``[]``: none.
    """
    if playback not in PLAYBACKS:
        raise ValueError(f"playback: expected one of {', '.join(PLAYBACKS)}, got {playback!r}")
    xy = rows[["x_m", "y_m"]].to_numpy()
    if geometry is None:
        walls = [list(w) for w in (walls or [])]
        flow = flow_axis(rows)
        across = np.array([-flow[1], flow[0]])
        bounds = open_ground_bounds(rows)
        centre = np.median(xy, axis=0)
        along = (xy - centre) @ across
        start = centre + np.percentile(along, 15) * across
        goal = centre + np.percentile(along, 85) * across
    else:
        if walls:
            raise ValueError("walls come from the geometry of a corridor: give one or the other")
        walls = []
        polygon = np.array(geometry["walkable_polygon_m"])
        bounds = [polygon[:, 0].min(), polygon[:, 0].max(), polygon[:, 1].min(), polygon[:, 1].max()]
        for obstacle in geometry["obstacles_m"]:
            o = np.array(obstacle)
            walls.append([_r(o[:, 0].min()), _r(o[:, 0].max()), _r(o[:, 1].min()), _r(o[:, 1].max())])
        centre = np.array(geometry["measurement_area_m"]).mean(0)
        width = float(geometry["corridor_width_m"])
        start = np.array([centre[0], ROBOT_WALL_CLEAR_M])
        goal = np.array([centre[0], width - ROBOT_WALL_CLEAR_M])
    distance = float(np.linalg.norm(goal - start))
    timeout = 5 * math.ceil((10 + 3 * distance) / 5)
    spread = [[_r(p[0] - START_SPREAD_M), _r(p[0] + START_SPREAD_M)] for p in (start, goal)]
    y_spread = [[_r(p[1] - START_SPREAD_M), _r(p[1] + START_SPREAD_M)] for p in (start, goal)]
    if geometry is not None:  # along the corridor only: across it the walls are near
        y_spread = [[_r(start[1]), _r(start[1])], [_r(goal[1]), _r(goal[1])]]
    heading = math.degrees(math.atan2(goal[1] - start[1], goal[0] - start[0]))
    return {
        "name": f"{name}_{playback}",
        "source": source,
        "bounds_m": [_r(b) for b in bounds],
        "walls": walls,
        "robot": {
            "start": [spread[0], y_spread[0]],
            "yaw_deg": _r(heading),
            "goal": [spread[1], y_spread[1]],
        },
        "timeout_s": timeout,
        "people": [],
        "rule": dict(RULE),
        "recording": {
            **recording,
            "playback": playback,
            "window_within_s": [0.0, _r(EVALUATED_SHARE * duration_s)],
        },
    }
