"""Actors: whatever drives the robot (a navigation stack, a route follower, a reactive rule, a
learned policy, a user's own function), passed into a rollout, never written inside the physics.
One kind for both worlds of the toolkit: the arena's scenes (:mod:`jaxsim.scenes.actor`, action
``(v, omega)``) and the warehouse day and protocol (:mod:`jaxsim.step`, action
:class:`jaxsim.robot.RobotCommand`).

An :class:`Actor` is two pure functions::

    init(key, observation) -> actor_state
    act(params, actor_state, observation, key) -> (action, actor_state)

``params`` is any pytree (weights, layer parameters, the map or plan the actor was given); its
leaves are traced, so a new checkpoint or a parameter sweep does not recompile. ``actor_state``
is any pytree of fixed shapes (a path, a recurrent state, a filter).

A stack that plans at a slower rate than it acts is an actor wrapped by :func:`replanning`:
``replanning(actor, plan, every_steps=10)`` runs ``plan(params, actor_state, observation, key)
-> actor_state`` before every tenth ``act`` (``every_steps=0``: before the first only). The
rollouts know nothing of planning.

A :class:`Driver` is an actor with its params, the one pytree a rollout takes: the actor is its
static part (the compiled program's cache key), the params its leaves.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import jax
import jax.numpy as jnp
from flax import struct

ActorState = Any
Params = Any
Observation = Any
Action = Any


@dataclasses.dataclass(frozen=True)
class Actor:
    """A controller of the robot (static: hashable, compared by its functions).

    Attributes:
      init: ``(key, observation) -> actor_state``.
      act: ``(params, actor_state, observation, key) -> (action, actor_state)``.
      name: shown in tables and errors.
    """

    init: Callable[[jax.Array, Observation], ActorState]
    act: Callable[[Params, ActorState, Observation, jax.Array], tuple[Action, ActorState]]
    name: str = "actor"


Plan = Callable[[Params, ActorState, Observation, jax.Array], ActorState]
# Folded into an act's key for the plan that runs before it (the act keeps its key as given).
PLAN_FOLD = 1


@struct.dataclass
class Replanned:
    """The state of an actor wrapped by :func:`replanning`.

    Attributes:
      inner: the wrapped actor's state.
      steps: () int32, the control steps taken so far. It starts from a constant and only ever
        counts up, so under ``vmap`` it stays one number for the whole batch (every episode of a
        batch steps together): the ``lax.cond`` that asks whether a plan is due keeps a scalar
        predicate and runs the plan only on the steps it is due, where a batched predicate
        would turn it into a select that plans on every step.
    """

    inner: ActorState
    steps: jax.Array


def replanning(actor: Actor, plan: Plan, every_steps: int) -> Actor:
    """``actor`` whose state ``plan`` updates before every ``every_steps``-th action, the first
    included (``every_steps = 0``: before the first action only, a plan for the whole episode).
    ``plan(params, actor_state, observation, key) -> actor_state`` sees the same params and
    observation as the ``act`` that follows it. The wrapped actor's state is
    :class:`Replanned` (``inner_state`` reads the wrapped one)."""
    every = int(every_steps)
    if every < 0:
        raise ValueError(f"replanning: every_steps must be >= 0, got {every_steps}")

    def init(key, observation) -> Replanned:
        return Replanned(inner=actor.init(key, observation), steps=jnp.zeros((), jnp.int32))

    def act(params, state: Replanned, observation, key):
        due = state.steps == 0 if every == 0 else state.steps % every == 0
        replan = lambda s: plan(params, s, observation, jax.random.fold_in(key, PLAN_FOLD))  # only when due
        inner = jax.lax.cond(due, replan, lambda s: s, state.inner)
        action, inner = actor.act(params, inner, observation, key)
        return action, Replanned(inner=inner, steps=state.steps + 1)

    return Actor(init=init, act=act, name=actor.name)


def inner_state(state: ActorState) -> ActorState:
    """The innermost actor's state of ``state`` (through any :func:`replanning`)."""
    while isinstance(state, Replanned):
        state = state.inner
    return state


@struct.dataclass
class Driver:
    """An actor and its params as one pytree (what the warehouse rollout and protocol take).

    Attributes:
      actor: the :class:`Actor` (static: part of the tree's structure, so two drivers with the
        same actor and params of the same shapes share a compiled program).
      params: its params (traced leaves).
    """

    actor: Actor = struct.field(pytree_node=False)
    params: Params = None
