"""Walls as a precomputed signed distance field, and line-of-sight lookups (host side, numpy).

The walls are axis-aligned boxes. Rather than testing every agent against every box each step
(51 x 38 box distances), the simulator looks the distance up in a grid precomputed once (one
packed gather per agent and step; the analytic alternative was not benchmarked). Each cell
stores the signed distance to the nearest wall surface (negative inside a box) and the unit
vector pointing away from that wall, which is exactly what pedsim's obstacle force needs (it
only uses the closest obstacle point).
"""

from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class DistanceField:
    """Signed distance to the walls on a regular grid.

    Attributes:
      origin_m: (2,) world position of cell (0, 0)'s centre.
      resolution_m: cell size.
      sdf_m: (H, W) float32 signed distance (negative inside walls), row = y, column = x.
      normal_x, normal_y: (H, W) float32 unit vector pointing away from the nearest wall.
    """

    origin_m: np.ndarray
    resolution_m: float
    sdf_m: np.ndarray
    normal_x: np.ndarray
    normal_y: np.ndarray


def _centres_and_halves(boxes_m, xp):
    centre = xp.stack([(boxes_m[:, 0] + boxes_m[:, 1]) / 2, (boxes_m[:, 2] + boxes_m[:, 3]) / 2], axis=-1)
    half = xp.stack([(boxes_m[:, 1] - boxes_m[:, 0]) / 2, (boxes_m[:, 3] - boxes_m[:, 2]) / 2], axis=-1)
    return centre, half


def box_distance(xy, boxes_m, xp=np):
    """Exact signed distance from points to the union of axis-aligned boxes, and the unit
    normal pointing away from the nearest one. One formula for the host (``xp=numpy``, float64:
    the precomputed fields) and for traced code (``xp=jax.numpy``: the scenes' robot and band).

    Args:
      xy: (..., 2) points.
      boxes_m: (B, 4) boxes ``xmin, xmax, ymin, ymax``.
      xp: the array module, ``numpy`` or ``jax.numpy``.

    Returns:
      ((...,) distance to the nearest box surface, negative inside; (..., 2) unit vector from
      that surface towards the point: outside along the offset from the box, inside along the
      axis of the closest face).
    """
    centre, half = _centres_and_halves(boxes_m, xp)
    offset = xy[..., None, :] - centre  # (..., B, 2)
    q = xp.abs(offset) - half
    outside = xp.linalg.norm(xp.maximum(q, 0.0), axis=-1)
    inside = xp.minimum(xp.max(q, axis=-1), 0.0)
    sd = outside + inside
    sign = xp.where(offset >= 0, 1.0, -1.0)
    out_dir = sign * xp.maximum(q, 0.0) / xp.maximum(outside, 1e-9)[..., None]
    face_x = q[..., 0] >= q[..., 1]
    in_dir = xp.where(
        face_x[..., None],
        xp.stack([sign[..., 0], 0.0 * sign[..., 0]], -1),
        xp.stack([0.0 * sign[..., 1], sign[..., 1]], -1),
    )
    normal = xp.where((outside > 0)[..., None], out_dir, in_dir)
    k = xp.argmin(sd, axis=-1)
    nearest = xp.min(sd, axis=-1)  # = sd at k, without a gather
    n = xp.take_along_axis(normal, k[..., None, None], axis=-2)[..., 0, :]
    return nearest, n


def box_signed_distance(px: np.ndarray, py: np.ndarray, boxes_m: np.ndarray):
    """:func:`box_distance` on the host in float64, the coordinates and normal apart: the same
    bits (tested), one box at a time (a running minimum; a tie keeps the earlier box, as
    ``argmin`` does) rather than every box at once, which holds a (..., B, 2) array per operation
    and is many times slower on a simulated day's positions.

    Args:
      px, py: (...,) point coordinates.
      boxes_m: (B, 4) boxes ``xmin, xmax, ymin, ymax``, at least one.

    Returns:
      (sd, nx, ny), each shaped like ``px``.
    """
    px, py = np.broadcast_arrays(np.asarray(px, np.float64), np.asarray(py, np.float64))
    sd = np.full(px.shape, np.inf)
    nx, ny = np.zeros(px.shape), np.zeros(px.shape)
    for centre, half in zip(*_centres_and_halves(np.asarray(boxes_m, np.float64), np)):
        box_sd, box_nx, box_ny = _to_box_host(px - centre[0], py - centre[1], half[0], half[1])
        closer = box_sd < sd
        sd, nx, ny = np.where(closer, box_sd, sd), np.where(closer, box_nx, nx), np.where(closer, box_ny, ny)
    return sd, nx, ny


