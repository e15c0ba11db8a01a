"""Counter-based random numbers: a world's draws are a hash of (world seed, step, stream, agent).

Like ``fold_in``, the draws of world ``b`` at step ``t`` do not depend on how time or worlds are
chunked, so the same seed gives the same logs bit for bit. About ten integer operations per
32-bit word against threefry's hundred (threefry was 40 % of a step). Statistical quality is
ample for noise and discrete choices (``tests/test_physics.py`` checks moments and independence
of neighbours); not for cryptography.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

# Rows of a step's draws: workers use all six (destination, duration, spot radius, spot angle,
# two for the random force); the robot's controller uses the first three of its own column.
STEP_ROWS = 6
ROBOT_ROWS = 3


def _fmix32(h: jax.Array) -> jax.Array:
    """murmur3's 32-bit finaliser: a bijective avalanche mix of uint32 words."""
    h = h ^ (h >> 16)
    h = h * jnp.uint32(0x85EBCA6B)
    h = h ^ (h >> 13)
    h = h * jnp.uint32(0xC2B2AE35)
    return h ^ (h >> 16)


def hash_uniform16(seed_u32: jax.Array, step: jax.Array, shape: tuple[int, int]) -> jax.Array:
    """Uniform draws in (0, 1), 16-bit resolution, two per 32-bit hash.

    ``u[r, i] = fmix32(fmix32(seed ^ step * K1) ^ (r * A + i) * K2)``.

    Args:
      seed_u32: () uint32 world seed.
      step: () int32 step counter (or any counter: a task index for per-task streams).
      shape: (R, A) draws wanted.

    Returns:
      (R, A) float32.
    """
    rows, cols = shape
    half = (rows + 1) // 2
    base = _fmix32(seed_u32 ^ (step.astype(jnp.uint32) * jnp.uint32(0x9E3779B9)))
    counter = jnp.arange(half * cols, dtype=jnp.uint32).reshape(half, cols)
    bits = _fmix32(base ^ (counter * jnp.uint32(0x632BE5AB) + jnp.uint32(0x7F4A7C15)))
    words = jnp.concatenate([bits >> 16, bits & 0xFFFF])[:rows]
    return (words.astype(jnp.float32) + 0.5) * (1.0 / 65536.0)


def world_seed_u32(key: jax.Array) -> jax.Array:
    """A uint32 seed from a JAX key (for :func:`hash_uniform16`)."""
    return jax.random.bits(key, (), jnp.uint32)


def step_uniforms(seed_u32: jax.Array, step: jax.Array, n_workers: int) -> tuple[jax.Array, jax.Array]:
    """The draws of one step: ``(workers (6, N), robot (3,))``.

    Every caller of the crowd step (the day simulation, the protocols) takes its draws from
    here, so the same seed gives the same crowd whoever drives the robot.
    """
    u = hash_uniform16(seed_u32, step, (STEP_ROWS, n_workers + 1))
    return u[:, :n_workers], u[:ROBOT_ROWS, n_workers]
