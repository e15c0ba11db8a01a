"""The arena's tables: per-episode metrics and trajectories as pandas frames, the per-scene summary.

:func:`episode_frame` and :func:`trajectory_frame` turn one method's metric arrays and
trajectories into frames (:func:`evaluation.arena.run.run_scene` calls them); :func:`summary`
reduces episodes to one row per scene and method, success rates with Wilson 95 % intervals
(``scipy.stats.binomtest``), the rest as means with Student t intervals (:func:`mean_interval`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats

from socialnav.common.intervals import wilson
from socialnav.evaluation.arena import episodes as arena
from socialnav.evaluation.arena import nav_metrics
from socialnav.evaluation.arena.papers import RATES

SUMMARY_MEANS = (
    "collisions",
    "intrusions",
    "d_min_m",
    "d_h_m",
    "d_1_m",
    "d_2_m",
    "time_s",
    "path_length_m",
    "chc_rad",
    "stalled_s",
    "spl",
    "zone_intimate",
    "zone_personal",
    "zone_social",
    "zone_public",
    "zone_body_intimate",
    "zone_body_personal",
    "zone_body_social",
    "zone_body_public",
    "group_share",
    "wall_contacts",
    "collisions_robot",
    "collisions_person",
    "intrusions_robot",
    "intrusions_person",
    "near_misses",
    "clearance_min_m",
    "group_intrusions",
    "speed_mean_mps",
    "turn_rate_mean_rps",
    "accel_mean_mps2",
    "jerk_mean_mps3",
    "path_irregularity_rad_per_m",
    "path_length_ratio",
    "no_progress_max_s",
    "people_speed_drop_mps",
    "people_deviation_m",
    "people_deviation_max_m",
)
# Shares of episodes reported in % beside the success rates (no interval).
SUMMARY_SHARES = ("deadlock", "timeout")


def episode_frame(
    scene: str, method: str, first: int, metrics: dict, wall_contacts, invalid_actions=None
) -> pd.DataFrame:
    """One row per episode: scalar metrics, zone shares, the first people's minimum distances,
    the wall contacts and ``invalid_action_steps`` (the steps whose action had a NaN or infinite
    entry, the base stopped instead; 0 for a sound actor)."""
    m = {k: np.asarray(v) for k, v in metrics.items()}
    n = len(m["goal_success"])
    rows = {"scene": [scene] * n, "method": [method] * n, "variant": np.arange(first, first + n)}
    for key, value in m.items():
        if key in ("zone_share", "zone_share_body"):
            for z, name in enumerate(nav_metrics.ZONE_NAMES):
                rows[f"zone_{'body_' if key.endswith('body') else ''}{name}"] = value[:, z]
        elif key == "d_person_m":
            for p in range(min(value.shape[1], 2)):
                rows[f"d_{p + 1}_m"] = np.where(np.isfinite(value[:, p]), value[:, p], np.nan)  # NaN: nobody there
        else:
            rows[key] = value
    rows["wall_contacts"] = np.asarray(wall_contacts)
    rows["invalid_action_steps"] = np.zeros(n, np.int32) if invalid_actions is None else np.asarray(invalid_actions)
    frame = pd.DataFrame(rows)
    frame["metrics_version"] = nav_metrics.VERSION
    return frame


# The trajectory's fields kept, each under its column name in the trajectory files.
_KEPT = {
    "robot_xy_m": "robot_xy",
    "robot_yaw_rad": "robot_yaw",
    "robot_speed_mps": "robot_speed",
    "reached": "reached",
    "speed_gain": "speed_gain",
    "people_xy_m": "people_xy",
    "people_present": "people_present",
}


def trajectory_frame(scene: str, method: str, first: int, tr: arena.Trajectory, keep: int, dt_s: float):
    """Long frame of the first ``keep`` episodes: one row per (variant, step), the robot's pose and
    speed, and ``p<k>_x, p<k>_y, p<k>_present`` per person slot."""
    keep = min(keep, tr.robot_xy_m.shape[0])
    if keep == 0:
        return None
    # To the host first, then the first ``keep``: slicing the device arrays compiled a small
    # program per array and scene shape (0.1-0.15 s a method, half a minute over the full table).
    host = {column: np.asarray(getattr(tr, name))[:keep] for name, column in _KEPT.items()}
    t = host["robot_xy"].shape[1]
    xy = host["robot_xy"].reshape(-1, 2)
    cols = {
        "scene": scene,
        "method": method,
        "variant": np.repeat(np.arange(first, first + keep), t),
        "t_s": np.tile((np.arange(t) + 1) * dt_s, keep),
        "robot_x": xy[:, 0],
        "robot_y": xy[:, 1],
        **{k: host[k].reshape(-1) for k in ("robot_yaw", "robot_speed", "reached", "speed_gain")},
    }
    pxy, present = host["people_xy"], host["people_present"]
    for p in range(pxy.shape[2]):
        cols[f"p{p}_x"] = pxy[:, :, p, 0].reshape(-1)
        cols[f"p{p}_y"] = pxy[:, :, p, 1].reshape(-1)
        cols[f"p{p}_present"] = present[:, :, p].reshape(-1)
    return pd.DataFrame(cols)


# The means that get a 95 % interval in the summary (``<key>_lo``, ``<key>_hi``).
INTERVAL_MEANS = (
    "collisions", "intrusions", "d_min_m", "d_h_m", "d_1_m", "d_2_m", "time_s", "path_length_m", "chc_rad", "spl",
    "zone_intimate", "zone_personal", "zone_social",
)  # fmt: skip


def mean_interval(values) -> tuple[float, float]:
    """95 % Student-t interval of a mean (``scipy.stats.t``; NaN and inf dropped); the mean itself
    twice when every value is equal, NaN with fewer than two values."""
    x = np.asarray(values, float)
    x = x[np.isfinite(x)]
    if len(x) < 2:
        return float("nan"), float("nan")
    m, se = float(x.mean()), float(stats.sem(x))
    if se == 0:
        return m, m
    lo, hi = stats.t.interval(0.95, len(x) - 1, loc=m, scale=se)
    return float(lo), float(hi)


def summary(episodes: pd.DataFrame) -> pd.DataFrame:
    """One row per (scene, method): n, goal and social success and the share of episodes with a
    personal-space intrusion (%, :data:`RATES`) with Wilson 95 % intervals
    (``_ci`` as text, ``_lo``/``_hi`` in %), means, t intervals of :data:`INTERVAL_MEANS`, and
    ``invalid_action_pct``, the share of episodes in which the actor gave a NaN or infinite
    action at least once (its rows measure a robot stopped on those steps, not the method)."""
    rows = []
    for (scene, method), g in episodes.groupby(["scene", "method"], sort=False):
        n = len(g)
        row = {"scene": scene, "method": method, "n": n}
        for key in RATES:
            if key not in g:  # a run from before a rate existed
                continue
            k = int(g[key].sum())
            lo, hi = wilson(k, n)
            row[key + "_pct"] = 100.0 * k / n
            row[key + "_ci"] = f"{100 * lo:.0f}-{100 * hi:.0f}"
            row[key + "_lo"], row[key + "_hi"] = 100.0 * lo, 100.0 * hi
        for key in SUMMARY_SHARES:
            if key in g:
                row[key + "_pct"] = 100.0 * float(g[key].mean())
        if "invalid_action_steps" in g:
            row["invalid_action_pct"] = 100.0 * float((g["invalid_action_steps"] > 0).mean())
        for key in SUMMARY_MEANS:
            if key in g:
                values = g[key].replace([np.inf, -np.inf], np.nan)
                row[key] = float(values.mean())
                if key in INTERVAL_MEANS:
                    row[key + "_lo"], row[key + "_hi"] = mean_interval(values)
        rows.append(row)
    return pd.DataFrame(rows)
