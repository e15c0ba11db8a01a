"""Seed 000's evaluation metrics (Sec. 5.3) and statistics, from the experiment's per-task table.

Input: the task table of :func:`planners.evaluation.task_table`, one row per task with columns
``method, slot, replica, task, outcome, refused, time_s, stalled_s, distance_m, planned_m,
battery_used_pct, collisions``; and per (method, slot, replica) histograms of robot-person
distances. Everything here is numpy/pandas/scipy, outside JAX.

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

import numpy as np
import pandas as pd
from scipy import optimize, special, stats

# Hall's proxemic zones (outer radius, m), as in the paper's Fig. 10.
HALL_ZONES_M = {"intimate": 0.5, "personal": 1.2, "social": 3.6, "public": 7.6}
OUTCOMES = ("success", "congestion", "battery")


def add_components(tasks: pd.DataFrame) -> pd.DataFrame:
    """The table with the Fig. 9 components per task (zero where a component does not apply)."""
    t = tasks.copy()
    ok = t["outcome"] == "success"
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


def mean_ci(values, confidence: float = 0.95) -> tuple[float, float, float]:
    """(mean, low, high): Student-t interval of the mean (the mean alone for one value)."""
    v = np.asarray(values, np.float64)
    if v.size == 0:
        raise ValueError("no values")
    m = float(v.mean())
    if v.size < 2:
        return m, m, m
    half = float(stats.t.ppf(0.5 + confidence / 2, v.size - 1) * v.std(ddof=1) / np.sqrt(v.size))
    return m, m - half, m + half


def summary_with_ci(runs: pd.DataFrame, columns=None) -> pd.DataFrame:
    """Per method: mean and 95 % interval over runs of each column of :func:`per_run`."""
    columns = columns or ["success_pct", "success", "congestion", "battery", "refused", "collisions",
                          "active_h", "stalled_h", "wasted_h", "planned_km", "extra_km", "wasted_km",
                          "effective_cycles", "wasted_cycles", "wasted_distance_pct", "wasted_time_pct",
                          "wasted_battery_pct"]
    rows = []
    for method, g in runs.groupby("method", sort=False):
        for col in columns:
            m, lo, hi = mean_ci(g[col])
            rows.append({"method": method, "metric": col, "mean": m, "ci_low": lo, "ci_high": hi, "runs": len(g)})
    return pd.DataFrame(rows)


def chi_square_success(tasks: pd.DataFrame, a: str, b: str) -> dict:
    """Chi-square test of independence of method and success/failure (2 x 2, Yates-corrected)."""
    table = np.array([[((tasks["method"] == m) & (tasks["outcome"] == "success")).sum(),
                       ((tasks["method"] == m) & (tasks["outcome"] != "success")).sum()] for m in (a, b)])
    if (table.sum(axis=0) == 0).any():  # all succeed (or all fail): no difference to test
        return {"test": "chi-square", "statistic": 0.0, "p_value": 1.0, "table": table.tolist()}
    chi2, p, dof, _ = stats.chi2_contingency(table)
    return {"test": "chi-square", "statistic": float(chi2), "p_value": float(p), "dof": int(dof),
            "table": table.tolist()}


def _nb_loglik(y: np.ndarray, mu: np.ndarray, alpha: float) -> float:
    """NB2 log-likelihood (variance mu + alpha mu^2)."""
    r = 1.0 / alpha
    return float(np.sum(special.gammaln(y + r) - special.gammaln(r) - special.gammaln(y + 1)
                        + r * np.log(r / (r + mu)) + y * np.log(np.where(mu > 0, mu / (r + mu), 1.0))))


def _nb_profile(y: np.ndarray, mu: np.ndarray) -> tuple[float, float]:
    """(max log-likelihood over alpha, alpha) with the means fixed; Poisson limit as alpha -> 0."""
    res = optimize.minimize_scalar(lambda la: -_nb_loglik(y, mu, np.exp(la)), bounds=(-12.0, 6.0), method="bounded")
    return -float(res.fun), float(np.exp(res.x))


def negative_binomial_test(counts_a, counts_b) -> dict:
    """Likelihood-ratio test that two groups of counts have the same mean, under NB2.

    An NB2 model with one mean per group (log link, group indicator: the MLE of each mean is
    the group's sample mean) against one common mean, the dispersion profiled out in both;
    the LR statistic is chi-square with 1 dof. Also returns the rate ratio b / a.
    """
    ya, yb = np.asarray(counts_a, np.float64), np.asarray(counts_b, np.float64)
    if ya.size == 0 or yb.size == 0:
        raise ValueError("both groups need counts")
    if (ya < 0).any() or (yb < 0).any():
        raise ValueError("counts must be >= 0")
    y = np.concatenate([ya, yb])
    if y.sum() == 0:
        return {"test": "negative binomial LR", "statistic": 0.0, "p_value": 1.0, "rate_ratio": float("nan")}
    mu1 = np.concatenate([np.full(ya.size, ya.mean()), np.full(yb.size, yb.mean())])
    ll1, alpha = _nb_profile(y, mu1)
    ll0, _ = _nb_profile(y, np.full(y.size, y.mean()))
    lr = max(0.0, 2.0 * (ll1 - ll0))
    ratio = float(yb.mean() / ya.mean()) if ya.mean() > 0 else float("inf")
    return {"test": "negative binomial LR", "statistic": lr, "p_value": float(stats.chi2.sf(lr, 1)),
            "dispersion_alpha": alpha, "rate_ratio": ratio}


def mann_whitney(x, y) -> dict:
    """Two-sided Mann-Whitney U test (scipy, asymptotic with tie correction)."""
    x, y = np.asarray(x, np.float64), np.asarray(y, np.float64)
    if x.size == 0 or y.size == 0:
        return {"test": "Mann-Whitney U", "statistic": float("nan"), "p_value": float("nan")}
    res = stats.mannwhitneyu(x, y, alternative="two-sided", method="asymptotic")
    return {"test": "Mann-Whitney U", "statistic": float(res.statistic), "p_value": float(res.pvalue),
            "median_a": float(np.median(x)), "median_b": float(np.median(y))}


def mann_whitney_binned(hist_a, hist_b) -> dict:
    """Mann-Whitney U test of two samples given as counts over the same ordered bins.

    Values in one bin are ties (midranks); two-sided normal approximation with tie and
    continuity correction, as scipy's asymptotic method computes it on the raw samples. Lets
    millions of robot-person distances be compared without materialising them.
    """
    a, b = np.asarray(hist_a, np.float64), np.asarray(hist_b, np.float64)
    if a.shape != b.shape:
        raise ValueError(f"histograms differ in shape: {a.shape} vs {b.shape}")
    n1, n2 = a.sum(), b.sum()
    if n1 == 0 or n2 == 0:
        return {"test": "Mann-Whitney U (binned)", "statistic": float("nan"), "p_value": float("nan")}
    below_b = np.cumsum(b) - b
    u1 = float(np.sum(a * (below_b + 0.5 * b)))
    t = a + b
    n = n1 + n2
    mu = n1 * n2 / 2.0
    var = n1 * n2 / 12.0 * ((n + 1) - np.sum(t ** 3 - t) / (n * (n - 1)))
    if var <= 0:
        return {"test": "Mann-Whitney U (binned)", "statistic": u1, "p_value": 1.0}
    z = (abs(u1 - mu) - 0.5) / np.sqrt(var)
    return {"test": "Mann-Whitney U (binned)", "statistic": u1, "p_value": float(min(1.0, 2 * stats.norm.sf(z)))}


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


def compare(tasks: pd.DataFrame, hists: dict[str, np.ndarray], bin_m: float, a: str = "baseline",
            b: str = "causal") -> dict:
    """The paper's tests between methods ``a`` and ``b`` (Sec. 5.3) plus interval estimates.

    ``hists``: method -> summed robot-person distance histogram.
    """
    t = add_components(tasks)
    ta, tb = t[t["method"] == a], t[t["method"] == b]
    runs = per_run(tasks)
    ra, rb = runs[runs["method"] == a], runs[runs["method"] == b]
    tests = {
        "success_failure": chi_square_success(tasks, a, b),
        "collisions_per_run": negative_binomial_test(ra["collisions"], rb["collisions"]),
        "collisions_per_task": negative_binomial_test(ta["collisions"], tb["collisions"]),
        "task_time_s": mann_whitney(ta["time_s"], tb["time_s"]),
        "distance_m": mann_whitney(ta["distance_m"], tb["distance_m"]),
        "battery_used_pct": mann_whitney(ta["battery_used_pct"], tb["battery_used_pct"]),
        "robot_person_distance_m": mann_whitney_binned(hists[a], hists[b]),
    }
    return tests
