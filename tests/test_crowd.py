"""The crowd's step: one function for the warehouse and the arena; ORCA as the other human model."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from socialnav.data import DATA_DIR
from socialnav.evaluation.arena import episodes as arena
from socialnav.jaxsim import crowd, orca, rng
from socialnav.jaxsim.grid import Grid
from socialnav.jaxsim.scenario import load_scenario
from socialnav.jaxsim.scenes import people as people_lib
from socialnav.jaxsim.scenes.spec import load_scene
from socialnav.jaxsim.scenes.variant import sample_variant
from socialnav.jaxsim.walkers import Aims, RobotDisc, Walkers

# No walls within reach: a distance field 100 m from everything.
OPEN = Grid.of_samples(jnp.tile(jnp.array([100.0, 1.0, 0.0]), (4, 4, 1)), -50.0, -50.0, 30.0)
FAR_ROBOT = RobotDisc(jnp.float32(100.0), jnp.float32(100.0), jnp.float32(0.0), jnp.float32(0.0), 0.3)


@pytest.fixture(scope="module")
def params():
    return load_scenario().params


@pytest.mark.slow
def test_the_warehouse_and_the_arena_move_people_with_one_function(monkeypatch, short_day, params):
    from socialnav.jaxsim import humans
    from socialnav.jaxsim import step as step_lib

    calls = []
    original = crowd.step_crowd

    def counted(params, wall_field, dt, people, *args):
        calls.append(people.ignores_robot is not None)
        return original(params, wall_field, dt, people, *args)

    monkeypatch.setitem(humans.STEPS, "social_force", counted)
    scenario, world, controller = short_day
    state = step_lib.init_state(scenario.params, world, controller, jax.random.key(0))
    workers, robot = state.workers, state.robot
    u = jnp.full((6, workers.x_m.shape[0]), 0.5)
    step_lib.crowd_step(scenario.params, world, workers, robot, jnp.float32(0.0), jnp.int32(0), u)
    setup = arena.setup_scene(load_scene(DATA_DIR / "scenes" / "casn_head_on.json"))
    variant = jax.tree_util.tree_map(jnp.asarray, sample_variant(setup.spec, 0, 0))
    people = people_lib.init_people(variant)
    robot_at_rest = RobotDisc.of(jnp.zeros(2), jnp.zeros(2), 0.3)
    constants = humans.human_params("social_force", params)
    people_lib.step_people("social_force", constants, setup.env.world, variant, people, robot_at_rest, jnp.int32(0))
    assert calls == [False, True]  # the warehouse's workers all feel the robot; the arena's may not


@pytest.mark.parametrize("model", ["collision_free_speed_calibrated", pytest.param("orca", marks=pytest.mark.slow)])
def test_the_warehouse_and_the_arena_move_people_by_the_chosen_human_model(monkeypatch, short_day, params, model):
    from socialnav.jaxsim import humans
    from socialnav.jaxsim import step as step_lib
    from socialnav.jaxsim.state import WALKING
    from socialnav.jaxsim.world import build_world

    calls = []
    original = humans.step_humans
    monkeypatch.setattr(humans, "step_humans", lambda m, *a, **k: calls.append(m) or original(m, *a, **k))
    scenario, sf_world, controller = short_day
    world = build_world(scenario, model)
    state = step_lib.init_state(scenario.params, world, controller, jax.random.key(0))
    u = jnp.full((6, state.workers.x_m.shape[0]), 0.5)
    # Two workers walking, 0.3 m apart: the chosen model moves them, not the social force.
    w = state.workers.replace(
        x_m=state.workers.x_m.at[:2].set(jnp.array([10.0, 10.3])),
        y_m=state.workers.y_m.at[:2].set(10.0),
        status=state.workers.status.at[:2].set(WALKING),
    )
    args = (jnp.float32(0.0), jnp.int32(0), u)
    # Each step compiled as one program (as the rollouts run it), not op by op.
    chosen = jax.jit(lambda w: step_lib.crowd_step(scenario.params, world, w, state.robot, *args))(w)
    social = jax.jit(lambda w: step_lib.crowd_step(scenario.params, sf_world, w, state.robot, *args))(w)
    assert not np.allclose(np.asarray(chosen.x_m[:2]), np.asarray(social.x_m[:2]), atol=1e-4)
    setup = arena.setup_scene(load_scene(DATA_DIR / "scenes" / "casn_head_on.json"), arena.ArenaConfig.of(model))
    variant = jax.tree_util.tree_map(jnp.asarray, sample_variant(setup.spec, 0, 0))
    constants = humans.human_params(model, params, setup.env.orca)
    robot_at_rest = RobotDisc.of(jnp.zeros(2), jnp.zeros(2), 0.3)
    jax.jit(lambda v: people_lib.step_people(model, constants, setup.env.world, v, people_lib.init_people(v),
                                             robot_at_rest, jnp.int32(0)))(variant)  # fmt: skip
    assert calls == [model, "social_force", model]
    with pytest.raises(ValueError, match="human model must be one of"):
        build_world(scenario, "helbing")


@pytest.mark.parametrize(
    "model",
    ["social_force", "collision_free_speed"]
    + [pytest.param(m, marks=pytest.mark.slow) for m in ("orca", "steering_speed", "anticipation", "power_law")],
)
def test_every_human_model_steps_the_one_signature_and_keeps_who_does_not_move(params, model):
    from socialnav.jaxsim import humans

    assert set(humans.STEPS) == {humans.kind_of(m) for m in humans.HUMAN_MODELS} == set(humans.PARAMS_OF)
    n = 5
    people = Walkers(
        jnp.array([0.0, 1.0, 2.0, 0.5, 4.0]), jnp.array([0.0, 0.6, -0.4, 1.5, 0.0]), jnp.full(n, 0.8), jnp.zeros(n),
        present=jnp.array([True, True, True, True, False]), moving=jnp.array([True, False, True, False, False]),
        ignores_robot=jnp.array([False, False, True, False, False]),
    )  # fmt: skip
    aims = Aims(jnp.full(n, 6.0), jnp.zeros(n), jnp.full(n, 1.2), jnp.full(n, 1.2))
    robot = RobotDisc(jnp.float32(2.5), jnp.float32(0.0), jnp.float32(-0.5), jnp.float32(0.0), 0.3)
    bundle = humans.human_params(model, params)
    step = jax.jit(
        lambda p: humans.step_humans(model, bundle, OPEN, p, aims, robot, (jnp.full(n, 0.3), jnp.full(n, 0.7)))
    )
    after = step(people)
    assert isinstance(after, Walkers) and after.x_m.shape == (n,)
    for flag in ("present", "moving", "ignores_robot"):
        np.testing.assert_array_equal(np.asarray(getattr(after, flag)), np.asarray(getattr(people, flag)))
    still = ~np.asarray(people.moving)  # who does not move keeps their place, at velocity 0
    np.testing.assert_array_equal(np.asarray(after.xy_m)[still], np.asarray(people.xy_m)[still])
    np.testing.assert_array_equal(np.asarray(after.velocity_mps)[still], 0.0)
    walked = np.asarray(after.x_m - people.x_m)[[0, 2]]
    assert np.all(walked > 0.0) and np.all(walked <= 1.2 * params.dt_s + 1e-6)  # towards the aim, within its speed


def test_a_person_walking_into_a_wall_stops_at_the_clearance_without_velocity_into_it(params):
    # A wall whose surface is the line x = 0, the free side x > 0: distance x, normal +x.
    xs = np.arange(-1.0, 3.01, 0.05, dtype=np.float32)
    field = np.zeros((3, len(xs), 3), np.float32)
    field[..., 0] = xs[None, :]
    field[..., 1] = 1.0
    wall = Grid.of_samples(jnp.asarray(field), -1.0, -0.05, 0.05)
    one = jnp.ones(1, bool)
    person = Walkers(jnp.array([1.0]), jnp.array([0.0]), jnp.array([-1.5]), jnp.array([0.0]), one, one)
    uniforms = (jnp.array([0.5]), jnp.array([0.25]))
    aims = Aims(jnp.array([-5.0]), jnp.array([0.0]), jnp.array([1.5]), jnp.array([1.5]))  # into the wall
    for _ in range(40):
        person = crowd.step_crowd(params, wall, params.dt_s, person, aims, FAR_ROBOT, uniforms)
        assert float(person.x_m[0]) >= crowd.WALL_CLEARANCE_M - 1e-6
    # One step that would cross the clearance (no wall force to slow it): pushed back onto the
    # clearance, the velocity into the wall removed.
    person = person.moved(jnp.array([0.15]), person.y_m, jnp.array([-1.5]), person.vy_mps)
    no_wall_force = params.replace(worker_obstacle_force_factor=0.0)
    person = crowd.step_crowd(no_wall_force, wall, params.dt_s, person, aims, FAR_ROBOT, uniforms)
    assert float(person.x_m[0]) == pytest.approx(crowd.WALL_CLEARANCE_M, abs=1e-6)
    assert float(person.vx_mps[0]) == pytest.approx(0.0, abs=1e-6)


@pytest.mark.slow
def test_a_person_who_ignores_the_robot_moves_as_if_it_were_not_there(params):
    people = Walkers(
        jnp.array([0.0, 3.0]), jnp.array([0.0, 0.0]), jnp.array([0.8, 0.0]), jnp.array([0.0, 0.0]),
        present=jnp.ones(2, bool), moving=jnp.array([True, False]),
    )  # fmt: skip
    aims = Aims(jnp.array([5.0, 0.0]), jnp.array([0.0, 0.0]), jnp.full(2, 1.2), jnp.full(2, 1.2))
    u = rng.hash_uniform16(jnp.uint32(7), jnp.int32(3), (2, 2))
    near = RobotDisc(jnp.float32(1.0), jnp.float32(0.2), jnp.float32(-0.5), jnp.float32(0.0), 0.3)
    felt = crowd.step_crowd(params, OPEN, params.dt_s, people, aims, near, (u[0], u[1]))
    blind = people.replace(ignores_robot=jnp.ones(2, bool))
    ignored = crowd.step_crowd(params, OPEN, params.dt_s, blind, aims, near, (u[0], u[1]))
    absent = crowd.step_crowd(params, OPEN, params.dt_s, people, aims, FAR_ROBOT, (u[0], u[1]))
    assert abs(float(felt.vx_mps[0] - absent.vx_mps[0])) > 1e-3  # the robot 1 m ahead pushes
    np.testing.assert_allclose(np.asarray(ignored.velocity_mps), np.asarray(absent.velocity_mps), atol=1e-6)
    np.testing.assert_allclose(np.asarray(ignored.xy_m), np.asarray(absent.xy_m), atol=1e-6)


def _orca_run(x, y, aim_x, aim_y, moving, steps):
    p = orca.ORCAParams()
    n = x.shape[0]

    @jax.jit
    def step(people):
        aims = Aims(aim_x - people.x_m, aim_y - people.y_m, jnp.ones(n), jnp.ones(n))
        return orca.step_orca(p, OPEN, 0.1, people, aims, FAR_ROBOT)

    people = Walkers(x, y, jnp.zeros(n), jnp.zeros(n), jnp.ones(n, bool), moving)
    gaps = []
    for _ in range(steps):
        people = step(people)
        gaps.append(float(jnp.hypot(people.x_m[0] - people.x_m[1], people.y_m[0] - people.y_m[1])))
    return people.x_m, people.y_m, people.vx_mps, people.vy_mps, np.array(gaps)


@pytest.mark.slow
def test_orca_two_people_head_on_swap_without_contact():
    x, y = jnp.array([-3.0, 3.0]), jnp.array([0.05, -0.05])
    x, y, _, _, gaps = _orca_run(x, y, jnp.array([3.0, -3.0]), jnp.array([0.05, -0.05]), jnp.ones(2, bool), 120)
    np.testing.assert_allclose(np.asarray(x), [3.0, -3.0], atol=0.05)  # swapped
    assert gaps.min() >= 2 * orca.ORCAParams().radius_m  # bodies never overlap


def test_orca_a_person_stops_before_a_standing_one():
    x, y = jnp.array([-3.0, 0.0]), jnp.array([0.0, 0.0])
    x, _, vx, vy, gaps = _orca_run(x, y, jnp.zeros(2), jnp.zeros(2), jnp.array([True, False]), 300)
    assert gaps.min() >= 2 * orca.ORCAParams().radius_m
    assert float(jnp.hypot(vx[0], vy[0])) < 0.05 and float(x[1]) == 0.0  # stopped; the standing one stayed


@pytest.mark.slow
def test_the_arena_runs_with_orca_humans():
    from socialnav.planners import actors

    spec = load_scene(DATA_DIR / "scenes" / "casn_head_on.json")
    sf = arena.setup_scene(spec)
    oc = arena.setup_scene(spec, arena.ArenaConfig.of("orca"))
    variants = jax.tree_util.tree_map(jnp.asarray, sample_variant(spec, 0, 0, n_slots=sf.n_slots))
    variants = jax.tree_util.tree_map(lambda a: a[None], variants)
    actor = actors.go_to_goal()
    a = arena.actor_function(sf, actor, sf.env.robot)(variants)
    b = arena.actor_function(oc, actor, oc.env.robot)(variants)
    assert not np.allclose(np.asarray(a.people_xy_m), np.asarray(b.people_xy_m))
    walked = np.linalg.norm(np.asarray(b.people_xy_m)[0, -1, 0] - np.asarray(b.people_xy_m)[0, 0, 0])
    assert walked > 3.0  # the walker crossed the room
