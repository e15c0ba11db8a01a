"""Wrappers of :class:`jaxsim.scenes.env.Env` in the brax and gymnax style: what a training loop,
the Gymnasium adapter or an evaluation would otherwise write around ``step`` inline, written once.

A wrapper is an environment: ``reset(key, variant)`` and ``step(state, action)`` as the one it
wraps, every other attribute (``config``, ``robot``, ``observation_spec`` ...) read through. What
it keeps per episode lives in the state's ``extras`` dict under its own names (brax's
``State.info``), so a wrapped state is still an :class:`~jaxsim.scenes.env.EnvState` and a batch
of them restarts with :func:`reset_where` like a bare one::

    env = EpisodeStatistics(RuleMonitor.of(PotentialShaping(FromPool(env, pool), potential, fields, 0.1), rule))
    state, ts = env.reset(key, index)            # index: the pool's variant
    state, ts = env.step(state, action)          # ts.reward shaped
    state.extras["episode_return"], state.extras["rule_kept"]

* :class:`FromPool`: ``reset(key, index)`` from a :class:`VariantPool` drawn once (so a reset
  inside a compiled loop needs no host); the index kept as ``extras["pool_index"]``.
* :class:`PotentialShaping`: potential-based reward shaping (Ng, Harada and Russell 1999, which
  keeps the optimal policy): ``weight * (phi(before) - phi(after))`` added to the reward.
* :class:`RuleMonitor`: the scene's social rule checked step by step
  (:mod:`jaxsim.scenes.rule_monitor`): ``extras["rule_kept"]``, the arena's verdict so far.
* :class:`EpisodeStatistics`: the episode's return, length and whether the robot has touched a
  person so far (``extras["episode_return"]``, ``["episode_steps"]``, ``["episode_person_contact"]``).

Wrap the shaping inside the statistics so that the return is the shaped one. A wrapper's static
parts (a potential function, a rule) are compared by value where they can be (the rule as JSON),
so a wrapped env built inside a jitted function compiles once.

A batch of B episodes steps as one ``vmap`` of ``env.step``. When some end, they restart from
fresh draws while the others go on: :func:`reset_where` resets the whole batch inside a
``lax.cond`` that runs only on steps where at least one episode needs it (under ``jit`` one
branch runs; a per-episode ``where`` around ``reset`` would reset every episode on every step),
and keeps the fresh state only where asked; a wrapped env's reset restarts its extras too.

The callers differ in when they reset, and keep that choice: the Gymnasium adapter resets on
the step after an episode ended (Gymnasium's ``NEXT_STEP`` autoreset, the ended step's
observation returned first), the PPO trainer on the step that ended it (the next observation is
the fresh episode's, as in brax's ``AutoResetWrapper``).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from socialnav.common import pytree
from socialnav.jaxsim.scenes import rule_monitor
from socialnav.jaxsim.scenes.variant import Variant


def reset_where(env, mask: jax.Array, keys: jax.Array, variants, state, timestep):
    """The batch ``(state, timestep)`` with the episodes where ``mask`` restarted.

    Args:
      env: the environment (:class:`jaxsim.scenes.env.Env` or a wrapper of it).
      mask: (B,) bool, the episodes to restart.
      keys: (B,) the reset keys; variants: what the B episodes restart from, as ``env.reset``
        takes it (B variants, leaves (B, ...); B pool indices for :class:`FromPool`).
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


def _with_extras(state, **extras):
    return state.replace(extras={**state.extras, **extras})


@struct.dataclass
class Wrapper:
    """An environment around ``env`` (an :class:`~jaxsim.scenes.env.Env` or a wrapper): ``reset``
    and ``step`` pass through, every other attribute is ``env``'s. A pytree like the env."""

    env: Any

    def reset(self, key: jax.Array, variant):
        return self.env.reset(key, variant)

    def step(self, state, action: jax.Array):
        return self.env.step(state, action)

    def __getattr__(self, name: str):
        if name == "env" or name.startswith("__"):  # not yet set (unpickling, copying)
            raise AttributeError(name)
        return getattr(self.env, name)

    @property
    def unwrapped(self):
        """The bare :class:`~jaxsim.scenes.env.Env` under every wrapper."""
        env = self.env
        while isinstance(env, Wrapper):
            env = env.env
        return env


