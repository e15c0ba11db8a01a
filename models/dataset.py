"""GSCL's procedural dataset (seed 002 Sec. 4.1): (input map, target cost map) pairs, 40 x 40.

Each family is a pure function ``key -> (input uint8 (40, 40), target float32 (40, 40))``;
:func:`generate` vmaps each over keys folded from one seed, so a dataset is deterministic by
seed and fast enough to make fresh rather than read from disk. Inputs use the paper's pixel
codes (:mod:`models.grid`); targets are costs in [0, 1] (x 255 for the paper's 0-255 images)
built from :mod:`models.social_costs`.

Families so far (the rest of Sec. 4.1 - hallways and queues - is still to come):

* ``corner`` (2000): two walls meeting at a random point with a random orientation, the wall
  block's angle in [60, 120] degrees; cost around the corner on the free (reflex) side. The
  robot (image centre) is always on the free side.
* ``proxemics`` (1000): one person, standing (half) or walking at 0.5-1.5 m/s, with up to three
  random walls kept 1.2 m from them; proxemic + passing cost.
* ``group`` (4500) / ``non_group`` (4500): 2-6 standing people on a circle of radius 1-1.5 m,
  spread over an arc from half to all of the circle (from L-shaped and face-to-face pairs to
  circles, covering the F-formations), facing the centre (group: proxemics + the interaction
  zone) or facing out (non-group: proxemics only).
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np

from models import grid
from models import social_costs as sc

# Paper's sample counts per family (Sec. 4.1).
PAPER_COUNTS = {"corner": 2000, "proxemics": 1000, "group": 4500, "non_group": 4500}
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


def sample_proxemics(key):
    """One person (standing or walking) among random walls."""
    k_p, k_h, k_m, k_v, k_w = jax.random.split(key, 5)
    x, y = jax.random.uniform(k_p, (2,), minval=-5.0, maxval=5.0)
    heading = jax.random.uniform(k_h, (), minval=-jnp.pi, maxval=jnp.pi)
    walking = jax.random.bernoulli(k_m)
    speed = jnp.where(walking, jax.random.uniform(k_v, (), minval=0.5, maxval=1.5), 0.0)
    segments, valid = _random_walls(k_w, 3, x[None], y[None], clearance_m=1.2)
    image = _walls_image(segments, valid)
    image = grid.draw_people(image, x[None], y[None], heading[None], jnp.ones(1, bool))
    return image, sc.proxemic_cost(x, y, heading, speed)


MAX_GROUP = 6


def _group_layout(key):
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
    x, y, angle, valid, cx, cy, radius = _group_layout(key)
    heading = angle + (jnp.pi if inward else 0.0)
    image = grid.draw_people(_blank(), x, y, heading, valid)
    cost = sc.people_cost(x, y, heading, jnp.zeros_like(x), valid)
    if inward:
        cost = jnp.maximum(cost, sc.disc_plateau(cx, cy, radius))
    return image, cost


sample_group = functools.partial(_sample_circle, inward=True)
sample_non_group = functools.partial(_sample_circle, inward=False)

FAMILIES = {"corner": sample_corner, "proxemics": sample_proxemics, "group": sample_group,
            "non_group": sample_non_group}


@functools.lru_cache(maxsize=None)
def _batched(name: str):
    return jax.jit(jax.vmap(FAMILIES[name]))


def family_keys(seed: int, family: str, n: int) -> jax.Array:
    """(n,) keys of a family: sample ``i`` of a family is the same whatever the other counts."""
    base = jax.random.fold_in(jax.random.key(seed), list(FAMILIES).index(family))
    return jax.vmap(lambda i: jax.random.fold_in(base, i))(jnp.arange(n))


def generate(seed: int, counts: dict[str, int] | None = None) -> dict[str, np.ndarray]:
    """A dataset: ``inputs`` (N, 40, 40) uint8, ``targets`` (N, 40, 40) float32 in [0, 1],
    ``family`` (N,) int8 index into ``names`` (the family names, in order).

    Args:
      counts: samples per family (default :data:`PAPER_COUNTS`); unknown names raise ValueError.
    """
    counts = dict(PAPER_COUNTS if counts is None else counts)
    unknown = sorted(set(counts) - set(FAMILIES))
    if unknown:
        raise ValueError(f"unknown families {unknown}; known: {list(FAMILIES)}")
    if any(n < 0 for n in counts.values()):
        raise ValueError(f"counts must be >= 0, got {counts}")
    names = [f for f in FAMILIES if counts.get(f, 0) > 0]
    inputs, targets, family = [], [], []
    for idx, name in enumerate(names):
        x, y = _batched(name)(family_keys(seed, name, counts[name]))
        inputs.append(np.asarray(x))
        targets.append(np.asarray(y, np.float32))
        family.append(np.full(counts[name], idx, np.int8))
    if not names:
        empty = np.zeros((0, grid.GRID, grid.GRID))
        return {"inputs": empty.astype(np.uint8), "targets": empty.astype(np.float32),
                "family": np.zeros(0, np.int8), "names": np.asarray([], str)}
    return {"inputs": np.concatenate(inputs), "targets": np.concatenate(targets),
            "family": np.concatenate(family), "names": np.asarray(names)}
