"""The prediction test's windows of a shipped recording, between its walls (``socialnav humans
predict --run``), and the protocol's sampling of any recording (:func:`every_sample`).

A Jülich corridor run records its walkable area (``runs.json``'s ``geometry``: the polygon PedPy's
notebooks measure in, and its obstacles); everything outside it inside the polygon's reach is a
wall. The polygon's ends along the walking direction are where the recording's people enter and
leave (its trajectories are cut to it), so the walls stop there: the field covers the polygon's
extent along the flow and reaches :data:`MARGIN_M` past it across the flow. ETH/UCY records no
walls: its runs are predicted in open space, as the field's protocol does.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from socialnav.data import recorded
from socialnav.evaluation.humans import validation
from socialnav.jaxsim.grid import Grid

MARGIN_M = 1.0  # how far past the walkable area, across the flow, its walls reach (m)


def every_sample(rows: pd.DataFrame, frames_per_s: float, sample_s: float) -> pd.DataFrame:
    """``rows`` (``frame`` a column) read every ``sample_s`` seconds: every k-th frame of the
    rows' frame step, k the whole number nearest to ``sample_s`` over that step (a coarser
    recording keeps its own step)."""
    frames = np.unique(rows["frame"].to_numpy())
    step = int(np.median(np.diff(frames))) if len(frames) > 1 else 1
    every = max(1, round(sample_s * frames_per_s / step)) * step
    return rows[((rows["frame"] - frames[0]) % every == 0).to_numpy()]


def run_walls(run: str, resolution_m: float = 0.05) -> Grid | None:
    """The wall field of shipped ``run`` (:func:`validation.walls_field`) from its walkable
    polygon and obstacles, or None for a run that records no geometry (open space)."""
    import shapely

    from socialnav.jaxsim.scenes.from_recording import walls_from_occupancy

    geometry = recorded.run_info(run).get("geometry")
    if not geometry or "walkable_polygon_m" not in geometry:
        return None
    area = shapely.Polygon(geometry["walkable_polygon_m"])
    for obstacle in geometry.get("obstacles_m") or []:
        area = area.difference(shapely.Polygon(obstacle))
    xmin, ymin, xmax, ymax = area.bounds
    along_x = abs(geometry.get("walking_direction", (0.0, 1.0))[0]) > 0.5
    bounds = (
        (xmin, xmax, ymin - MARGIN_M, ymax + MARGIN_M) if along_x else (xmin - MARGIN_M, xmax + MARGIN_M, ymin, ymax)
    )
    xs = np.arange(bounds[0] + resolution_m / 2, bounds[1], resolution_m)
    ys = np.arange(bounds[2] + resolution_m / 2, bounds[3], resolution_m)
    occupied = ~shapely.contains_xy(area, *np.meshgrid(xs, ys))  # row k at y = ys[k], as a ROS map read
    boxes = walls_from_occupancy(occupied, resolution_m, (bounds[0], bounds[2]), bounds)
    return validation.walls_field(boxes, bounds, resolution_m)


def run_windows(run: str, sample_s: float = 0.4, walls: bool = True) -> validation.PredictionWindows:
    """The prediction windows of shipped ``run`` read every ``sample_s`` seconds
    (:func:`every_sample`), between its walls (:func:`run_walls`) unless ``walls`` is False."""
    rows = every_sample(recorded.trajectories(run), recorded.frame_numbers_per_s(recorded.run_info(run)), sample_s)
    return validation.windows_of(rows).replace(walls=run_walls(run) if walls else None)


__all__ = ["MARGIN_M", "every_sample", "run_walls", "run_windows"]