def _to_box_host(ox, oy, half_x, half_y):
    """:func:`box_distance`'s terms for one box on the host with x and y apart: the same float64
    operations in the same order (the same bits, tested), without numpy's slow reductions over a
    last axis of two.

    Args:
      ox, oy: (...,) the points' offset from the box's centre.
      half_x, half_y: the box's half size.

    Returns:
      (sd, nx, ny), each (...,).
    """
    qx, qy = np.abs(ox) - half_x, np.abs(oy) - half_y
    mx, my = np.maximum(qx, 0.0), np.maximum(qy, 0.0)
    outside = np.sqrt(mx * mx + my * my)
    sd = outside + np.minimum(np.maximum(qx, qy), 0.0)
    sx, sy = np.where(ox >= 0, 1.0, -1.0), np.where(oy >= 0, 1.0, -1.0)
    den = np.maximum(outside, 1e-9)
    face_x = qx >= qy
    out = outside > 0
    nx = np.where(out, sx * mx / den, np.where(face_x, sx, 0.0 * sx))
    ny = np.where(out, sy * my / den, np.where(face_x, 0.0 * sy, sy))
    return sd, nx, ny


def build_distance_field(
    boxes_m: np.ndarray, bounds_m: tuple[float, float, float, float], resolution_m: float = 0.05
) -> DistanceField:
    """Precompute the signed distance field over ``bounds_m = (xmin, xmax, ymin, ymax)``: what
    :func:`box_distance` gives at each cell centre, the same bits (tested), one box at a time
    (:func:`box_signed_distance`), several times faster than every box at once: every process
    that builds the warehouse pays it."""
    boxes_m = np.asarray(boxes_m, np.float64)
    if not len(boxes_m):
        raise ValueError("a distance field needs at least one box")
    xmin, xmax, ymin, ymax = bounds_m
    xs = np.arange(xmin, xmax + resolution_m / 2, resolution_m)
    ys = np.arange(ymin, ymax + resolution_m / 2, resolution_m)
    sd, nx, ny = box_signed_distance(*np.meshgrid(xs, ys), boxes_m)  # (H, W)
    return DistanceField(np.array([xmin, ymin]), resolution_m, *(a.astype(np.float32) for a in (sd, nx, ny)))


def segment_hits_boxes(p0, p1, boxes_m, xp=np):
    """Whether segments cross any box (slab test): one formula for numpy (``xp=np``, float64: the
    warehouse's waypoint grid) and ``jax.numpy`` (``xp=jnp``, traced: the arena's line of sight).

    Args:
      p0, p1: (..., 2) segment end points.
      boxes_m: (B, 4) boxes ``(xmin, xmax, ymin, ymax)``.
      xp: the array module.

    Returns:
      (...,) bool.
    """
    if xp is np:
        p0, p1, boxes_m = (np.asarray(a, np.float64) for a in (p0, p1, boxes_m))
    p0 = p0[..., None, :]
    d = p1[..., None, :] - p0
    low, high = boxes_m[:, [0, 2]], boxes_m[:, [1, 3]]
    # A zero direction component: the slab is either always (inside) or never crossed.
    zero = d == 0
    safe = xp.where(zero, 1.0, d)
    t_low, t_high = (low - p0) / safe, (high - p0) / safe
    inside = (low <= p0) & (p0 <= high)
    t_enter = xp.where(zero, xp.where(inside, -xp.inf, xp.inf), xp.minimum(t_low, t_high))
    t_exit = xp.where(zero, xp.where(inside, xp.inf, -xp.inf), xp.maximum(t_low, t_high))
    t_enter = xp.maximum(xp.max(t_enter, axis=-1), 0.0)
    t_exit = xp.minimum(xp.min(t_exit, axis=-1), 1.0)
    return xp.any(t_enter <= t_exit, axis=-1)


@dataclasses.dataclass(frozen=True)
class WaypointGrid:
    """For each grid cell, the nearest waypoint in line of sight (-1 if none).

    Attributes:
      origin_m, resolution_m: grid placement, as for :class:`DistanceField`.
      nearest: (H, W) int32 waypoint index.
    """

    origin_m: np.ndarray
    resolution_m: float
    nearest: np.ndarray


def build_waypoint_grid(
    waypoint_xy_m: np.ndarray,
    allowed: np.ndarray,
    boxes_m: np.ndarray,
    bounds_m: tuple[float, float, float, float],
    resolution_m: float = 0.25,
    candidates: int = 8,
) -> WaypointGrid:
    """Nearest visible allowed waypoint per cell, checking the ``candidates`` nearest ones."""
    xmin, xmax, ymin, ymax = bounds_m
    xs = np.arange(xmin, xmax + resolution_m / 2, resolution_m)
    ys = np.arange(ymin, ymax + resolution_m / 2, resolution_m)
    gx, gy = np.meshgrid(xs, ys)
    cells = np.stack([gx.ravel(), gy.ravel()], -1)
    idx = np.flatnonzero(allowed)
    wp = waypoint_xy_m[idx]
    dist = np.linalg.norm(cells[:, None, :] - wp[None], axis=-1)
    k = min(candidates, len(idx))
    order = np.argsort(dist, axis=1)[:, :k]
    nearest = np.full(len(cells), -1, np.int32)
    for j in range(k):  # closest candidate first; keep the first one in sight
        cand = order[:, j]
        open_ = (nearest < 0) & ~segment_hits_boxes(cells, wp[cand], boxes_m)
        nearest[open_] = idx[cand[open_]]
    # Cells with no waypoint in sight (inside walls, behind shelves): fall back to the nearest.
    nearest[nearest < 0] = idx[order[nearest < 0, 0]]
    return WaypointGrid(np.array([xmin, ymin]), resolution_m, nearest.reshape(gy.shape))
