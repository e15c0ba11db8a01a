"""SNAPE's social map (seed 004, Sec. 3.2, Eq. 3-4), in JAX.

Each person carries an asymmetric Gaussian, longer in front (Eq. 3: a 2-D Gaussian turned to the
person's orientation; its ``k_xy`` term is what the turn produces), summed over people (Eq. 4).
Its contour lines bound the proxemic zones: the intimate zone is inaccessible (lethal), the
personal and social zones weighted, personal dearer than social; objects add their interaction
spaces (polygons with a cost, seed 004 Fig. 4: a table, a fridge).

Choices (the paper fixes the form, not these numbers; all are parameters of :class:`SNAPEParams`):

* **Variances**: front 2, sides 4/3 (seed 004 Fig. 4's ``sigma_x = 2``, ``sigma_y = 4/3``), rear 1:
  Kirby's form, front longest, rear shortest. The two published Kirby ratio sets differ
  (SocNavBench: sides 1/4, rear 1/3 of the front; SRPB: sides 2/3, rear 1/2 in variance): Fig. 4's
  sides are 2/3 of the front, as SRPB's, and the rear is taken between SRPB's and the sides'. The
  paper makes them depend on orientation only, not speed.
* **Zones**: the contour of ``G`` (Eq. 4) at the level one person's Gaussian has at Hall's distance
  on its side axis: the intimate zone is ``G >= exp(-0.45^2 / (2 sigma_side^2))``, personal 1.2 m,
  social 3.6 m. For one person a zone reaches Hall's distance at the sides, 1.5 x it in front,
  0.75 x behind; where people stand close, their zones merge (Eq. 4's sum), as seed 004 Fig. 5b
  shows for two interacting people.
* **Weights** (Nav2 scale, added to the base weight 1 by the weighted-grid planner): intimate
  lethal (the paper's "occupied"; Fig. 4's 100 is moot once inaccessible), personal 50 (the paper:
  between social and intimate), social 10 (Fig. 4), public 0. Fig. 4's caption gives the public
  space 8 while Sec. 3.2's text leaves it "unaltered"; Hall's public zone reaches 7.6 m, so 8 would
  cover a whole flat: we follow the text, ``public_cost`` takes Fig. 4's 8.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct

from socialnav.planners.layers.costmap import LETHAL
from socialnav.planners.layers.scene import Scene, objects_layer


@struct.dataclass
class SNAPEParams:
    """The social map's numbers: standard deviations in m, zone distances in m (Hall), costs on
    Nav2's scale."""

    sigma_front_m: float = 2.0
    sigma_side_m: float = 4.0 / 3.0
    sigma_rear_m: float = 1.0
    intimate_m: float = 0.45
    personal_m: float = 1.2
    social_m: float = 3.6
    public_m: float = 7.6
    personal_cost: float = 50.0
    social_cost: float = 10.0
    public_cost: float = 0.0


def person_gaussian(x_m, y_m, xy, heading_rad, params: SNAPEParams = SNAPEParams()):
    """(H, W) one person's asymmetric Gaussian (Eq. 3), peak 1 at the person."""
    dx, dy = x_m - xy[0], y_m - xy[1]
    c, s = jnp.cos(heading_rad), jnp.sin(heading_rad)
    along = c * dx + s * dy
    across = -s * dx + c * dy
    sigma_along = jnp.where(along >= 0, params.sigma_front_m, params.sigma_rear_m)
    return jnp.exp(-(along**2 / (2 * sigma_along**2) + across**2 / (2 * params.sigma_side_m**2)))


def interaction_space(scene: Scene, x_m, y_m, params: SNAPEParams = SNAPEParams()):
    """(H, W) ``G`` of Eq. 4: the sum of every valid person's Gaussian."""
    each = jax.vmap(lambda xy, h: person_gaussian(x_m, y_m, xy, h, params))(scene.people_xy_m, scene.people_heading_rad)
    return jnp.sum(jnp.where(scene.people_valid[:, None, None], each, 0.0), axis=0)


def zone_level(distance_m, params: SNAPEParams = SNAPEParams()):
    """The contour level of ``G`` that bounds the zone reaching ``distance_m`` at a person's side."""
    return jnp.exp(-(distance_m**2) / (2 * params.sigma_side_m**2))


def snape_layer(scene: Scene, x_m, y_m, params: SNAPEParams = SNAPEParams()):
    """SNAPE's social map at cell centres ``x_m, y_m`` (H, W): (H, W) float32 on Nav2's scale,
    lethal in intimate zones, the zone weights elsewhere, objects' interaction spaces by max."""
    g = interaction_space(scene, x_m, y_m, params)
    cost = jnp.where(g >= zone_level(params.public_m, params), params.public_cost, 0.0)
    cost = jnp.where(g >= zone_level(params.social_m, params), params.social_cost, cost)
    cost = jnp.where(g >= zone_level(params.personal_m, params), params.personal_cost, cost)
    cost = jnp.where(g >= zone_level(params.intimate_m, params), LETHAL, cost)
    return jnp.maximum(cost, objects_layer(scene, x_m, y_m)).astype(jnp.float32)
