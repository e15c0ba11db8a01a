"""The queue scene (seed 002 Sec. 5.2.5/5.3.5) as the arena runs it: the stop-and-go every
method gets there (planners.actors.with_stop_and_go), the people left to the social layer by the
global planner (people_in_global_plan false) but for those inside the local costmap's window,
and the queue rule (jaxsim/scenes/rule_monitor.py)
on whole episodes: a robot that joins the line at its tail and advances with it obeys the rule
and reaches the goal in time; one that drives straight to the desk cuts in."""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from socialnav.data import SCENES_DIR
from socialnav.evaluation.arena import episodes as arena
from socialnav.evaluation.arena import nav_metrics
from socialnav.jaxsim.scenes import people
from socialnav.jaxsim.scenes.actor import Actor
from socialnav.jaxsim.scenes.env import Observation
from socialnav.jaxsim.scenes.spec import load_scene, mirror
from socialnav.jaxsim.scenes.variant import sample_variants
from socialnav.models import grid
from socialnav.models import social_costs as sc
from socialnav.planners import actors, layers
from socialnav.planners.stack import METHODS


def _observation(people_xy, yaw=0.0, robot_xy=(0.0, 0.0), goal=(5.0, 0.0)):
    n = len(people_xy)
    return Observation(
        robot_xy_m=jnp.asarray(robot_xy, jnp.float32),
        robot_yaw_rad=jnp.float32(yaw),
        robot_speed_mps=jnp.float32(0.5),
        robot_turn_rate_rps=jnp.float32(0.0),
        goal_xy_m=jnp.asarray(goal, jnp.float32),
        people_xy_m=jnp.asarray(people_xy, jnp.float32).reshape(n, 2),
        people_heading_rad=jnp.zeros(n, jnp.float32),
        people_velocity_mps=jnp.zeros((n, 2), jnp.float32),
        people_visible=jnp.ones(n, bool),
        occupancy=jnp.zeros((0, 0), jnp.float32),
        time_s=jnp.float32(0.0),
    )


def _forward(params, st, obs, key):
    del params, obs, key
    return jnp.array([0.5, 0.25], jnp.float32), st


FORWARD = Actor(init=lambda key, obs: (), act=_forward, name="forward")


@pytest.mark.parametrize(
    "person, stops",
    [
        ((0.8, 0.0), True),  # the next person in line, 0.8 m ahead
        ((0.5, 0.6), True),  # ahead, 50 deg off the heading (a neighbour in line stepped aside)
        ((1.2, 0.0), False),  # ahead but the gap is open
        ((0.0, 0.8), False),  # beside, not ahead
        ((-0.5, 0.0), False),  # behind
    ],
)
def test_stop_and_go_holds_the_forward_speed_for_the_next_person_in_line(person, stops):
    wrapped = actors.with_stop_and_go(FORWARD, 0.9)
    action, _ = wrapped.act(None, (), _observation([person]), jax.random.PRNGKey(0))
    assert float(action[0]) == (0.0 if stops else 0.5)
    assert float(action[1]) == 0.25  # turning is the actor's
    assert wrapped is actors.with_stop_and_go(FORWARD, 0.9)  # cached: one compiled program


@pytest.mark.slow
def test_the_global_planner_leaves_the_people_to_the_social_layer_when_the_scene_says_so():
    """navfn (no social layer) from (0, 0) to (3.8, 0) with a person at (2, 0): round them when
    people are obstacles (the default), straight through their place when they are not."""
    setup = arena.setup_scene(load_scene(SCENES_DIR / "gscl_queue.json"))
    actor = actors.stack_parts(METHODS["navfn"], setup.grid, 0.275)  # its plan alone
    obs = _observation([(2.0, 0.0)], goal=(3.8, 0.0)).replace(robot_xy_m=jnp.array([0.0, 0.0], jnp.float32))
    offsets = {}
    for seen in (True, False):
        params = actors.stack_params(setup.env.robot, setup.map, people_are_obstacles=seen)
        st = actor.plan(params, actor.init(jax.random.PRNGKey(0), obs), obs, jax.random.PRNGKey(0))
        path = np.asarray(st.path[: int(st.path_len)])
        offsets[seen] = np.abs(path[:, 1]).max()
    assert offsets[True] > 0.4  # at least a body and the robot's radius off the person's centre
    assert offsets[False] < 0.15  # the straight line, to a cell
    # A person inside the local costmap's window (1.5 m, Nav2's 3 m x 3 m) is an obstacle either way:
    # the path the robot follows is the one its controller would keep clear of them.
    near = _observation([(1.2, 0.0)], goal=(3.8, 0.0)).replace(robot_xy_m=jnp.array([0.0, 0.0], jnp.float32))
    params = actors.stack_params(setup.env.robot, setup.map, people_are_obstacles=False)
    assert float(params.local_costmap_half_m) == actors.LOCAL_COSTMAP_HALF_M == 1.5
    st = actor.plan(params, actor.init(jax.random.PRNGKey(0), near), near, jax.random.PRNGKey(0))
    assert np.abs(np.asarray(st.path[: int(st.path_len)])[:, 1]).max() > 0.4


