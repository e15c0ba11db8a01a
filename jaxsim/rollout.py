"""Batched rollouts: ``lax.scan`` over time, ``vmap`` over worlds, chunked and sharded.

Layout of the compiled program for a batch of ``B`` worlds and ``n_samples`` samples of
``steps_per_sample`` steps each::

    shard_map over host devices (B split across them)
      lax.map over chunks of ``world_chunk`` worlds      (bounded live memory per chunk)
        vmap over the chunk's worlds
          scan over samples -> measure()                  (one Record per sample)
            control_loop over steps_per_sample steps      (jaxsim.control: act, env_step)

The robot's driver (an actor and its params, :class:`jaxsim.actor.Driver`, e.g.
:func:`jaxsim.route_follower.route_follower`) and the dynamic parameters are ordinary inputs of
the compiled program: another plan of the same shape or another value of a float parameter
reuses it. With ``params_batched`` every world has its own parameters (a sweep:
:meth:`jaxsim.params.SimParams.stack`), still one compilation.

Randomness is counter-based (:mod:`jaxsim.rng`): results do not depend on how time or worlds are
chunked, and the same seed gives the same logs bit for bit, whatever the batch size and the
number of host devices (a vmapped chunk always holds at least two worlds: :func:`map_worlds`).

:func:`run_until_done` runs any batched step until every world is done, retiring finished
worlds as it goes (batch compaction); the evaluation protocols use it.

Two host devices are what lets XLA use both cores of a CPU: the ``socialnav`` command asks XLA
for one per core before JAX is imported.
"""

from __future__ import annotations

import functools
from collections.abc import Callable

import jax
import jax.numpy as jnp
import numpy as np

from socialnav.common import xla
from socialnav.common.pytree import put, take
from socialnav.common.pytree import to_numpy as _to_numpy
from socialnav.jaxsim import control
from socialnav.jaxsim import step as step_lib
from socialnav.jaxsim.actor import Driver
from socialnav.jaxsim.params import SimParams
from socialnav.jaxsim.rng import world_seed_u32
from socialnav.jaxsim.state import Record, SimState
from socialnav.jaxsim.world import World

DEFAULT_WORLD_CHUNK = 64
# The fewest worlds vectorised together (see map_worlds: one alone compiles differently).
MIN_CHUNK = 2
# Key folded into a world's key for its initial state (kept apart from its step seed).
INIT_FOLD = 2**31 - 1


def world_keys(seed: int, n_worlds: int, first_world: int = 0) -> jax.Array:
    """(n_worlds,) independent keys of worlds ``first_world ..``; world ``b`` always gets the same
    key for a given seed (so worlds can be cut into shards)."""
    base = jax.random.key(seed)
    return jax.vmap(lambda b: jax.random.fold_in(base, b))(jnp.arange(first_world, first_world + n_worlds))


@functools.lru_cache(maxsize=4)
def _init_fn(params_batched: bool):
    def init(params, world, driver, key):
        return step_lib.init_state(params, world, driver, jax.random.fold_in(key, INIT_FOLD))

    # Run once per batch and mostly random draws: compiled for speed of compiling (common.xla).
    return jax.jit(
        jax.vmap(init, in_axes=(0 if params_batched else None, None, None, 0)), compiler_options=xla.ONCE_PER_RUN
    )


def init_batch(
    params: SimParams, world: World, driver: Driver, keys: jax.Array, params_batched: bool = False
) -> SimState:
    """Initial states of a batch of worlds, one per key (init key = ``fold_in(key, INIT_FOLD)``)."""
    return _init_fn(params_batched)(params, world, driver, keys)


def _run_one(
    params: SimParams,
    world: World,
    driver: Driver,
    state: SimState,
    key: jax.Array,
    n_samples: int,
    steps_per_sample: int,
) -> tuple[SimState, Record]:
    seed = world_seed_u32(key)
    world_step = lambda s, command: step_lib.env_step(params, world, s, command, seed)
    observe = lambda s: step_lib.observe(params, world, s)

    def sample(carry, _):
        s, actor_state = carry
        keys = step_lib.actor_keys(seed, s.step, steps_per_sample)
        (s, _, actor_state), _ = control.control_loop(
            world_step, driver.actor, driver.params, s, None, actor_state, keys, observe=observe
        )
        return (s, actor_state), step_lib.measure(params, world, s)

    # The loop keeps the actor's state apart from the world's; it goes back into the state after.
    (state, actor_state), records = jax.lax.scan(sample, (state.replace(actor=()), state.actor), None, length=n_samples)
    return state.replace(actor=actor_state), records


