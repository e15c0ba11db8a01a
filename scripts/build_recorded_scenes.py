"""Write the recorded-crowd scenes (``data/scenes/recorded/*.json``) from the shipped pedestrian runs.

    python scripts/build_recorded_scenes.py            # writes the files, prints one line each

One scene per recording and playback mode (``<name>_replayed``, ``<name>_reactive``): the five
ETH/UCY test scenes (``univ`` from ``students003``: ``students001`` has up to 79 people at once,
above the scene format's 64 slots) and the two Jülich corridors that have room to cross. Every
number comes from the recording, by the rules below, so nothing is chosen after seeing a result:

* bounds: the recording's extent, one metre wider on every side (the Jülich corridors: their
  walkable area); walls: the Jülich corridors' walls (ETH/UCY ships no map of its walls);
* the robot crosses the crowd's main flow: the flow is the principal axis of the people's
  velocities (sign ignored); the robot's start and goal lie on the perpendicular through the
  people's median position, at the 15th and 85th percentiles of their positions along it
  (the corridors: half a metre from each wall), each drawn within 0.5 m of that point;
* timeout: 10 s and 3 s per metre between start and goal (the robot's 0.5 m/s top speed covers
  a metre in 2 s), rounded up to 5 s;
* windows: evaluated and training windows lie in the first two thirds of the recording; held-out
  windows in the last third;
* rule: never within 0.45 m of anyone, centre to centre, as in the seed scenes.

The scenes are committed; this script is their record and rebuilds them.
"""

from __future__ import annotations

import json
import math

import numpy as np

from socialnav.data import DATA_DIR, recorded
from socialnav.jaxsim.scenes import recording as recording_lib

OUT = DATA_DIR / "scenes" / "recorded"
ETH_UCY = {
    "eth": "biwi_eth",
    "hotel": "biwi_hotel",
    "univ": "students003",
    "zara1": "crowds_zara01",
    "zara2": "crowds_zara02",
}
JUELICH = {"juelich_bi_corridor": "bi_corr_400_b_03", "juelich_uni_corridor": "uni_corr_500_01"}
START_SPREAD_M = 0.5
ROBOT_WALL_CLEAR_M = 0.5
EVALUATED_SHARE = 2 / 3


def _r(x: float) -> float:
    return round(float(x), 2)


def _flow_axis(rows) -> np.ndarray:
    """The principal axis of the people's velocities (unit, sign as the first eigenvector's)."""
    rows = rows.sort_values(["person", "t_s"])
    d = rows.groupby("person")[["x_m", "y_m", "t_s"]].diff().dropna()
    v = d[["x_m", "y_m"]].to_numpy() / d[["t_s"]].to_numpy()
    moving = np.linalg.norm(v, axis=1) > 0.2
    _, vectors = np.linalg.eigh(v[moving].T @ v[moving])
    return vectors[:, -1]


def _scene(name: str, run: str, playback: str) -> dict:
    rows = recorded.trajectories(run)
    info = recorded.run_info(run)
    xy = rows[["x_m", "y_m"]].to_numpy()
    flow = _flow_axis(rows)
    across = np.array([-flow[1], flow[0]])
    walls, geometry = [], info.get("geometry")
    if geometry is None:
        lo, hi = np.floor(xy.min(0) - 1.0), np.ceil(xy.max(0) + 1.0)
        bounds = [lo[0], hi[0], lo[1], hi[1]]
        centre = np.median(xy, axis=0)
        along = (xy - centre) @ across
        start = centre + np.percentile(along, 15) * across
        goal = centre + np.percentile(along, 85) * across
        source = f"{run} (ETH/UCY, scene {info['scene']}): the robot crosses the main flow"
    else:
        polygon = np.array(geometry["walkable_polygon_m"])
        bounds = [polygon[:, 0].min(), polygon[:, 0].max(), polygon[:, 1].min(), polygon[:, 1].max()]
        for obstacle in geometry["obstacles_m"]:
            o = np.array(obstacle)
            walls.append([_r(o[:, 0].min()), _r(o[:, 0].max()), _r(o[:, 1].min()), _r(o[:, 1].max())])
        area = np.array(geometry["measurement_area_m"])
        centre = area.mean(0)
        width = float(geometry["corridor_width_m"])  # the corridor runs along x from y = 0
        start = np.array([centre[0], ROBOT_WALL_CLEAR_M])
        goal = np.array([centre[0], width - ROBOT_WALL_CLEAR_M])
        source = f"{run} (Jülich corridor, {width:g} m wide): the robot crosses the corridor and its flow"
    distance = float(np.linalg.norm(goal - start))
    timeout = 5 * math.ceil((10 + 3 * distance) / 5)
    duration = recording_lib.load_recording(run).duration_s
    spread = [[_r(p[0] - START_SPREAD_M), _r(p[0] + START_SPREAD_M)] for p in (start, goal)]
    y_spread = [[_r(p[1] - START_SPREAD_M), _r(p[1] + START_SPREAD_M)] for p in (start, goal)]
    if geometry is not None:  # along the corridor only: across it the walls are near
        y_spread = [[_r(start[1]), _r(start[1])], [_r(goal[1]), _r(goal[1])]]
    heading = math.degrees(math.atan2(goal[1] - start[1], goal[0] - start[0]))
    return {
        "name": f"{name}_{playback}",
        "source": f"{source}; {playback} (scripts/build_recorded_scenes.py)",
        "bounds_m": [_r(b) for b in bounds],
        "walls": walls,
        "robot": {
            "start": [spread[0], y_spread[0]],
            "yaw_deg": _r(heading),
            "goal": [spread[1], y_spread[1]],
        },
        "timeout_s": timeout,
        "people": [],
        "rule": {"type": "min_distance", "distance_m": 0.45},
        "recording": {
            "run": run,
            "playback": playback,
            "window_within_s": [0.0, _r(EVALUATED_SHARE * duration)],
        },
    }


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    for name, run in {**ETH_UCY, **JUELICH}.items():
        for playback in ("replayed", "reactive"):
            scene = _scene(name, run, playback)
            file = OUT / f"{scene['name']}.json"
            file.write_text(json.dumps(scene, indent=1) + "\n")
            data = recording_lib.load_recording(run)
            print(
                f"{file.name}: {run}, {data.duration_s:.0f} s, up to {recording_lib.slots_needed(data)} people, "
                f"timeout {scene['timeout_s']} s"
            )


if __name__ == "__main__":
    main()
