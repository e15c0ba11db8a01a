"""Measures of pedestrian motion, applied alike to recorded and simulated trajectories.

Trajectories are frames of ``run, person, frame, x_m, y_m`` rows (:mod:`socialnav.data.recorded`'s
form; a simulation writes the same) at a known frame rate.

* :func:`voronoi_density_speed`: density (persons/m²) and speed (m/s, along the walking
  direction) in a measurement area, per frame, by PedPy's Voronoi method (Steffen & Seyfried 2010;
  PedPy is the maintained library of the group that ran the Jülich experiments, so the data and
  the models are measured by the same code as the published diagrams).
* :func:`binned`: mean and standard deviation of speed per density bin.
* :func:`weidmann_speed`: Weidmann's (1993) fundamental diagram.
* :func:`lane_order`: the lane order parameter of counterflow (Rex & Löwen 2007's form).
* :func:`overlaps`: how often and how deep two bodies overlap.
* :func:`ade_fde`: displacement errors of predictions.
* :func:`walking_groups`: who walks together in an observed window.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from scipy import stats
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

# Weidmann (1993): v(rho) = v_free (1 - exp(-gamma (1/rho - 1/rho_max))), v_free 1.34 m/s,
# gamma 1.913 /m², rho_max 5.4 /m².
WEIDMANN_FREE_MPS = 1.34
WEIDMANN_GAMMA = 1.913
WEIDMANN_JAM_PER_M2 = 5.4
# The density bins of the fundamental diagram's comparison: 0.5-wide, centred at 0.5 ... 3.5 /m².
DENSITY_BINS = tuple(0.5 * k for k in range(1, 8))
# The frames a density bin of one run (or of a calibration's training runs) needs to be counted.
MIN_BIN_FRAMES = 100


def weidmann_speed(density_per_m2) -> np.ndarray:
    """Weidmann's speed (m/s) at ``density_per_m2`` (0 from the jam density on)."""
    rho = np.maximum(np.asarray(density_per_m2, float), 1e-9)
    v = WEIDMANN_FREE_MPS * (1.0 - np.exp(-WEIDMANN_GAMMA * (1.0 / rho - 1.0 / WEIDMANN_JAM_PER_M2)))
    return np.maximum(v, 0.0)


def voronoi_density_speed(
    rows: pd.DataFrame,
    frames_per_s: float,
    walkable_polygon_m: Sequence[Sequence[float]],
    measurement_area_m: Sequence[Sequence[float]],
    walking_direction: Sequence[float] | None = None,
    obstacles_m: Sequence[Sequence[Sequence[float]]] = (),
    frames: tuple[int, int] | None = None,
    speed_frame_step: int | None = None,
) -> pd.DataFrame:
    """``frame, density, speed`` in the measurement area by PedPy's Voronoi method.

    Args:
      rows: one run's ``person, frame, x_m, y_m``.
      walkable_polygon_m, obstacles_m: the walkable area (the Voronoi cells are cut to it).
      measurement_area_m: the polygon measured in.
      walking_direction: (2,) unit vector; speeds are along it (None: the speed's magnitude).
      frames: ``(first, last)`` frames kept (a steady state), inclusive; None: every frame.
      speed_frame_step: frames either side of a position for its speed (default: 0.3 s).
    """
    import pedpy

    data = pd.DataFrame(
        {
            "id": rows["person"].to_numpy(np.int64),
            "frame": rows["frame"].to_numpy(np.int64),
            "x": rows["x_m"].to_numpy(float),
            "y": rows["y_m"].to_numpy(float),
        }
    )
    step = speed_frame_step if speed_frame_step is not None else max(1, round(0.3 * frames_per_s))
    if frames is not None:
        data = _rows_for_frames(data, frames, step)
    traj = pedpy.TrajectoryData(data=data, frame_rate=float(frames_per_s))
    walkable = pedpy.WalkableArea(
        [tuple(p) for p in walkable_polygon_m], obstacles=[[tuple(p) for p in o] for o in obstacles_m] or None
    )
    area = pedpy.MeasurementArea(measurement_area_m)
    cells = pedpy.compute_individual_voronoi_polygons(
        traj_data=traj, walkable_area=walkable, cut_off=pedpy.Cutoff(radius=1.2, quad_segments=3)
    )
    density, intersection = pedpy.compute_voronoi_density(individual_voronoi_data=cells, measurement_area=area)
    individual = pedpy.compute_individual_speed(
        traj_data=traj,
        frame_step=step,
        movement_direction=None if walking_direction is None else np.asarray(walking_direction, float),
        speed_calculation=pedpy.SpeedCalculation.BORDER_SINGLE_SIDED,
    )
    speed = pedpy.compute_voronoi_speed(
        traj_data=traj, individual_speed=individual, individual_voronoi_intersection=intersection, measurement_area=area
    )
    out = density.merge(speed, on="frame")[["frame", "density", "speed"]]
    if frames is not None:
        out = out[(out["frame"] >= frames[0]) & (out["frame"] <= frames[1])]
    return out[out["density"] > 0].reset_index(drop=True)


