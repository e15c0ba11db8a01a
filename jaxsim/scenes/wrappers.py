"""Batches of episodes that restart when they end: what the Gymnasium adapter and the PPO trainer
both need of :class:`jaxsim.scenes.env.Env`, written once.

A batch of B episodes steps as one ``vmap`` of ``env.step``. When some end, they restart from
fresh draws while the others go on: :func:`reset_where` resets the whole batch inside a
``lax.cond`` that runs only on steps where at least one episode needs it (under ``jit`` one
branch runs; a per-episode ``where`` around ``reset`` would reset every episode on every step),
and keeps the fresh state only where asked. The draws come from a pool of variants drawn once
(:class:`VariantPool`), so that a reset inside a compiled loop needs no host.

The two callers differ in when they reset, and keep that choice: the Gymnasium adapter resets on
the step after an episode ended (Gymnasium's ``NEXT_STEP`` autoreset, the ended step's
observation returned first), the PPO trainer on the step that ended it (the next observation is
the fresh episode's, as in brax's ``AutoResetWrapper``).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct

from socialnav.common import pytree
from socialnav.jaxsim.scenes.variant import Variant


def reset_where(env, mask: jax.Array, keys: jax.Array, variants: Variant, state, timestep):
    """The batch ``(state, timestep)`` with the episodes where ``mask`` restarted.

    Args:
      env: the environment (:class:`jaxsim.scenes.env.Env`).
      mask: (B,) bool, the episodes to restart.
      keys: (B,) the reset keys; variants: the B variants to restart from (leaves (B, ...)).
      state, timestep: the batch as stepped (``EnvState`` and ``TimeStep``, leaves (B, ...)).

    Returns:
      ``(state, timestep)``: ``env.reset(keys[b], variants[b])`` where ``mask[b]``, the input
      elsewhere. The reset runs only when some ``mask[b]`` is set (a ``lax.cond``).
    """

    def restart():
        fresh = jax.vmap(env.reset)(keys, variants)
        return pytree.select_rows(mask, fresh, (state, timestep))

    return jax.lax.cond(jnp.any(mask), restart, lambda: (state, timestep))


@struct.dataclass
class VariantPool:
    """A scene's variants drawn once and stacked (leaves (N, ...), one padded shape), to restart
    episodes from inside a compiled loop.

    Attributes:
      variants: the stacked :class:`~jaxsim.scenes.variant.Variant`.
    """

    variants: Variant

    @property
    def size(self) -> int:
        """N, the variants in the pool."""
        return jax.tree_util.tree_leaves(self.variants)[0].shape[0]

    def take(self, index: jax.Array) -> Variant:
        """The variants at ``index`` (int array of any shape; leaves ``index.shape + (...)``)."""
        return pytree.take(self.variants, index)

    def draw(self, key: jax.Array, n: int) -> jax.Array:
        """``n`` indices into the pool, uniform with replacement."""
        return jax.random.randint(key, (n,), 0, self.size)
