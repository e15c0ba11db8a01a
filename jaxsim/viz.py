"""Pictures of the warehouse: the map, a snapshot of workers and robot, densities per slot."""

from __future__ import annotations

import pathlib

import matplotlib
import numpy as np
from matplotlib.collections import LineCollection, PatchCollection
from matplotlib.patches import Circle, Rectangle

from socialnav.common import figures
from socialnav.jaxsim.scenario import Scenario
from socialnav.jaxsim.state import ACTIVITY, WALKING

BOX_COLOURS = {"wall": "#333333", "shelf": "#8c6d46", "table": "#b08850", "tray": "#3a7d44"}


def draw_map(ax, scenario: Scenario, *, edges: bool = True, labels: bool = False, building_only: bool = True):
    """Walls, furniture, the waypoint discs and (optionally) the graph on ``ax``."""
    for (x0, x1, y0, y1), kind in zip(scenario.boxes_m, scenario.box_kinds):
        ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, color=BOX_COLOURS.get(kind, "#555555"), lw=0))
    xy = scenario.waypoint_xy_m
    if edges:
        segs = np.stack([xy[scenario.edges[:, 0]], xy[scenario.edges[:, 1]]], 1)
        ax.add_collection(LineCollection(segs, colors="#9bb7d4", linewidths=0.4, zorder=1))
    discs = [Circle(c, r) for c, r in zip(xy, scenario.waypoint_radius_m)]
    ax.add_collection(PatchCollection(discs, facecolor="none", edgecolor="#7090b0", lw=0.5, zorder=1))
    if labels:
        for name, (x, y) in zip(scenario.waypoint_ids, xy):
            ax.text(x, y, name, fontsize=4, ha="center", va="center", color="#334")
    b = scenario.boxes_m
    ax.set_xlim(b[:, 0].min() - 0.5, b[:, 1].max() + 0.5)
    ax.set_ylim(b[:, 2].min() - 0.5, (b[:, 3].max() + 0.5) if building_only else xy[:, 1].max() + 3.5)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


def snapshot_png(scenario: Scenario, snapshot: dict, path: str | pathlib.Path) -> pathlib.Path:
    """Workers (walking / at an activity) and the robot at one instant, on the map."""
    fig = figures.figure(figsize=(9, 6.5))
    ax = fig.subplots()
    draw_map(ax, scenario)
    status = np.asarray(snapshot["worker_status"])
    for code, colour, label in [(WALKING, "#d62728", "walking"), (ACTIVITY, "#ff9f1c", "at an activity")]:
        m = status == code
        ax.scatter(
            np.asarray(snapshot["worker_x_m"])[m],
            np.asarray(snapshot["worker_y_m"])[m],
            s=22,
            c=colour,
            edgecolors="k",
            linewidths=0.3,
            zorder=3,
            label=f"{label} ({m.sum()})",
        )
    r = scenario.params.robot_radius_m
    ax.add_patch(Circle((snapshot["robot_x_m"], snapshot["robot_y_m"]), r, color="#1f77b4", zorder=4, label="robot"))
    t = snapshot["time_s"]
    slot = snapshot["slot"]
    ax.set_title(f"{scenario.name}: t = {t:.0f} s, slot {scenario.slot_names[slot]} ({scenario.slot_clock[slot]})")
    ax.legend(loc="upper right", fontsize=8, framealpha=0.9)
    return figures.save(fig, path)


def density_by_slot_png(
    scenario: Scenario, mean_density: np.ndarray, path: str | pathlib.Path, top: int = 3
) -> pathlib.Path:
    """One panel per slot, waypoint discs shaded by mean people density (seed 000 Fig. 6/7).

    Args:
      mean_density: (S, W) mean Eq. (3) density (people per m^2); NaN rows are left blank.
      top: the ``top`` most crowded waypoints of each slot are named.
    """
    s = scenario.n_slots
    cols = 4
    rows = int(np.ceil(s / cols))
    fig = figures.figure(figsize=(4.2 * cols, 3.1 * rows))
    axes = fig.subplots(rows, cols, squeeze=False)
    vmax = float(np.nanmax(mean_density)) if np.isfinite(mean_density).any() else 1.0
    cmap = matplotlib.colormaps["inferno_r"]
    xy = scenario.waypoint_xy_m
    for k, ax in enumerate(axes.ravel()):
        if k >= s:
            ax.axis("off")
            continue
        draw_map(ax, scenario, edges=False)
        d = mean_density[k]
        if np.isfinite(d).any():
            discs = [Circle(c, r) for c, r in zip(xy, scenario.waypoint_radius_m)]
            pc = PatchCollection(discs, cmap=cmap, zorder=2, alpha=0.85)
            pc.set_array(np.nan_to_num(d))
            pc.set_clim(0, vmax)
            ax.add_collection(pc)
            for i in np.argsort(-np.nan_to_num(d))[:top]:
                if d[i] > 0:
                    ax.text(
                        xy[i, 0],
                        xy[i, 1] + scenario.waypoint_radius_m[i] + 0.4,
                        scenario.waypoint_ids[i],
                        fontsize=6,
                        ha="center",
                        color="#0b3d91",
                        zorder=4,
                    )
        ax.set_title(f"{scenario.slot_names[k]} {scenario.slot_clock[k]}", fontsize=9)
    sm = matplotlib.cm.ScalarMappable(cmap=cmap, norm=matplotlib.colors.Normalize(0, vmax))
    fig.colorbar(sm, ax=axes.ravel().tolist(), shrink=0.6, label="mean people density D (people / m$^2$)")
    fig.suptitle("Mean people density per waypoint and time slot")
    return figures.save(fig, path)
