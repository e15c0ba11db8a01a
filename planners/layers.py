"""Every social cost layer in one shape: a :class:`CostLayer`.

The layers' own functions grew with their papers and differ (SNL returns an array, CASN a pair
with its frozen collision points, GSCL takes a network and an occupancy grid first). Through this
module each is the same thing::

    layer = layers.casn()                      # or snl(), snape(), gscl(predict, occupancy)
    state = layer.init(scene)                  # what it carries in time (() for most)
    costs, state = layer(scene, grid, state)   # costs (H, W) float32 on Nav2's 0..253 scale

``scene`` is a :class:`planners.scene.Scene` (the people, objects, robot and goal at one moment),
``grid`` a :class:`planners.costmap.GridSpec` (static: its cells' centres are where the layer is
read). ``state`` may be left out: the layer starts from ``init(scene)``. ``layer.params`` is a
pytree (the paper's parameters, or the network's prediction function closed over for GSCL) and
``layer.apply(params, scene, grid, state)`` the pure function behind the call, for ``jit`` with
``grid`` static and a parameter sweep that does not recompile.

Which layer is which paper: SNL (ROS ``social_navigation_layers``, seed 001's baseline), CASN
(seed 001), SNAPE's interaction spaces and person Gaussians (seed 004), GSCL (seed 002, a trained
U-Net; :class:`socialnav.models.inference.SocialCostModel` gives ``predict``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import jax
import jax.numpy as jnp

from socialnav.planners import casn as casn_lib
from socialnav.planners import gscl_layer
from socialnav.planners import snape as snape_lib
from socialnav.planners import snl as snl_lib
from socialnav.planners.costmap import GridSpec
from socialnav.planners.scene import Scene

__all__ = ["BY_NAME", "CostLayer", "casn", "gscl", "snape", "snl"]


@dataclasses.dataclass(frozen=True)
class CostLayer:
    """A social cost layer: ``init(scene) -> state`` and ``apply(params, scene, grid, state) ->
    (costs (H, W) float32, state)``; calling the layer applies it with its own ``params``."""

    name: str
    params: Any
    init: Callable[[Scene], Any]
    apply: Callable[[Any, Scene, GridSpec, Any], tuple[jax.Array, Any]]

    def __call__(self, scene: Scene, grid: GridSpec, state: Any = None) -> tuple[jax.Array, Any]:
        state = self.init(scene) if state is None else state
        return self.apply(self.params, scene, grid, state)


def _centres(grid: GridSpec):
    x_m, y_m = grid.cell_centres()
    return jnp.asarray(x_m), jnp.asarray(y_m)


def _no_state(scene: Scene):
    return ()


def snl(params: snl_lib.SNLParams = snl_lib.SNLParams(), passing: bool = True, passing_side: float = -1.0):
    """SNL's proxemic Gaussians, and its passing layer unless ``passing=False`` (no state)."""

    def apply(p, scene, grid, state):
        x_m, y_m = _centres(grid)
        return snl_lib.snl_layer(scene, x_m, y_m, p, passing, passing_side).astype(jnp.float32), state

    return CostLayer("snl", params, _no_state, apply)


def casn(params: casn_lib.CASNParams = casn_lib.CASNParams()):
    """CASN's collision-point discs and group spaces; its state is the frozen collision points
    (:class:`planners.casn.CASNState`), to be passed on from one moment of a scene to the next."""

    def apply(p, scene, grid, state):
        x_m, y_m = _centres(grid)
        return casn_lib.casn_layer(scene, x_m, y_m, state, p)

    return CostLayer("casn", params, lambda scene: casn_lib.initial_state(scene.n_people), apply)


def snape(params: snape_lib.SNAPEParams = snape_lib.SNAPEParams()):
    """SNAPE's person Gaussians and the objects' interaction spaces (no state)."""

    def apply(p, scene, grid, state):
        x_m, y_m = _centres(grid)
        return jnp.asarray(snape_lib.snape_layer(scene, x_m, y_m, p), jnp.float32), state

    return CostLayer("snape", params, _no_state, apply)


def gscl(predict: Callable, occupancy, robot_frame: bool = False):
    """GSCL: the network's 40 x 40 window around the robot placed on the grid (0 outside it).

    Args:
      predict: (B, 40, 40) uint8 input maps -> (B, 40, 40) costs in [0, 1]; e.g.
        ``SocialCostModel.load().function`` (:mod:`socialnav.models.inference`; the model shipped
        with the package). The layer's costs are ``252 x`` the network's, on the grid's cells.
      occupancy: (H, W) the walls on ``grid`` (1 occupied), the network's wall channel.
      robot_frame: the window turned with the robot (the paper's) instead of on the world axes.
    """
    occupancy = jnp.asarray(occupancy, jnp.float32)

    def apply(p, scene, grid, state):
        return gscl_layer.gscl_layer(predict, p, grid, scene, robot_frame), state

    return CostLayer("gscl", occupancy, _no_state, apply)


BY_NAME = {"snl": snl, "casn": casn, "snape": snape}
"""The layers that need nothing but their parameters, by name (GSCL needs a network)."""
