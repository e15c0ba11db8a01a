"""The families of GSCL's procedural dataset (seed 002 Sec. 4.1), one sampler each.

Each family is a pure function ``key -> (input uint8 (40, 40), target float32 (40, 40))``
(:data:`FAMILIES`); :mod:`models.dataset` vmaps them over keys into datasets. Inputs use the
paper's pixel codes (:mod:`models.grid`); targets are costs in [0, 1] (x 255 for the paper's
0-255 images) built from :mod:`models.social_costs`.

Families (paper's Fig. 1 (a)-(h), the hallway split in its three configurations):

* ``corner`` (2000): two walls meeting at a random point with a random orientation, the wall
  block's angle in [60, 120] degrees; cost around the corner on the free (reflex) side. The
  robot (image centre) is always on the free side.
* ``proxemics`` (1000): one person with a random heading, with up to three random walls kept
  1.2 m from them; proxemic + passing cost. The paper's "standing or walking" cannot be told
  apart in its input encoding, so every person's cost has one shape (:mod:`models.social_costs`).
* ``group`` (4500) / ``non_group`` (4500): 2-6 standing people on a circle of radius 1-1.5 m,
  spread over an arc from half to all of the circle (from L-shaped and face-to-face pairs to
  circles, covering the F-formations), facing the centre (group: proxemics + the interaction
  zone) or facing out (non-group: proxemics only).
* ``hallway_straight`` / ``hallway_l`` / ``hallway_people`` (5000 together): a corridor 1.6-4 m
  wide through the robot, random orientation and wall lengths, the goal along it; cost on the
  left half relative to the way to the goal (keep right; rising smoothly from 0 on the centre
  line to 0.6 at the left wall), the L's blind inner corner, and walkers' proxemics.
* ``queue`` (3600) / ``non_queue`` (3600): 3-10 m of people facing the head, gaps between bodies
  triangular in [0.3, 0.8] m (the paper's "distance between individuals", read as the gap:
  centre spacing = gap + 0.4 m), up to two random walls kept 1.5 m away; goal 0.8 m ahead of the
  head with the U-shaped cost (both sides and the front, open at the tail), or elsewhere beside
  the queue with proxemics only.

Every target is a function of what the input shows: people's costs are centred on the cell
they are drawn in and point along the drawn heading (one of 8 directions), and the rules' edges
are soft or lie on wall pixels. A target that depended on more than the input (a person's exact
position within the 0.4 m cell, their exact heading or speed) would add an error no network can
remove.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp

from models import grid
from models import social_costs as sc

WALL_LENGTH_M = 24.0  # long enough to cross the 16 m image from anywhere inside it


def _blank():
    return jnp.zeros((grid.GRID, grid.GRID), jnp.uint8)


def _walls_image(segments, valid):
    return jnp.where(grid.wall_mask(segments, valid), jnp.uint8(grid.WALL), jnp.uint8(grid.FREE))


def sample_corner(key):
    """A blind corner: walls from the corner point along two directions ``beta`` apart."""
    k1, k2, k3 = jax.random.split(key, 3)
    cx, cy = jax.random.uniform(k1, (2,), minval=-4.0, maxval=4.0)
    theta0 = jax.random.uniform(k2, (), minval=-jnp.pi, maxval=jnp.pi)
    beta = jnp.deg2rad(jax.random.uniform(k3, (), minval=60.0, maxval=120.0))
    # Keep the robot (origin) outside the wall block's wedge: turn the wedge round if needed.
    rel = (jnp.arctan2(-cy, -cx) - theta0) % (2 * jnp.pi)
    theta0 = jnp.where(rel <= beta, theta0 + jnp.pi, theta0)
    ends = [(cx + WALL_LENGTH_M * jnp.cos(a), cy + WALL_LENGTH_M * jnp.sin(a)) for a in (theta0, theta0 + beta)]
    segments = jnp.stack([jnp.stack([cx, cy, ex, ey]) for ex, ey in ends])
    image = _walls_image(segments, jnp.ones(2, bool))
    rel_cells = (jnp.arctan2(grid.CELL_Y_M - cy, grid.CELL_X_M - cx) - theta0) % (2 * jnp.pi)
    free = (rel_cells > beta) & (image == grid.FREE)
    return image, sc.corner_cost(cx, cy, free)


def _random_walls(key, n_max: int, keep_from_x, keep_from_y, clearance_m: float):
    """Up to ``n_max`` random wall segments, each dropped if it comes within ``clearance_m`` of
    any of the points ``keep_from`` ((P,) arrays; NaN entries ignored)."""
    k_n, k_c, k_a, k_l = jax.random.split(key, 4)
    n = jax.random.randint(k_n, (), 0, n_max + 1)
    centre = jax.random.uniform(k_c, (n_max, 2), minval=-7.0, maxval=7.0)
    angle = jax.random.uniform(k_a, (n_max,), minval=0.0, maxval=jnp.pi)
    half = 0.5 * jax.random.uniform(k_l, (n_max,), minval=3.0, maxval=12.0)
    d = jnp.stack([jnp.cos(angle), jnp.sin(angle)], -1) * half[:, None]
    segments = jnp.concatenate([centre - d, centre + d], -1)
    # Distance of each kept point to each segment.
    p = jnp.stack([keep_from_x, keep_from_y], -1)[None]  # (1, P, 2)
    a, b = segments[:, None, :2], segments[:, None, 2:]
    t = jnp.clip(jnp.sum((p - a) * (b - a), -1) / jnp.maximum(jnp.sum((b - a) ** 2, -1), 1e-9), 0, 1)
    dist = jnp.linalg.norm(a + t[..., None] * (b - a) - p, axis=-1)
    clear = jnp.all(jnp.where(jnp.isnan(dist), True, dist > clearance_m), axis=1)
    return segments, (jnp.arange(n_max) < n) & clear


def _as_drawn(x_m, y_m, heading_rad):
    """People as the input map shows them: at their cell's centre, heading one of 8 directions."""
    x_m, y_m = grid.snap_to_cell(x_m, y_m)
    return x_m, y_m, grid.quantise_heading(heading_rad)


