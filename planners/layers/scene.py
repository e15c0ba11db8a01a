"""What a cost layer sees: :class:`Scene`, a pytree of fixed-shape arrays (people, objects, robot).

People and objects are padded to fixed counts and masked (``*_valid``), so scenes with different
numbers of people stack into one batch and a layer vmaps over them. The static occupancy grid
travels beside the scene (it is the obstacle layer's input, see :mod:`planners.layers.costmap`).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct


@struct.dataclass
class Scene:
    """One moment of a scene, as the robot's perception reports it.

    Attributes (P people, M objects of at most V vertices; all float32 unless said):
      people_xy_m: (P, 2) positions.
      people_heading_rad: (P,) body orientation (where a person looks; for a walker, where they walk).
      people_velocity_mps: (P, 2) velocities.
      people_valid: (P,) bool; padding rows are False.
      objects_xy_m: (M, V, 2) the vertices of each object's interaction space, a convex polygon
        listed counter-clockwise (pad a polygon with fewer vertices by repeating its last one).
      objects_cost: (M,) the cost inside each interaction space (Nav2 scale).
      objects_valid: (M,) bool.
      robot_xy_m: (2,) robot position; robot_yaw_rad: () its heading.
      goal_xy_m: (2,) the goal.
    """

    people_xy_m: jnp.ndarray
    people_heading_rad: jnp.ndarray
    people_velocity_mps: jnp.ndarray
    people_valid: jnp.ndarray
    objects_xy_m: jnp.ndarray
    objects_cost: jnp.ndarray
    objects_valid: jnp.ndarray
    robot_xy_m: jnp.ndarray
    robot_yaw_rad: jnp.ndarray
    goal_xy_m: jnp.ndarray

    @property
    def n_people(self) -> int:
        return self.people_valid.shape[-1]


def make_scene(
    people_xy_m=(),
    people_heading_rad=None,
    people_velocity_mps=None,
    robot_xy_m=(0.0, 0.0),
    robot_yaw_rad=0.0,
    goal_xy_m=(0.0, 0.0),
    objects=(),
    max_people: int | None = None,
    max_objects: int | None = None,
    max_vertices: int = 4,
) -> Scene:
    """A :class:`Scene` from plain lists, padded to ``max_people`` / ``max_objects``.

    Args:
      people_xy_m: (P, 2) positions. people_heading_rad: (P,) (default: the direction of the
        velocity, 0 for a person standing still). people_velocity_mps: (P, 2) (default 0).
      objects: a sequence of ``(vertices (V, 2) counter-clockwise, cost)``.
      max_people, max_objects: padded sizes (default: the given counts; at least 1 each, so that
        every array has a fixed, non-empty shape).
    """
    xy = np.asarray(people_xy_m, np.float32).reshape(-1, 2)
    n = len(xy)
    if not np.all(np.isfinite(xy)):
        raise ValueError("make_scene: people_xy_m must be finite")
    velocity = (
        np.zeros((n, 2), np.float32)
        if people_velocity_mps is None
        else np.asarray(people_velocity_mps, np.float32).reshape(n, 2)
    )
    if people_heading_rad is None:
        heading = np.arctan2(velocity[:, 1], velocity[:, 0]).astype(np.float32)
    else:
        heading = np.asarray(people_heading_rad, np.float32).reshape(n)
    max_people = max(1, n if max_people is None else max_people)
    if n > max_people:
        raise ValueError(f"make_scene: {n} people exceed max_people={max_people}")
    pad = max_people - n

    n_obj = len(objects)
    max_objects = max(1, n_obj if max_objects is None else max_objects)
    if n_obj > max_objects:
        raise ValueError(f"make_scene: {n_obj} objects exceed max_objects={max_objects}")
    verts = np.zeros((max_objects, max_vertices, 2), np.float32)
    costs = np.zeros(max_objects, np.float32)
    for k, (polygon, cost) in enumerate(objects):
        polygon = np.asarray(polygon, np.float32).reshape(-1, 2)
        if not 3 <= len(polygon) <= max_vertices:
            raise ValueError(f"make_scene: object {k} has {len(polygon)} vertices (3 to {max_vertices} allowed)")
        verts[k, : len(polygon)] = polygon
        verts[k, len(polygon) :] = polygon[-1]
        costs[k] = cost

    return Scene(
        people_xy_m=jnp.asarray(np.pad(xy, ((0, pad), (0, 0)))),
        people_heading_rad=jnp.asarray(np.pad(heading, (0, pad))),
        people_velocity_mps=jnp.asarray(np.pad(velocity, ((0, pad), (0, 0)))),
        people_valid=jnp.asarray(np.arange(max_people) < n),
        objects_xy_m=jnp.asarray(verts),
        objects_cost=jnp.asarray(costs),
        objects_valid=jnp.asarray(np.arange(max_objects) < n_obj),
        robot_xy_m=jnp.asarray(robot_xy_m, jnp.float32),
        robot_yaw_rad=jnp.asarray(robot_yaw_rad, jnp.float32),
        goal_xy_m=jnp.asarray(goal_xy_m, jnp.float32),
    )


def wrap_angle(angle_rad):
    """Angles wrapped to [-pi, pi)."""
    return (angle_rad + jnp.pi) % (2 * jnp.pi) - jnp.pi


def inside_convex(x_m, y_m, vertices_m):
    """(...,) bool: points inside (or on) a convex counter-clockwise polygon (V, 2); repeated
    vertices (padding) give degenerate edges that every point passes."""
    a = vertices_m
    b = jnp.roll(vertices_m, -1, axis=0)
    ex, ey = (b - a)[:, 0], (b - a)[:, 1]
    cross = ex * (y_m[..., None] - a[:, 1]) - ey * (x_m[..., None] - a[:, 0])
    return jnp.all(cross >= -1e-6, axis=-1)


def objects_layer(scene: Scene, x_m, y_m):
    """(H, W) the cost of each object's interaction space (max over objects), 0 outside.

    Args: x_m, y_m: (H, W) cell centres (:meth:`planners.layers.costmap.GridSpec.cell_centres`).
    """

    def one(vertices, cost, valid):
        return jnp.where(valid & inside_convex(x_m, y_m, vertices), cost, 0.0)

    layers = jax.vmap(one)(scene.objects_xy_m, scene.objects_cost, scene.objects_valid)
    return jnp.max(layers, axis=0).astype(jnp.float32)
