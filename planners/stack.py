"""Navigation stacks composed from parts, and the seeds' methods as named configurations.

A stack is a cost layer (none; SNL small, large, or matched to CASN's radius; CASN; SNAPE's
social map; GSCL), a global grid planner replanning at a rate (NavFn-like or SNAPE's weighted
Dijkstra) and a local planner at the control rate (pure pursuit, the classic elastic band, or
SNAPE's social band with its speed gain). :data:`METHODS` names the seeds' configurations; any other combination is one
``StackConfig(...)``.
"""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp
from flax import struct

from socialnav.planners import layers
from socialnav.planners.global_planners import grid_planner
from socialnav.planners.layers import casn_layer as casn
from socialnav.planners.layers import costmap
from socialnav.planners.layers import snape_layer as snape
from socialnav.planners.layers import snl_layer as snl
from socialnav.planners.layers.scene import Scene
from socialnav.planners.local import elastic_band, pure_pursuit

LAYERS = ("none", "snl_small", "snl_large", "snl_matched", "casn", "snape", "gscl")
GLOBAL_PLANNERS = ("navfn", "weighted")
# The social band's speed gain is read at no less than this speed: a robot standing still would
# predict itself nowhere and never meet anyone (seed 004 Sec. 3.3 gives no floor; ours).
GAIN_MIN_SPEED_MPS = 0.1
LOCAL_PLANNERS = ("pursuit", "eband", "social_eband")

# Seed 001's SNL: "the radius of the gradient matches the radius of our cost model" (CASN's
# personal 1.2 m): the covariance whose standing radius at cutoff is 1.2 m (0.354).
SNL_MATCHED = snl.SNLParams(covariance=snl.covariance_for_radius(1.2))


@dataclasses.dataclass(frozen=True)
class StackConfig:
    """A navigation stack (static: hashable).

    Attributes:
      layer: the social cost layer (:data:`LAYERS`).
      global_planner: ``navfn`` (cells 50 + 0.8 c) or ``weighted`` (SNAPE's 1 + c).
      local_planner: ``pursuit``, ``eband`` (classic: ``k_s = 0``, no speed gain) or
        ``social_eband`` (SNAPE's social band and speed gain).
      band_points, band_horizon_m, band_iterations: the elastic band's size and relaxations per
        control step.
      replan: replan at the arena's rate (1 Hz, seed 002's behaviour tree) or plan once and let
        the local planner adapt (SNAPE, seed 004 Sec. 3.3: the global path is computed once
        between two distant points, the social band deforms it in real time).
    """

    layer: str
    global_planner: str = "navfn"
    local_planner: str = "pursuit"
    band_points: int = 16
    band_horizon_m: float = 4.0
    band_iterations: int = 10
    replan: bool = True

    def __post_init__(self):
        for value, allowed, what in (
            (self.layer, LAYERS, "layer"),
            (self.global_planner, GLOBAL_PLANNERS, "global_planner"),
            (self.local_planner, LOCAL_PLANNERS, "local_planner"),
        ):
            if value not in allowed:
                raise ValueError(f"StackConfig: {what} must be one of {', '.join(allowed)}, got {value!r}")


METHODS: dict[str, StackConfig] = {
    "navfn": StackConfig("none"),
    "snl_small": StackConfig("snl_small"),
    "snl_large": StackConfig("snl_large"),
    "snl_matched": StackConfig("snl_matched"),
    "casn": StackConfig("casn"),
    "gscl": StackConfig("gscl"),
    "snape_eband": StackConfig("snape", "weighted", "eband", replan=False),
    "snape_social_eband": StackConfig("snape", "weighted", "social_eband", replan=False),
}


@struct.dataclass
class LayerParams:
    """The parameters of every layer and local planner a stack may use (dynamic floats: traced in
    an episode program, so a sweep does not recompile). :func:`layer_params` gives a method's
    defaults (the seeds' values)."""

    snl: snl.SNLParams = snl.SNLParams()
    casn: casn.CASNParams = casn.CASNParams()
    snape: snape.SNAPEParams = snape.SNAPEParams()
    band: elastic_band.BandParams = elastic_band.BandParams()
    pursuit: pure_pursuit.PursuitParams = pure_pursuit.PursuitParams()


def program_config(config: StackConfig) -> StackConfig:
    """The stack whose compiled episode program runs ``config``: the three SNL variants differ only
    in their covariances, which enter the program traced (:class:`LayerParams`), so they run the
    ``snl_small`` program with their own :func:`layer_params` (one compilation instead of three
    per scene shape, the same episodes bit for bit)."""
    if config.layer in ("snl_large", "snl_matched"):
        return dataclasses.replace(config, layer="snl_small")
    return config


