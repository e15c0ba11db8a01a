"""The control loop both worlds run (jaxsim.control): a known answer on a toy world, and the
warehouse day, seed 000's protocol and the arena's episode all driven through it."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from socialnav.data import DATA_DIR
from socialnav.evaluation import protocol
from socialnav.evaluation.arena import episodes as arena
from socialnav.jaxsim import control, rollout
from socialnav.jaxsim.actor import Actor
from socialnav.jaxsim.scenes import actor as scene_actor
from socialnav.jaxsim.scenes.spec import load_scene
from socialnav.jaxsim.scenes.variant import sample_variant


@struct.dataclass
class Seen:
    observation: jax.Array


def _toward(target_per_step_m: float) -> Actor:
    """Moves a point on a line toward ``params`` by at most ``target_per_step_m`` a step; its
    state counts its steps and sums a uniform of each key it is given."""

    def act(params, state, observation, key):
        action = jnp.clip(params - observation, -target_per_step_m, target_per_step_m)
        steps, draws = state
        return action, (steps + 1, draws + jax.random.uniform(key))

    return Actor(init=lambda key, observation: (jnp.int32(0), jnp.float32(0.0)), act=act, name="toward")


def test_the_loop_acts_on_each_observation_then_steps_the_world():
    world_step = lambda x, action: (x + action, Seen(observation=x + action))
    keys = jax.random.split(jax.random.key(3), 5)
    (x, seen, (steps, draws)), kept = control.control_loop(
        world_step,
        _toward(1.0),
        jnp.float32(2.5),
        jnp.float32(0.0),
        jnp.float32(0.0),
        (jnp.int32(0), jnp.float32(0.0)),
        keys,
        record=lambda observation, action, actor_state, timestep: (observation, action, timestep.observation),
    )
    acted_on, actions, after = (np.asarray(a) for a in kept)
    np.testing.assert_allclose(actions, [1.0, 1.0, 0.5, 0.0, 0.0])
    np.testing.assert_allclose(acted_on, [0.0, 1.0, 2.0, 2.5, 2.5])  # each step's observation is the last step's
    np.testing.assert_allclose(after, [1.0, 2.0, 2.5, 2.5, 2.5])
    assert float(x) == float(seen) == 2.5 and int(steps) == 5
    np.testing.assert_allclose(float(draws), float(sum(jax.random.uniform(k) for k in keys)), rtol=1e-6)
    start = (jnp.float32(0.0), jnp.float32(0.0), (jnp.int32(0), jnp.float32(0.0)))
    _, nothing = control.control_loop(world_step, _toward(1.0), jnp.float32(2.5), *start, keys)
    assert nothing is None  # without a record nothing is kept
    # An observation that is the state itself, computed each step instead of carried: the same run.
    blind_step = lambda x, action: (x + action, Seen(observation=None))
    (x2, unread, _), kept2 = control.control_loop(
        blind_step,
        _toward(1.0),
        jnp.float32(2.5),
        jnp.float32(0.0),
        None,
        (jnp.int32(0), jnp.float32(0.0)),
        keys,
        record=lambda observation, action, actor_state, timestep: (observation, action),
        observe=lambda x: x,
    )
    assert unread is None and float(x2) == 2.5
    np.testing.assert_array_equal(np.asarray(kept2[0]), acted_on)
    np.testing.assert_array_equal(np.asarray(kept2[1]), actions)


def test_the_warehouse_the_protocol_and_the_arena_run_one_control_loop(monkeypatch, short_day):
    calls = []
    original = control.control_loop

    def counted(step, actor, *args, **kwargs):
        calls.append(actor.name)
        return original(step, actor, *args, **kwargs)

    monkeypatch.setattr(control, "control_loop", counted)
    scenario, world, follower = short_day
    params = scenario.params
    key = jax.random.key(0)
    # Traced only (make_jaxpr): which loop each world's program is built from.
    state = rollout.init_batch(params, world, follower, rollout.world_keys(0, 2))
    one = jax.tree.map(lambda a: a[0], state)
    jax.make_jaxpr(lambda s: rollout._run_one(params, world, follower, s, key, 2, 3))(one)
    cfg = protocol.ProtocolConfig.for_params(params)
    xs = protocol.init_experiment(params, cfg, world, follower, jnp.int32(0), key)
    jax.make_jaxpr(lambda s: protocol._advance_one(params, cfg, world, follower, s, key, 4))(xs)
    setup = arena.setup_scene(load_scene(DATA_DIR / "scenes" / "casn_head_on.json"))
    variant = jax.tree.map(jnp.asarray, sample_variant(setup.spec, 0, 0))
    still = Actor(init=lambda k, o: (), act=lambda p, s, o, k: (jnp.zeros(2), s), name="still")
    jax.make_jaxpr(lambda v: scene_actor.rollout(setup.env, still, None, v, key, n_steps=3))(variant)
    assert calls == [follower.actor.name, follower.actor.name, "still"]
