"""Cost-map conventions (Nav2 / costmap_2d), the grid's geometry, layer combination and inflation.

Every layer in :mod:`planners` returns a float32 ``(H, W)`` grid on Nav2's scale, kept as floats
so that layers stay differentiable and exact:

* ``0`` free, ``(0, 252]`` graded (:data:`MAX_GRADED`), ``253`` inscribed (:data:`INSCRIBED`: the
  robot's centre here puts its body on an obstacle), ``254`` lethal (:data:`LETHAL`). ``255``
  (unknown) is not used: a scene's grid is fully known. :func:`to_uint8` truncates to the
  ``unsigned char`` a ROS costmap stores (as the ROS layers do with ``(unsigned char) a``).
* Layers combine cell-wise by max (:func:`combine_max`, Nav2's ``updateWithMax``), so an obstacle
  always dominates a social cost.

Grid layout: the ROS ``OccupancyGrid``'s. Cell ``(i, j)`` covers
``x in origin_x + [j, j + 1) * resolution``, ``y in origin_y + [i, i + 1) * resolution`` (row index
grows with y); :class:`GridSpec` holds the static part (shape, resolution, origin).
"""

from __future__ import annotations

import dataclasses
import functools
import math

import jax
import jax.numpy as jnp
import numpy as np

FREE = 0.0
MAX_GRADED = 252.0
INSCRIBED = 253.0
LETHAL = 254.0

OCCUPIED_ABOVE = 0.6  # occupancy above which a cell is an obstacle (the GSCL paper's threshold)

# Nav2 inflation layer defaults (docs.nav2.org, costmap-plugins/inflation).
INFLATION_RADIUS_M = 0.55
COST_SCALING_FACTOR = 10.0


