"""The simulators run in float32 and say so under JAX's x64 switch (:mod:`jaxsim.precision`)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from socialnav.evaluation.humans import validation
from socialnav.jaxsim import control, humans
from socialnav.jaxsim.actor import Actor
from socialnav.jaxsim.scenario import load_scenario
from socialnav.jaxsim.walkers import Aims, RobotDisc, Walkers


def _step_three_people():
    params = humans.human_params("social_force", load_scenario().params)
    everyone = jnp.ones(3, bool)
    people = Walkers.of(jnp.array([[1.0, 0.6], [1.0, 1.2], [3.0, 0.9]]), jnp.zeros((3, 2)), everyone, everyone)
    aims = Aims(jnp.full(3, 5.0), jnp.zeros(3), jnp.full(3, 1.3), jnp.full(3, 1.3))
    robot = RobotDisc.of(jnp.array([8.0, 0.9]), jnp.array([-0.5, 0.0]), 0.3)
    field = validation.corridor_field(1.8, 10.0)
    return humans.step_humans("social_force", params, field, people, aims, robot, (jnp.full(3, 0.5), jnp.full(3, 0.5)))


def _count_to_three():
    actor = Actor(init=lambda key, obs: (), act=lambda params, state, obs, key: (jnp.float32(1.0), state))
    step = lambda state, action: (state + action, control.Observed(observation=state + action))
    (state, _, _), _ = control.control_loop(
        step, actor, None, jnp.float32(0.0), jnp.float32(0.0), (), jax.random.split(jax.random.key(0), 3)
    )
    return state


@pytest.mark.parametrize(
    "run, where", [(_step_three_people, "jaxsim.humans.step_humans"), (_count_to_three, "jaxsim.control.control_loop")]
)
def test_a_simulation_under_x64_says_how_to_run_it_and_runs_as_float32_when_told(run, where):
    """Under ``jax.enable_x64(True)`` the step of the people and the control loop of both worlds
    refuse in one sentence naming themselves and the way out; taken inside
    ``jax.enable_x64(False)`` (the way out) they give the float32 answer."""
    expected = run()
    with jax.enable_x64(True):
        with pytest.raises(RuntimeError, match=rf"^{where}: .*jax_enable_x64 is on.*'with jax\.enable_x64\(False\):'"):
            run()
        with jax.enable_x64(False):
            got = run()
    for a, b in zip(jax.tree.leaves(got), jax.tree.leaves(expected)):
        assert a.dtype == b.dtype and a.dtype != jnp.float64
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