@struct.dataclass
class FromPool(Wrapper):
    """Episodes from a pool of variants by index: ``reset(key, index)`` runs
    ``env.reset(key, pool.take(index))`` and keeps ``extras["pool_index"]`` (() int32), so that
    what is stored per variant (a guidance field, a label) can be read in the episode."""

    pool: VariantPool

    def reset(self, key: jax.Array, index: jax.Array):
        state, timestep = self.env.reset(key, self.pool.take(index))
        return _with_extras(state, pool_index=index), timestep


@struct.dataclass
class PotentialShaping(Wrapper):
    """Potential-based reward shaping (Ng, Harada and Russell 1999): each step's reward gains
    ``weight * clip(phi(before) - phi(after), -clip_m, clip_m)``, ``phi = potential(state,
    potential_params)`` in metres (the distance still to go along a guidance field, say); no gain
    where either value is not finite (off the field, inside a wall) or once the goal had been
    reached before the step.

    Attributes:
      potential: ``(EnvState, potential_params) -> ()`` float (static).
      potential_params: what it reads (a pytree, traced: a stack of guidance fields is an
        argument of the compiled program, not a constant in it).
      weight: reward per metre gained (static). clip_m: the most one step counts (static).
    """

    potential: Callable = struct.field(pytree_node=False)
    potential_params: Any = None
    weight: float = struct.field(pytree_node=False, default=0.1)
    clip_m: float = struct.field(pytree_node=False, default=0.5)

    def step(self, state, action: jax.Array):
        new, timestep = self.env.step(state, action)
        before, after = self.potential(state, self.potential_params), self.potential(new, self.potential_params)
        finite = jnp.isfinite(before) & jnp.isfinite(after)
        gained = jnp.where(finite, jnp.clip(before - after, -self.clip_m, self.clip_m), 0.0)
        gained = jnp.where(state.reached, 0.0, gained)
        return new, timestep.replace(reward=timestep.reward + self.weight * gained)


@struct.dataclass
class RuleMonitor(Wrapper):
    """A scene's social rule (:attr:`jaxsim.scenes.spec.SceneSpec.rule`) checked as the episode
    runs (:func:`jaxsim.scenes.rule_monitor.monitor`): ``extras["rule_state"]`` and
    ``extras["rule_kept"]`` (() bool, the rule kept so far: after the step that reaches the goal,
    the arena's verdict). Build it with :meth:`of`; the rule is kept as JSON (hashable; its arrays
    as lists, which the monitor reads back as float32 with the same values)."""

    rule_json: str = struct.field(pytree_node=False, default="")

    @classmethod
    def of(cls, env, rule: dict) -> RuleMonitor:
        return cls(env, json.dumps(rule, sort_keys=True, default=lambda a: np.asarray(a).tolist()))

    def _monitor(self):
        return rule_monitor.monitor(json.loads(self.rule_json))

    def reset(self, key: jax.Array, variant):
        state, timestep = self.env.reset(key, variant)
        init, _, verdict = self._monitor()
        fresh = init()
        return _with_extras(state, rule_state=fresh, rule_kept=verdict(fresh)), timestep

    def step(self, state, action: jax.Array):
        new, timestep = self.env.step(state, action)
        _, update, verdict = self._monitor()
        info, variant = timestep.info, new.variant
        checked = update(
            new.extras["rule_state"],
            rule_monitor.Step(new.robot.xy, info.reached, info.people_xy_m, info.people_present),
            rule_monitor.Episode(variant.start_xy, variant.end_xy, variant.group),
        )
        return _with_extras(new, rule_state=checked, rule_kept=verdict(checked)), timestep


@struct.dataclass
class EpisodeStatistics(Wrapper):
    """The episode so far: ``extras["episode_return"]`` (() float32, the sum of the rewards as
    the wrapped env gives them), ``["episode_steps"]`` (() int32) and
    ``["episode_person_contact"]`` (() bool, the robot has touched a person)."""

    def reset(self, key: jax.Array, variant):
        state, timestep = self.env.reset(key, variant)
        return _with_extras(
            state,
            episode_return=jnp.float32(0.0),
            episode_steps=jnp.int32(0),
            episode_person_contact=jnp.array(False),
        ), timestep

    def step(self, state, action: jax.Array):
        new, timestep = self.env.step(state, action)
        e = state.extras
        return _with_extras(
            new,
            episode_return=e["episode_return"] + timestep.reward,
            episode_steps=e["episode_steps"] + 1,
            episode_person_contact=e["episode_person_contact"] | timestep.info.person_contact,
        ), timestep
