"""The control loop of both worlds: act on the observation, step the world, record; one ``lax.scan``.

The warehouse day (:func:`jaxsim.rollout.run_samples`), seed 000's protocol
(:mod:`evaluation.protocol`), the arena's episode (:func:`jaxsim.scenes.actor.rollout`) and PPO's
rollouts (:func:`planners.learning.policy_training.make_collect`: a batch of episodes that restart
as they end, as one world) drive their robot through :func:`control_loop`; only the world's step
differs::

    for key in keys:
        action, actor_state = actor.act(params, actor_state, observation, key)
        state, timestep = step(state, action)
        records.append(record(observation, action, actor_state, timestep))
        observation = timestep.observation

``step(state, action) -> (state, timestep)`` is a world's transition with its static parts bound
(the arena's :meth:`jaxsim.scenes.env.Env.step`; the warehouse's
:func:`jaxsim.step.env_step`, bound to its world and seed); ``timestep`` is any pytree with an
``observation`` field (the arena's :class:`~jaxsim.scenes.env.TimeStep` also carries the reward
and what the metrics read). Where the observation is a function of the state alone (the
warehouse's and the protocol's: the robot and the workers' positions), the caller passes that
function as ``observe`` and the loop computes it at each step instead of carrying it from the
step before: a carried observation is a second copy of arrays the state holds, which cost the
warehouse's compiled step ten buffer copies a step (measured on its optimised HLO; with
``observe`` it is the program the day ran before it had a shared loop, op for op). The arena's
observation is made by its step (the perception's tracks), so it is carried. The loop knows
nothing of planning (a stack that plans at a slower
rate is an actor wrapped by :func:`jaxsim.actor.replanning`), of resets or of batches (``vmap``
it over episodes or worlds).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import jax
from flax import struct

from socialnav.jaxsim.actor import Actor, ActorState, Observation, Params
from socialnav.jaxsim.precision import require_float32

Step = Callable[[Any, Any], tuple[Any, Any]]


@struct.dataclass
class Observed:
    """A timestep that carries the actor's next observation and nothing else (the warehouse's
    and the protocol's steps return it; the arena's :class:`~jaxsim.scenes.env.TimeStep` carries
    more)."""

    observation: Observation


Record = Callable[[Observation, Any, ActorState, Any], Any]


def control_loop(
    step: Step,
    actor: Actor,
    params: Params,
    state,
    observation: Observation | None,
    actor_state: ActorState,
    keys: jax.Array,
    record: Record | None = None,
    observe: Callable[[Any], Observation] | None = None,
) -> tuple[tuple[Any, Observation, ActorState], Any]:
    """``len(keys)`` control steps of ``actor`` (with ``params``) in the world ``step`` moves.

    Args:
      step: ``(state, action) -> (state, timestep)``; ``timestep.observation`` is what the actor
        sees next.
      state, observation, actor_state: where the loop starts (the observation of ``state``).
      keys: (T,) the actor's key at each step.
      record: ``(observation acted on, action, actor state after it, timestep) -> pytree``, kept
        for every step; None keeps nothing (the warehouse measures between loops instead).
      observe: ``state -> observation`` where the observation is a function of the state alone:
        then computed at each step instead of carried (``observation`` and
        ``timestep.observation`` are not read, XLA drops what computed the latter, and the
        observation returned is None).

    Returns:
      ``((state, observation, actor_state) after T steps, records)``: the records stacked over
      the T steps (None without ``record``).
    """
    require_float32("jaxsim.control.control_loop")

    def control(carry, key):
        state, observation, actor_state = carry
        if observe is not None:
            observation = observe(state)
        action, actor_state = actor.act(params, actor_state, observation, key)
        state, timestep = step(state, action)
        kept = None if record is None else record(observation, action, actor_state, timestep)
        return (state, None if observe is not None else timestep.observation, actor_state), kept

    return jax.lax.scan(control, (state, None if observe is not None else observation, actor_state), keys)
