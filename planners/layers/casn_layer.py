"""CASN, context-aware social navigation (seed 001, Haarslev et al., ICINCO 2021), in JAX.

The paper (Sec. 3) fixes the shapes; it leaves the costs, the group detector's details and the
speed-to-``p`` mapping open. This project's choices, all parameters of :class:`CASNParams`:

* **Personal spaces** (Eq. 4, 7): constant-cost discs, intimate 0.45 m and personal 1.2 m (Hall),
  summed as Eq. 4 says: personal 100, intimate 152, so a cell inside the intimate disc costs
  252, the dearest cost that is not an obstacle (a person's own body is the obstacle layer's).
* **Groups** (Eq. 5, 8; Sec. 3.3): two static people belong together when they stand at most 3 m
  apart (the paper's figure) and either look at each other (each within
  ``look_half_angle_rad`` = 30 deg of the line to the other) or share a focus point (their lines
  of sight cross in front of both, within ``focus_range_m`` = 3 m): the paper's "rewarded if they
  look towards each other ... or have the same focus point". Groups are the connected components
  of that relation. A group of 2 or more gets an o-space (centre: the members' centroid; radius:
  their mean distance to it) and a p-space (the o-space radius plus ``p_space_margin_m`` = 0.6 m,
  the ring the members stand in), constant costs 152 and 100, summed as Eq. 5 (252 inside).
* **Moving people** are replaced by their collision point with the robot (Sec. 3.3):
  - *head-on* (walking towards the robot, within ``head_on_half_angle_rad`` = 45 deg):
    ``h_hat = h - p (h - r)``; the paper sets ``p`` "dynamically based on the estimated velocity"
    without a formula: we take ``p = |v_h| / (|v_h| + v_robot)``, where two bodies meeting at
    constant speeds actually meet (``p`` grows with the person's speed; equal speeds give the
    paper's example 0.5);
  - *crossing* (velocity within 45 deg of perpendicular to the robot's heading): ``h_hat = r +
    0.8 v_x`` (the paper's ``p = 0.8``, ``v_x`` the component of ``h - r`` along the robot's
    heading), shifted by ``crossing_shift_m`` = 0.6 m sideways in the direction the person walks,
    so the shorter way round passes behind them. (The paper shifts "along ``-v_y``", the side
    opposite the person's lateral offset: the same direction while the person approaches the
    robot's line, and still behind them once they have crossed it.)
  - the head-on test comes first, so a walker crossing the robot's path counts as head-on while
    its velocity points within ``head_on_half_angle_rad`` of the robot: far up its path, or near
    the crossing point when the robot is too. The paper gives no angle for either test; at the
    crossing, how fast walkers are treated depends on this one (the results page's seed 001
    speed classes sweep it).
  - other moving people (walking away, alongside) keep their discs at their position.
  - **freeze**: once ``|h_hat - r| < 2 m`` the collision point is frozen until the robot has passed
    the person (the person is behind the robot). The frozen points are state carried between
    calls: :class:`CASNState` goes in and comes out of :func:`casn_layer`.
* Everything is summed (Eq. 6) and clipped to 252 (Nav2's graded range).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct

from socialnav.planners.layers.costmap import MAX_GRADED
from socialnav.planners.layers.scene import Scene


@struct.dataclass
class CASNParams:
    """CASN's numbers (dynamic floats; distances in m, speeds in m/s, angles in rad, costs on
    Nav2's scale). See the module docstring for where each comes from."""

    intimate_radius_m: float = 0.45
    personal_radius_m: float = 1.2
    intimate_cost: float = 152.0
    personal_cost: float = 100.0
    group_max_distance_m: float = 3.0
    look_half_angle_rad: float = 0.5236  # 30 deg
    focus_range_m: float = 3.0
    p_space_margin_m: float = 0.6
    o_space_cost: float = 152.0
    p_space_cost: float = 100.0
    still_speed_mps: float = 0.1
    head_on_half_angle_rad: float = 0.7854  # 45 deg
    crossing_half_angle_rad: float = 0.7854  # 45 deg from perpendicular
    robot_speed_mps: float = 0.5
    crossing_p: float = 0.8
    crossing_shift_m: float = 0.6
    freeze_distance_m: float = 2.0


