"""Every social cost layer in one shape: a :class:`CostLayer`, the thing a stack takes.

The layers' own functions grew with their papers and differ (SNL returns an array, CASN a pair
with its frozen collision points, GSCL takes a network and an occupancy grid first). Through this
module each is the same thing::

    layer = layers.casn()                      # or snl(), snape(), gscl(model), none()
    state = layer.init(n_people)               # what it carries in time (() for most)
    costs, state = layer(scene, grid, state)   # costs (H, W) float32 on Nav2's 0..253 scale

``scene`` is a :class:`planners.layers.scene.Scene` (the people, objects, robot and goal at one moment),
``grid`` a :class:`planners.layers.costmap.GridSpec` (static: its cells' centres are where the layer is
read). ``state`` may be left out: the layer starts from ``init(scene.n_people)``. The GSCL layer
also reads the walls: ``layer(scene, grid, occupancy=occupancy)``, (H, W) in [0, 1] on ``grid``.

Static apart from dynamic, as a JAX environment keeps them: ``layer.name``, ``layer.init`` and
``layer.apply(params, scene, grid, state, occupancy)`` are the layer's static part (compared and
hashed: two layers of the same kind and options are equal, so an actor built on one is cached and
its compiled program reused), and ``layer.params`` its pytree of parameters (the paper's numbers,
or the GSCL network's weights), passed to ``apply`` traced: a parameter sweep or another
checkpoint of the same network does not recompile. A navigation stack
(:func:`planners.actors.stack_actor`) takes the layer and carries ``layer.params`` in its own
params, so a layer's function and its parameters travel together, from the command line's
``--gscl-run`` to the plan, as one object.

Which layer is which paper: SNL (ROS ``social_navigation_layers``, seed 001's baseline), CASN
(seed 001), SNAPE's interaction spaces and person Gaussians (seed 004), GSCL (seed 002, a trained
U-Net: :class:`socialnav.models.inference.SocialCostModel`), and ``none`` (no social layer:
NavFn's stack).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable
from typing import Any

import jax
import jax.numpy as jnp

from socialnav.planners.layers import casn_layer as casn_lib
from socialnav.planners.layers import gscl_layer
from socialnav.planners.layers import snape_layer as snape_lib
from socialnav.planners.layers import snl_layer as snl_lib
from socialnav.planners.layers.costmap import GridSpec
from socialnav.planners.layers.scene import Scene

__all__ = ["BY_NAME", "CostLayer", "casn", "gscl", "none", "snape", "snl"]


@dataclasses.dataclass(frozen=True)
class CostLayer:
    """A social cost layer.

    Attributes:
      name: the layer's kind (``none``, ``snl``, ``casn``, ``snape``, ``gscl``).
      init: ``n_people -> state``, what the layer carries from one moment of a scene to the next.
      apply: ``(params, scene, grid, state, occupancy) -> (costs (H, W) float32, state)``, pure;
        ``grid`` static, ``occupancy`` (H, W) the walls on ``grid`` (read by GSCL only; None for
        the others).
      params: the layer's parameters (a pytree; not part of the layer's identity).

    Calling the layer applies it with its own ``params``.
    """

    name: str
    init: Callable[[int], Any]
    apply: Callable[..., tuple[jax.Array, Any]]
    params: Any = dataclasses.field(default=(), compare=False, hash=False)

    def __call__(self, scene: Scene, grid: GridSpec, state: Any = None, occupancy=None) -> tuple[jax.Array, Any]:
        state = self.init(scene.n_people) if state is None else state
        return self.apply(self.params, scene, grid, state, occupancy)

    def replace(self, params: Any) -> CostLayer:
        """The same layer with other parameters (same identity: the same compiled program)."""
        return dataclasses.replace(self, params=params)


def _centres(grid: GridSpec):
    x_m, y_m = grid.cell_centres()
    return jnp.asarray(x_m), jnp.asarray(y_m)


def _no_state(n_people: int):
    return ()


def _none_apply(params, scene, grid, state, occupancy):
    return jnp.zeros(grid.shape, jnp.float32), state


def none() -> CostLayer:
    """No social layer (zeros): NavFn's stack, the obstacle layer alone."""
    return CostLayer("none", _no_state, _none_apply)


