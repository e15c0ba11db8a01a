"""The static arrays of a scene: walls as boxes (line of sight) and as a distance field (the
people's wall force, the robot's contact), and the occupancy grid a planner rasterises from."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from socialnav.jaxsim import geometry
from socialnav.jaxsim.grid import Grid
from socialnav.jaxsim.scenes import spec as spec_lib

FIELD_RESOLUTION_M = 0.05


@struct.dataclass
class SceneWorld:
    """Attributes: walls_m (K, 4) boxes (at least one, padded far away); wall_field: (H, W, 3)
    signed distance and outward normal (:class:`jaxsim.grid.Grid`)."""

    walls_m: jnp.ndarray
    wall_field: Grid


def wall_boxes(walls_m, bounds_m) -> np.ndarray:
    """(K, 4) a scene's wall boxes ``walls_m``; for a scene without walls, one box far outside its
    ``bounds_m`` (``xmin, xmax, ymin, ymax``), which keeps the shapes fixed."""
    if len(walls_m):
        return walls_m
    xmin, xmax, ymin, ymax = bounds_m
    return np.array([[xmax + 100.0, xmax + 101.0, ymax + 100.0, ymax + 101.0]], np.float32)


def build_scene_world(walls_m, bounds_m) -> SceneWorld:
    """A scene's walls ``walls_m`` (K, 4) within ``bounds_m`` as boxes and a distance field (host
    side, numpy, once per scene; the result is a pytree of arrays)."""
    boxes = wall_boxes(walls_m, bounds_m)
    field = geometry.build_distance_field(boxes, bounds_m, FIELD_RESOLUTION_M)
    values = np.stack([field.sdf_m, field.normal_x, field.normal_y], axis=-1)
    grid = Grid.of_samples(jnp.asarray(values), float(field.origin_m[0]), float(field.origin_m[1]), FIELD_RESOLUTION_M)
    return SceneWorld(walls_m=jnp.asarray(boxes), wall_field=grid)


def occupancy(
    walls_m, bounds_m, resolution_m: float, turned_from: tuple | None = None
) -> tuple[np.ndarray, tuple[float, float]]:
    """(H, W) float32 occupancy (1 where a cell centre lies in one of the walls ``walls_m`` or in
    the border cells of ``bounds_m``) over ``bounds_m``, and its origin (x, y).

    ``turned_from``: for a turned scene (:func:`jaxsim.scenes.spec.turn`), the ``(walls_m,
    bounds_m)`` of the scene it was turned from, whose grid it gets, turned a quarter turn
    (``np.rot90(grid, -1)``): a wall face exactly half a cell from a cell's centre is inside or
    outside by float rounding, which a turn decides differently (86 such cells at 0.2 m in
    gscl_group), so rasterised afresh the turned walls would differ by a cell here and there.
    Exact at the cells :data:`~jaxsim.scenes.spec.TURN_CELL_M` divides into whole numbers (0.2,
    0.1, 0.05 m)."""
    if turned_from is not None and _whole(spec_lib.TURN_CELL_M / resolution_m):
        original_walls, original_bounds = turned_from
        grid, _ = occupancy(original_walls, spec_lib.turn_bounds_m(original_bounds), resolution_m)
        return np.ascontiguousarray(np.rot90(grid, -1)), (bounds_m[0], bounds_m[2])
    xmin, xmax, ymin, ymax = bounds_m
    width = int(np.ceil((xmax - xmin) / resolution_m))
    height = int(np.ceil((ymax - ymin) / resolution_m))
    xs = xmin + (np.arange(width) + 0.5) * resolution_m
    ys = ymin + (np.arange(height) + 0.5) * resolution_m
    gx, gy = np.meshgrid(xs, ys)
    sd, _, _ = geometry.box_signed_distance(gx, gy, wall_boxes(walls_m, bounds_m))
    occ = (sd <= resolution_m / 2).astype(np.float32)
    occ[[0, -1], :] = 1.0  # the scene's edge is a wall for the planner
    occ[:, [0, -1]] = 1.0
    return occ, (xmin, ymin)


def _whole(x: float) -> bool:
    return abs(x - round(x)) < 1e-6


def wall_distance(xy, walls_m):
    """Exact signed distance from points (..., 2) to the nearest wall box, and the unit normal
    pointing away from it: ((...,), (..., 2)). Pure JAX (:func:`jaxsim.geometry.box_distance`;
    the robot and its band use it: the 0.05 m distance field's rounding lets a body creep into
    corners)."""
    return geometry.box_distance(xy, walls_m, xp=jnp)


def wall_clearance(xy, walls_m, per_box: bool = True):
    """(...,) the signed distance from points (..., 2) to the nearest wall box (K, 4): the value
    of :func:`wall_distance` without its normal (tested equal).

    Args:
      per_box: take the boxes one at a time in a ``fori_loop``, keeping the running minimum, so
        that every operation is elementwise over the points and the program does not grow with
        the boxes: fastest for a few points called often (the elastic band's 12 inner points, 6
        times per relaxation). ``False``: one (..., K) array and a minimum over it, fastest for
        many points at once (the dynamic window's arcs). Both give the same values (a minimum
        is exact in any order).
    """
    if not per_box:
        centre_x = (walls_m[:, 0] + walls_m[:, 1]) / 2
        centre_y = (walls_m[:, 2] + walls_m[:, 3]) / 2
        qx = jnp.abs(xy[..., 0, None] - centre_x) - (walls_m[:, 1] - walls_m[:, 0]) / 2
        qy = jnp.abs(xy[..., 1, None] - centre_y) - (walls_m[:, 3] - walls_m[:, 2]) / 2
        return jnp.min(_signed_from_offsets(qx, qy), axis=-1)
    x, y = xy[..., 0], xy[..., 1]

    def box(k):
        xmin, xmax, ymin, ymax = walls_m[k, 0], walls_m[k, 1], walls_m[k, 2], walls_m[k, 3]
        qx = jnp.abs(x - (xmin + xmax) / 2) - (xmax - xmin) / 2
        qy = jnp.abs(y - (ymin + ymax) / 2) - (ymax - ymin) / 2
        return _signed_from_offsets(qx, qy)

    return jax.lax.fori_loop(1, walls_m.shape[0], lambda k, nearest: jnp.minimum(nearest, box(k)), box(0))


def _signed_from_offsets(qx, qy):
    """A box's signed distance from a point's offsets beyond its half-widths (``|d| - half``)."""
    outside = jnp.sqrt(jnp.maximum(qx, 0.0) ** 2 + jnp.maximum(qy, 0.0) ** 2)
    return outside + jnp.minimum(jnp.maximum(qx, qy), 0.0)


def segment_blocked(p0, p1, walls_m):
    """(...,) bool: the segments p0 -> p1 (..., 2) cross a wall box (pure JAX;
    :func:`jaxsim.geometry.segment_hits_boxes`, the warehouse's test)."""
    return geometry.segment_hits_boxes(p0, p1, walls_m, xp=jnp)