@struct.dataclass
class CASNState:
    """The frozen collision points carried between calls: (P, 2) points, (P,) bool frozen."""

    frozen_xy_m: jnp.ndarray
    frozen: jnp.ndarray


def initial_state(n_people: int) -> CASNState:
    return CASNState(frozen_xy_m=jnp.zeros((n_people, 2), jnp.float32), frozen=jnp.zeros(n_people, bool))


def _unit(angle_rad):
    return jnp.stack([jnp.cos(angle_rad), jnp.sin(angle_rad)], axis=-1)


def detect_groups(scene: Scene, params: CASNParams = CASNParams()):
    """Group labels of static people: (P,) int32, the smallest member index of each person's
    group, -1 for a person in no group of 2 or more (or moving, or padding).

    The pairwise relation (distance, mutual look, shared focus point) is one (P, P) array; its
    connected components come from min-label propagation (P rounds of a (P, P) min).
    """
    xy = scene.people_xy_m
    n = xy.shape[0]
    speed = jnp.linalg.norm(scene.people_velocity_mps, axis=-1)
    static = scene.people_valid & (speed <= params.still_speed_mps)
    facing = _unit(scene.people_heading_rad)  # (P, 2)
    d = xy[None, :, :] - xy[:, None, :]  # d[i, j] = x_j - x_i
    dist = jnp.linalg.norm(d, axis=-1)
    cos_look = jnp.sum(facing[:, None, :] * d, axis=-1) / jnp.maximum(dist, 1e-6)
    looks_at = cos_look >= jnp.cos(params.look_half_angle_rad)  # i looks at j
    mutual = looks_at & looks_at.T

    # Lines of sight x_i + t_i f_i = x_j + t_j f_j: both t in (0, focus_range].
    fi, fj = facing[:, None, :], facing[None, :, :]
    det = fi[..., 0] * (-fj[..., 1]) - fi[..., 1] * (-fj[..., 0])
    safe = jnp.where(jnp.abs(det) > 1e-6, det, 1.0)
    t_i = (d[..., 0] * (-fj[..., 1]) - d[..., 1] * (-fj[..., 0])) / safe
    t_j = (fi[..., 0] * d[..., 1] - fi[..., 1] * d[..., 0]) / safe
    shared_focus = (
        (jnp.abs(det) > 1e-6) & (t_i > 0) & (t_j > 0) & (t_i <= params.focus_range_m) & (t_j <= params.focus_range_m)
    )
    pair = (
        static[:, None]
        & static[None, :]
        & (dist <= params.group_max_distance_m)
        & (mutual | shared_focus)
        & ~jnp.eye(n, dtype=bool)
    )
    linked = pair | jnp.eye(n, dtype=bool)

    def spread(labels, _):
        return jnp.min(jnp.where(linked, labels[None, :], n), axis=1), None

    labels, _ = jax.lax.scan(spread, jnp.arange(n), None, length=n)
    size = jnp.sum(labels[None, :] == labels[:, None], axis=1)
    return jnp.where(static & (size >= 2), labels, -1).astype(jnp.int32)


def group_spaces(scene: Scene, labels, params: CASNParams = CASNParams()):
    """Each group's o-space: (P, 2) centres, (P,) radii, (P,) bool valid (row g is the group whose
    label is g)."""
    xy = scene.people_xy_m
    n = xy.shape[0]
    member = labels[None, :] == jnp.arange(n)[:, None]  # (G=P, P)
    count = jnp.sum(member, axis=1)
    centre = (member.astype(jnp.float32) @ xy) / jnp.maximum(count, 1)[:, None]
    spread = jnp.linalg.norm(xy[None, :, :] - centre[:, None, :], axis=-1)
    radius = jnp.sum(jnp.where(member, spread, 0.0), axis=1) / jnp.maximum(count, 1)
    return centre, radius, count >= 2