@dataclasses.dataclass(frozen=True)
class GridSpec:
    """The static geometry of a cost grid (hashable: pass it as a static argument under ``jit``).

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

    @classmethod
    def of_grid(cls, grid) -> GridSpec:
        """The geometry of a simulator's value grid (:class:`jaxsim.world.Grid`, values (H, W, ...)).

        The one place where the two origin conventions meet: a ``Grid``'s origin is cell (0, 0)'s
        centre (its lookups round to the nearest centre), a ``GridSpec``'s that cell's lower-left
        corner (Nav2's ``costmap_2d``), half a cell lower and to the left."""
        h, w = grid.values.shape[:2]
        half = grid.resolution_m / 2
        return cls(h, w, grid.resolution_m, grid.origin_x_m - half, grid.origin_y_m - half)

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

    def contains(self, ij):
        """(...,) bool: the cells lie on the grid."""
        ij = jnp.asarray(ij)
        return (ij[..., 0] >= 0) & (ij[..., 0] < self.height) & (ij[..., 1] >= 0) & (ij[..., 1] < self.width)


def combine_max(*layers):
    """Cell-wise max of layers (Nav2's ``updateWithMax``)."""
    out = jnp.asarray(layers[0], jnp.float32)
    for layer in layers[1:]:
        out = jnp.maximum(out, layer)
    return out


def to_uint8(costs) -> np.ndarray:
    """A float cost grid as the ``uint8`` grid a ROS costmap stores (truncation, as the ROS layers)."""
    return np.asarray(jnp.clip(jnp.floor(costs), 0, 255)).astype(np.uint8)


def obstacle_distance_m(occupied, resolution_m: float, max_distance_m: float):
    """(H, W) Euclidean distance from every cell centre to the nearest occupied cell centre.

    Exact below ``max_distance_m`` (beyond it, any value above ``max_distance_m``: ``inf`` when no
    obstacle is that close). A separable transform over a window of ``ceil(max_distance_m /
    resolution_m)`` cells each way: a pass along rows gives the nearest obstacle column in each
    row, a pass along columns takes the minimum of ``dx^2 + dy^2`` over rows; both are shifted
    minima, no per-cell loop.

    Args:
      occupied: (H, W) bool. resolution_m, max_distance_m: static floats.
    """
    occupied = jnp.asarray(occupied, bool)
    radius = max(1, math.ceil(max_distance_m / resolution_m))
    big = jnp.float32(np.inf)
    height, width = occupied.shape

    def shifted(a, di, dj, fill):
        """a[i + di, j + dj], ``fill`` off the grid."""
        padded = jnp.pad(a, ((radius, radius), (radius, radius)), constant_values=fill)
        return jax.lax.dynamic_slice(padded, (radius + di, radius + dj), (height, width))

    # Horizontal: squared column distance (in cells) to the nearest obstacle in the same row.
    row_d2 = jnp.where(occupied, 0.0, big)
    for dj in range(1, radius + 1):
        near = shifted(occupied, 0, dj, False) | shifted(occupied, 0, -dj, False)
        row_d2 = jnp.where(near, jnp.minimum(row_d2, float(dj * dj)), row_d2)
    # Vertical: min over rows of (row distance)^2 + that row's horizontal squared distance.
    d2 = row_d2
    for di in range(1, radius + 1):
        d2 = jnp.minimum(d2, jnp.minimum(shifted(row_d2, di, 0, big), shifted(row_d2, -di, 0, big)) + di * di)
    return jnp.sqrt(d2) * resolution_m


@functools.partial(
    jax.jit,
    static_argnames=("spec", "inscribed_radius_m", "inflation_radius_m", "cost_scaling_factor", "occupied_above"),
)
def obstacle_layer(
    occupancy,
    spec: GridSpec,
    inscribed_radius_m: float,
    inflation_radius_m: float = INFLATION_RADIUS_M,
    cost_scaling_factor: float = COST_SCALING_FACTOR,
    occupied_above: float = OCCUPIED_ABOVE,
):
    """Static obstacles with Nav2's inflation: (H, W) float32 costs.

    Lethal (254) on occupied cells, inscribed (253) within ``inscribed_radius_m`` of one, then
    ``252 exp(-cost_scaling_factor (d - inscribed_radius_m))`` out to ``inflation_radius_m``, 0
    beyond (Nav2's ``computeCost``; defaults 0.55 m and 10).

    Args:
      occupancy: (H, W) occupancy in [0, 1] (or bool); cells above ``occupied_above`` are obstacles.
      spec: the grid (its resolution sets the distances). The radii are static floats.

    Compiled as one program per grid shape and radii: called outside a trace (a scene's set-up),
    its eager form compiled a program for each of its dozens of operations. Inside a traced
    program it is inlined.
    """
    occupied = jnp.asarray(occupancy, jnp.float32) > occupied_above
    reach = max(inflation_radius_m, inscribed_radius_m)
    d = obstacle_distance_m(occupied, spec.resolution_m, reach)
    graded = MAX_GRADED * jnp.exp(-cost_scaling_factor * (d - inscribed_radius_m))
    cost = jnp.where(d <= inflation_radius_m, graded, FREE)
    cost = jnp.where(d <= inscribed_radius_m, INSCRIBED, cost)
    return jnp.where(occupied, LETHAL, cost).astype(jnp.float32)


def traversal_cost(costs, neutral: float, factor: float):
    """(H, W) cost per metre of entering each cell: ``neutral + factor * c`` for ``c < 253``,
    ``inf`` (impassable) for inscribed and lethal cells.

    NavFn: ``neutral`` 50, ``factor`` 0.8 (:func:`navfn_traversal`); SNAPE's weighted grid: 1 and 1.
    """
    costs = jnp.asarray(costs, jnp.float32)
    return jnp.where(costs >= INSCRIBED, jnp.inf, neutral + factor * costs).astype(jnp.float32)


NAVFN_NEUTRAL = 50.0  # nav2_navfn_planner navfn.hpp: COST_NEUTRAL
NAVFN_FACTOR = 0.8  # COST_FACTOR


def navfn_traversal(costs):
    """NavFn's cell costs: ``50 + 0.8 c``, inscribed and lethal impassable (Nav2 navfn.hpp)."""
    return traversal_cost(costs, NAVFN_NEUTRAL, NAVFN_FACTOR)


def weighted_traversal(costs):
    """SNAPE's weighted grid (seed 004 Sec. 3.2): every cell weighs 1, social zones add their
    weight, inaccessible cells (inscribed, lethal) are impassable: ``1 + c``."""
    return traversal_cost(costs, 1.0, 1.0)