def sample_proxemics(key):
    """One person among random walls."""
    k_p, k_h, k_w = jax.random.split(key, 3)
    x, y = jax.random.uniform(k_p, (2, 1), minval=-5.0, maxval=5.0)
    x, y, heading = _as_drawn(x, y, jax.random.uniform(k_h, (1,), minval=-jnp.pi, maxval=jnp.pi))
    segments, valid = _random_walls(k_w, 3, x, y, clearance_m=1.2)
    image = _walls_image(segments, valid)
    image = grid.draw_people(image, x, y, heading, jnp.ones(1, bool))
    return image, sc.people_cost(x, y, heading, jnp.ones(1, bool))


MAX_GROUP = 6


def group_layout(key):
    """(x, y, valid) of 2-6 people on a circle and its centre and radius."""
    k_n, k_c, k_r, k_arc, k_rot, k_j = jax.random.split(key, 6)
    n = jax.random.randint(k_n, (), 2, MAX_GROUP + 1)
    cx, cy = jax.random.uniform(k_c, (2,), minval=-4.0, maxval=4.0)
    radius = jax.random.uniform(k_r, (), minval=1.0, maxval=1.5)
    full = 2 * jnp.pi * (n - 1) / n  # arc of n evenly spread people on the whole circle
    arc = jax.random.uniform(k_arc, (), minval=0.5, maxval=1.0) * jnp.where(n == 2, jnp.pi, full)
    i = jnp.arange(MAX_GROUP)
    jitter = jax.random.uniform(k_j, (MAX_GROUP,), minval=-0.1, maxval=0.1)
    angle = jax.random.uniform(k_rot, (), minval=-jnp.pi, maxval=jnp.pi) + arc * (i / jnp.maximum(n - 1, 1) + jitter)
    valid = i < n
    return cx + radius * jnp.cos(angle), cy + radius * jnp.sin(angle), angle, valid, cx, cy, radius


def _sample_circle(key, inward: bool):
    x, y, angle, valid, cx, cy, radius = group_layout(key)
    x, y, heading = _as_drawn(x, y, angle + (jnp.pi if inward else 0.0))
    image = grid.draw_people(_blank(), x, y, heading, valid)
    cost = sc.people_cost(x, y, heading, valid)
    if inward:
        cost = jnp.maximum(cost, sc.disc_plateau(cx, cy, radius))
    return image, cost


sample_group = functools.partial(_sample_circle, inward=True)
sample_non_group = functools.partial(_sample_circle, inward=False)


def _rotate(x, y, angle):
    c, s = jnp.cos(angle), jnp.sin(angle)
    return x * c - y * s, x * s + y * c


def _local(angle, ox=0.0, oy=0.0):
    """Cell centres in a frame rotated by ``angle`` with origin (ox, oy) (world frame)."""
    return _rotate(grid.CELL_X_M - ox, grid.CELL_Y_M - oy, -angle)


MAX_WALKERS = 4


