"""Elastic bands: the classic one (Quinlan & Khatib 1993) and SNAPE's social one (seed 004 Sec. 4,
Eq. 6-12), with SNAPE's speed gain (Eq. 5). Pure JAX, fixed shapes.

The band is ``n_points`` points from the robot to the global path's point ``horizon_m`` ahead.
Each relaxation moves every inner point by ``step_m_per_unit x (k_c f_c + k_f f_r + k_s f_s)``
(Eq. 12): contraction ``f_c`` (Eq. 7), repulsion ``f_r = (D0 - D) dD/dp`` within ``D0`` of an
obstacle (Eq. 8-9, ``D`` the clearance to walls and people, its gradient by central differences),
social ``f_s = sum_i (L0 - L_i) dL_i/dp`` within ``L0`` of a person's interaction space (Eq.
10-11, people predicted ``predict_s`` ahead). The classic band is ``k_s = 0``, computed without
the social term (:func:`relax`'s ``social=False``).

Choices the paper leaves open (all parameters of :class:`BandParams`):

* Units: the paper's forces "are not in conventional force units"; with its gains (k_c 10, k_f 2,
  k_s 10, D0 1 m, L0 2 m) a point moves ``step_m_per_unit`` = 0.01 m per unit of force, at most
  ``max_step_m`` = 0.1 m per relaxation, 10 relaxations per control step.
* Signs: Eq. 8 and 10 as printed difference ``D(p - delta) - D(p + delta)``, minus the gradient,
  which would pull the band into obstacles; the forces here push away, as in Quinlan & Khatib.
* A point is not moved where its clearance would fall below ``min_clearance_m`` (the robot's
  body, 0.3 m) and shrink: the classic band's collision-free bubbles; the social force alone
  (k_s 10 against k_f 2) would otherwise push a band through a wall, as seed 004 Fig. 10 shows
  for a large ``k_s``.
* External forces act across the band only (their component along it is removed, as in the
  classic band), so they bend it without bunching its points.
* Eq. 6 inserts or merges points to keep them half a robot length apart; with a fixed number of
  points the band is instead resampled evenly along its length after every relaxation.
* ``L_i``: the distance from p to person i's intimate zone of SNAPE's asymmetric Gaussian
  (:mod:`planners.layers.snape_layer`), measured in side-equivalent metres (``sigma_side sqrt(-2 ln g_i)``
  minus the intimate radius), so it is longer in front of a person than behind.
* Eq. 5 as printed (``2 / (1 + exp((d_h - d_p)^lambda / d_p^lambda)) - 1`` with lambda 0.001) is
  about -0.46 at every distance (x^0.001 is about 1); we read lambda as a slope per millimetre (the
  paper's units): ``kappa = 2 / (1 + exp(-lambda d)) - 1`` with ``d`` in mm, the distance
  between the nearest person's position predicted 2 s ahead and the band's point 2 s ahead:
  0 when they meet, 0.46 at 1 m, 0.76 at 2 m, 1 far away.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct

from socialnav.jaxsim.params import PERSON_RADIUS_M
from socialnav.planners.layers.snape_layer import SNAPEParams, person_gaussian


@struct.dataclass
class BandParams:
    """Gains (seed 004 Table 1), thresholds in m, and this project's numerical choices."""

    k_c: float = 10.0
    k_f: float = 2.0
    k_s: float = 10.0
    d0_m: float = 1.0
    l0_m: float = 2.0
    step_m_per_unit: float = 0.01
    max_step_m: float = 0.1
    delta_m: float = 0.05
    predict_s: float = 2.0
    person_radius_m: float = PERSON_RADIUS_M
    speed_gain_lambda_per_mm: float = 0.001
    min_clearance_m: float = 0.3


def band_from_path(path_xy, path_len, robot_xy, horizon_m: float, n_points: int):
    """(n_points, 2) points evenly spaced along the path from the robot to ``horizon_m`` ahead
    (or the path's end). path_xy: (L, 2) with ``path_len`` valid points."""
    index = jnp.arange(path_xy.shape[0])
    valid = index < path_len
    pts = jnp.where(valid[:, None], path_xy, path_xy[jnp.maximum(path_len - 1, 0)])
    # From the path point nearest the robot on (a path planned once falls behind the robot).
    nearest = jnp.argmin(jnp.where(valid, jnp.linalg.norm(path_xy - robot_xy, axis=-1), jnp.inf))
    pts = jnp.where((index <= nearest)[:, None], robot_xy, pts)
    seg = jnp.linalg.norm(jnp.diff(pts, axis=0), axis=-1)
    s = jnp.concatenate([jnp.zeros(1), jnp.cumsum(seg)])
    end = jnp.minimum(s[-1], horizon_m)
    return _interpolate(pts, s, jnp.linspace(0.0, 1.0, n_points) * end)


def _interpolate(pts, s, targets):
    """Points at arc lengths ``targets`` along the polyline ``pts`` with arc lengths ``s``."""
    k = jnp.clip(jnp.searchsorted(s, targets, side="right", method="compare_all") - 1, 0, pts.shape[0] - 2)
    span = jnp.maximum(s[k + 1] - s[k], 1e-9)
    t = jnp.clip((targets - s[k]) / span, 0.0, 1.0)[:, None]
    return pts[k] + t * (pts[k + 1] - pts[k])


def resample(band):
    """The band's points moved to even spacing along it (endpoints kept)."""
    seg = jnp.linalg.norm(jnp.diff(band, axis=0), axis=-1)
    s = jnp.concatenate([jnp.zeros(1), jnp.cumsum(seg)])
    return _interpolate(band, s, jnp.linspace(0.0, 1.0, band.shape[0]) * s[-1])


