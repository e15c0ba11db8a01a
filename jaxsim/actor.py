"""Actors: whatever drives the robot (a navigation stack, a route follower, a reactive rule, a
learned policy, a user's own function), passed into a rollout, never written inside the physics.
One kind for both worlds of the toolkit: the arena's scenes (:mod:`jaxsim.scenes.actor`, action
``(v, omega)``) and the warehouse day and protocol (:mod:`jaxsim.step`, action
:class:`jaxsim.robot.RobotCommand`).

An :class:`Actor` is two pure functions and two static numbers::

    init(key, observation) -> actor_state
    act(params, actor_state, observation, key) -> (action, actor_state)

``params`` is any pytree (weights, layer parameters, the map or plan the actor was given); its
leaves are traced, so a new checkpoint or a parameter sweep does not recompile. ``actor_state``
is any pytree of fixed shapes (a path, a recurrent state, a filter).

A stack that replans at a slower rate adds ``plan(params, actor_state, observation, key) ->
actor_state`` and ``plan_every_steps`` (the arena's rollout runs it; see
:func:`jaxsim.scenes.actor.rollout`).

A :class:`Driver` is an actor with its params, the one pytree a rollout takes: the actor is its
static part (the compiled program's cache key), the params its leaves.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import jax
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
      plan: optional ``(params, actor_state, observation, key) -> actor_state`` run every
        ``plan_every_steps`` control steps (0: once, at the start).
      name: shown in tables and errors.
    """

    init: Callable[[jax.Array, Observation], ActorState]
    act: Callable[[Params, ActorState, Observation, jax.Array], tuple[Action, ActorState]]
    plan: Callable[[Params, ActorState, Observation, jax.Array], ActorState] | None = None
    plan_every_steps: int = 1
    name: str = "actor"


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
