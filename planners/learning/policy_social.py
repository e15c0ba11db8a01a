"""The policy's optional social channel: a social cost layer seen on its guidance window.

A learned policy can take a cost map as an input (``PolicyConfig.social_layer``): the layer's
cost at the guidance window's points (:func:`planners.learning.policy.window_points`: ``field_cells`` x
``field_cells`` around the robot, turned with it), over Nav2's lethal 254, computed from the
people the robot sees (the env's observation, never the simulator's truth). The layers:

* ``snl_small``, ``snl_large``, ``snl_matched``: the social navigation layer's Gaussians with
  the stacks' covariances (:func:`planners.stack.layer_params`); no state.
* ``casn``: CASN's layer (:mod:`planners.layers.casn_layer`) with its default parameters; its frozen collision
  points are state carried from step to step (:class:`SocialState`), as the CASN stack carries
  them between its layer updates.
* ``gscl``: a trained GSCL U-Net (:mod:`planners.layers.gscl_layer`; the run named by
  ``PolicyConfig.gscl_run``). The network's 40 x 40 window of 0.4 m (world axes, centred on the
  robot) is recomputed every ``PolicyConfig.gscl_every_steps`` steps (10: 1 Hz, the rate the
  arena's stacks update their layers; a network call per step would cost the training about
  50 times its time: about 1,000-1,400 windows/s for the CPU recipe's U-Net on this machine)
  and read in between at the window's points, where they are now (nearest 0.4 m cell; 0 outside
  it). In the benchmark the actor computes it at the episode's first step; in training the
  episodes restart at different steps and the network runs for all of them at once, so a fresh
  episode sees no GSCL costs (zeros) until the next common refresh, at most
  ``gscl_every_steps - 1`` steps.
"""

from __future__ import annotations

from collections.abc import Callable

import jax
import jax.numpy as jnp
from flax import struct

from socialnav.jaxsim.scenes.env import Observation
from socialnav.models import grid as gscl_grid
from socialnav.planners import stack
from socialnav.planners.layers import casn_layer as casn
from socialnav.planners.layers import costmap, gscl_layer
from socialnav.planners.layers import snl_layer as snl
from socialnav.planners.layers.scene import Scene

SOCIAL_LAYERS = ("none", "snl_small", "snl_large", "snl_matched", "casn", "gscl")


@struct.dataclass
class SocialState:
    """What the channel carries between steps (one episode; a batch adds a leading axis):
    ``casn``: CASN's frozen collision points (P people slots); ``gscl_costs`` (40, 40) in
    [0, 1], the network's last window, centred at ``gscl_centre_xy_m`` (2,); ``gscl_ready`` ()
    bool, a window has been computed in this episode."""

    casn: casn.CASNState
    gscl_costs: jax.Array
    gscl_centre_xy_m: jax.Array
    gscl_ready: jax.Array


def initial_state(n_people: int) -> SocialState:
    """An episode's start: nothing frozen, no GSCL window yet."""
    return SocialState(
        casn=casn.initial_state(n_people),
        gscl_costs=jnp.zeros((gscl_grid.GRID, gscl_grid.GRID), jnp.float32),
        gscl_centre_xy_m=jnp.zeros(2, jnp.float32),
        gscl_ready=jnp.array(False),
    )


def perceived_scene(obs: Observation) -> Scene:
    """The people the robot sees as a :class:`~planners.layers.scene.Scene` (no objects)."""
    return Scene(
        people_xy_m=obs.people_xy_m,
        people_heading_rad=obs.people_heading_rad,
        people_velocity_mps=obs.people_velocity_mps,
        people_valid=obs.people_visible,
        objects_xy_m=jnp.zeros((1, 3, 2), jnp.float32),
        objects_cost=jnp.zeros((1,), jnp.float32),
        objects_valid=jnp.zeros((1,), bool),
        robot_xy_m=obs.robot_xy_m,
        robot_yaw_rad=obs.robot_yaw_rad,
        goal_xy_m=obs.goal_xy_m,
    )


def window(layer: str, obs: Observation, points_m, state: SocialState):
    """``(costs (c * c,) in [0, 1], next state)``: ``layer``'s cost at ``points_m`` (c, c, 2) over
    254 (empty for ``"none"``)."""
    if layer == "none":
        return jnp.zeros((0,), jnp.float32), state
    x_m, y_m = points_m[..., 0], points_m[..., 1]
    if layer == "gscl":
        cost = gscl_layer.read_window(
            state.gscl_costs, x_m - state.gscl_centre_xy_m[0], y_m - state.gscl_centre_xy_m[1]
        )
        cost = jnp.where(state.gscl_ready, cost, 0.0)
        return (cost / costmap.LETHAL).reshape(-1).astype(jnp.float32), state
    scene = perceived_scene(obs)
    if layer == "casn":
        cost, casn_state = casn.casn_layer(scene, x_m, y_m, state.casn)
        state = state.replace(casn=casn_state)
    elif layer in ("snl_small", "snl_large", "snl_matched"):
        cost = snl.snl_layer(scene, x_m, y_m, stack.layer_params(stack.METHODS[layer]).snl)
    else:
        raise ValueError(f"social layer must be one of {', '.join(SOCIAL_LAYERS)}, got {layer!r}")
    return (cost / costmap.LETHAL).reshape(-1).astype(jnp.float32), state


def gscl_refresh(predict: Callable, occupancy, spec: costmap.GridSpec, obs: Observation, state: SocialState):
    """``state`` with a new GSCL window around the robot: ``predict`` maps (B, 40, 40) input maps
    to costs (one episode here; vmap it over a batch: one network call)."""
    scene = perceived_scene(obs)
    costs = predict(gscl_layer.window_input(occupancy, spec, scene)[None])[0]
    return state.replace(
        gscl_costs=costs.astype(jnp.float32), gscl_centre_xy_m=obs.robot_xy_m.astype(jnp.float32), gscl_ready=True
    )


def load_gscl(run):
    """The GSCL model of the channel: a training run's latest checkpoint or an exported model
    (:class:`models.inference.SocialCostModel`: ``model.apply(weights, maps)`` with
    ``model.weights`` traced); ``ValueError`` naming the folder otherwise."""
    from socialnav.models.inference import SocialCostModel

    return SocialCostModel.load(run)