def _gradient(fn, p, delta):
    """Central differences of a scalar field ``fn`` at points p (N, 2): (..., N, 2) where ``fn``
    gives (..., N) (one field per leading index: the social term's people at once)."""
    dx = jnp.array([delta, 0.0])
    dy = jnp.array([0.0, delta])
    gx = (fn(p + dx) - fn(p - dx)) / (2 * delta)
    gy = (fn(p + dy) - fn(p - dy)) / (2 * delta)
    return jnp.stack([gx, gy], axis=-1)


def _value_and_gradient(fn, p, delta):
    """``fn`` at p (N, 2) and :func:`_gradient` there, from one call of ``fn`` on the five point
    sets (p, p +- delta x, p +- delta y) stacked (5N, 2): the same values as five calls. ``fn``
    gives (..., M) for (M, 2) points; returns (..., N) and (..., N, 2). Used for the social term
    (a vmap over people, cheaper at once over 5N points); the clearance keeps its five calls, as
    XLA fuses its per-person loop worse over the stacked points."""
    dx = jnp.array([delta, 0.0])
    dy = jnp.array([0.0, delta])
    at, x_plus, x_minus, y_plus, y_minus = jnp.split(fn(jnp.concatenate([p, p + dx, p - dx, p + dy, p - dy])), 5, -1)
    gx = (x_plus - x_minus) / (2 * delta)
    gy = (y_plus - y_minus) / (2 * delta)
    return at, jnp.stack([gx, gy], axis=-1)


def relax(
    band,
    clearance_fn,
    people_xy,
    people_heading,
    people_valid,
    p: BandParams,
    snape: SNAPEParams,
    iterations: int,
    social: bool = True,
):
    """``iterations`` relaxation steps of Eq. 12 on a band (N, 2); returns the band.

    Args:
      clearance_fn: (N, 2) -> (N,) distance to the nearest obstacle (walls and people), ``D``.
      people_xy, people_heading, people_valid: (P,) people as predicted for the social force.
      social: static; ``False`` is the classic band (Eq. 12 without ``k_s f_s``, whatever
        ``p.k_s``): the social term is not computed at all, where ``k_s = 0`` would compute it and
        multiply it by zero. The same band as ``k_s = 0`` (bit for bit in one call; inside a
        larger program XLA may fuse the shorter sum differently, a float rounding apart).
    """

    def social_distance(q):
        g = jax.vmap(lambda xy, h: person_gaussian(q[:, 0], q[:, 1], xy, h, snape))(people_xy, people_heading)
        d_eff = snape.sigma_side_m * jnp.sqrt(-2.0 * jnp.log(jnp.clip(g, 1e-30, 1.0)))
        return jnp.where(people_valid[:, None], d_eff - snape.intimate_m, jnp.inf)  # (P, N)

    def one(b, _):
        prev, cur, nxt = b[:-2], b[1:-1], b[2:]

        def unit(v):
            return v / jnp.maximum(jnp.linalg.norm(v, axis=-1, keepdims=True), 1e-9)

        f_c = unit(prev - cur) + unit(nxt - cur)
        d = clearance_fn(cur)
        f_r = jnp.where((d < p.d0_m)[:, None], (p.d0_m - d)[:, None] * _gradient(clearance_fn, cur, p.delta_m), 0.0)
        f_s = jnp.zeros_like(f_r)  # the classic band: Eq. 12's sum with a zero social term
        if social:
            l_i, grad_l = _value_and_gradient(social_distance, cur, p.delta_m)  # (P, N), (P, N, 2)
            grad_l = jnp.where(jnp.isfinite(grad_l), grad_l, 0.0)
            f_s = jnp.sum(jnp.where((l_i < p.l0_m)[..., None], (p.l0_m - l_i)[..., None] * grad_l, 0.0), axis=0)
        external = p.k_f * f_r + p.k_s * f_s
        tangent = unit(nxt - prev)
        external = external - jnp.sum(external * tangent, axis=-1, keepdims=True) * tangent
        move = p.step_m_per_unit * (p.k_c * f_c + external)
        norm = jnp.linalg.norm(move, axis=-1, keepdims=True)
        move = move * jnp.minimum(1.0, p.max_step_m / jnp.maximum(norm, 1e-9))
        # A band stays collision-free (Quinlan & Khatib's bubbles): a point is not moved to where
        # its clearance would fall below the robot's body.
        moved = cur + move
        keep = (clearance_fn(moved) < p.min_clearance_m) & (clearance_fn(moved) < d)
        b = b.at[1:-1].set(jnp.where(keep[:, None], cur, moved))
        return resample(b), None

    band, _ = jax.lax.scan(one, band, None, length=iterations)
    return band


def speed_gain(band, robot_speed_mps, people_xy, people_velocity, people_valid, p: BandParams):
    """SNAPE's speed gain (Eq. 5 as read in the module docstring): in [0, 1)."""
    seg = jnp.linalg.norm(jnp.diff(band, axis=0), axis=-1)
    s = jnp.concatenate([jnp.zeros(1), jnp.cumsum(seg)])
    ahead = _interpolate(band, s, jnp.minimum(robot_speed_mps * p.predict_s, s[-1])[None])[0]
    predicted = people_xy + p.predict_s * people_velocity
    d = jnp.min(jnp.where(people_valid, jnp.linalg.norm(predicted - ahead, axis=-1), jnp.inf))
    return 2.0 / (1.0 + jnp.exp(-p.speed_gain_lambda_per_mm * 1000.0 * d)) - 1.0