def _sample_hallway(key, kind: str):
    """A hallway through the robot (``straight``, ``l_shaped``, ``people``); travel towards the goal.

    Local frame: travel along +x through the origin (the robot). Straight: walls at y = +-h.
    L-shaped: the corridor turns left (or right, mirrored) at x = a: leg 1 is y in [-h, h] up to
    the outer wall x = a + h, leg 2 is x in [a - h, a + h] from there on; the inner corner
    (a - h, h) is a blind corner. Cost: the left half of the corridor relative to the travel
    direction (keep right), and for the L the blind corner's cost.
    """
    k_w, k_o, k_l, k_a, k_g, k_t, k_p = jax.random.split(key, 7)
    h = 0.5 * jax.random.uniform(k_w, (), minval=1.6, maxval=4.0)
    phi = jax.random.uniform(k_o, (), minval=-jnp.pi, maxval=jnp.pi)
    behind_m, ahead_m = jax.random.uniform(k_l, (2,), minval=3.0, maxval=12.0)  # wall extents
    back, front = -behind_m, ahead_m
    lx, ly = _local(phi)
    if kind == "l_shaped":
        a = jax.random.uniform(k_a, (), minval=1.5, maxval=5.0)
        side = jnp.where(jax.random.bernoulli(k_t), 1.0, -1.0)  # +1 turns left, -1 right
        ly = ly * side  # mirror a right turn onto a left one
        far = WALL_LENGTH_M
        local_segments = jnp.array(
            [
                [back, -h, a + h, -h],  # leg 1 outer wall, up to the outer corner
                [a + h, -h, a + h, far],  # outer wall of leg 2
                [back, h, a - h, h],  # leg 1 inner wall, up to the inner corner
                [a - h, h, a - h, far],
            ]
        )  # inner wall of leg 2
        in_leg1 = (lx <= a + h) & (jnp.abs(ly) < h) & (lx >= back)
        in_leg2 = (jnp.abs(lx - a) < h) & (ly >= -h)
        inside = in_leg1 | in_leg2
        # Left of the way (leg 1's centre line up to x = a, then leg 2's): the distance to that
        # path on its left, as a fraction of the half-width (continuous through the turn).
        left = jnp.where((lx < a) & (ly > 0), jnp.minimum(ly, a - lx) / h, 0.0)
        goal_l = jnp.stack([a, jax.random.uniform(k_g, (), minval=2.0, maxval=5.0)])
        corner_l = jnp.stack([a - h, h])
    else:
        local_segments = jnp.array([[back, -h, front, -h], [back, h, front, h]])
        inside = (jnp.abs(ly) < h) & (lx >= back) & (lx <= front)
        left = ly / h
        goal_l = jnp.stack([jnp.minimum(jax.random.uniform(k_g, (), minval=3.0, maxval=7.0), front - 0.5), 0.0])
        side = 1.0

    # Back to the world frame (undo the mirror first).
    def to_world(x, y):
        return _rotate(x, y * side, phi)

    sx0, sy0 = to_world(local_segments[:, 0], local_segments[:, 1])
    sx1, sy1 = to_world(local_segments[:, 2], local_segments[:, 3])
    segments = jnp.stack([sx0, sy0, sx1, sy1], -1)
    image = _walls_image(segments, jnp.ones(segments.shape[0], bool))
    gx, gy = to_world(goal_l[0], goal_l[1])
    cost = jnp.where(inside, sc.HALLWAY_LEFT_COST * sc.smoothstep(left), 0.0)
    if kind == "l_shaped":
        cx, cy = to_world(corner_l[0], corner_l[1])
        cost = jnp.maximum(cost, sc.corner_cost(cx, cy, inside))
    if kind == "people":
        k_n, k_x, k_y, k_d = jax.random.split(k_p, 4)
        n = jax.random.randint(k_n, (), 1, MAX_WALKERS + 1)
        px = jax.random.uniform(k_x, (MAX_WALKERS,), minval=-6.0, maxval=6.0)
        py = jax.random.uniform(k_y, (MAX_WALKERS,), minval=-0.6, maxval=0.6) * h
        heading_l = jnp.where(jax.random.bernoulli(k_d, shape=(MAX_WALKERS,)), 0.0, jnp.pi)
        valid = (jnp.arange(MAX_WALKERS) < n) & (px >= back) & (px <= front)
        wx, wy, heading = _as_drawn(*to_world(px, py), heading_l * side + phi)
        image = grid.draw_people(image, wx, wy, heading, valid)
        cost = jnp.maximum(cost, sc.people_cost(wx, wy, heading, valid))
    image = grid.draw_goal(image, gx, gy)
    cost = jnp.where(image == grid.WALL, 0.0, cost)
    return image, cost


