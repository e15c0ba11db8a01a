"""The evaluation metrics: one home for the definitions every protocol shares.

* Collisions counted once per encounter (:func:`collision_encounters`, JAX, used inside the
  protocols' steps) and Hall's proxemic zones (:data:`HALL_ZONES_M`, :func:`zone_shares`).
* Seed 000's metrics (Sec. 5.3) from the experiment's per-task table.
* The social-navigation arena's per-episode metrics (seeds 001, 002, 004) live beside it in
  :mod:`evaluation.arena.nav_metrics`, built on the same collision counter.

Input of the latter: the task table of :func:`evaluation.warehouse.task_table`, one row per task with columns
``method, slot, replica, task, outcome, refused, time_s, stalled_s, distance_m, planned_m,
battery_used_pct, collisions``; and per (method, slot, replica) histograms of robot-person
distances. Everything but :func:`collision_encounters` is numpy/pandas, outside JAX; the tests of
differences are in :mod:`evaluation.statistics`.

Metric definitions (Sec. 5.3-5.4):

* outcome: success, congestion failure (deadline), battery failure (battery below B_min);
* time: *active* (successful tasks, robot moving), *stalled* (successful tasks, speed 0),
  *wasted* (failed tasks, all of it);
* distance: *planned* (successful tasks, the planned route's length), *extra* (successful
  tasks, driven minus planned), *wasted* (failed tasks, driven);
* battery: *effective* (successful tasks) and *wasted* (failed tasks), in cycles (100 % = 1);
* collisions: encounters of a person with the robot's circumscribed region (counted once each);
* space compliance: robot-person distances against Hall's zones.

One *run* is one replica of all slots (2090 tasks on the warehouse), the unit the paper
reports; means and 95 % intervals are over replicas (Student t).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pandas as pd

from socialnav.evaluation import statistics
from socialnav.evaluation.outcomes import OUTCOME_NAMES, OUTCOMES, SUCCESS
from socialnav.evaluation.statistics import mean_ci

# Hall's proxemic zones (outer radius, m), as in seed 000's Fig. 10.
HALL_ZONES_M = {"intimate": 0.5, "personal": 1.2, "social": 3.6, "public": 7.6}


def collision_encounters(
    in_contact: jax.Array, dist_m: jax.Array, present: jax.Array, radius_m: float, release_m: float
) -> tuple[jax.Array, jax.Array]:
    """Collisions counted once per encounter (JAX, one step of one world).

    A present person closer than ``radius_m`` starts an encounter unless already in one; an
    encounter lasts while they stay within ``radius_m + release_m``.

    Args:
      in_contact: (N,) bool, in an encounter before this step.
      dist_m: (N,) robot-person centre distances now; present: (N,) bool.

    Returns:
      (in_contact now, () int32 number of encounters that started now).
    """
    touching = present & (dist_m < radius_m)
    held = present & in_contact & (dist_m < radius_m + release_m)
    return touching | held, jnp.sum(touching & ~in_contact).astype(jnp.int32)


def add_components(tasks: pd.DataFrame) -> pd.DataFrame:
    """The table with the Fig. 9 components per task (zero where a component does not apply)."""
    t = tasks.copy()
    ok = t["outcome"] == OUTCOME_NAMES[SUCCESS]
    t["active_s"] = np.where(ok, t["time_s"] - t["stalled_s"], 0.0)
    t["stalled_ok_s"] = np.where(ok, t["stalled_s"], 0.0)
    t["wasted_s"] = np.where(ok, 0.0, t["time_s"])
    t["planned_ok_m"] = np.where(ok, t["planned_m"], 0.0)
    t["extra_m"] = np.where(ok, t["distance_m"] - t["planned_m"], 0.0)
    t["wasted_m"] = np.where(ok, 0.0, t["distance_m"])
    t["effective_cycles"] = np.where(ok, t["battery_used_pct"], 0.0) / 100.0
    t["wasted_cycles"] = np.where(ok, 0.0, t["battery_used_pct"]) / 100.0
    return t


def per_run(tasks: pd.DataFrame, by: tuple[str, ...] = ("method", "replica")) -> pd.DataFrame:
    """Totals per group (default: per method and replica = per run of all slots).

    Columns: tasks, success, congestion, battery (counts), refused, success_pct, collisions,
    the time components in h, the distance components in km, the battery components in cycles.
    """
    t = add_components(tasks)
    g = t.groupby(list(by), sort=True)
    out = pd.DataFrame({"tasks": g.size()})
    for name in OUTCOMES:
        out[name] = g["outcome"].apply(lambda s, n=name: int((s == n).sum()))
    out["refused"] = g["refused"].sum().astype(int)
    out["success_pct"] = 100.0 * out["success"] / out["tasks"]
    out["collisions"] = g["collisions"].sum().astype(int)
    for col in ("active_s", "stalled_ok_s", "wasted_s"):
        out[col.replace("_ok", "").replace("_s", "_h")] = g[col].sum() / 3600.0
    for col in ("planned_ok_m", "extra_m", "wasted_m"):
        out[col.replace("_ok", "").replace("_m", "_km")] = g[col].sum() / 1000.0
    for col in ("effective_cycles", "wasted_cycles"):
        out[col] = g[col].sum()
    driven = out["planned_km"] + out["extra_km"] + out["wasted_km"]
    out["wasted_distance_pct"] = 100.0 * out["wasted_km"] / driven.where(driven > 0)
    spent = out["active_h"] + out["stalled_h"] + out["wasted_h"]
    out["wasted_time_pct"] = 100.0 * out["wasted_h"] / spent.where(spent > 0)
    used = out["effective_cycles"] + out["wasted_cycles"]
    out["wasted_battery_pct"] = 100.0 * out["wasted_cycles"] / used.where(used > 0)
    return out.reset_index()


def summary_with_ci(runs: pd.DataFrame, columns=None) -> pd.DataFrame:
    """Per method: mean and 95 % interval over runs of each column of :func:`per_run`."""
    columns = columns or [
        "success_pct",
        "success",
        "congestion",
        "battery",
        "refused",
        "collisions",
        "active_h",
        "stalled_h",
        "wasted_h",
        "planned_km",
        "extra_km",
        "wasted_km",
        "effective_cycles",
        "wasted_cycles",
        "wasted_distance_pct",
        "wasted_time_pct",
        "wasted_battery_pct",
    ]
    rows = []
    for method, g in runs.groupby("method", sort=False):
        for col in columns:
            m, lo, hi = mean_ci(g[col])
            rows.append({"method": method, "metric": col, "mean": m, "ci_low": lo, "ci_high": hi, "runs": len(g)})
    return pd.DataFrame(rows)


def hist_quantiles(hist, bin_m: float, qs=(0.05, 0.25, 0.5, 0.75, 0.95)) -> np.ndarray:
    """Quantiles of binned distances (linear inside a bin)."""
    h = np.asarray(hist, np.float64)
    if h.sum() == 0:
        return np.full(len(qs), np.nan)
    cdf = np.concatenate([[0.0], np.cumsum(h) / h.sum()])
    edges = np.arange(len(h) + 1) * bin_m
    return np.interp(qs, cdf, edges)


def zone_shares(hist, bin_m: float) -> dict[str, float]:
    """Share of robot-person distance samples inside each of Hall's zones (and beyond public)."""
    h = np.asarray(hist, np.float64)
    upper = (np.arange(len(h)) + 1) * bin_m
    total = max(h.sum(), 1.0)
    shares, inner = {}, 0.0
    for name, radius in HALL_ZONES_M.items():
        inside = h[upper <= radius + 1e-9].sum()
        shares[name] = float((inside - inner) / total)
        inner = inside
    shares["beyond"] = float((h.sum() - inner) / total)
    return shares


def compare(
    tasks: pd.DataFrame, hists: dict[str, np.ndarray], bin_m: float, a: str = "baseline", b: str = "causal"
) -> dict:
    """The paper's tests between methods ``a`` and ``b`` (Sec. 5.3) plus interval estimates.

    ``hists``: method -> summed robot-person distance histogram.
    """
    t = add_components(tasks)
    ta, tb = t[t["method"] == a], t[t["method"] == b]
    runs = per_run(tasks)
    ra, rb = runs[runs["method"] == a], runs[runs["method"] == b]
    tests = {
        "success_failure": statistics.chi_square_success(tasks, a, b),
        "collisions_per_run": statistics.negative_binomial_test(ra["collisions"], rb["collisions"]),
        "collisions_per_task": statistics.negative_binomial_test(ta["collisions"], tb["collisions"]),
        "task_time_s": statistics.mann_whitney(ta["time_s"], tb["time_s"]),
        "distance_m": statistics.mann_whitney(ta["distance_m"], tb["distance_m"]),
        "battery_used_pct": statistics.mann_whitney(ta["battery_used_pct"], tb["battery_used_pct"]),
        "robot_person_distance_m": statistics.mann_whitney_binned(hists[a], hists[b]),
    }
    return tests
