"""Pictures of arena runs, from the trajectories frame (:func:`evaluation.arena.report.trajectory_frame`):
each method's path with the people's tracks (as seed 002 Fig. 9-10), the distance to the nearest
person over time (seed 001 Fig. 7-8), the speed profile with the speed gain (seed 004 Fig. 13),
and an animation of one episode."""

from __future__ import annotations

import pathlib

import numpy as np
import pandas as pd

from socialnav.common import figures
from socialnav.common.atomic import write_atomic
from socialnav.jaxsim.params import TIAGO_RADIUS_M
from socialnav.jaxsim.scenes.spec import SceneSpec


def _people_columns(frame: pd.DataFrame) -> int:
    return sum(1 for c in frame.columns if c.startswith("p") and c.endswith("_present"))


def _scene_name(frame: pd.DataFrame) -> str:
    """The scene row a trajectories frame is of (its ``scene`` column), or "" for an empty one."""
    return str(frame["scene"].iloc[0]) if len(frame) else ""


def _draw_scene(ax, walls_m, objects, bounds_m):
    """A scene's walls (K, 4) boxes, objects (``(name, polygon, cost)``) and bounds on ``ax``."""
    from matplotlib.patches import Polygon, Rectangle

    for x0, x1, y0, y1 in walls_m:
        ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, color="0.3"))
    for _, poly, _ in objects:
        ax.add_patch(Polygon(poly, closed=True, color="tab:olive", alpha=0.3))
    xmin, xmax, ymin, ymax = bounds_m
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


def paths_figure(spec: SceneSpec, frame: pd.DataFrame, path, variant: int = 0) -> pathlib.Path:
    """One panel per method: the robot's path (blue, black dot at the start), the people's tracks
    (red, a dot where they end), for one variant."""
    frame = frame[frame["variant"] == variant]
    methods = list(dict.fromkeys(frame["method"]))
    n_people = _people_columns(frame)
    fig = figures.figure(figsize=(2.6 * len(methods), 2.4))
    axes = fig.subplots(1, len(methods), squeeze=False)[0]
    for ax, method in zip(axes, methods, strict=True):
        g = frame[frame["method"] == method]
        _draw_scene(ax, spec.walls_m, spec.objects, spec.bounds_m)
        for p in range(n_people):
            here = g[f"p{p}_present"].to_numpy()
            if here.any():
                x, y = g[f"p{p}_x"].to_numpy()[here], g[f"p{p}_y"].to_numpy()[here]
                ax.plot(x, y, color="tab:red", lw=1, alpha=0.7)
                ax.plot(x[-1], y[-1], "o", color="tab:red", ms=3)
        upto = g["reached"].to_numpy()
        stop = int(np.argmax(upto)) + 1 if upto.any() else len(g)
        ax.plot(g["robot_x"].to_numpy()[:stop], g["robot_y"].to_numpy()[:stop], color="tab:blue", lw=1.5)
        ax.plot(g["robot_x"].iloc[0], g["robot_y"].iloc[0], "o", color="black", ms=3)
        ax.set_title(method + ("" if upto.any() else " (no goal)"), fontsize=8)
    fig.suptitle(f"{_scene_name(frame) or spec.name}, variant {variant}", fontsize=9)
    return figures.save(fig, path, dpi=80)


def nearest_distance(frame: pd.DataFrame) -> np.ndarray:
    """(T,) distance from the robot to the nearest present person, per row of ``frame``."""
    n_people = _people_columns(frame)
    if n_people == 0:
        return np.full(len(frame), np.inf)
    rx, ry = frame["robot_x"].to_numpy()[:, None], frame["robot_y"].to_numpy()[:, None]
    px = np.stack([frame[f"p{p}_x"].to_numpy() for p in range(n_people)], axis=1)
    py = np.stack([frame[f"p{p}_y"].to_numpy() for p in range(n_people)], axis=1)
    present = np.stack([frame[f"p{p}_present"].to_numpy() for p in range(n_people)], axis=1)
    return np.where(present, np.hypot(px - rx, py - ry), np.inf).min(axis=1)


def distance_figure(frame: pd.DataFrame, path, variant: int = 0) -> pathlib.Path:
    """Distance to the nearest person over time, one line per method, Hall's zones shaded (the
    scene row named from ``frame``)."""
    frame = frame[frame["variant"] == variant]
    fig = figures.figure(figsize=(5.0, 2.6))
    ax = fig.subplots()
    for edge, name in ((0.45, "intimate"), (1.2, "personal")):
        ax.axhline(edge, color="0.6", lw=0.8, ls="--")
        ax.text(0.2, edge + 0.05, name, fontsize=7, color="0.4")
    for method, g in frame.groupby("method", sort=False):
        d = nearest_distance(g)
        reached = g["reached"].to_numpy()
        stop = int(np.argmax(reached)) + 1 if reached.any() else len(g)
        ax.plot(g["t_s"].to_numpy()[:stop], np.where(np.isfinite(d), d, np.nan)[:stop], lw=1.2, label=method)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("nearest person (m)")
    ax.set_ylim(0, 6)
    ax.legend(fontsize=6, ncol=2)
    ax.set_title(f"{_scene_name(frame)}, variant {variant}", fontsize=9)
    return figures.save(fig, path, dpi=90)


