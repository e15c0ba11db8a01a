"""A recorded-crowd scene written from a recording by fixed rules (``socialnav arena-scene``,
``scripts/build_recorded_scenes.py``): nothing in it is chosen after seeing a result.

* bounds: the recording's extent, one metre wider on every side, rounded out to whole metres
  (a corridor with a known geometry: its walkable area); walls: the corridor's (a recording
  without a geometry has none: the planners see open ground);
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


def recorded_scene(
    rows,
    name: str,
    playback: str,
    recording: dict,
    duration_s: float,
    source: str,
    geometry: dict | None = None,
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
    """
    if playback not in PLAYBACKS:
        raise ValueError(f"playback: expected one of {', '.join(PLAYBACKS)}, got {playback!r}")
    xy = rows[["x_m", "y_m"]].to_numpy()
    walls = []
    if geometry is None:
        flow = flow_axis(rows)
        across = np.array([-flow[1], flow[0]])
        lo, hi = np.floor(xy.min(0) - 1.0), np.ceil(xy.max(0) + 1.0)
        bounds = [lo[0], hi[0], lo[1], hi[1]]
        centre = np.median(xy, axis=0)
        along = (xy - centre) @ across
        start = centre + np.percentile(along, 15) * across
        goal = centre + np.percentile(along, 85) * across
    else:
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