def collision_points(scene: Scene, state: CASNState, params: CASNParams = CASNParams()):
    """Where each person's personal discs go: (P, 2) points and the next :class:`CASNState`.

    Static people and people walking away keep their position; a person walking at the robot
    or across its heading is replaced by the collision point (module docstring), frozen within
    ``freeze_distance_m`` of the robot until the robot has passed them.
    """
    h = scene.people_xy_m
    r = scene.robot_xy_m
    u = scene.people_velocity_mps
    speed = jnp.linalg.norm(u, axis=-1)
    moving = scene.people_valid & (speed > params.still_speed_mps)
    forward = _unit(scene.robot_yaw_rad)
    left = jnp.stack([-forward[1], forward[0]])
    v = h - r  # robot -> person
    dist = jnp.linalg.norm(v, axis=-1)
    u_dir = u / jnp.maximum(speed, 1e-6)[:, None]

    towards = jnp.sum(u_dir * (-v), axis=-1) / jnp.maximum(dist, 1e-6)
    head_on = moving & (towards >= jnp.cos(params.head_on_half_angle_rad))
    across = jnp.abs(u_dir @ forward) <= jnp.sin(params.crossing_half_angle_rad)
    v_x = v @ forward
    crossing = moving & ~head_on & across & (v_x > 0)

    p = speed / (speed + params.robot_speed_mps)
    head_on_point = h - p[:, None] * v
    lateral_walk = jnp.sign(u @ left)
    crossing_point = (
        r + params.crossing_p * v_x[:, None] * forward + (params.crossing_shift_m * lateral_walk)[:, None] * left
    )
    point = jnp.where(head_on[:, None], head_on_point, jnp.where(crossing[:, None], crossing_point, h))

    passed = (v @ forward) < 0
    still_frozen = state.frozen & ~passed & scene.people_valid
    freeze_now = ~state.frozen & (head_on | crossing) & (jnp.linalg.norm(point - r, axis=-1) < params.freeze_distance_m)
    frozen = still_frozen | freeze_now
    frozen_xy = jnp.where(still_frozen[:, None], state.frozen_xy_m, jnp.where(freeze_now[:, None], point, 0.0))
    point = jnp.where(frozen[:, None], frozen_xy, point)
    return point, CASNState(frozen_xy_m=frozen_xy.astype(jnp.float32), frozen=frozen)


def _discs(x_m, y_m, centres, radius_m, cost, valid):
    """(H, W) sum over discs of ``cost`` inside radius (vectorised over the (K,) discs)."""
    d = jnp.hypot(x_m[None] - centres[:, 0, None, None], y_m[None] - centres[:, 1, None, None])
    inside = (d < jnp.broadcast_to(radius_m, centres.shape[:1])[:, None, None]) & valid[:, None, None]
    return jnp.sum(jnp.where(inside, jnp.broadcast_to(cost, centres.shape[:1])[:, None, None], 0.0), axis=0)


def casn_layer(scene: Scene, x_m, y_m, state: CASNState | None = None, params: CASNParams = CASNParams()):
    """CASN's cost layer at cell centres ``x_m, y_m`` (H, W): ``(costs (H, W) float32, next state)``.

    Pass the returned state into the next call (one scene over time); ``None`` starts with nothing
    frozen.
    """
    if state is None:
        state = initial_state(scene.n_people)
    points, state = collision_points(scene, state, params)
    valid = scene.people_valid
    total = _discs(x_m, y_m, points, params.personal_radius_m, params.personal_cost, valid)
    total = total + _discs(x_m, y_m, points, params.intimate_radius_m, params.intimate_cost, valid)
    labels = detect_groups(scene, params)
    centre, radius, group_valid = group_spaces(scene, labels, params)
    total = total + _discs(x_m, y_m, centre, radius + params.p_space_margin_m, params.p_space_cost, group_valid)
    total = total + _discs(x_m, y_m, centre, radius, params.o_space_cost, group_valid)
    return jnp.minimum(total, MAX_GRADED).astype(jnp.float32), state
