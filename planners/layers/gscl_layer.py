"""The GSCL layer (seed 002 Sec. 4.3): the trained U-Net's social costs placed into a planner's grid.

Per scene: the 40 x 40 input map around the robot (:func:`models.inference.input_map`: walls from
the occupancy grid, people with their heading pixel, the goal), the network's cost map, and that
map placed into the planner's grid at the planner's resolution: each planner cell takes the value
of the 0.4 m network cell holding its centre (nearest neighbour, the paper's "rescaled"), zero
outside the 16 m window. The network's graded range ``[0, GRADED_TOP]``
(:data:`models.social_costs.GRADED_TOP`) becomes ``[0, 252]`` on Nav2's scale, so that combined by
max with the obstacle layer (:func:`planners.layers.costmap.combine_max`) an obstacle always dominates,
as the paper's Eq. 3 (``distance x max(obstacle cost, social cost)``) and Nav2's ``updateWithMax``
have it; costs from :data:`models.social_costs.FORBIDDEN_FROM` up (the queue's U) are lethal
(254), and the actor inflates them with the walls (:func:`planners.actors.stack_actor`). A model
trained on graded targets only (runs saved before the U was forbidden, and "paths" runs) is
scaled into the graded range when loaded (:meth:`models.inference.SocialCostModel.load`), so it is
read as before.

The window keeps the world's axes (``robot_frame=False``, default; the dataset's maps have no
preferred robot heading: the goal pixel gives the direction of travel); ``robot_frame=True`` turns
it with the robot's yaw.

``predict`` is any JAX function from (B, 40, 40) uint8 input maps to (B, 40, 40) costs in [0, 1]:
``models.inference.SocialCostModel.load(run).function`` for a trained run. A stack takes the layer
as one object, :func:`planners.layers.gscl` (the network's function and its weights together).
"""

from __future__ import annotations

from collections.abc import Callable

import jax
import jax.numpy as jnp

from socialnav.models import grid
from socialnav.models.inference import input_map
from socialnav.models.social_costs import FORBIDDEN_FROM, GRADED_TOP
from socialnav.planners.layers.costmap import LETHAL, MAX_GRADED, GridSpec
from socialnav.planners.layers.scene import Scene


def window_input(occupancy, spec: GridSpec, scene: Scene, robot_frame: bool = False):
    """(40, 40) uint8: the network's input map for one scene (occupancy: (H, W) in [0, 1])."""
    return input_map(
        occupancy,
        spec.resolution_m,
        jnp.array([spec.origin_x_m, spec.origin_y_m], jnp.float32),
        scene.robot_xy_m,
        scene.people_xy_m,
        scene.people_heading_rad,
        scene.goal_xy_m,
        people_valid=scene.people_valid,
        robot_yaw_rad=scene.robot_yaw_rad if robot_frame else 0.0,
    )


def read_cost(value):
    """Nav2 costs of network costs (any shape): ``252 x value / GRADED_TOP`` (clipped to [0, 252])
    below ``FORBIDDEN_FROM``, lethal (254) from there up."""
    graded = MAX_GRADED * jnp.clip(value / GRADED_TOP, 0.0, 1.0)
    return jnp.where(value >= FORBIDDEN_FROM, LETHAL, graded).astype(jnp.float32)


def read_window(window_costs, dx_m, dy_m):
    """float32 Nav2 costs (:func:`read_cost`) of the (40, 40) network costs at offsets ``dx_m``,
    ``dy_m`` (any shape) from the window's centre in its own axes (nearest 0.4 m cell; 0 outside
    the window)."""
    row, col = grid.cell_of(dx_m, dy_m)
    on = grid.inside(row, col)
    value = window_costs[jnp.clip(row, 0, grid.GRID - 1), jnp.clip(col, 0, grid.GRID - 1)]
    return jnp.where(on, read_cost(value), 0.0).astype(jnp.float32)


def place_window(window_costs, spec: GridSpec, scene: Scene, robot_frame: bool = False):
    """(H, W) float32: the (40, 40) network costs placed into the planner's grid (:func:`read_cost`)."""
    x_m, y_m = spec.cell_centres()
    dx, dy = x_m - scene.robot_xy_m[0], y_m - scene.robot_xy_m[1]
    yaw = scene.robot_yaw_rad if robot_frame else 0.0
    c, s = jnp.cos(yaw), jnp.sin(yaw)
    return read_window(window_costs, c * dx + s * dy, -s * dx + c * dy)


def gscl_layers(predict: Callable, occupancy, spec: GridSpec, scenes: Scene, robot_frame: bool = False) -> jax.Array:
    """(B, H, W) GSCL layers of a batch of scenes (leading axis B on every scene leaf) on one
    occupancy grid (H, W) or one per scene (B, H, W): input maps by vmap, one network call on
    the (B, 40, 40) batch, placement by vmap. Jit it with ``predict`` and ``spec`` static (or
    closed over)."""
    occupancy = jnp.asarray(occupancy, jnp.float32)
    occ_axis = 0 if occupancy.ndim == 3 else None
    maps = jax.vmap(lambda occ, sc: window_input(occ, spec, sc, robot_frame), in_axes=(occ_axis, 0))(occupancy, scenes)
    costs = predict(maps)
    return jax.vmap(lambda w, sc: place_window(w, spec, sc, robot_frame))(costs, scenes)


def gscl_layer(predict: Callable, occupancy, spec: GridSpec, scene: Scene, robot_frame: bool = False):
    """(H, W) the GSCL layer of one scene (see :func:`gscl_layers`)."""
    batch = jax.tree_util.tree_map(lambda a: a[None], scene)
    return gscl_layers(predict, occupancy, spec, batch, robot_frame)[0]
