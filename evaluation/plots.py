"""Figures of the evaluation: seed 000's Fig. 9 (efficiency), Fig. 10 (safety), Fig. 11 (routes)."""

from __future__ import annotations

import pathlib

import numpy as np

from socialnav.common import figures
from socialnav.evaluation import metrics
from socialnav.jaxsim import viz

METHOD_COLOURS = {"baseline": "#1f77b4", "causal": "#ff7f0e"}
ZONE_COLOURS = {"intimate": "#f4a3a3", "personal": "#fbe3a0", "social": "#b9d3f0", "public": "#c6e8c1"}


def _stacked(ax, runs, methods, parts, colours, title, unit):
    means = runs.groupby("method")[[p for p, _ in parts]].mean()
    for i, m in enumerate(methods):
        bottom = 0.0
        total = float(means.loc[m].clip(lower=0).sum())
        for (col, label), colour in zip(parts, colours):
            v = float(means.loc[m, col])
            if v < 0:  # e.g. extra distance when the robot cuts corners: written, not stacked
                ax.text(
                    i,
                    -0.02,
                    f"{label} {v:+.2f} {unit}",
                    ha="center",
                    va="top",
                    fontsize=7,
                    transform=ax.get_xaxis_transform(),
                    color=colour,
                )
                v = 0.0
            ax.bar(i, v, bottom=bottom, color=colour, edgecolor="white", width=0.6, label=label if i == 0 else None)
            if total > 0 and v / total > 0.04:
                ax.text(i, bottom + v / 2, f"{100 * v / total:.1f}%", ha="center", va="center", fontsize=8)
            bottom += v
    ax.set_xticks(range(len(methods)), methods)
    ax.tick_params(axis="x", pad=12)
    ax.set_title(title)
    ax.set_ylabel(unit)
    ax.legend(fontsize=7, loc="upper left")


def efficiency_figure(result, path) -> pathlib.Path:
    """Fig. 9: stacked bars per method (means per run): outcomes, distance, time, battery."""
    runs = metrics.per_run(result.tasks)
    methods = [m for m in ("baseline", "causal") if m in set(runs["method"])]
    fig = figures.figure(figsize=(9, 7.5))
    axes = fig.subplots(2, 2)
    red, blue, orange = "#d62728", "#1f77b4", "#ff7f0e"
    _stacked(
        axes[0, 0],
        runs,
        methods,
        [("success", "success"), ("congestion", "failure: congestion"), ("battery", "failure: battery")],
        [blue, orange, red],
        "Task outcomes",
        "tasks",
    )
    _stacked(
        axes[0, 1],
        runs,
        methods,
        [("planned_km", "planned"), ("extra_km", "extra"), ("wasted_km", "wasted")],
        [blue, orange, red],
        "Travelled distance",
        "km",
    )
    _stacked(
        axes[1, 0],
        runs,
        methods,
        [("active_h", "active"), ("stalled_h", "stalled"), ("wasted_h", "wasted")],
        [blue, orange, red],
        "Task time",
        "h",
    )
    _stacked(
        axes[1, 1],
        runs,
        methods,
        [("effective_cycles", "effective"), ("wasted_cycles", "wasted")],
        [blue, red],
        "Battery usage",
        "cycles",
    )
    n = result.config["replicas"]
    fig.suptitle(f"Efficiency, all slots (mean of {n} run{'s' if n > 1 else ''} of {runs['tasks'].iloc[0]} tasks)")
    fig.tight_layout()
    return figures.save(fig, path)


def _bxp_stats(hist, bin_m, label):
    q = metrics.hist_quantiles(hist, bin_m, (0.25, 0.5, 0.75))
    iqr = q[2] - q[0]
    lo_q, hi_q = metrics.hist_quantiles(hist, bin_m, (0.0, 1.0))
    return {
        "label": label,
        "q1": q[0],
        "med": q[1],
        "q3": q[2],
        "whislo": max(lo_q, q[0] - 1.5 * iqr),
        "whishi": min(hi_q, q[2] + 1.5 * iqr),
        "fliers": [],
    }


