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
grows with y); :class:`~jaxsim.grid.GridSpec` (the toolkit's one grid geometry, re-exported here)
holds the static part (shape, resolution, origin).
"""

from __future__ import annotations

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np

from socialnav.jaxsim.grid import GridSpec

FREE = 0.0
MAX_GRADED = 252.0
INSCRIBED = 253.0
LETHAL = 254.0

OCCUPIED_ABOVE = 0.6  # occupancy above which a cell is an obstacle (the GSCL paper's threshold)

# Nav2 inflation layer defaults (docs.nav2.org, costmap-plugins/inflation).
INFLATION_RADIUS_M = 0.55
COST_SCALING_FACTOR = 10.0


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
