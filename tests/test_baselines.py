"""The reactive baselines (ORCA, the social-force robot, DWA): against a maintained reference
(navground's ORCA), against the crowd's own force, and in closed loop on the built-in scenes."""

from __future__ import annotations

import pathlib

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from socialnav.data import SCENES_DIR
from socialnav.evaluation.arena import episodes as arena
from socialnav.jaxsim import social_force as sf
from socialnav.jaxsim.scenes.env import Observation
from socialnav.jaxsim.scenes.robot import RobotParams
from socialnav.jaxsim.scenes.spec import load_scene
from socialnav.jaxsim.scenes.variant import sample_variants
from socialnav.planners.reactive import actor as reactive
from socialnav.planners.reactive import baselines, dwa, orca_robot, social_force_robot

FAR_WALL = np.array([[1e4, 1e4 + 1, 1e4, 1e4 + 1]], np.float32)  # no wall within reach

# (robot xy, robot velocity, target, [(person xy, person velocity)]): head-on, crossing, two
# people, a wall of three standing people ahead.
ORCA_CASES = [
    ((0.0, 0.0), (0.5, 0.0), (5.0, 0.0), [((2.0, 0.1), (-1.0, 0.0))]),
    ((0.0, 0.0), (0.5, 0.0), (5.0, 0.0), [((1.5, -1.5), (0.0, 1.0))]),
    ((0.0, 0.0), (0.3, 0.1), (5.0, 1.0), [((2.0, 0.3), (-1.0, 0.0)), ((1.5, -0.8), (0.0, 0.8))]),
    ((0.0, 0.0), (0.0, 0.0), (5.0, 0.0), [((1.0, y), (0.0, 0.0)) for y in (0.0, 0.6, -0.6)]),
    ((1.0, 2.0), (0.2, -0.3), (-3.0, -2.0), [((0.0, 1.0), (0.6, 0.6)), ((-1.0, 0.5), (0.3, 0.0))]),
]


def _orca(xy, velocity, target, people, walls=FAR_WALL, params=orca_robot.ORCARobotParams(safety_space_m=0.0)):
    xy = np.asarray(xy, np.float32)
    to = np.asarray(target, np.float32) - xy
    pref = to / np.linalg.norm(to) * 0.5
    pxy = np.array([p for p, _ in people], np.float32)
    pv = np.array([v for _, v in people], np.float32)
    out = orca_robot.orca_robot_velocity(
        params, jnp.asarray(xy), jnp.asarray(velocity, jnp.float32), jnp.asarray(pref), 0.5, 0.275, jnp.asarray(pxy),
        jnp.asarray(pv), 0.25, jnp.ones(len(people), bool), jnp.asarray(walls), 0.1,
    )  # fmt: skip
    return np.asarray(out)


@pytest.mark.slow
@pytest.mark.parametrize("case", range(len(ORCA_CASES)))
def test_orca_robot_velocity_equals_navgrounds_orca(case):
    """navground's ORCABehavior (RVO2's programs, holonomic kinematics, the same horizons and radii)
    gives the same velocity to float rounding. Not compared: two bodies already overlapping, where
    RVO2 (and this module) cut the velocity obstacle at one time step and navground does not use
    the step."""
    core = pytest.importorskip("navground.core")
    xy, velocity, target, people = ORCA_CASES[case]
    kinematics = core.kinematics.OmnidirectionalKinematics(max_speed=0.5)
    behavior = core.behaviors.ORCABehavior(kinematics=kinematics, radius=0.275)
    behavior.time_horizon = behavior.static_time_horizon = 5.0
    behavior.horizon = 10.0  # its neighbour range (our neighbor_dist_m)
    behavior.optimal_speed = 0.5
    behavior.position, behavior.velocity, behavior.orientation = xy, velocity, 0.0
    behavior.target = core.Target.Point(target)
    behavior.environment_state.neighbors = [core.Neighbor(p, 0.25, v, i) for i, (p, v) in enumerate(people)]
    behavior.compute_cmd(0.1)
    reference = np.asarray(behavior.desired_velocity)
    ours = _orca(xy, velocity, target, people)
    np.testing.assert_allclose(ours, reference, atol=2e-5)
    assert np.linalg.norm(ours) <= 0.5 + 1e-5


def test_orca_robot_keeps_a_wall_line_hard_against_people():
    """A person coming head-on beside a wall: the robot may not answer by heading into the wall;
    its velocity towards the wall is at most what closes the gap in the obstacle horizon."""
    wall = np.array([[-5.0, 5.0, -0.6, -0.5]], np.float32)  # 0.5 m below the robot's centre
    people = [((1.5, 0.2), (-1.0, 0.0))]
    v = _orca((0.0, 0.0), (0.5, 0.0), (5.0, 0.0), people, walls=wall)
    gap = 0.5 - 0.275
    assert -v[1] <= gap / 5.0 + 1e-5  # the obstacle line of ORCA: time horizon 5 s
    free = _orca((0.0, 0.0), (0.5, 0.0), (5.0, 0.0), people)
    assert free[1] < v[1] - 0.05  # without the wall it dodges further down


