"""pedsim's social force model (Helbing & Molnar 1995 with the Moussaid et al. 2009 interaction).

All functions are pure and take separate x / y arrays (measured 10x faster than (N, 2) arrays).
The acceleration of walker i is

  a_i = (v0_i e_i - v_i) / tau                        desired force (relaxation)
      + f_soc * sum_j w_j F_Moussaid(i, j)             social force
      + f_obs * exp(-(d_wall - r) / sigma) n_wall      obstacle force (nearest wall only)
      + xi,  xi ~ N(0, sigma_rand^2 I)                 small random force

with pedsim's Moussaid term: ``D = lambda (v_i - v_j) + e_ij``, ``B = gamma |D|``, ``theta`` the
signed angle from ``D`` to ``e_ij``, and
``F = -exp(-d/B - (n' B theta)^2) D/|D| - sign(theta) exp(-d/B - (n B theta)^2) left(D/|D|)``.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxsim.params import SimParams

_EPS = 1e-6


def fast_atan2(y, x):
    """``arctan2`` by a 7th-order minimax polynomial (max error 2e-4 rad).

    XLA's CPU ``atan2`` was three quarters of the social force's time; this is 4x faster
    (``benchmarks/bench_simulator.py`` and the test against ``jnp.arctan2``).
    """
    ax, ay = jnp.abs(x), jnp.abs(y)
    a = jnp.minimum(ax, ay) / jnp.maximum(jnp.maximum(ax, ay), 1e-30)
    s = a * a
    r = ((-0.0464964749 * s + 0.15931422) * s - 0.327622764) * s * a + a
    r = jnp.where(ay > ax, 1.57079637 - r, r)
    r = jnp.where(x < 0, 3.14159274 - r, r)
    return jnp.where(y < 0, -r, r)


def desired_force(params: SimParams, dx_m, dy_m, vx, vy, speed_mps):
    """Relaxation towards ``speed_mps`` along ``(dx, dy)``: returns (ax, ay), shapes of ``vx``."""
    dist = jnp.sqrt(dx_m * dx_m + dy_m * dy_m) + _EPS
    inv_tau = 1.0 / params.worker_relaxation_time_s
    return ((speed_mps * dx_m / dist - vx) * inv_tau, (speed_mps * dy_m / dist - vy) * inv_tau)


def social_force(params: SimParams, x, y, vx, vy, weight):
    """Moussaid interaction on every agent from every other one.

    Args:
      x, y, vx, vy: (A,) positions and velocities of all agents (workers and robot).
      weight: (A,) force factor of each agent as a source (0 for absent agents).

    Returns:
      (ax, ay): (A,) summed social acceleration, already scaled by ``social_force_factor``.
    """
    dx = x[None, :] - x[:, None]  # (i, j): from i to j
    dy = y[None, :] - y[:, None]
    dist = jnp.sqrt(dx * dx + dy * dy)
    inv = 1.0 / jnp.maximum(dist, _EPS)
    ex, ey = dx * inv, dy * inv
    ix = params.worker_social_lambda * (vx[:, None] - vx[None, :]) + ex
    iy = params.worker_social_lambda * (vy[:, None] - vy[None, :]) + ey
    ilen = jnp.sqrt(ix * ix + iy * iy)
    iinv = 1.0 / jnp.maximum(ilen, _EPS)
    ix, iy = ix * iinv, iy * iinv
    theta = fast_atan2(ix * ey - iy * ex, ix * ex + iy * ey)
    b = params.worker_social_gamma * ilen
    base = -dist / jnp.maximum(b, _EPS)
    nb_theta = b * theta
    f_vel = -jnp.exp(base - (params.worker_social_n_prime * nb_theta) ** 2)
    f_ang = -jnp.sign(theta) * jnp.exp(base - (params.worker_social_n * nb_theta) ** 2)
    n = x.shape[0]
    w = weight[None, :] * (1.0 - jnp.eye(n, dtype=x.dtype)) * params.worker_social_force_factor
    ax = jnp.sum(w * (f_vel * ix - f_ang * iy), axis=1)
    ay = jnp.sum(w * (f_vel * iy + f_ang * ix), axis=1)
    return ax, ay


def obstacle_force(params: SimParams, wall_dist_m, normal_x, normal_y):
    """pedsim's wall repulsion from the nearest wall point: returns (ax, ay)."""
    amount = params.worker_obstacle_force_factor * jnp.exp(
        -(wall_dist_m - params.worker_radius_m) / params.worker_obstacle_sigma_m)
    return amount * normal_x, amount * normal_y


def random_force(params: SimParams, u1, u2):
    """Gaussian random force from two uniform draws in (0, 1] (Box-Muller): returns (ax, ay)."""
    r = params.worker_random_force_std_mps2 * jnp.sqrt(-2.0 * jnp.log(jnp.maximum(u1, 1e-12)))
    angle = 2.0 * jnp.pi * u2
    return r * jnp.cos(angle), r * jnp.sin(angle)
