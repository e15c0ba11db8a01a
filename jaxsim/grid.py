"""One grid type for every map of the toolkit, with one origin convention: a cell's lower-left corner.

:class:`GridSpec` is a grid's static geometry (shape, cell size, origin), the layout of ROS's
``OccupancyGrid`` and Nav2's ``costmap_2d``: cell ``(i, j)`` covers ``x in origin_x + [j, j + 1) *
resolution``, ``y in origin_y + [i, i + 1) * resolution`` (the row index grows with y).
:class:`Grid` is values on such cells (a pytree: the values traced, the geometry static): the
simulator's wall distance field and waypoint tables, the scenes' occupancy, and what the planners'
cost layers are drawn on (:mod:`planners.layers.costmap` works on a ``GridSpec`` and its ``(H,
W)`` arrays).

A field sampled at regular points (the wall distance field, the nearest waypoint of each point,
:mod:`jaxsim.geometry`'s host-side builders) is the grid whose cells are centred on the samples
(:meth:`Grid.of_samples`); a lookup reads the cell that holds a point, which is the nearest sample.
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct


@dataclasses.dataclass(frozen=True)
class GridSpec:
    """The static geometry of a grid (hashable: pass it as a static argument under ``jit``).

    Attributes:
      height, width: cells along y (rows) and x (columns).
      resolution_m: cell size in metres.
      origin_x_m, origin_y_m: world position of cell (0, 0)'s lower-left corner.
    """

    height: int
    width: int
    resolution_m: float
    origin_x_m: float = 0.0
    origin_y_m: float = 0.0

    def __post_init__(self):
        if int(self.height) != self.height or int(self.width) != self.width or self.height < 2 or self.width < 2:
            raise ValueError(f"GridSpec: height and width must be integers >= 2, got {self.height} x {self.width}")
        if not (math.isfinite(self.resolution_m) and self.resolution_m > 0):
            raise ValueError(f"GridSpec: resolution_m must be a positive number, got {self.resolution_m}")
        if not (math.isfinite(self.origin_x_m) and math.isfinite(self.origin_y_m)):
            raise ValueError(f"GridSpec: origin must be finite, got ({self.origin_x_m}, {self.origin_y_m})")

    @property
    def shape(self) -> tuple[int, int]:
        return (int(self.height), int(self.width))

    def cell_centres(self) -> tuple[np.ndarray, np.ndarray]:
        """(x_m, y_m), each (H, W) float32: the world position of every cell's centre."""
        xs = self.origin_x_m + (np.arange(self.width) + 0.5) * self.resolution_m
        ys = self.origin_y_m + (np.arange(self.height) + 0.5) * self.resolution_m
        x, y = np.meshgrid(xs.astype(np.float32), ys.astype(np.float32))
        return x, y

    def cell_of(self, xy_m):
        """(..., 2) int32 (row, col) of the cell holding each point (may lie off the grid)."""
        xy_m = jnp.asarray(xy_m, jnp.float32)
        col = jnp.floor((xy_m[..., 0] - self.origin_x_m) / self.resolution_m).astype(jnp.int32)
        row = jnp.floor((xy_m[..., 1] - self.origin_y_m) / self.resolution_m).astype(jnp.int32)
        return jnp.stack([row, col], axis=-1)

    def centre_of(self, ij):
        """(..., 2) float32 world (x, y) of the centre of cells (row, col)."""
        ij = jnp.asarray(ij)
        x = self.origin_x_m + (ij[..., 1] + 0.5) * self.resolution_m
        y = self.origin_y_m + (ij[..., 0] + 0.5) * self.resolution_m
        return jnp.stack([x, y], axis=-1).astype(jnp.float32)

    def clamp(self, ij):
        """(..., 2) int32 cells (row, col) moved onto the grid: the nearest edge cell for one off it."""
        ij = jnp.asarray(ij)
        top = jnp.array([self.height - 1, self.width - 1], jnp.int32)
        return jnp.clip(ij, 0, top).astype(jnp.int32)

    def contains(self, ij):
        """(...,) bool: the cells lie on the grid."""
        ij = jnp.asarray(ij)
        return (ij[..., 0] >= 0) & (ij[..., 0] < self.height) & (ij[..., 1] >= 0) & (ij[..., 1] < self.width)


@struct.dataclass
class Grid:
    """Values on the cells of a :class:`GridSpec`.

    Attributes:
      values: (H, W, ...) one value (or a vector: the wall field's distance and normal) per cell.
      spec: the cells' geometry (static: a change recompiles).
    """

    values: jax.Array
    spec: GridSpec = struct.field(pytree_node=False)

    @classmethod
    def of_samples(cls, values, first_x_m: float, first_y_m: float, resolution_m: float) -> Grid:
        """The grid of values sampled at the points ``(first_x_m + col * resolution_m, first_y_m + row
        * resolution_m)``: each sample is the value of the cell centred on it."""
        h, w = np.shape(values)[:2]
        half = resolution_m / 2
        return cls(values, GridSpec(h, w, resolution_m, first_x_m - half, first_y_m - half))

    @property
    def first_centre_m(self) -> tuple[float, float]:
        """World ``(x, y)`` of cell (0, 0)'s centre (a sampled field's first sample)."""
        half = self.spec.resolution_m / 2
        return self.spec.origin_x_m + half, self.spec.origin_y_m + half

    def nearest_cell(self, x, y):
        """``(row, col)`` of the cell holding points ``x, y`` (any shape), as whole floats, not
        clamped: a point off the grid gets a row or column outside ``[0, H)`` or ``[0, W)``."""
        x0, y0 = self.first_centre_m
        res = self.spec.resolution_m
        return jnp.round((y - y0) / res), jnp.round((x - x0) / res)

    def index(self, x, y):
        """``(row, col)`` int32 of the cell holding points ``x, y`` (any shape), clamped to the grid."""
        row, col = self.nearest_cell(x, y)
        h, w = self.spec.shape
        return jnp.clip(row, 0, h - 1).astype(jnp.int32), jnp.clip(col, 0, w - 1).astype(jnp.int32)

    def lookup(self, x, y):
        """The values of the cells holding points ``x, y`` (clamped to the grid): the points' shape, then
        the values' trailing axes."""
        row, col = self.index(x, y)
        return self.values[row, col]
