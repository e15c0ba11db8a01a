"""Typed specs of what the environment takes and gives, in the dm_env and jumanji style.

:meth:`jaxsim.scenes.env.Env.observation_spec` is an :class:`~jaxsim.scenes.env.Observation`
whose fields are :class:`Array` specs (the same pytree structure as an observation, so
``jax.tree.map`` walks the two together) and :meth:`~jaxsim.scenes.env.Env.action_spec` a
:class:`BoundedArray`. A spec says a value's shape and dtype, makes a value of them
(:meth:`Array.zeros`, :meth:`Array.shape_dtype` for ``jax.eval_shape``) and checks one with a
message naming the field (:meth:`Array.problem`).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np


@dataclasses.dataclass(frozen=True)
class Array:
    """An array of a fixed ``shape`` and ``dtype``, called ``name`` in messages."""

    shape: tuple[int, ...]
    dtype: Any
    name: str = ""

    def zeros(self) -> jax.Array:
        """A value of the spec, all zeros (False for a bool)."""
        return jnp.zeros(self.shape, self.dtype)

    def shape_dtype(self) -> jax.ShapeDtypeStruct:
        """The spec as ``jax.ShapeDtypeStruct`` (for ``jax.eval_shape``: traces, runs nothing)."""
        return jax.ShapeDtypeStruct(self.shape, self.dtype)

    def problem(self, value) -> str | None:
        """What is wrong with ``value`` for this spec (its shape, its dtype's kind), or None."""
        shape, dtype = tuple(np.shape(value)), jnp.result_type(value)
        if shape != tuple(self.shape):
            return f"{self.name or 'value'}: shape {shape}, expected {tuple(self.shape)}"
        if jnp.issubdtype(dtype, jnp.bool_) != jnp.issubdtype(self.dtype, jnp.bool_) or (
            jnp.issubdtype(self.dtype, jnp.floating) and not jnp.issubdtype(dtype, jnp.number)
        ):
            return f"{self.name or 'value'}: dtype {dtype}, expected {jnp.dtype(self.dtype)}"
        return None


@dataclasses.dataclass(frozen=True)
class BoundedArray(Array):
    """An :class:`Array` whose entries lie in ``[minimum, maximum]`` (each a number or a tuple
    broadcast against ``shape``). The bounds are not enforced by :meth:`problem` (the base clips
    an action to its limits): they are a learner's action space."""

    minimum: float | tuple[float, ...] = -np.inf
    maximum: float | tuple[float, ...] = np.inf


def problems(spec, value) -> list[str]:
    """Every field of ``value`` (a pytree of the same structure as ``spec``) that does not match
    its :class:`Array` spec, as messages naming the field."""
    leaves = jax.tree_util.tree_leaves(spec, is_leaf=lambda s: isinstance(s, Array))
    values = jax.tree_util.tree_structure(spec, is_leaf=lambda s: isinstance(s, Array)).flatten_up_to(value)
    return [p for s, v in zip(leaves, values, strict=True) if (p := s.problem(v)) is not None]


__all__ = ["Array", "BoundedArray", "problems"]