def _rows_for_frames(data: pd.DataFrame, frames: tuple[int, int], step: int) -> pd.DataFrame:
    """The rows of ``id, frame, x, y`` that PedPy needs for the points of ``frames`` (inclusive):
    each person's rows from ``step`` rows before their first row inside ``frames`` to ``step`` rows
    after their last, and no one with no row inside. The points come out the same as from every
    row: a frame's Voronoi cells are that frame's people's, and a person's speed at a row is taken
    ``step`` of their own rows either side (PedPy's shift within a person), so the rows cut are
    only ever read for points that are dropped. It saves the Voronoi cells of the frames outside
    (a run's start-up, a simulation's warm-up: a third to a half of the frames)."""
    inside = data["frame"].between(*frames)
    position = data.groupby("id").cumcount()
    first = position.where(inside).groupby(data["id"]).transform("min")
    last = position.where(inside).groupby(data["id"]).transform("max")
    return data[(position >= first - step) & (position <= last + step)]  # NaN (no row inside): dropped


def binned(points: pd.DataFrame, bins: Sequence[float] = DENSITY_BINS, half_width: float = 0.25) -> pd.DataFrame:
    """``density_bin, n, speed_mean, speed_sd`` of ``density, speed`` points, a bin holding the
    points within ``half_width`` of its centre (bins with no point are left out)."""
    rows = []
    for centre in bins:
        inside = points[(points["density"] >= centre - half_width) & (points["density"] < centre + half_width)]
        if len(inside):
            rows.append(
                {
                    "density_bin": centre,
                    "n": len(inside),
                    "speed_mean": float(inside["speed"].mean()),
                    "speed_sd": float(inside["speed"].std(ddof=1)) if len(inside) > 1 else 0.0,
                }
            )
    return pd.DataFrame(rows, columns=["density_bin", "n", "speed_mean", "speed_sd"])


def against_band(bins: pd.DataFrame, data_bins: pd.DataFrame) -> pd.DataFrame:
    """The diagram's check bin by bin: ``density_bin, speed_mean, speed_mean_data, speed_sd_data,
    z, inside`` for the bins both :func:`binned` tables hold, ``z`` the speed's distance from the
    data's mean in the data's standard deviations and ``inside`` whether ``|z| <= 1``."""
    data_side = data_bins[["density_bin", "speed_mean", "speed_sd"]].rename(
        columns={"speed_mean": "speed_mean_data", "speed_sd": "speed_sd_data"}
    )
    both = data_side.merge(bins[["density_bin", "speed_mean"]], on="density_bin")
    z = (both["speed_mean"] - both["speed_mean_data"]) / both["speed_sd_data"].clip(lower=1e-9)
    return both.assign(z=z, inside=z.abs() <= 1.0)[
        ["density_bin", "speed_mean", "speed_mean_data", "speed_sd_data", "z", "inside"]
    ]


def band_score(band: pd.DataFrame) -> dict:
    """An :func:`against_band` table in three numbers: ``inside`` and ``of`` (bins), ``z2_mean``
    (the mean squared distance from the band's mean, in standard deviations)."""
    return {"inside": int(band["inside"].sum()), "of": len(band), "z2_mean": float(np.mean(band["z"] ** 2))}


def lane_order(
    rows: pd.DataFrame,
    direction_of: dict,
    box_m: tuple[float, float, float, float],
    band_half_m: float = 0.25,
    reach_m: float = 2.0,
) -> float:
    """The lane order parameter of a counterflow (Rex & Löwen 2007's form): for each person in
    ``box_m = (xmin, xmax, ymin, ymax)`` at a frame, ``phi = ((n_same - n_opp) / (n_same +
    n_opp))^2`` over the others within ``band_half_m`` sideways and ``reach_m`` along the
    corridor (x); averaged over the people with anyone in their band. 1: everyone walks in a
    lane of their own direction; about 1/(the neighbours in a band) for a random mixture.

    Args:
      rows: ``person, frame, x_m, y_m`` (the corridor along x).
      direction_of: person -> +1 or -1, the way they walk.
    """
    xmin, xmax, ymin, ymax = box_m
    phis = []
    for _, g in rows.groupby("frame", sort=False):
        x, y = g["x_m"].to_numpy(), g["y_m"].to_numpy()
        d = g["person"].map(direction_of).to_numpy(float)
        inside = (x >= xmin) & (x <= xmax) & (y >= ymin) & (y <= ymax)
        near = (np.abs(y[:, None] - y[None, :]) < band_half_m) & (np.abs(x[:, None] - x[None, :]) < reach_m)
        np.fill_diagonal(near, False)
        same = (near & (d[:, None] == d[None, :])).sum(axis=1)
        opposite = (near & (d[:, None] != d[None, :])).sum(axis=1)
        counted = inside & (same + opposite > 0)
        if counted.any():
            phis.append((((same - opposite) / np.maximum(same + opposite, 1)) ** 2)[counted])
    return float(np.concatenate(phis).mean()) if phis else float("nan")


