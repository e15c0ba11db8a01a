"""Pytree helpers shared by the simulator, the protocols and the learners."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np


def select(cond: jax.Array, a, b):
    """``a`` where ``cond`` else ``b``, leaf by leaf (a pytree ``jnp.where``)."""
    return jax.tree.map(lambda x, y: jnp.where(cond, x, y), a, b)


def select_rows(mask: jax.Array, a, b):
    """``a`` where ``mask`` else ``b``, leaf by leaf, ``mask`` (B,) choosing along every leaf's
    leading batch axis (B, ...)."""
    return jax.tree.map(lambda x, y: jnp.where(mask.reshape((-1,) + (1,) * (x.ndim - 1)), x, y), a, b)


def to_numpy(tree, copy: bool = True):
    """Bring a pytree of device arrays to host numpy arrays (one transfer); ``copy=True`` makes
    every leaf a writable copy, ``copy=False`` may return read-only views."""
    return jax.tree.map(np.array if copy else np.asarray, jax.device_get(tree))


def take(tree, index):
    """``x[index]`` for every leaf (host or device arrays)."""
    return jax.tree.map(lambda x: x[index], tree)


def put(dst, index, src) -> None:
    """``dst[index] = src`` leaf by leaf, in place (host numpy pytrees of the same structure)."""
    for d, v in zip(jax.tree.leaves(dst), jax.tree.leaves(src), strict=True):
        d[index] = v


def stack(trees):
    """Stack a sequence of pytrees of the same structure along a new leading axis."""
    return jax.tree.map(lambda *xs: jnp.stack([jnp.asarray(x) for x in xs]), *trees)