def safety_figure(result, path) -> pathlib.Path:
    """Fig. 10: collisions per run (mean, 95 % CI) and robot-person distances over Hall's zones."""
    runs = metrics.per_run(result.tasks)
    methods = [m for m in ("baseline", "causal") if m in set(runs["method"])]
    fig = figures.figure(figsize=(10, 4.5))
    a0, a1 = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1, 1.6]})
    for i, m in enumerate(methods):
        mean, lo, hi = metrics.mean_ci(runs[runs["method"] == m]["collisions"])
        a0.bar(i, mean, color=METHOD_COLOURS[m], width=0.6, yerr=[[mean - lo], [hi - mean]], capsize=6)
        a0.text(i, mean, f"{mean:.1f}", ha="center", va="bottom", fontsize=9)
    a0.set_xticks(range(len(methods)), methods)
    a0.set_ylabel("collisions per run")
    a0.set_title("Human-robot collisions (95% CI)")
    inner = 0.0
    for zone, radius in metrics.HALL_ZONES_M.items():
        a1.axhspan(inner, radius, color=ZONE_COLOURS[zone], alpha=0.6, lw=0, label=f"{zone} (<= {radius} m)")
        inner = radius
    stats = [_bxp_stats(result.distance_hist[m].sum(axis=(0, 1)), result.distance_bin_m, m) for m in methods]
    box = a1.bxp(stats, showfliers=False, patch_artist=True, widths=0.5)
    for patch, m in zip(box["boxes"], methods):
        patch.set_facecolor(METHOD_COLOURS[m])
    a1.set_ylabel("robot-person distance (m)")
    a1.set_ylim(0, max(8.5, max(s["whishi"] for s in stats) + 0.5))
    a1.set_title("Proxemic compliance (whiskers 1.5 IQR)")
    a1.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    return figures.save(fig, path)


def pick_route_example(result, waypoint_ids):
    """(slot, start, goal) of the task whose two routes differ and whose baseline fails most
    often relative to the causal planner; None when the routes never differ."""
    t = result.tasks
    rate = (
        t.assign(failed=t["outcome"] != "success")
        .groupby(["slot", "start", "goal", "method"], observed=True)["failed"]
        .mean()
        .unstack("method")
    )
    if not {"baseline", "causal"} <= set(rate.columns):
        return None
    rate = rate.dropna()
    ids = {n: i for i, n in enumerate(waypoint_ids)}
    base, causal = result.plans["baseline"], result.plans["causal"]
    best, best_gap = None, -np.inf
    for (slot, start, goal), row in rate.iterrows():
        i, j = ids[start], ids[goal]
        if np.array_equal(np.asarray(base.routes[slot, i, j]), np.asarray(causal.routes[slot, i, j])):
            continue
        gap = row["baseline"] - row["causal"]
        if gap > best_gap:
            best, best_gap = (int(slot), start, goal), gap
    return best


def route_figure(result, scenario, path) -> pathlib.Path:
    """Fig. 11: one task where the methods chose different routes, over the slot's predicted density."""
    pick = pick_route_example(result, scenario.waypoint_ids)
    fig = figures.figure(figsize=(9, 6.5))
    ax = fig.subplots()
    viz.draw_map(ax, scenario)
    if pick is None:
        ax.set_title("the two methods chose the same route for every task")
        return figures.save(fig, path)
    slot, start, goal = pick
    ids = {n: i for i, n in enumerate(scenario.waypoint_ids)}
    i, j = ids[start], ids[goal]
    xy = scenario.waypoint_xy_m
    dens = np.nan_to_num(result.density_ppm2[slot])
    sc = ax.scatter(
        xy[:, 0],
        xy[:, 1],
        c=dens,
        s=25 + 400 * dens / max(dens.max(), 1e-9),
        cmap="Reds",
        edgecolors="k",
        linewidths=0.3,
        zorder=2,
    )
    fig.colorbar(sc, ax=ax, shrink=0.6, label="E[D | do(S), W] (people/m²)")
    t = result.tasks[(result.tasks["slot"] == slot) & (result.tasks["start"] == start) & (result.tasks["goal"] == goal)]
    for name, offset in (("baseline", -0.12), ("causal", 0.12)):
        plan = result.plans[name]
        hops = int(plan.hops[slot, i, j])
        route = [i] + [int(k) for k in np.asarray(plan.routes[slot, i, j])[:hops]]
        share = 100 * (t[t["method"] == name]["outcome"] == "success").mean()
        ax.plot(
            xy[route, 0] + offset,
            xy[route, 1] + offset,
            "-o",
            lw=2.5,
            ms=3,
            color=METHOD_COLOURS[name],
            zorder=3,
            label=f"{name}: {float(plan.length_m[slot, i, j]):.1f} m, success {share:.0f}% "
            f"of {len(t[t['method'] == name])} runs",
        )
    ax.annotate("start", xy[i], fontsize=9, weight="bold")
    ax.annotate("goal", xy[j], fontsize=9, weight="bold")
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title(f"{scenario.slot_names[slot]}: {start} -> {goal}")
    return figures.save(fig, path)