def layer_params(config: StackConfig) -> LayerParams:
    """A stack's default parameters: its SNL variant's covariances (small, large or matched to
    CASN's radius), every other part's defaults."""
    sigma = {"snl_large": snl.SIGMA_LARGE, "snl_matched": SNL_MATCHED}.get(config.layer, snl.SIGMA_SMALL)
    return LayerParams(snl=sigma)


def layer_kind(config: StackConfig) -> str:
    """The kind of :class:`planners.layers.CostLayer` a stack's ``layer`` names (the SNL variants
    are one kind, ``snl``, with other covariances)."""
    return "snl" if config.layer.startswith("snl_") else config.layer


def cost_layer(config: StackConfig, params: LayerParams | None = None, gscl_model=None) -> layers.CostLayer:
    """The stack's social layer (:class:`planners.layers.CostLayer`) with its parameters: the SNL
    variants' covariances, CASN's or SNAPE's from ``params`` (:class:`LayerParams`, default
    :func:`layer_params`), GSCL's network and weights from ``gscl_model`` (a
    :class:`socialnav.models.inference.SocialCostModel` or a function of the maps,
    :func:`planners.layers.gscl`; ``ValueError`` without one)."""
    params = layer_params(config) if params is None else params
    if config.layer == "none":
        return layers.none()
    if config.layer in ("snl_small", "snl_large", "snl_matched"):
        return layers.snl(params.snl)
    if config.layer == "casn":
        return layers.casn(params.casn)
    if config.layer == "snape":
        return layers.snape(params.snape)
    if gscl_model is None:
        raise ValueError("the gscl layer needs a trained model (gscl_model)")
    return layers.gscl(gscl_model)


def global_plan(config: StackConfig, costs, start_xy, goal_xy, spec: costmap.GridSpec, max_steps: int = 0):
    """The global path: ((max_steps + 1, 2) metres, () valid points, () reached)."""
    plan_fn = grid_planner.navfn_plans if config.global_planner == "navfn" else grid_planner.weighted_plans
    plan = plan_fn(costs[None], start_xy[None], goal_xy[None], spec, max_steps=max_steps)
    path = grid_planner.path_xy_m(plan, spec)[0]
    path = path.at[0].set(start_xy)  # from the robot itself, not its cell's centre
    length = plan.path_length[0]
    path = path.at[jnp.maximum(length - 1, 1)].set(
        jnp.where(plan.reached[0], goal_xy, path[jnp.maximum(length - 1, 1)])
    )
    return path, length, plan.reached[0]


def local_command(
    config: StackConfig,
    path_xy,
    path_len,
    robot_xy,
    robot_yaw,
    robot_speed,
    max_speed_mps,
    people: Scene,
    clearance_fn,
    band_params: elastic_band.BandParams = elastic_band.BandParams(),
    pursuit: pure_pursuit.PursuitParams = pure_pursuit.PursuitParams(),
    snape_params: snape.SNAPEParams = snape.SNAPEParams(),
):
    """``(v, omega, band (band_points, 2), speed gain ())`` for one control step (the gain is 1
    except for the social band)."""
    if config.local_planner == "pursuit":
        target = pure_pursuit.lookahead_point(path_xy, path_len, robot_xy, pursuit.lookahead_m)
        v, w = pure_pursuit.pursue(target, robot_xy, robot_yaw, max_speed_mps, pursuit)
        band = jnp.broadcast_to(target, (config.band_points, 2))
        return v, w, band, jnp.float32(1.0)
    social = config.local_planner == "social_eband"  # the classic band: no social term (k_s ignored)
    band = elastic_band.band_from_path(path_xy, path_len, robot_xy, config.band_horizon_m, config.band_points)
    predicted = people.people_xy_m + band_params.predict_s * people.people_velocity_mps
    band = elastic_band.relax(
        band,
        clearance_fn,
        predicted,
        people.people_heading_rad,
        people.people_valid,
        band_params,
        snape_params,
        config.band_iterations,
        social=social,
    )
    target = pure_pursuit.lookahead_point(band, config.band_points, robot_xy, pursuit.lookahead_m)
    v, w = pure_pursuit.pursue(target, robot_xy, robot_yaw, max_speed_mps, pursuit)
    gain = jnp.float32(1.0)
    if social:
        gain = elastic_band.speed_gain(
            band,
            jnp.maximum(robot_speed, GAIN_MIN_SPEED_MPS),
            people.people_xy_m,
            people.people_velocity_mps,
            people.people_valid,
            band_params,
        )
    return v * gain, w, band, gain