def _band_costs(level):
    """A GSCL network's stand-in (:func:`planners.layers.gscl`): a band of ``level`` across the
    way 1.6-2.4 m ahead of the robot (|y| < 2 m), with one 0.4 m cell open at y 0-0.4 m, in the
    network's 40 x 40 window."""
    x, y = np.asarray(grid.CELL_X_M), np.asarray(grid.CELL_Y_M)
    band = (x > 1.7) & (x < 2.3) & (np.abs(y) < 2.0) & ~np.isclose(y, 0.2)
    costs = jnp.asarray(np.where(band, level, 0.0), jnp.float32)
    return lambda maps: jnp.broadcast_to(costs, maps.shape)


@pytest.mark.slow
def test_a_forbidden_social_cost_is_inflated_with_the_walls_and_a_graded_one_is_not():
    """The gscl stack from (0, 0) to (3.8, 0) with a social band across the way and a 0.4 m gap in
    it: forbidden (lethal, then inflated by the robot's radius) the gap is closed and the plan goes
    round the band's end; at the top of the graded range the plan goes straight on."""
    setup = arena.setup_scene(load_scene(SCENES_DIR / "gscl_queue.json"))
    obs = _observation([(-5.0, 3.0)], goal=(3.8, 0.0))
    widest = {}
    for level in (sc.FORBIDDEN, sc.GRADED_TOP):
        layer = layers.gscl(_band_costs(level))
        params = actors.stack_params(setup.env.robot, setup.map, layer=layer, people_are_obstacles=False)
        actor = actors.stack_parts(METHODS["gscl"], setup.grid, 0.275, layer=layer)
        st = actor.plan(params, actor.init(jax.random.PRNGKey(0), obs), obs, jax.random.PRNGKey(0))
        path = np.asarray(st.path[: int(st.path_len)])
        assert np.linalg.norm(path[-1] - [3.8, 0.0]) < 0.1, level
        widest[level] = np.abs(path[:, 1]).max()
        if level == sc.FORBIDDEN:  # never within the robot's radius of a forbidden cell
            in_x = (path[:, 0] > 1.6 - 0.275) & (path[:, 0] < 2.4 + 0.275)
            assert np.all(np.abs(path[in_x, 1]) > 2.0 + 0.275 - 0.06)
    assert widest[sc.FORBIDDEN] > 2.2
    assert widest[sc.GRADED_TOP] < 1.0


def _queue_then_goal(behind_xy):
    """An actor that drives to ``behind_xy`` (behind the line's tail), then along the line to
    the goal: it relies on the scene's stop-and-go to wait its turn."""

    def init(key, obs):
        del key, obs
        return jnp.int32(0)

    def act(robot, leg, obs, key):
        del key
        waypoint = jnp.asarray(behind_xy, jnp.float32)
        leg = jnp.where(jnp.linalg.norm(obs.robot_xy_m - waypoint) < 0.3, 1, leg)
        target = jnp.where(leg == 0, waypoint, obs.goal_xy_m)
        to = target - obs.robot_xy_m
        error = jnp.arctan2(to[1], to[0]) - obs.robot_yaw_rad
        error = jnp.arctan2(jnp.sin(error), jnp.cos(error))
        v = robot.max_speed_mps * jnp.clip(jnp.cos(error), 0.0, 1.0) ** 4
        return jnp.stack([v, 2.0 * error]).astype(jnp.float32), leg

    return Actor(init=init, act=act, name="queue_then_goal")