def map_worlds(run_one: Callable, batched: tuple, world_chunk: int):
    """``vmap(run_one)`` over the leading (world) axis of the pytree tuple ``batched``, chunked.

    ``lax.map`` runs ``ceil(B / world_chunk)`` chunks of equal size one after another, which
    bounds live memory; the batch is padded to a whole number of chunks with copies of its last
    world (their results are dropped). A chunk holds at least :data:`MIN_CHUNK` worlds: XLA
    compiles a ``vmap`` of one world as the unbatched program, whose float rounding differs, so
    without the floor one world alone (or one per host device) drifted from the same world in a
    batch (measured: bitwise equal for 2 to 100 worlds, different from step 2,140 for one). So
    a world's steps are the same bit for bit whatever the batch size and the number of host
    devices (``tests/test_determinism.py``). The reshape is spelled out (``lax.map``'s
    ``batch_size`` infers it with -1, which fails for zero-size leaves such as a world without
    workers).
    """
    b = jax.tree.leaves(batched)[0].shape[0]
    n_chunks = -(-b // max(world_chunk, MIN_CHUNK))
    chunk = max(MIN_CHUNK, -(-b // n_chunks))
    padded = n_chunks * chunk

    def split(x):
        if padded > b:
            x = jnp.concatenate([x, jnp.repeat(x[-1:], padded - b, axis=0)])
        return x.reshape((n_chunks, chunk) + x.shape[1:])

    merge = lambda x: x.reshape((padded,) + x.shape[2:])[:b]
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


def shard_worlds(fn: Callable, n_shared: int, n_batched: int, n_dev: int) -> Callable:
    """``jit(fn)``, split over ``n_dev`` host devices along the world axis.

    ``fn(*shared, *batched)``: the first ``n_shared`` arguments are replicated (world, plans),
    the next ``n_batched`` have a leading world axis; every output has one.
    """
    if n_dev == 1:
        return jax.jit(fn)
    spec, rep = jax.sharding.PartitionSpec("worlds"), jax.sharding.PartitionSpec()
    # check_vma off: every shard is independent (no collectives), and the check rejects the
    # zero-size worker arrays of a world without workers (their varying-axis type is dropped).
    return jax.jit(
        jax.shard_map(
            fn, mesh=_mesh(n_dev), in_specs=(rep,) * n_shared + (spec,) * n_batched, out_specs=spec, check_vma=False
        )
    )


def place(n_dev: int, shared: tuple, batched: tuple) -> tuple[tuple, tuple]:
    """Put ``shared`` on every device and split ``batched`` along the world axis."""
    if n_dev == 1:
        return shared, batched
    mesh = _mesh(n_dev)
    split = jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec("worlds"))
    same = jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec())
    return jax.device_put(shared, same), jax.device_put(batched, split)


@functools.lru_cache(maxsize=16)
def _compiled(n_samples: int, steps_per_sample: int, world_chunk: int, n_dev: int, params_batched: bool):
    def run(params, world, driver, states, keys):
        one = lambda p, s, k: _run_one(p, world, driver, s, k, n_samples, steps_per_sample)
        if params_batched:
            return map_worlds(one, (params, states, keys), world_chunk)
        return map_worlds(lambda s, k: one(params, s, k), (states, keys), world_chunk)

    if params_batched:
        return shard_worlds(lambda w, c, p, s, k: run(p, w, c, s, k), 2, 3, n_dev)
    return shard_worlds(run, 3, 2, n_dev)


def run_samples(
    params: SimParams,
    world: World,
    driver: Driver,
    states: SimState,
    keys: jax.Array,
    n_samples: int,
    steps_per_sample: int,
    world_chunk: int = DEFAULT_WORLD_CHUNK,
    params_batched: bool = False,
) -> tuple[SimState, Record]:
    """Advance a batch of worlds by ``n_samples * steps_per_sample`` steps.

    Args:
      params: the parameters of every world, or with ``params_batched`` one set per world
        (leading axis B on every dynamic field).
      driver: the robot's driver (replicated over the batch).
      states: batched :class:`SimState` with leading axis B.
      keys: (B,) world keys (see :func:`world_keys`).
      n_samples: records to return per world.
      steps_per_sample: steps between two records.
      world_chunk: worlds vectorised together inside ``lax.map``.

    Returns:
      (final states, records) with records shaped (B, n_samples, ...).
    """
    n_dev = devices_for(keys.shape[0])
    fn = _compiled(n_samples, steps_per_sample, world_chunk, n_dev, params_batched)
    if params_batched:
        shared, batched = place(n_dev, (world, driver), (params, states, keys))
    else:
        shared, batched = place(n_dev, (params, world, driver), (states, keys))
    return fn(*shared, *batched)


def rollout(
    params: SimParams,
    world: World,
    driver: Driver,
    seed: int,
    n_worlds: int,
    n_steps: int,
    sample_every_steps: int = 1,
    params_batched: bool = False,
) -> tuple[SimState, Record]:
    """Convenience: a whole rollout in memory (use :mod:`jaxsim.logs` for long runs).

    With ``params_batched``, ``params`` carries one set per world (``n_worlds`` of them).
    """
    if n_steps % sample_every_steps:
        raise ValueError(f"n_steps={n_steps} is not a multiple of sample_every_steps={sample_every_steps}")
    keys = world_keys(seed, n_worlds)
    states = init_batch(params, world, driver, keys, params_batched)
    return run_samples(
        params,
        world,
        driver,
        states,
        keys,
        n_steps // sample_every_steps,
        sample_every_steps,
        params_batched=params_batched,
    )


def to_numpy(tree):
    """Device arrays -> host numpy (one transfer)."""
    return _to_numpy(tree, copy=False)


def run_until_done(
    advance_for: Callable[[int], Callable],
    shared: tuple,
    states,
    keys: jax.Array,
    *,
    is_done: Callable[[object], np.ndarray],
    max_segments: int,
    work_done: Callable[[object], np.ndarray] | None = None,
    progress: Callable[[int, int], None] | None = None,
    total_work: int = 0,
    shrink_at: float = 0.5,
    pad_multiple: int = 8,
):
    """Advance a batch segment by segment until every world is done, retiring finished ones.

    After each segment, once the unfinished worlds are at most ``shrink_at`` of the batch, the
    finished ones are copied out and the rest continue in a smaller batch (rounded up to a
    multiple of ``pad_multiple`` per device, padded with copies whose results are dropped);
    each new size compiles once. A world's steps are the same whichever batch it is in (to
    float rounding: XLA may vectorise another batch shape differently).

    Args:
      advance_for: ``n_dev -> fn`` where ``fn(*shared, states, keys)`` advances a batch by one
        segment (compiled for a batch split over ``n_dev`` devices, see :func:`shard_worlds`).
      shared: arguments replicated over the batch.
      states: batched states (leading axis B); keys: (B,) keys, passed along with them.
      is_done: host function of a batch of states -> (B,) bool.
      max_segments: a bound on the segments needed (exceeding it is an error).
      work_done, progress, total_work: optional progress report ``progress(done, total_work)``
        with ``done`` the sum of ``work_done(states)`` over retired and running worlds.
      shrink_at: share of unfinished worlds below which the batch is compacted (0: never).

    Returns:
      the final states as host numpy arrays, in the order of the input batch.

    Raises:
      RuntimeError: some world is not done after ``max_segments`` segments.
    """
    final = _to_numpy(states, copy=True)
    all_keys = keys
    ids = np.arange(jax.tree.leaves(states)[0].shape[0])  # world held by each batch entry (-1: padding)
    retired_work = 0

    def start(states, keys, ids):
        n_dev = devices_for(len(ids))
        placed_shared, (states, keys) = place(n_dev, shared, (states, keys))
        return advance_for(n_dev), placed_shared, states, keys

    advance, placed, states, keys = start(states, keys, ids)
    for _ in range(max_segments):
        states = advance(*placed, states, keys)
        real = ids >= 0
        done = np.asarray(is_done(states))
        if progress is not None and work_done is not None:
            progress(retired_work + int(np.asarray(work_done(states))[real].sum()), total_work)
        if done[real].all():
            put(final, ids[real], take(_to_numpy(states), real))
            return final
        left = np.flatnonzero(real & ~done)
        if shrink_at > 0 and len(left) <= shrink_at * len(ids) and len(ids) > pad_multiple:
            host = _to_numpy(states)
            put(final, ids[real], take(host, real))
            if work_done is not None:
                retired_work += int(np.asarray(work_done(host))[real & done].sum())
            n_dev = jax.local_device_count()
            block = pad_multiple * n_dev
            size = -(-len(left) // block) * block if len(left) > block else len(left)
            pick = np.concatenate([left, np.full(size - len(left), left[0])])
            new_keys = all_keys[jnp.asarray(ids[pick])]
            ids = np.concatenate([ids[left], np.full(size - len(left), -1)])
            advance, placed, states, keys = start(take(host, pick), new_keys, ids)
    raise RuntimeError(f"not every world was done after {max_segments} segments")