@functools.cache
def _snl_apply(passing: bool, passing_side: float):
    def apply(p, scene, grid, state, occupancy):
        x_m, y_m = _centres(grid)
        return snl_lib.snl_layer(scene, x_m, y_m, p, passing, passing_side).astype(jnp.float32), state

    return apply


def snl(params: snl_lib.SNLParams = snl_lib.SNLParams(), passing: bool = True, passing_side: float = -1.0):
    """SNL's proxemic Gaussians, and its passing layer unless ``passing=False`` (no state)."""
    return CostLayer("snl", _no_state, _snl_apply(bool(passing), float(passing_side)), params)


def _casn_apply(p, scene, grid, state, occupancy):
    x_m, y_m = _centres(grid)
    return casn_lib.casn_layer(scene, x_m, y_m, state, p)


def casn(params: casn_lib.CASNParams = casn_lib.CASNParams()):
    """CASN's collision-point discs and group spaces; its state is the frozen collision points
    (:class:`planners.layers.casn_layer.CASNState`), to be passed on from one moment of a scene to the next."""
    return CostLayer("casn", casn_lib.initial_state, _casn_apply, params)


def _snape_apply(p, scene, grid, state, occupancy):
    x_m, y_m = _centres(grid)
    return jnp.asarray(snape_lib.snape_layer(scene, x_m, y_m, p), jnp.float32), state


def snape(params: snape_lib.SNAPEParams = snape_lib.SNAPEParams()):
    """SNAPE's person Gaussians and the objects' interaction spaces (no state)."""
    return CostLayer("snape", _no_state, _snape_apply, params)


@functools.lru_cache(maxsize=16)
def _gscl_apply(network: Callable, robot_frame: bool):
    def apply(weights, scene, grid, state, occupancy):
        if occupancy is None:
            raise ValueError("the gscl layer reads the walls: call it with occupancy=(H, W) on the grid")
        predict = lambda maps: network(weights, maps)
        return gscl_layer.gscl_layer(predict, occupancy, grid, scene, robot_frame), state

    return apply


@functools.lru_cache(maxsize=16)
def _without_weights(predict: Callable) -> Callable:
    return lambda weights, maps: predict(maps)


def gscl(model, robot_frame: bool = False) -> CostLayer:
    """GSCL: the network's 40 x 40 window around the robot placed on the grid (0 outside it).

    Args:
      model: the trained network: a :class:`socialnav.models.inference.SocialCostModel` (its
        ``apply(weights, maps)`` is the layer's function and its ``weights`` the layer's params,
        traced: another checkpoint of the same network reuses the compiled program), or any JAX
        function ``maps (B, 40, 40) uint8 -> costs (B, 40, 40)`` in [0, 1] (its weights closed
        over; no params). The layer's costs are ``252 x`` the network's on the grid's cells
        (:mod:`planners.layers.gscl_layer`).
      robot_frame: the window turned with the robot (the paper's) instead of on the world axes.
    """
    if hasattr(model, "apply") and hasattr(model, "weights"):
        network, weights = model.apply, model.weights
    elif callable(model):
        network, weights = _without_weights(model), ()
    else:
        raise TypeError(f"layers.gscl: model must be a SocialCostModel or a function of the maps, got {model!r}")
    return CostLayer("gscl", _no_state, _gscl_apply(network, bool(robot_frame)), weights)


BY_NAME = {"none": none, "snl": snl, "casn": casn, "snape": snape}
"""The layers that need nothing but their parameters, by name (GSCL needs a network)."""