@pytest.mark.slow
@pytest.mark.parametrize("held_out", [False, True])
def test_joining_at_the_tail_obeys_the_queue_rule_and_driving_to_the_desk_does_not(held_out):
    spec = load_scene(SCENES_DIR / "gscl_queue.json")
    if held_out:
        spec = mirror(spec)
    setup = arena.setup_scene(spec)
    n = 6
    variants = jax.tree_util.tree_map(jnp.asarray, sample_variants(spec, 0, n, 0, held_out, setup.n_slots))
    behind = (-1.2, float(spec.robot["goal"][1][0]))  # behind the longest line (its tail at -0.2 m)

    def verdicts(actor):
        tr = arena.actor_function(setup, actor, setup.env.robot)(variants)
        ok = jax.vmap(nav_metrics.rule_satisfied, in_axes=(None, 0, 0, 0, 0, 0, 0, 0))(
            spec.rule,
            tr.robot_xy_m,
            tr.reached,
            tr.people_xy_m,
            variants.start_xy,
            variants.end_xy,
            tr.people_present,
            variants.group,
        )
        return np.asarray(tr.reached[:, -1]), np.asarray(ok), tr

    reached, ok, tr = verdicts(_queue_then_goal(behind))
    assert reached.all() and ok.all()
    # It waited its turn: in the scene's own lines (3-5 people, one served every 5-8 s) it
    # stood behind someone for several seconds.
    at = np.argmax(np.asarray(tr.reached), axis=1)
    stood_s = [0.1 * np.sum(np.asarray(tr.robot_speed_mps[k, : at[k]]) < 0.02) for k in range(n)]
    assert held_out or min(stood_s) > 3.0  # this actor never stops of itself
    reached, ok, tr = verdicts(actors.go_to_goal())
    # Straight to the desk: never a social success while someone still waits in line when it
    # arrives (a held-out line can be short and served quickly enough to be gone by then).
    at = np.argmax(np.asarray(tr.reached), axis=1)
    people = np.asarray(tr.people_xy_m)[np.arange(n), at]
    waiting = (np.asarray(tr.people_present)[np.arange(n), at] & (np.abs(people[..., 1]) < 0.6)).any(axis=1)
    assert waiting.all() or held_out
    assert not (ok & reached & waiting).any()
    # Without the stop-and-go the same queueing actor walks into the line's last person (the
    # held-out lines are short and served before it gets there).
    if not held_out:
        setup = arena.setup_scene(dataclasses.replace(spec, stop_and_go_m=None))
        _, ok, _ = verdicts(_queue_then_goal(behind))
        assert not ok.any()


@pytest.mark.slow
def test_the_line_steps_up_from_the_front_and_stays_in_line():
    """people.queue_place: the head is served every interval and each place behind steps up
    QUEUE_STEP_UP_DELAY_S after the one ahead; in a run (the robot far away) the people waiting
    stay on the line's axis and the served ones leave."""
    spec = load_scene(SCENES_DIR / "gscl_queue.json")
    setup = arena.setup_scene(spec)
    v = sample_variants(spec, 0, 1, 0, False, setup.n_slots)
    one = jax.tree_util.tree_map(lambda a: jnp.asarray(a[0]), v)
    interval, delay = float(one.queue_interval_s[0]), people.QUEUE_STEP_UP_DELAY_S
    n = int(one.valid.sum())
    for t, want in [
        (0.0, np.arange(n)),
        (interval - 0.01, np.arange(n)),  # nobody served yet
        (interval + 0.01, np.arange(n) - np.eye(n, dtype=int)[0]),  # the head is served; the rest not yet moved
        (interval + delay + 0.01, np.arange(n) - (np.arange(n) < 2)),  # the second has stepped up
    ]:
        np.testing.assert_array_equal(np.asarray(people.queue_place(one, t))[:n], want, err_msg=f"t = {t}")
    variants = jax.tree_util.tree_map(jnp.asarray, sample_variants(spec, 0, 4, 0, False, setup.n_slots))
    run = arena.counterfactual_function(setup)(variants)
    place = jax.vmap(jax.vmap(people.queue_place, in_axes=(None, 0)), in_axes=(0, None))(
        variants, jnp.arange(run.people_xy_m.shape[1]) * 0.1
    )
    waiting = np.asarray(place >= 0) & np.asarray(run.people_present) & np.asarray(variants.valid)[:, None]
    assert np.abs(np.asarray(run.people_xy_m)[..., 1])[waiting].max() < 0.01  # on the axis y = 0
    assert not np.asarray(run.people_present)[:, -1].any()  # everyone served by the timeout