def _observation(robot_xy, yaw, speed, goal, people_xy, people_v):
    n = len(people_xy)
    return Observation(
        robot_xy_m=jnp.asarray(robot_xy, jnp.float32),
        robot_yaw_rad=jnp.float32(yaw),
        robot_speed_mps=jnp.float32(speed),
        robot_turn_rate_rps=jnp.float32(0.0),
        goal_xy_m=jnp.asarray(goal, jnp.float32),
        people_xy_m=jnp.asarray(people_xy, jnp.float32).reshape(n, 2),
        people_heading_rad=jnp.zeros(n, jnp.float32),
        people_velocity_mps=jnp.asarray(people_v, jnp.float32).reshape(n, 2),
        people_visible=jnp.ones(n, bool),
        occupancy=jnp.zeros((0, 0), jnp.float32),
        time_s=jnp.float32(0.0),
    )


def _context(setup, walls=FAR_WALL):
    env = setup.env
    params = baselines.baseline_params("orca", env, setup.map)
    guide = params.guide.replace(map=params.guide.map.replace(walls_m=jnp.asarray(walls)))
    return params.replace(guide=guide)


@pytest.fixture(scope="module")
def head_on():
    return arena.setup_scene(load_scene(SCENES_DIR / "casn_head_on.json"))


@pytest.mark.slow
def test_the_social_force_robot_feels_the_crowds_own_force(head_on):
    """The robot's social acceleration is the row of the crowd's all-pairs force (the people as
    sources of weight 1) for an agent in its place: the same force that moves the people."""
    crowd = arena.crowd_params()
    xy, v = np.array([0.0, 0.0], np.float32), np.array([0.4, 0.1], np.float32)
    pxy = np.array([[1.0, 0.3], [0.5, -0.8], [-1.2, 0.4]], np.float32)
    pv = np.array([[-0.8, 0.0], [0.0, 0.9], [0.3, 0.0]], np.float32)
    ours = social_force_robot.social_acceleration(crowd, xy, v, pxy, pv, jnp.ones(3, bool))
    x = np.concatenate([xy[:1], pxy[:, 0]])
    y = np.concatenate([xy[1:], pxy[:, 1]])
    vx = np.concatenate([v[:1], pv[:, 0]])
    vy = np.concatenate([v[1:], pv[:, 1]])
    ax, ay = sf.social_force_dense(crowd, *(jnp.asarray(a) for a in (x, y, vx, vy)), jnp.ones(4, jnp.float32))
    np.testing.assert_allclose(np.asarray(ours), [float(ax[0]), float(ay[0])], rtol=1e-5, atol=1e-6)
    assert np.linalg.norm(np.asarray(ours)) > 0.05  # the people are close enough to push
    hidden = social_force_robot.social_acceleration(crowd, xy, v, pxy, pv, jnp.zeros(3, bool))
    np.testing.assert_array_equal(np.asarray(hidden), 0.0)  # unseen people do not push


@pytest.mark.slow
def test_the_social_force_robot_turns_away_from_a_person_ahead(head_on):
    ctx = _context(head_on)
    rule = social_force_robot.SocialForceRobotParams(crowd=arena.crowd_params())
    alone = _observation((0, 0), 0.0, 0.5, (5, 0), [(50.0, 50.0)], [(0.0, 0.0)])
    v, w = social_force_robot.command(rule, ctx, alone, jnp.array([1.0, 0.0]), 0.1)
    assert abs(float(w)) < 1e-5 and float(v) == pytest.approx(0.5, abs=1e-5)
    ahead = _observation((0, 0), 0.0, 0.5, (5, 0), [(1.0, 0.05)], [(-0.8, 0.0)])
    v2, w2 = social_force_robot.command(rule, ctx, ahead, jnp.array([1.0, 0.0]), 0.1)
    assert float(w2) < -1e-3  # the person is slightly to the left: the robot turns right
    assert float(v2) < 0.5


def test_dwa_window_stays_within_the_limits_and_one_step_of_acceleration(head_on):
    ctx = _context(head_on)
    p = dwa.DWAParams()
    v, w = dwa.window(p, ctx, jnp.float32(0.48), jnp.float32(0.95), 0.1)
    r = RobotParams()
    assert v.shape == (p.v_samples * p.omega_samples,)
    assert float(v.max()) <= r.max_speed_mps + 1e-6 and float(v.min()) >= 0.48 - r.max_accel_mps2 * 0.1 - 1e-6
    assert float(w.max()) <= r.max_turn_rate_rps + 1e-6 and float(w.min()) >= 0.95 - r.max_turn_accel_rps2 * 0.1 - 1e-6


