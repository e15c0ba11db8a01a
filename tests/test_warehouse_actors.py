"""The warehouse's robot driven by actors (jaxsim/actor.py): the route follower and the causal
planner as actors, a user's own actor through the day and the protocol, and the docs'
quickstart."""

from __future__ import annotations

import pathlib
import re

import jax.numpy as jnp
import numpy as np
import pytest

from socialnav.evaluation import protocol as ex
from socialnav.evaluation.outcomes import CONGESTION, NOT_RUN, SUCCESS
from socialnav.jaxsim.actor import Actor, Driver
from socialnav.jaxsim.robot import RobotCommand
from socialnav.jaxsim.rollout import rollout, to_numpy
from socialnav.jaxsim.route_follower import route_follower
from socialnav.jaxsim.scenario import load_scenario
from socialnav.jaxsim.world import build_world
from socialnav.planners.warehouse.actors import causal_planner
from socialnav.planners.warehouse.routes import shortest_path_plan

SIMULATOR_PAGE = pathlib.Path(__file__).parent.parent / "docs" / "simulator.md"


def _stand_still(key, obs):
    return ()


def _aim_where_it_stands(params, state, obs, key):
    r = obs.robot
    return RobotCommand(aim_x_m=r.x_m, aim_y_m=r.y_m, speed_mps=jnp.float32(0.5), planned_length_m=0.0), state


STAND_STILL = Actor(init=_stand_still, act=_aim_where_it_stands, name="stand_still")


@pytest.fixture(scope="module")
def quiet():
    """Nobody inside, no obstacles, 4 tasks per slot."""
    scenario = load_scenario(n_workers=0, robot_obstacle_probability=0.0)
    world = build_world(scenario)
    return scenario, world.replace(robot_goal_count=jnp.minimum(world.robot_goal_count, 4))


def test_an_actor_that_never_moves_fails_every_task_on_the_hop_deadline(quiet):
    """Reaching the point it stands on is no progress: the hop deadline still runs out."""
    scenario, world = quiet
    slots = np.array([0, 0])
    cfg = ex.ProtocolConfig.for_params(scenario.params, warmup_s=1.0, arrival_spread_s=1.0)
    state = ex.run_experiments(
        scenario.params, world, Driver(STAND_STILL), slots, ex.experiment_keys(0, slots, np.arange(2)), cfg
    )
    log = state.log
    assert (log.outcome[:, :4] == CONGESTION).all() and (log.outcome[:, 4:] == NOT_RUN).all()
    # The first step's aim (where it stands) is reached once, a new point: the clock restarts
    # then, and never again.
    deadline, dt = scenario.params.robot_leg_deadline_s, scenario.params.dt_s
    assert ((log.time_s[:, :4] >= deadline) & (log.time_s[:, :4] <= deadline + 2 * dt + 1e-3)).all()
    assert (log.distance_m[:, :4] == 0).all()


def test_the_day_robot_of_an_actor_that_never_moves_stays_at_its_start(quiet):
    scenario, world = quiet
    _, rec = rollout(
        scenario.params, world, Driver(STAND_STILL), seed=0, n_worlds=2, n_steps=300, sample_every_steps=10
    )
    rec = to_numpy(rec)
    start = scenario.waypoint_xy_m[scenario.robot_start]
    assert np.allclose(rec.robot_x_m, start[0]) and np.allclose(rec.robot_y_m, start[1])
    assert (rec.tasks_succeeded == 0).all() and (rec.tasks_started == 1).all()  # the first leg never ends


@pytest.mark.slow
def test_the_commanded_speed_is_capped_and_slows_the_robot(quiet):
    scenario, world = quiet
    follower = route_follower(shortest_path_plan(scenario), world)

    def at(speed):
        def act(params, state, obs, key):
            command, state = follower.actor.act(params, state, obs, key)
            return command.replace(speed_mps=jnp.float32(speed)), state

        driver = Driver(Actor(init=follower.actor.init, act=act, name=f"speed {speed}"), follower.params)
        _, rec = rollout(scenario.params, world, driver, seed=0, n_worlds=2, n_steps=400, sample_every_steps=2)
        return to_numpy(rec).robot_speed_mps

    assert at(0.2).max() == pytest.approx(0.2) and at(9.0).max() == pytest.approx(scenario.params.robot_max_speed_mps)


@pytest.mark.slow
def test_the_causal_planner_refuses_by_eq_10_and_the_follower_never(quiet):
    """With a predicted cost of 85 % every task is refused (the battery reset first); with 0 none."""
    scenario, world = quiet
    plan = shortest_path_plan(scenario)
    slots = np.array([1, 1])
    keys = ex.experiment_keys(0, slots, np.arange(2))
    cfg = ex.ProtocolConfig.for_params(scenario.params, warmup_s=1.0, arrival_spread_s=1.0)
    costly = ex.run_experiments(
        scenario.params, world, causal_planner(plan, world, np.full(plan.hops.shape, 85.0)), slots, keys, cfg
    )
    free = ex.run_experiments(
        scenario.params, world, causal_planner(plan, world, np.zeros(plan.hops.shape)), slots, keys, cfg
    )
    follower = ex.run_experiments(scenario.params, world, route_follower(plan, world), slots, keys, cfg)
    assert costly.log.refused[:, :4].all() and not free.log.refused.any() and not follower.log.refused.any()
    assert (costly.log.outcome[:, :4] == SUCCESS).all()
    # Refusing changes only the battery: the same routes, times and distances as the follower.
    np.testing.assert_array_equal(free.log.time_s, follower.log.time_s)
    np.testing.assert_array_equal(costly.log.distance_m, follower.log.distance_m)


@pytest.mark.slow
def test_the_docs_warehouse_actor_quickstart_runs(capsys):
    text = SIMULATOR_PAGE.read_text()
    match = re.search(r"<!-- warehouse-actor-quickstart -->\s*```python\n(.*?)```", text, re.S)
    assert match, "docs/simulator.md: the warehouse actor quickstart is missing"
    exec(compile(match.group(1), "docs/simulator.md warehouse-actor-quickstart", "exec"), {})
    lines = dict(line.split(" ", 1) for line in capsys.readouterr().out.strip().splitlines())
    times = {name: float(re.search(r"mean task time ([\d.]+) s", rest).group(1)) for name, rest in lines.items()}
    assert set(times) == {"follower", "cautious"} and times["cautious"] > times["follower"]
