"""The rollout's generic parts: batch compaction (run until every world is done, retiring
finished ones) and parameter sweeps as one vmap over stacked dynamic parameters."""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from flax import struct

from socialnav.jaxsim import rollout
from socialnav.jaxsim.params import SimParams


@struct.dataclass
class Countdown:
    """A toy world: ``left`` steps to go; ``trace`` accumulates a key-dependent value per step."""

    left: jax.Array
    steps: jax.Array
    trace: jax.Array


@functools.cache
def _advance(n_dev: int):
    def fn(scale, states, keys):
        def one(s, k):
            noise = jax.random.uniform(k)

            def body(s, _):
                running = s.left > 0
                return s.replace(
                    left=s.left - running,
                    steps=s.steps + running,
                    trace=s.trace + jnp.where(running, scale * noise, 0.0),
                ), None

            return jax.lax.scan(body, s, None, length=3)[0]

        return rollout.map_worlds(one, (states, keys), 4)

    return rollout.shard_worlds(fn, 1, 2, n_dev)


def _countdowns(lengths):
    n = len(lengths)
    return Countdown(left=jnp.asarray(lengths, jnp.int32), steps=jnp.zeros(n, jnp.int32), trace=jnp.zeros(n))


@pytest.mark.parametrize("shrink_at", [0.0, 0.5, 0.9])
def test_compaction_keeps_every_world_in_its_place(shrink_at):
    lengths = [1, 40, 2, 3, 25, 1, 2, 7, 60, 2, 1, 4, 3, 33, 2, 1, 9, 2, 5, 1]
    keys = rollout.world_keys(0, len(lengths))
    seen = []
    final = rollout.run_until_done(
        _advance,
        (jnp.float32(0.5),),
        _countdowns(lengths),
        keys,
        is_done=lambda s: np.asarray(s.left) == 0,
        max_segments=30,
        work_done=lambda s: np.asarray(s.steps),
        total_work=sum(lengths),
        progress=lambda done, total: seen.append((done, total)),
        shrink_at=shrink_at,
        pad_multiple=2,
    )
    np.testing.assert_array_equal(final.left, 0)
    np.testing.assert_array_equal(final.steps, lengths)  # each world ran exactly its own length
    noise = np.asarray(jax.vmap(jax.random.uniform)(keys))
    np.testing.assert_allclose(final.trace, 0.5 * noise * np.asarray(lengths), rtol=1e-5)
    assert seen[-1] == (sum(lengths), sum(lengths))  # progress counts retired and running work
    assert all(a[0] <= b[0] for a, b in zip(seen, seen[1:], strict=False))


def test_run_until_done_reports_worlds_that_never_finish():
    with pytest.raises(RuntimeError, match="not every world was done after 2 segments"):
        rollout.run_until_done(
            _advance,
            (jnp.float32(1.0),),
            _countdowns([1, 100]),
            rollout.world_keys(0, 2),
            is_done=lambda s: np.asarray(s.left) == 0,
            max_segments=2,
        )


def test_params_stack_to_a_leading_axis_and_refuse_other_statics(warehouse):
    p = warehouse.params
    stacked = SimParams.stack([p.replace(robot_obstacle_probability=q) for q in (0.1, 0.2, 0.3)])
    np.testing.assert_allclose(stacked.robot_obstacle_probability, [0.1, 0.2, 0.3], rtol=1e-6)
    assert stacked.worker_radius_m.shape == (3,) and stacked.n_workers == p.n_workers  # statics stay scalars
    assert "n_workers" not in SimParams.dynamic_names() and "worker_radius_m" in SimParams.dynamic_names()
    with pytest.raises(ValueError, match="static field 'n_workers'"):
        SimParams.stack([p, p.replace(n_workers=3)])


@pytest.mark.slow
def test_a_new_dynamic_value_reuses_the_compiled_rollout(warehouse):
    """Dynamic parameters are inputs of the compiled program: another value compiles nothing new."""
    from plans import scipy_shortest_plan

    from socialnav.jaxsim.route_follower import route_follower
    from socialnav.jaxsim.world import build_world

    s = warehouse.replace_params(n_workers=2, slot_length_s=20.0)
    world = build_world(s)
    controller = route_follower(scipy_shortest_plan(s), world)
    fn = rollout._compiled(5, 2, rollout.DEFAULT_WORLD_CHUNK, 1, False)
    keys = rollout.world_keys(0, 1)
    states = rollout.init_batch(s.params, world, controller, keys)
    before = fn._cache_size()
    for speed in (0.3, 0.4):
        rollout.run_samples(s.params.replace(robot_max_speed_mps=speed), world, controller, states, keys, 5, 2)
    assert fn._cache_size() - before <= 1