def speed_figure(frame: pd.DataFrame, method: str, path, variant: int = 0) -> pathlib.Path:
    """The robot's speed and the local planner's speed gain over time, with the distance to the
    nearest person (seed 004 Fig. 13), the scene row named from ``frame``."""
    g = frame[(frame["variant"] == variant) & (frame["method"] == method)]
    fig = figures.figure(figsize=(5.0, 2.6))
    ax = fig.subplots()
    t = g["t_s"].to_numpy()
    ax.plot(t, g["robot_speed"].to_numpy(), label="speed (m/s)", color="tab:blue")
    ax.plot(t, g["speed_gain"].to_numpy(), label="speed gain", color="tab:green", lw=0.8)
    ax.set_xlabel("time (s)")
    ax.set_ylim(0, 1.05)
    twin = ax.twinx()
    d = nearest_distance(g)
    twin.plot(t, np.where(np.isfinite(d), d, np.nan), color="tab:red", lw=0.8, label="nearest person (m)")
    twin.set_ylabel("nearest person (m)", color="tab:red")
    ax.legend(fontsize=7, loc="upper left")
    ax.set_title(f"{_scene_name(frame)}: {method}, variant {variant}", fontsize=9)
    return figures.save(fig, path, dpi=90)


def animation(
    spec: SceneSpec, frame: pd.DataFrame, method: str, path, variant: int = 0, every: int = 5
) -> pathlib.Path:
    """A GIF of one episode (every ``every``-th step): robot (blue disc), people (red)."""
    from matplotlib.animation import FuncAnimation, PillowWriter
    from matplotlib.patches import Circle

    g = frame[(frame["variant"] == variant) & (frame["method"] == method)].reset_index(drop=True)
    reached = g["reached"].to_numpy()
    stop = int(np.argmax(reached)) + 1 if reached.any() else len(g)
    steps = list(range(0, stop, every))
    n_people = _people_columns(g)
    fig = figures.figure(
        figsize=(3.6, 3.6 * (spec.bounds_m[3] - spec.bounds_m[2]) / (spec.bounds_m[1] - spec.bounds_m[0]))
    )
    ax = fig.subplots()
    _draw_scene(ax, spec.walls_m, spec.objects, spec.bounds_m)
    trail = ax.plot([], [], color="tab:blue", lw=1)[0]
    robot = Circle((0, 0), TIAGO_RADIUS_M, color="tab:blue")
    ax.add_patch(robot)
    people = [Circle((0, 0), 0.25, color="tab:red") for _ in range(n_people)]
    for c in people:
        ax.add_patch(c)
    title = ax.set_title("", fontsize=8)

    def draw(k):
        i = steps[k]
        trail.set_data(g["robot_x"].to_numpy()[: i + 1], g["robot_y"].to_numpy()[: i + 1])
        robot.center = (g["robot_x"].iloc[i], g["robot_y"].iloc[i])
        for p, c in enumerate(people):
            c.center = (g[f"p{p}_x"].iloc[i], g[f"p{p}_y"].iloc[i])
            c.set_visible(bool(g[f"p{p}_present"].iloc[i]))
        title.set_text(f"{spec.name}: {method}, t = {g['t_s'].iloc[i]:.1f} s")
        return [trail, robot, title, *people]

    anim = FuncAnimation(fig, draw, frames=len(steps), blit=False)
    return write_atomic(path, lambda tmp: anim.save(tmp, writer=PillowWriter(fps=10), dpi=100))


# The composite view's panels: (column of the summary, title, better when higher).
METHOD_PANELS = (
    ("goal_success_pct", "goal success (%)", True),
    ("social_success_pct", "social success (%)", True),
    ("collisions", "collisions / episode", False),
    ("intrusions", "personal-space entries", False),
    ("clearance_min_m", "min body gap (m)", True),
    ("time_s", "time (s)", False),
    ("path_length_ratio", "path length ratio", False),
    ("jerk_mean_mps3", "jerk (m/s^3)", False),
    ("people_deviation_m", "people's deviation (m)", False),
)


def methods_figure(summary: pd.DataFrame, path) -> pathlib.Path:
    """Per method, its mean over the run's scenes of each of :data:`METHOD_PANELS` (one panel per
    metric, one bar per method, a dot per scene), from :func:`evaluation.arena.report.summary`.
    Scenes weigh equally; held-out rows count as scenes of their own."""
    panels = [p for p in METHOD_PANELS if p[0] in summary]
    methods = list(dict.fromkeys(summary["method"]))
    cols = 3
    rows = -(-len(panels) // cols)
    fig = figures.figure(figsize=(3.4 * cols, 0.35 * len(methods) * rows + 1.0 * rows), layout="constrained")
    x = np.arange(len(methods))
    for k, (key, title, higher) in enumerate(panels):
        ax = fig.add_subplot(rows, cols, k + 1)
        # reindexed: a method whose values are all NaN (a broken actor's) keeps its row, empty
        per_scene = summary.pivot_table(index="scene", columns="method", values=key, sort=False, dropna=False)
        per_scene = per_scene.reindex(columns=methods)
        means = per_scene.mean(axis=0).to_numpy()
        ax.barh(x, means, color="tab:blue" if higher else "tab:orange", alpha=0.7)
        for j, m in enumerate(methods):
            ax.plot(per_scene[m].to_numpy(), np.full(len(per_scene), j), "k.", ms=2, alpha=0.5)
        ax.set_yticks(x, methods if k % cols == 0 else [""] * len(methods), fontsize=7)
        ax.invert_yaxis()
        ax.set_title(title + (" (higher better)" if higher else " (lower better)"), fontsize=8)
        ax.tick_params(axis="x", labelsize=7)
    fig.suptitle(f"methods over {summary['scene'].nunique()} scene(s): bars the mean, dots each scene", fontsize=9)
    return figures.save(fig, path, dpi=100)