def overlaps(rows: pd.DataFrame, radius_m: float) -> dict:
    """How bodies of ``radius_m`` overlap: ``pair_frames`` (pairs closer than two radii, over all
    pairs and frames), ``share_people`` (share of person-frames overlapping anyone), ``max_depth_m``
    and ``share_deeper_0_1_m`` (person-frames overlapping someone by more than 0.1 m)."""
    pairs, overlapping, deep, people, depth = 0, 0, 0, 0, 0.0
    for _, g in rows.groupby("frame", sort=False):
        xy = g[["x_m", "y_m"]].to_numpy()
        d = np.linalg.norm(xy[:, None] - xy[None, :], axis=-1)
        np.fill_diagonal(d, np.inf)
        gap = 2 * radius_m - d  # > 0: overlapping by that much
        worst = gap.max(axis=1) if len(xy) > 1 else np.full(len(xy), -np.inf)
        pairs += int((gap > 0).sum() // 2)
        overlapping += int((worst > 0).sum())
        deep += int((worst > 0.1).sum())
        people += len(xy)
        depth = max(depth, float(worst.max()) if len(xy) > 1 else 0.0)
    return {
        "pair_frames": pairs,
        "share_people": overlapping / max(people, 1),
        "max_depth_m": max(depth, 0.0),
        "share_deeper_0_1_m": deep / max(people, 1),
    }


def ade_fde(predicted_xy, true_xy) -> tuple[np.ndarray, np.ndarray]:
    """Per trajectory: the mean displacement over the predicted frames and the final one (m).
    ``predicted_xy``, ``true_xy``: (N, T, 2)."""
    err = np.linalg.norm(np.asarray(predicted_xy) - np.asarray(true_xy), axis=-1)
    return err.mean(axis=1), err[:, -1]


def paired_difference(error_m, baseline_error_m, window, block_windows: int = 20, confidence: float = 0.95,
                      resamples: int = 2000, seed: int = 0) -> tuple[float, float, float]:  # fmt: skip
    """The mean of ``error_m - baseline_error_m`` over scored people and its ``confidence``
    interval: ``(difference, low, high)`` (m; below 0: the model's error is the smaller).

    Prediction windows start at every frame and overlap, so a person's errors in neighbouring
    windows are not independent draws: the interval is a block bootstrap (scipy's, percentile)
    over blocks of ``block_windows`` consecutive windows (windows that far apart share no frame,
    8 observed + 12 predicted), each block's summed difference over its people counted, the
    statistic the ratio of the two sums.

    Args:
      error_m, baseline_error_m: (N,) each scored person's error under the model and the baseline.
      window: (N,) the index of the window each person was scored in (windows in time order).
    """
    sums, counts = _block_sums(error_m, baseline_error_m, window, block_windows)
    ratio = lambda s, c, axis=-1: np.sum(s, axis=axis) / np.sum(c, axis=axis)
    if len(sums) < 2:
        return float(ratio(sums, counts)), float("nan"), float("nan")
    result = stats.bootstrap((sums, counts), ratio, paired=True, vectorized=True, confidence_level=confidence,
                             n_resamples=resamples, method="percentile", rng=np.random.default_rng(seed))  # fmt: skip
    return float(ratio(sums, counts)), float(result.confidence_interval.low), float(result.confidence_interval.high)


def mean_paired_difference(groups, block_windows: int = 20, confidence: float = 0.95, resamples: int = 2000,
                           seed: int = 0) -> tuple[float, float, float]:  # fmt: skip
    """The mean over ``groups`` (scenes) of each one's :func:`paired_difference`, and its
    ``confidence`` interval: ``(difference, low, high)`` (m). The five-scene average of ETH/UCY
    weighs every scene alike whatever its number of people, so the interval is a stratified block
    bootstrap: each scene's blocks resampled apart from the others' (scipy's unpaired samples,
    percentile), the statistic the mean of the scenes' ratios.

    Args:
      groups: a sequence of ``(error_m, baseline_error_m, window)``, one a scene, as
        :func:`paired_difference` takes them.
    """
    blocks = [_block_sums(*group, block_windows) for group in groups]
    point = float(np.mean([s.sum() / c.sum() for s, c in blocks]))
    if any(len(s) < 2 for s, _ in blocks):
        return point, float("nan"), float("nan")

    def mean_of_ratios(*picks, axis=-1):
        return np.mean([s[k].sum(axis=axis) / c[k].sum(axis=axis) for (s, c), k in zip(blocks, picks, strict=True)],
                       axis=0)  # fmt: skip

    result = stats.bootstrap([np.arange(len(s)) for s, _ in blocks], mean_of_ratios, paired=False, vectorized=True,
                             confidence_level=confidence, n_resamples=resamples, method="percentile",
                             rng=np.random.default_rng(seed))  # fmt: skip
    return point, float(result.confidence_interval.low), float(result.confidence_interval.high)


def clearly_ahead(ade_high_m, fde_high_m):
    """Whether a model is clearly ahead of its baseline: both the ADE's and the FDE's interval of
    the difference (their ``high`` ends, scalars or arrays) lie below 0."""
    return (np.asarray(ade_high_m) < 0) & (np.asarray(fde_high_m) < 0)


def _block_sums(error_m, baseline_error_m, window, block_windows: int):
    """Each block's summed ``error_m - baseline_error_m`` and its number of people: ``(sums,
    counts)``, the blocks ``block_windows`` consecutive windows (the empty ones dropped)."""
    block = np.asarray(window) // block_windows
    _, block = np.unique(block, return_inverse=True)
    diff = np.asarray(error_m, float) - np.asarray(baseline_error_m, float)
    return np.bincount(block, weights=diff), np.bincount(block).astype(float)


def walking_groups(observed_xy, reach_m: float = 1.0, moving_m: float = 0.5) -> np.ndarray:
    """(W, P) int32 group ids of the people in observed windows (-1: walking alone).

    Two people walk together when both are present in every observed frame, each of them moved
    at least ``moving_m`` over the window, and they were never farther apart than ``reach_m``
    (default 1 m: the distance Moussaïd et al. 2010's pair holds, where their attraction starts,
    :mod:`jaxsim.groups`); a group is a connected set of such pairs, its id its lowest member's
    index. ETH/UCY ships no group labels, so this is the detection; ``scripts`` or a user may
    sweep ``reach_m`` (``docs/humans.md`` reports 0.8-1.5 m).

    Args:
      observed_xy: (W, P, T, 2) positions, NaN where a person is absent.
    """
    xy = np.asarray(observed_xy, float)
    w, p = xy.shape[:2]
    seen = ~np.isnan(xy[..., 0]).any(axis=-1)  # (W, P) present throughout
    moved = np.linalg.norm(np.nan_to_num(xy[:, :, -1] - xy[:, :, 0]), axis=-1) >= moving_m
    # The farthest two people are over the window (inf where either is absent), a frame at a time
    # with x and y apart: numpy's norm over a last axis of two is slow, every frame at once holds
    # (W, P, P, T) arrays (a gigabyte each for a training split), and the square root of the same
    # sum gives the same bits.
    farthest = np.full((w, p, p), -np.inf)
    for frame in np.moveaxis(xy, 2, 0):  # (W, P, 2)
        dx, dy = (frame[:, :, None, k] - frame[:, None, :, k] for k in (0, 1))
        gap = np.sqrt(dx * dx + dy * dy)
        farthest = np.maximum(farthest, np.where(np.isnan(gap), np.inf, gap))
    near = farthest <= reach_m
    ok = seen & moved
    paired = near & ok[:, :, None] & ok[:, None, :] & ~np.eye(p, dtype=bool)  # (W, P, P)
    # Groups are the connected components of the pairs, every window's people one block of one
    # graph (scipy's connected components); a group's id is its lowest member's index.
    window, a, b = np.nonzero(paired)
    graph = coo_matrix((np.ones(len(a), bool), (window * p + a, window * p + b)), shape=(w * p, w * p))
    _, component = connected_components(graph, directed=False)
    lowest = np.full(component.max() + 1 if len(component) else 0, w * p)
    np.minimum.at(lowest, component, np.arange(w * p))
    label = lowest[component].reshape(w, p) - p * np.arange(w)[:, None]
    return np.where(paired.any(axis=-1), label, -1).astype(np.int32)