sample_hallway_straight = functools.partial(_sample_hallway, kind="straight")
sample_hallway_l = functools.partial(_sample_hallway, kind="l_shaped")
sample_hallway_people = functools.partial(_sample_hallway, kind="people")

MAX_QUEUE = 16
QUEUE_BODY_M = 0.4  # the triangular 0.3-0.8 m "distance between individuals" is read as the gap


def queue_layout(key):
    """A queue facing +phi: head position, people behind it, (P,) valid mask, and the goal at the head."""
    k_h, k_o, k_len, k_gap, k_j = jax.random.split(key, 5)
    hx, hy = jax.random.uniform(k_h, (2,), minval=-3.0, maxval=3.0)
    phi = jax.random.uniform(k_o, (), minval=-jnp.pi, maxval=jnp.pi)
    length = jax.random.uniform(k_len, (), minval=3.0, maxval=10.0)
    gap = jax.random.triangular(k_gap, 0.3, 0.55, 0.8)
    spacing = QUEUE_BODY_M + gap
    i = jnp.arange(MAX_QUEUE)
    jitter = jax.random.uniform(k_j, (2, MAX_QUEUE), minval=-1.0, maxval=1.0)
    along = -(i * spacing + 0.15 * spacing * jitter[0] * (i > 0))
    lateral = 0.05 * jitter[1]
    valid = i * spacing <= length
    px, py = _rotate(along, lateral, phi)
    return hx + px, hy + py, phi, valid, hx, hy, spacing


def _sample_queue(key, at_head: bool):
    k_l, k_g, k_w = jax.random.split(key, 3)
    x, y, phi, valid, hx, hy, spacing = queue_layout(k_l)
    x, y, heading = _as_drawn(x, y, jnp.full(MAX_QUEUE, phi))
    tail = jnp.max(jnp.where(valid, jnp.arange(MAX_QUEUE), 0)) * spacing
    if at_head:
        gx, gy = hx + 0.8 * jnp.cos(phi), hy + 0.8 * jnp.sin(phi)
    else:
        # Elsewhere: a point on a circle 3-6 m from the queue's middle, not ahead of the head.
        r_ang = jax.random.uniform(k_g, (2,))
        ang = phi + jnp.pi / 2 + (r_ang[0] - 0.5) * jnp.pi  # to the side of the queue
        mid_x, mid_y = hx - 0.5 * tail * jnp.cos(phi), hy - 0.5 * tail * jnp.sin(phi)
        dist = 3.0 + 3.0 * r_ang[1]
        side = jnp.where(r_ang[1] > 0.5, 1.0, -1.0)
        gx, gy = mid_x + side * dist * jnp.cos(ang), mid_y + side * dist * jnp.sin(ang)
    keep_x = jnp.concatenate([jnp.where(valid, x, jnp.nan), gx[None]])
    keep_y = jnp.concatenate([jnp.where(valid, y, jnp.nan), gy[None]])
    segments, wvalid = _random_walls(k_w, 2, keep_x, keep_y, clearance_m=1.5)
    image = _walls_image(segments, wvalid)
    image = grid.draw_people(image, x, y, heading, valid)
    image = grid.draw_goal(image, gx, gy)
    cost = sc.people_cost(x, y, heading, valid)
    if at_head:
        lx, ly = _local(phi, hx, hy)  # +x ahead of the head, the queue along -x
        along = sc.soft_band(lx, -tail, 1.6, 1.0, edge_m=0.3)  # from the tail to the front bar
        sides = along * sc.soft_band(jnp.abs(ly), 0.6, 1.4, sc.QUEUE_U_COST)
        front = sc.soft_band(jnp.abs(ly), -1.0, 1.4, 1.0) * sc.soft_band(lx, 1.4, 2.2, sc.QUEUE_U_COST)
        cost = jnp.maximum(cost, jnp.maximum(sides, front))
    cost = jnp.where(image == grid.WALL, 0.0, cost)
    return image, cost


sample_queue = functools.partial(_sample_queue, at_head=True)
sample_non_queue = functools.partial(_sample_queue, at_head=False)

FAMILIES = {
    "corner": sample_corner,
    "proxemics": sample_proxemics,
    "group": sample_group,
    "non_group": sample_non_group,
    "hallway_straight": sample_hallway_straight,
    "hallway_l": sample_hallway_l,
    "hallway_people": sample_hallway_people,
    "queue": sample_queue,
    "non_queue": sample_non_queue,
}
