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

import jax
import jax.numpy as jnp

from socialnav.jaxsim import native
from socialnav.jaxsim.params import SimParams

_EPS = 1e-6


def fast_atan2(y: jax.Array, x: jax.Array) -> jax.Array:
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


def cos_sin_turns(u: jax.Array) -> tuple[jax.Array, jax.Array]:
    """``(cos 2 pi u, sin 2 pi u)`` by Taylor polynomials of degree 12 and 11 on a quarter turn
    (max error 6e-7 against ``jnp.cos`` / ``jnp.sin`` in float32; any ``u``, the turn is periodic).

    For the uniform draws of the random force's and the activity spot's angles. XLA's CPU ``cos``
    and ``sin`` of those angles were 39 % of the whole warehouse step once the social force ran
    in C++ (``benchmarks/profile_step.py``-style ablation, interleaved: 13.0 -> 20.3 M
    agent-steps/s), as its ``atan2`` had been of the social force; the test holds the bound.
    """
    t = u - jnp.round(u)  # the same angle, in [-1/2, 1/2] of a turn
    flip = jnp.abs(t) > 0.25  # beyond a quarter turn: mirror (same sine, cosine negated)
    t = jnp.where(flip, jnp.where(t > 0, 0.5, -0.5) - t, t)
    x = (2.0 * jnp.pi) * t
    x2 = x * x
    sin = x * (1.0 + x2 * (-1 / 6 + x2 * (1 / 120 + x2 * (-1 / 5040 + x2 * (1 / 362880 + x2 * (-1 / 39916800))))))
    cos = 1.0 + x2 * (
        -1 / 2 + x2 * (1 / 24 + x2 * (-1 / 720 + x2 * (1 / 40320 + x2 * (-1 / 3628800 + x2 * (1 / 479001600)))))
    )
    return jnp.where(flip, -cos, cos), sin


def desired_force(
    params: SimParams, dx_m: jax.Array, dy_m: jax.Array, vx: jax.Array, vy: jax.Array, speed_mps: jax.Array
) -> tuple[jax.Array, jax.Array]:
    """Relaxation towards ``speed_mps`` along ``(dx, dy)``: returns (ax, ay), shapes of ``vx``."""
    dist = jnp.sqrt(dx_m * dx_m + dy_m * dy_m) + _EPS
    inv_tau = 1.0 / params.worker_relaxation_time_s
    return ((speed_mps * dx_m / dist - vx) * inv_tau, (speed_mps * dy_m / dist - vy) * inv_tau)


def _moussaid_pair(params: SimParams, dx, dy, dvx, dvy):
    """Moussaid force on i from j, given ``dx, dy = p_j - p_i`` and ``dvx, dvy = v_i - v_j``.

    Antisymmetric: swapping i and j flips both differences, the interaction vector D and the
    unit vector e flip together, |D|, B and theta are unchanged, so F_ji = -F_ij.
    """
    # sqrt and a division: XLA's CPU rsqrt measured 5x slower than either here.
    dist = jnp.sqrt(jnp.maximum(dx * dx + dy * dy, _EPS * _EPS))
    inv = 1.0 / dist
    ex, ey = dx * inv, dy * inv
    ix = params.worker_social_lambda * dvx + ex
    iy = params.worker_social_lambda * dvy + ey
    ilen = jnp.sqrt(jnp.maximum(ix * ix + iy * iy, _EPS * _EPS))
    iinv = 1.0 / ilen
    ix, iy = ix * iinv, iy * iinv
    theta = fast_atan2(ix * ey - iy * ex, ix * ex + iy * ey)
    b = params.worker_social_gamma * ilen
    base = -dist * iinv * (1.0 / params.worker_social_gamma)  # -d / B
    nb_theta = b * theta
    f_vel = -jnp.exp(base - (params.worker_social_n_prime * nb_theta) ** 2)
    f_ang = -jnp.sign(theta) * jnp.exp(base - (params.worker_social_n * nb_theta) ** 2)
    return f_vel * ix - f_ang * iy, f_vel * iy + f_ang * ix


def pair_force(params: SimParams, dx, dy, dvx, dvy):
    """The Moussaid force on agents at offsets ``-(dx, dy)`` from one source (``dx, dy = p_src -
    p_i``, ``dvx, dvy = v_i - v_src``), before ``social_force_factor``: for a single extra agent
    such as the arena's robot."""
    return _moussaid_pair(params, dx, dy, dvx, dvy)


