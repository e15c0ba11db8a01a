"""Batched rollouts: ``lax.scan`` over time, ``vmap`` over worlds, chunked and sharded.

Layout of the compiled program for a batch of ``B`` worlds and ``n_samples`` samples of
``steps_per_sample`` steps each::

    shard_map over host devices (B split across them)
      lax.map over chunks of ``world_chunk`` worlds      (bounded live memory per chunk)
        vmap over the chunk's worlds
          scan over samples -> measure()                  (one Record per sample)
            scan over steps_per_sample -> step()

Randomness is counter-based: the draws of world ``b`` at step ``t`` are a hash of the world's
seed (from ``world_key[b]``) and ``t`` (:func:`jaxsim.step.hash_uniform16`), so results do not
depend on how time or worlds are chunked, and the same seed gives the same logs bit for bit.

Two host devices are what lets XLA use both cores of a CPU: call
:func:`jaxsim.devices.request_host_devices` before JAX is imported (the command line and benchmark do).
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np

from jaxsim.params import SimParams
from jaxsim.state import Record, SimState
from jaxsim.step import init_state, measure, step, world_seed_u32
from jaxsim.world import RobotPlan, World

DEFAULT_WORLD_CHUNK = 64


def world_keys(seed: int, n_worlds: int) -> jax.Array:
    """(n_worlds,) independent keys, world ``b`` always gets the same key for a given seed."""
    base = jax.random.key(seed)
    return jax.vmap(lambda b: jax.random.fold_in(base, b))(jnp.arange(n_worlds))


def init_batch(params: SimParams, world: World, plan: RobotPlan, keys: jax.Array) -> SimState:
    """Initial states of a batch of worlds, one per key (init key = ``fold_in(key, 2**31 - 1)``)."""
    init = lambda k: init_state(params, world, plan, jax.random.fold_in(k, 2**31 - 1))  # noqa: E731
    return jax.jit(jax.vmap(init))(keys)


def _run_one(params: SimParams, world: World, plan: RobotPlan, state: SimState, key,
             n_samples: int, steps_per_sample: int):
    seed = world_seed_u32(key)

    def inner(s, _):
        return step(params, world, plan, s, seed), None

    def outer(s, _):
        s, _ = jax.lax.scan(inner, s, None, length=steps_per_sample)
        return s, measure(params, world, s)

    return jax.lax.scan(outer, state, None, length=n_samples)


def map_worlds(run_one, batched, world_chunk: int):
    """``vmap(run_one)`` over the leading (world) axis of the pytree tuple ``batched``, chunked.

    ``lax.map`` runs chunks of ``world_chunk`` worlds (the largest divisor of the batch not above
    it) one after another, which bounds live memory. The reshape is spelled out (``lax.map``'s
    ``batch_size`` infers it with -1, which fails for zero-size leaves such as a world without
    workers).
    """
    b = jax.tree.leaves(batched)[0].shape[0]
    chunk = max(c for c in range(1, min(world_chunk, b) + 1) if b % c == 0)
    split = lambda x: x.reshape((b // chunk, chunk) + x.shape[1:])  # noqa: E731
    merge = lambda x: x.reshape((b,) + x.shape[2:])  # noqa: E731
    out = jax.lax.map(lambda args: jax.vmap(run_one)(*args), jax.tree.map(split, batched))
    return jax.tree.map(merge, out)


@functools.lru_cache(maxsize=4)
def _mesh(n_dev: int):
    return jax.make_mesh((n_dev,), ("worlds",))


def devices_for(n_worlds: int) -> int:
    """Host devices a batch of ``n_worlds`` is split over (the most that divide it evenly)."""
    n_dev = jax.local_device_count()
    while n_dev > 1 and n_worlds % n_dev:
        n_dev -= 1
    return n_dev


def shard_worlds(fn, n_shared: int, n_batched: int, n_dev: int):
    """``jit(fn)``, split over ``n_dev`` host devices along the world axis.

    ``fn(*shared, *batched)``: the first ``n_shared`` arguments are replicated (world, plans),
    the next ``n_batched`` have a leading world axis; every output has one.
    """
    if n_dev == 1:
        return jax.jit(fn)
    spec, rep = jax.sharding.PartitionSpec("worlds"), jax.sharding.PartitionSpec()
    # check_vma off: every shard is independent (no collectives), and the check rejects the
    # zero-size worker arrays of a world without workers (their varying-axis type is dropped).
    return jax.jit(jax.shard_map(fn, mesh=_mesh(n_dev), in_specs=(rep,) * n_shared + (spec,) * n_batched,
                                 out_specs=spec, check_vma=False))


def place(n_dev: int, shared: tuple, batched: tuple) -> tuple[tuple, tuple]:
    """Put ``shared`` on every device and split ``batched`` along the world axis."""
    if n_dev == 1:
        return shared, batched
    mesh = _mesh(n_dev)
    split = jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec("worlds"))
    same = jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec())
    return jax.device_put(shared, same), jax.device_put(batched, split)


@functools.lru_cache(maxsize=16)
def _compiled(params: SimParams, n_samples: int, steps_per_sample: int, world_chunk: int, n_dev: int):
    def fn(world, plan, states, keys):
        run = functools.partial(_run_one, params, world, plan, n_samples=n_samples,
                                steps_per_sample=steps_per_sample)
        return map_worlds(run, (states, keys), world_chunk)

    return shard_worlds(fn, 2, 2, n_dev)


def run_samples(params: SimParams, world: World, plan: RobotPlan, states: SimState, keys: jax.Array,
                n_samples: int, steps_per_sample: int, world_chunk: int = DEFAULT_WORLD_CHUNK
                ) -> tuple[SimState, Record]:
    """Advance a batch of worlds by ``n_samples * steps_per_sample`` steps.

    Args:
      states: batched :class:`SimState` with leading axis B.
      keys: (B,) world keys (see :func:`world_keys`).
      n_samples: records to return per world.
      steps_per_sample: steps between two records.
      world_chunk: worlds vectorised together inside ``lax.map``.

    Returns:
      (final states, records) with records shaped (B, n_samples, ...).
    """
    n_dev = devices_for(keys.shape[0])
    fn = _compiled(params, n_samples, steps_per_sample, world_chunk, n_dev)
    shared, batched = place(n_dev, (world, plan), (states, keys))
    return fn(*shared, *batched)


def rollout(params: SimParams, world: World, plan: RobotPlan, seed: int, n_worlds: int,
            n_steps: int, sample_every_steps: int = 1) -> tuple[SimState, Record]:
    """Convenience: a whole rollout in memory (use :mod:`jaxsim.logs` for long runs)."""
    if n_steps % sample_every_steps:
        raise ValueError(f"n_steps={n_steps} is not a multiple of sample_every_steps={sample_every_steps}")
    keys = world_keys(seed, n_worlds)
    states = init_batch(params, world, plan, keys)
    return run_samples(params, world, plan, states, keys, n_steps // sample_every_steps, sample_every_steps)


def to_numpy(tree):
    """Device arrays -> host numpy (one transfer)."""
    return jax.tree.map(np.asarray, jax.device_get(tree))
