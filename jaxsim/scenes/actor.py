"""Actors in the arena's scenes: the rollout of an episode over an actor.

:class:`Actor` is :class:`jaxsim.actor.Actor` (one kind for the arena and the warehouse), here
with the arena's observation (:class:`jaxsim.scenes.env.Observation`) and action ``(v, omega)``::

    init(key, observation) -> actor_state
    act(params, actor_state, observation, key) -> (action (2,) = (v, omega), actor_state)

``params`` is any pytree (weights, layer parameters, the map the actor was given); its leaves
are traced, so a new checkpoint or a parameter sweep does not recompile. ``actor_state`` is any
pytree of fixed shapes (a path, a recurrent state, a filter). A stack that plans at a slower
rate is wrapped by :func:`jaxsim.actor.replanning`; :func:`rollout` is the control loop both
worlds run (:func:`jaxsim.control.control_loop`) over an episode, whatever the actor.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import jax
import jax.numpy as jnp
from flax import struct

from socialnav.jaxsim import control
from socialnav.jaxsim.actor import Actor, ActorState, Params, replanning
from socialnav.jaxsim.precision import require_float32
from socialnav.jaxsim.scenes.env import Env, EnvState, Observation, TimeStep, action_problem

__all__ = ["Actor", "ActorState", "Params", "StepRecord", "check_actor", "default_record", "replanning", "rollout"]


def check_actor(env: Env, actor: Actor, params: Params, n_people: int) -> None:
    """Trace ``actor``'s ``init`` and ``act`` once on an observation of ``env`` with
    ``n_people`` slots (shapes only: ``jax.eval_shape``, nothing runs) and check its action.

    Raises:
      ValueError: the action is not of shape (2,) = (v m/s, omega rad/s), named with the actor.
      Exception: whatever the actor's own code raises when traced.
    """
    observation = jax.tree.map(lambda spec: spec.shape_dtype(), env.observation_spec(n_people))
    key = jax.random.key(0)
    state = jax.eval_shape(actor.init, key, observation)
    action, _ = jax.eval_shape(actor.act, params, state, observation, key)
    try:  # as Env.step reads it: a tuple (v, omega) is an array of shape (2,)
        action = jax.eval_shape(jnp.asarray, action) if not hasattr(action, "shape") else action
    except (TypeError, ValueError) as e:
        raise ValueError(f"actor {actor.name!r}: its action is not an array of shape (2,) = (v, omega): {e}") from None
    problem = action_problem(action.shape, action.dtype)
    if problem is not None:
        raise ValueError(f"actor {actor.name!r}: {problem}")


@struct.dataclass
class StepRecord:
    """What :func:`rollout` keeps of each step by default (T steps; a batch adds a leading axis).

    Attributes:
      robot_xy_m (T, 2), robot_yaw_rad (T,), robot_speed_mps (T,): after the step.
      people_xy_m (T, P, 2), people_heading_rad (T, P), people_present (T, P): after the step.
      people_visible (T, P): what the actor saw when it chose its action.
      action (T, 2), reward (T,), reached (T,) bool: by the end of the step.
    """

    robot_xy_m: jax.Array
    robot_yaw_rad: jax.Array
    robot_speed_mps: jax.Array
    people_xy_m: jax.Array
    people_heading_rad: jax.Array
    people_present: jax.Array
    people_visible: jax.Array
    action: jax.Array
    reward: jax.Array
    reached: jax.Array


def default_record(seen: Observation, action, actor_state, timestep: TimeStep) -> StepRecord:
    """The record of one step: the observation acted on, the action, the actor's state after it,
    the timestep that followed."""
    del actor_state
    o, info = timestep.observation, timestep.info
    return StepRecord(
        robot_xy_m=o.robot_xy_m,
        robot_yaw_rad=o.robot_yaw_rad,
        robot_speed_mps=o.robot_speed_mps,
        people_xy_m=info.people_xy_m,
        people_heading_rad=info.people_heading_rad,
        people_present=info.people_present,
        people_visible=seen.people_visible,
        action=action,
        reward=timestep.reward,
        reached=info.reached,
    )


def rollout(
    env: Env,
    actor: Actor,
    params: Params,
    variant,
    key: jax.Array,
    n_steps: int | None = None,
    record: Callable = default_record,
) -> tuple[tuple[EnvState, ActorState], Any]:
    """One episode of ``variant`` driven by ``actor``; ``vmap`` it over variants (and keys).

    Runs ``n_steps`` (default ``env.config.max_steps``) whatever happens: an episode past its
    goal goes on with the base stopped, so every episode of a batch has one length. Returns
    ``((final env state, final actor state), records)``, ``records`` the pytree
    ``record(observation, action, actor_state, timestep)`` stacked over steps
    (:class:`StepRecord` by default).
    """
    require_float32("jaxsim.scenes.actor.rollout")
    n_steps = env.config.max_steps if n_steps is None else int(n_steps)
    key_reset, key_init, key_run = jax.random.split(key, 3)
    state, timestep = env.reset(key_reset, variant)
    actor_state = actor.init(key_init, timestep.observation)
    keys = jax.random.split(key_run, n_steps)
    (state, _, actor_state), records = control.control_loop(
        env.step, actor, params, state, timestep.observation, actor_state, keys, record
    )
    return (state, actor_state), records
