"""A learned policy as an actor: what it observes, how its output drives the base.

The policy is a local planner learned by reinforcement learning (:mod:`planners.learning.policy_training`)
on top of a static global guide, as robot_sf's and Nav2-style learned controllers follow a
global path: at the start of an episode the actor computes the *guidance field*, the cost-to-goal
of every cell of the scene's static map (:func:`guidance_field`: NavFn's cell costs on the
inflated walls, divided by NavFn's neutral cost so that free space costs 1 per metre; the
people are not in it), and at every step it sees:

* ``goal``: the goal's distance (/10 m, clipped at 1) and bearing (cos, sin) in its frame;
* ``own``: its speed and turn rate over their limits;
* ``guide``: the field on a ``field_cells`` x ``field_cells`` window of ``field_resolution_m``
  around it, turned with it, minus the field under it, over ``field_scale_m`` and clipped to
  [-1, 1] (walls and unreachable cells read 1): the way to the goal and the walls near it;
* ``occupancy``: the env's occupancy window (:class:`jaxsim.scenes.env.Observation`);
* ``social`` (optional, ``PolicyConfig.social_layer``): a social cost layer (SNL small, large
  or matched; CASN; a trained GSCL network) drawn from the people it sees, on the guidance
  window's points, over Nav2's 254: so a learned policy can use a cost map as an input channel
  (:mod:`planners.learning.policy_social`);
* ``people``: the ``n_people`` nearest people it sees, in its frame: position (/4 m), velocity
  (/1.5 m/s), the distance from its body to their centre (/4 m), and a flag (1 seen; all 0 for
  an empty slot).

Everything is what the robot perceives (the env's observation) and its map; nothing is read
from the simulator. The network's normalised output ``u`` (2,) becomes the command ``v =
(u0 + 1) / 2 * v_max``, ``omega = u1 * omega_max``; the base clips both (:func:`command`). In the
benchmark the actor takes the mean action (deterministic); training samples around it.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
from flax import struct

from socialnav.jaxsim.scenes.actor import Actor, replanning
from socialnav.jaxsim.scenes.env import Env, Observation
from socialnav.jaxsim.scenes.robot import RobotParams
from socialnav.models import policy_net
from socialnav.planners.global_planners import grid_planner
from socialnav.planners.layers import costmap
from socialnav.planners.learning import policy_social
from socialnav.planners.learning.policy_social import SOCIAL_LAYERS, SocialState


@dataclasses.dataclass(frozen=True)
class PolicyConfig:
    """The policy's static shape (a change is another network).

    Attributes:
      hidden: the MLPs' hidden widths.
      n_people: the nearest seen people observed (CrowdNav's and social-jym's crowds are 5-10).
      field_cells, field_resolution_m: the guidance window (9 x 9 at 0.5 m: 4 m across, the
        reach of the env's occupancy window).
      field_scale_m: field differences are divided by this (2 m: the window's half width).
      initial_log_std: the exploration noise at the start of training.
      social_layer: ``"none"`` or a social layer seen on the guidance window
        (:data:`~planners.learning.policy_social.SOCIAL_LAYERS`: SNL with the small, large or
        CASN-matched covariances, their parameters the stacks' own; CASN; ``gscl``, a trained
        U-Net); it adds ``field_cells ** 2`` features.
      gscl_run: the trained GSCL run folder (``socialnav gscl train --out``) of ``social_layer
        = "gscl"``, an absolute path (empty otherwise).
      gscl_every_steps: the GSCL window is recomputed every this many steps (10: 1 Hz, the
        arena's layer rate; :mod:`planners.learning.policy_social`).
    """

    hidden: tuple[int, ...] = (128, 128)
    n_people: int = 6
    field_cells: int = 9
    field_resolution_m: float = 0.5
    field_scale_m: float = 2.0
    initial_log_std: float = -0.5
    social_layer: str = "none"
    gscl_run: str = ""
    gscl_every_steps: int = 10

    def __post_init__(self):
        if self.social_layer not in SOCIAL_LAYERS:
            raise ValueError(f"social_layer must be one of {', '.join(SOCIAL_LAYERS)}, got {self.social_layer!r}")
        if (self.social_layer == "gscl") != bool(self.gscl_run):
            raise ValueError("gscl_run names the GSCL model of social_layer 'gscl' and nothing else")
        if not isinstance(self.gscl_every_steps, int) or self.gscl_every_steps < 1:
            raise ValueError(f"gscl_every_steps must be a whole number >= 1, got {self.gscl_every_steps!r}")

    def n_features(self, window_cells: int) -> int:
        """F, the feature vector's length with the env's occupancy window of ``window_cells``."""
        social = 0 if self.social_layer == "none" else self.field_cells**2
        return 3 + 2 + self.field_cells**2 + social + window_cells**2 + 6 * self.n_people

    def to_json(self) -> dict:
        return {**dataclasses.asdict(self), "hidden": list(self.hidden)}

    @classmethod
    def from_json(cls, d: dict) -> PolicyConfig:
        return cls(**{**d, "hidden": tuple(d["hidden"])})


@struct.dataclass
class PolicyParams:
    """The actor's dynamic inputs: the network's ``weights`` (an ``nnx.State``), the scene's
    ``traversal_per_m`` (H, W) (the guide's cell costs, ``inf`` impassable), the base's limits
    ``robot``, the map's ``occupancy`` (H, W) in [0, 1] (the GSCL network's walls) and the GSCL
    network's ``gscl_weights`` (None without that layer)."""

    weights: object
    traversal_per_m: jax.Array
    robot: RobotParams
    occupancy: jax.Array
    gscl_weights: object = None


@struct.dataclass
class PolicyState:
    """field (H, W): cost-to-goal in metres of free space (:func:`guidance_field`); social: the
    social channel's state (:class:`~planners.learning.policy_social.SocialState`)."""

    field: jax.Array
    social: SocialState


def scene_grid(env: Env) -> costmap.GridSpec:
    """The :class:`~jaxsim.grid.GridSpec` of ``env``'s occupancy grid."""
    return env.occupancy.spec


def traversal(env: Env) -> jax.Array:
    """(H, W) the guide's cost per metre: NavFn's ``50 + 0.8 c`` over the walls inflated for the
    robot's radius (Nav2's inflation), divided by 50, ``inf`` where the robot's body would touch
    a wall."""
    grid = scene_grid(env)
    costs = costmap.obstacle_layer(env.occupancy.values, grid, float(env.robot.radius_m))
    return costmap.navfn_traversal(costs) / costmap.NAVFN_NEUTRAL


def guidance_field(traversal_per_m, goal_xy_m, grid: costmap.GridSpec):
    """(H, W) cost-to-goal of every cell (metres of free space; ``inf`` unreachable): the exact
    potential of :func:`planners.global_planners.grid_planner.potential` from the goal's cell."""
    goal_ij = grid.clamp(grid.cell_of(goal_xy_m))
    return grid_planner.potential(traversal_per_m, goal_ij, grid.resolution_m)


@struct.dataclass
class PoolField:
    """One field of a stack (N, H, W) by its index: ``field[r, c]`` reads ``fields[index, r, c]``
    without gathering the whole (H, W) field (the trainer's episodes each index the pool's)."""

    fields: jax.Array
    index: jax.Array

    def __getitem__(self, rc):
        return self.fields[self.index, rc[0], rc[1]]


def field_at(field, xy_m, grid: costmap.GridSpec):
    """The field at points ``xy_m`` (..., 2) (nearest cell; off the grid: ``inf``).

    The cell is found in floats, not by :meth:`~jaxsim.grid.GridSpec.cell_of`: a NaN or huge
    coordinate is then off the grid (``inf``), where a conversion to int32 first would saturate it
    (NaN to 0) onto a cell."""
    col = jnp.floor((xy_m[..., 0] - grid.origin_x_m) / grid.resolution_m)
    row = jnp.floor((xy_m[..., 1] - grid.origin_y_m) / grid.resolution_m)
    inside = (row >= 0) & (row < grid.height) & (col >= 0) & (col < grid.width)
    r = jnp.clip(row, 0, grid.height - 1).astype(jnp.int32)
    c = jnp.clip(col, 0, grid.width - 1).astype(jnp.int32)
    return jnp.where(inside, field[r, c], jnp.inf)


def _to_robot_frame(vectors, yaw):
    cos, sin = jnp.cos(yaw), jnp.sin(yaw)
    return jnp.stack(
        [cos * vectors[..., 0] + sin * vectors[..., 1], -sin * vectors[..., 0] + cos * vectors[..., 1]], -1
    )


def window_points(config: PolicyConfig, obs: Observation):
    """(c, c, 2) the guidance window's points in the world: ``field_cells`` forward offsets
    (rows, -half to +half) by as many leftward ones (columns), turned with the robot."""
    c = config.field_cells
    offsets = (jnp.arange(c, dtype=jnp.float32) - (c - 1) / 2) * config.field_resolution_m
    fwd, left = jnp.meshgrid(offsets, offsets, indexing="ij")
    yaw = obs.robot_yaw_rad
    rotated = jnp.stack([jnp.cos(yaw) * fwd - jnp.sin(yaw) * left, jnp.sin(yaw) * fwd + jnp.cos(yaw) * left], -1)
    return obs.robot_xy_m + rotated


def features(config: PolicyConfig, obs: Observation, field, grid: costmap.GridSpec, robot: RobotParams, social=None):
    """(F,) the policy's input from one observation and the episode's guidance field.

    ``social``: the social channel's window ((field_cells ** 2,),
    :func:`planners.learning.policy_social.window`); left out, a stateless layer (none, SNL) is computed
    here, while CASN and GSCL, which carry state, must be given.
    """
    xy, yaw = obs.robot_xy_m, obs.robot_yaw_rad
    to_goal = _to_robot_frame(obs.goal_xy_m - xy, yaw)
    distance = jnp.linalg.norm(to_goal)
    bearing = to_goal / jnp.maximum(distance, 1e-6)
    goal = jnp.concatenate([jnp.minimum(distance / 10.0, 1.0)[None], bearing])
    own = jnp.stack([obs.robot_speed_mps / robot.max_speed_mps, obs.robot_turn_rate_rps / robot.max_turn_rate_rps])

    points = window_points(config, obs)
    here = field_at(field, xy, grid)
    window = field_at(field, points, grid)
    diff = jnp.where(jnp.isfinite(window) & jnp.isfinite(here), (window - here) / config.field_scale_m, 1.0)
    guide = jnp.clip(diff, -1.0, 1.0).reshape(-1)
    if social is None:
        if config.social_layer in ("casn", "gscl"):
            raise ValueError(f"features: the {config.social_layer} channel carries state: pass its window")
        social, _ = policy_social.window(config.social_layer, obs, points, policy_social.initial_state(1))

    rel = _to_robot_frame(obs.people_xy_m - xy, yaw)
    vel = _to_robot_frame(obs.people_velocity_mps, yaw)
    gap = jnp.linalg.norm(rel, axis=-1) - robot.radius_m
    order_key = jnp.where(obs.people_visible, gap, jnp.inf)
    k = min(config.n_people, order_key.shape[0])
    _, nearest = jax.lax.top_k(-order_key, k)
    seen = obs.people_visible[nearest]
    person = jnp.concatenate(
        [rel[nearest] / 4.0, vel[nearest] / 1.5, (gap[nearest] / 4.0)[:, None], jnp.ones((k, 1))], axis=-1
    )
    person = jnp.where(seen[:, None], person, 0.0)
    person = jnp.pad(person, ((0, config.n_people - k), (0, 0))).reshape(-1)
    return jnp.concatenate([goal, own, guide, social, obs.occupancy.reshape(-1), person]).astype(jnp.float32)


def command(u, robot: RobotParams):
    """(2,) ``(v, omega)`` of a normalised action ``u`` (..., 2), clipped to the base's limits."""
    v = jnp.clip((u[..., 0] + 1.0) / 2.0, 0.0, 1.0) * robot.max_speed_mps
    w = jnp.clip(u[..., 1], -1.0, 1.0) * robot.max_turn_rate_rps
    return jnp.stack([v, w], -1).astype(jnp.float32)


def observe(config: PolicyConfig, obs: Observation, field, grid, robot: RobotParams, social: SocialState):
    """``(features (F,), next social state)``: the social channel's window, then :func:`features`."""
    window, social = policy_social.window(config.social_layer, obs, window_points(config, obs), social)
    return features(config, obs, field, grid, robot, window), social


def policy_actor(config: PolicyConfig, graphdef, grid: costmap.GridSpec, name: str = "ppo", gscl_model=None) -> Actor:
    """The policy as an :class:`~jaxsim.scenes.actor.Actor` with :class:`PolicyParams`: it
    computes the guidance field once, at the start (:func:`jaxsim.actor.replanning` with
    ``every_steps = 0``), and then acts
    with the network's mean action (deterministic). With the GSCL channel (``gscl_model``: a
    :class:`~socialnav.models.inference.SocialCostModel`, its ``apply(weights, maps)`` with the
    weights ``PolicyParams.gscl_weights``, traced) it plans
    every ``config.gscl_every_steps`` steps instead: the network's window each time, the
    guidance field once."""
    gscl = config.social_layer == "gscl"
    if gscl and gscl_model is None:
        raise ValueError("policy_actor: the gscl channel needs the trained network (gscl_model)")
    network = gscl_model.apply if gscl else None

    def init(key, obs: Observation):
        del key
        return PolicyState(
            field=jnp.full((grid.height, grid.width), jnp.nan, jnp.float32),
            social=policy_social.initial_state(obs.people_xy_m.shape[0]),
        )

    def plan(params: PolicyParams, state: PolicyState, obs: Observation, key):
        del key
        fresh = jnp.isnan(state.field[0, 0])  # the episode's first plan
        field = jax.lax.cond(
            fresh, lambda: guidance_field(params.traversal_per_m, obs.goal_xy_m, grid), lambda: state.field
        )
        social = state.social
        if gscl:
            predict = lambda maps: network(params.gscl_weights, maps)
            social = policy_social.gscl_refresh(predict, params.occupancy, grid, obs, social)
        return PolicyState(field=field, social=social)

    def act(params: PolicyParams, state: PolicyState, obs: Observation, key):
        del key
        x, social = observe(config, obs, state.field, grid, params.robot, state.social)
        mean, _, _ = policy_net.apply(graphdef, params.weights, x)
        return command(mean, params.robot), state.replace(social=social)

    return replanning(Actor(init=init, act=act, name=name), plan, config.gscl_every_steps if gscl else 0)


def policy_params(env: Env, weights, gscl_model=None) -> PolicyParams:
    """The actor's params in ``env`` with the network's ``weights`` (and the GSCL model's,
    ``gscl_model.weights``)."""
    return PolicyParams(
        weights=weights,
        traversal_per_m=traversal(env),
        robot=env.robot,
        occupancy=jnp.asarray(env.occupancy.values, jnp.float32),
        gscl_weights=None if gscl_model is None else gscl_model.weights,
    )