def social_force(
    params: SimParams, x: jax.Array, y: jax.Array, vx: jax.Array, vy: jax.Array, weight: jax.Array
) -> tuple[jax.Array, jax.Array]:
    """Moussaid interaction on every agent from every other one; ``vmap`` over worlds as usual.

    On the CPU this is the hand-written kernel of :mod:`jaxsim.native` when it builds (the
    worlds of a ``vmap`` become its vector lanes; the whole step 2.0-2.35x as fast in
    ``benchmarks/bench_simulator.py``); on a GPU, for float64, without a C++ compiler or with
    ``SOCIALNAV_NATIVE=off`` it is :func:`social_force_xla`. The two agree to float rounding
    (tested), not bit for bit: their sums run in other orders. Not differentiable on the
    kernel's path (nothing differentiates the simulator).

    Args:
      x, y, vx, vy: (A,) positions (m) and velocities (m/s) of all agents (workers and robot).
      weight: (A,) force factor of each agent as a source (0 for absent agents).

    Returns:
      (ax, ay): (A,) summed social acceleration (m/s^2), scaled by ``social_force_factor``.
    """
    # Not even built where JAX's default backend is a GPU (platform_dependent below also keeps a
    # program lowered for another platform off the CPU kernel).
    if x.dtype != jnp.float32 or jax.default_backend() != "cpu" or not native.social_force_available():
        return social_force_xla(params, x, y, vx, vy, weight)
    coefficients = jnp.stack(
        [
            jnp.asarray(params.worker_social_lambda, jnp.float32),
            jnp.asarray(params.worker_social_gamma, jnp.float32),
            jnp.asarray(params.worker_social_n_prime, jnp.float32),
            jnp.asarray(params.worker_social_n, jnp.float32),
            jnp.asarray(params.worker_social_force_factor, jnp.float32),
        ]
    )

    def on_cpu(coefficients, x, y, vx, vy, weight):
        out = jax.ShapeDtypeStruct(x.shape, x.dtype)
        call = jax.ffi.ffi_call(native.SOCIAL_FORCE_TARGET, (out, out), vmap_method="broadcast_all")
        return tuple(call(x, y, vx, vy, weight, coefficients))

    def elsewhere(coefficients, x, y, vx, vy, weight):
        return social_force_xla(params, x, y, vx, vy, weight)

    return jax.lax.platform_dependent(coefficients, x, y, vx, vy, weight, cpu=on_cpu, default=elsewhere)


def social_force_xla(
    params: SimParams, x: jax.Array, y: jax.Array, vx: jax.Array, vy: jax.Array, weight: jax.Array
) -> tuple[jax.Array, jax.Array]:
    """Moussaid interaction on every agent from every other one, each pair computed once, in JAX.

    Pairs ``(i, i + k mod A)`` for ``k = 1 .. A // 2`` cover every unordered pair once when
    ``A`` is odd (for even ``A`` the ``k = A / 2`` row holds each pair twice and is applied to
    its first agent only). The force on ``i`` is ``+w_{i+k} F`` and on ``i + k`` it is
    ``-w_i F`` (Newton's third law holds for this model, see :func:`_moussaid_pair`), put in
    place by a static roll. Half the exponentials of the full ``(A, A)`` matrix
    (:func:`social_force_dense`, kept as the reference); the same result to float rounding.

    Args:
      x, y, vx, vy: (A,) positions and velocities of all agents (workers and robot).
      weight: (A,) force factor of each agent as a source (0 for absent agents).

    Returns:
      (ax, ay): (A,) summed social acceleration, already scaled by ``social_force_factor``.
    """
    a = x.shape[0]
    half = a // 2
    if half == 0:
        return jnp.zeros_like(x), jnp.zeros_like(y)
    shifts = range(1, half + 1)
    both = jnp.stack([x, y, vx, vy, weight])
    both = jnp.concatenate([both, both], axis=1)  # element i + k of a roll is a static slice
    xj, yj, vxj, vyj, wj = jnp.stack([both[:, k : k + a] for k in shifts], axis=1)  # (5, half, A)
    fx, fy = _moussaid_pair(params, xj - x, yj - y, vx - vxj, vy - vyj)  # (half, A): on i from i+k
    ax = jnp.sum(wj * fx, axis=0)
    ay = jnp.sum(wj * fy, axis=0)
    rx, ry = weight * fx, weight * fy  # reaction on i + k, still indexed by i
    for row, k in enumerate(shifts):
        if 2 * k == a:  # this row lists each pair twice: the action alone covers both agents
            continue
        ax = ax - jnp.roll(rx[row], k)
        ay = ay - jnp.roll(ry[row], k)
    scale = params.worker_social_force_factor
    return scale * ax, scale * ay


def social_force_dense(
    params: SimParams, x: jax.Array, y: jax.Array, vx: jax.Array, vy: jax.Array, weight: jax.Array
) -> tuple[jax.Array, jax.Array]:
    """Reference for :func:`social_force_xla`: the full ``(A, A)`` matrix of pair forces.

    Args:
      x, y, vx, vy: (A,) positions and velocities of all agents (workers and robot).
      weight: (A,) force factor of each agent as a source (0 for absent agents).

    Returns:
      (ax, ay): (A,) summed social acceleration, already scaled by ``social_force_factor``.
    """
    fx, fy = _moussaid_pair(
        params, x[None, :] - x[:, None], y[None, :] - y[:, None], vx[:, None] - vx[None, :], vy[:, None] - vy[None, :]
    )  # (i, j): on i from j
    w = weight[None, :] * (1.0 - jnp.eye(x.shape[0], dtype=x.dtype)) * params.worker_social_force_factor
    return jnp.sum(w * fx, axis=1), jnp.sum(w * fy, axis=1)


def obstacle_force(
    params: SimParams, wall_dist_m: jax.Array, normal_x: jax.Array, normal_y: jax.Array
) -> tuple[jax.Array, jax.Array]:
    """pedsim's wall repulsion from the nearest wall point: returns (ax, ay)."""
    amount = params.worker_obstacle_force_factor * jnp.exp(
        -(wall_dist_m - params.worker_radius_m) / params.worker_obstacle_sigma_m
    )
    return amount * normal_x, amount * normal_y


def random_force(params: SimParams, u1: jax.Array, u2: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Gaussian random force from two uniform draws in (0, 1] (Box-Muller): returns (ax, ay)."""
    r = params.worker_random_force_std_mps2 * jnp.sqrt(-2.0 * jnp.log(jnp.maximum(u1, 1e-12)))
    cos, sin = cos_sin_turns(u2)  # of the angle 2 pi u2
    return r * cos, r * sin