def test_dwa_arcs_are_the_bases_own_steps(head_on):
    """An arc's predicted poses are where the base (:func:`jaxsim.scenes.robot.step_robot`) goes
    under the same constant command in open space, once it runs at that command."""
    from socialnav.jaxsim.scenes import robot as robot_lib

    limits = RobotParams()
    v, w = jnp.array([0.5, 0.4]), jnp.array([0.0, 0.8])
    pts, yaws = dwa.arcs(jnp.array([1.0, 2.0]), jnp.float32(0.3), v, w, 0.1, 15)
    for s in range(2):
        state = robot_lib.init_robot(jnp.array([1.0, 2.0]), 0.3).replace(speed=v[s], turn_rate=w[s])
        for k in range(15):
            state = robot_lib.step_robot(limits, head_on.env.world, state, v[s], w[s], 0.1)
            np.testing.assert_allclose(np.asarray(pts[s, k]), np.asarray(state.xy), atol=1e-5)
            np.testing.assert_allclose(float(yaws[s, k]), float(state.yaw), atol=1e-5)
    np.testing.assert_allclose(np.asarray(pts[0, -1]), [1.0 + 0.75 * np.cos(0.3), 2.0 + 0.75 * np.sin(0.3)], atol=1e-5)


@pytest.mark.slow
def test_dwa_brakes_when_every_arc_meets_a_person(head_on):
    ctx = _context(head_on)
    blocked = _observation((0, 0), 0.0, 0.5, (5, 0), [(0.6, 0.0)], [(-1.2, 0.0)])
    v, _ = dwa.command(dwa.DWAParams(), ctx, blocked, jnp.array([1.0, 0.0]), 0.1)
    assert float(v) == 0.0
    free = _observation((0, 0), 0.0, 0.5, (5, 0), [(50.0, 50.0)], [(0.0, 0.0)])
    v, w = dwa.command(dwa.DWAParams(), ctx, free, jnp.array([1.0, 0.0]), 0.1)
    assert float(v) == pytest.approx(0.5, abs=1e-6) and abs(float(w)) < 1e-6


def test_a_velocity_behind_the_robot_turns_it_on_the_spot():
    ctx = reactive.ReactiveParams(guide=None, robot=RobotParams(), rule=None)
    v, w = reactive.track_velocity(jnp.array([-0.4, 0.01]), jnp.float32(0.0), ctx)
    assert float(v) == 0.0 and float(w) > 1.0


def _empty(setup, n):
    variants = sample_variants(setup.spec, 0, n, 0, False, setup.n_slots)
    variants = variants.replace(valid=np.zeros_like(variants.valid))  # nobody in the scene
    return jax.tree_util.tree_map(jnp.asarray, variants)


SCENES = sorted(p.stem for p in pathlib.Path(SCENES_DIR).glob("*.json"))


@pytest.mark.slow
@pytest.mark.parametrize("name", ["gscl_l_hallway", "snape_static_table_fridge"])
def test_every_baseline_reaches_the_goal_of_an_empty_scene_without_touching_a_wall(name):
    setup = arena.setup_scene(load_scene(SCENES_DIR / f"{name}.json"))
    for baseline in baselines.BASELINES:
        tr = arena.baseline_function(setup, baseline, arena.crowd_params())(_empty(setup, 4))
        assert np.asarray(tr.reached[:, -1]).all(), (name, baseline)
        assert int(np.asarray(tr.wall_contacts).max()) == 0, (name, baseline)


@pytest.mark.slow
@pytest.mark.parametrize("name", SCENES)
def test_dwa_reaches_the_goal_of_every_scene_without_people_and_never_enters_a_wall(name):
    setup = arena.setup_scene(load_scene(SCENES_DIR / f"{name}.json"))
    tr = arena.baseline_function(setup, "dwa", arena.crowd_params())(_empty(setup, 8))
    assert np.asarray(tr.reached[:, -1]).all()
    assert int(np.asarray(tr.wall_contacts).max()) == 0
    # The body never enters a wall: the centre keeps at least the radius from every box.
    gap = np.asarray(jax.vmap(lambda q: arena.world_lib.wall_distance(q, setup.env.world.walls_m)[0])(tr.robot_xy_m))
    assert gap.min() >= RobotParams().radius_m - 1e-4


@pytest.mark.slow
def test_the_baselines_are_methods_of_the_arena_command(tmp_path):
    from socialnav import cli

    out = tmp_path / "run"
    code = cli.main(
        ["arena", "--out", str(out), "--scenes", "casn_head_on", "--methods", "orca,social_force,dwa", "--variants",
         "2", "--no-progress"]
    )  # fmt: skip
    assert code == 0
    import pandas as pd

    summary = pd.read_csv(out / "summary.csv")
    assert set(summary["method"]) == {"orca", "social_force", "dwa"}
    for column in ("near_misses", "deadlock_pct", "people_deviation_m", "jerk_mean_mps3", "path_length_ratio"):
        assert summary[column].notna().all(), column
    assert (summary["path_length_ratio"] >= 0.99).all()
    assert (out / "pictures" / "methods.png").stat().st_size > 10_000  # the composite view
