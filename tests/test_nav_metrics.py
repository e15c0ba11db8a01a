"""The arena's motion-quality, safety and counterfactual metrics (issue 34) on hand-made
trajectories with known answers, and the counterfactual run in closed loop."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from socialnav.data import SCENES_DIR
from socialnav.evaluation.arena import episodes as arena
from socialnav.evaluation.arena import nav_metrics
from socialnav.jaxsim.scenes.spec import load_scene
from socialnav.jaxsim.scenes.variant import sample_variants

DT = 0.1


# One compiled program a trajectory's shape, as the arena runs it (op by op, each shape cost ~100 programs).
_episode_metrics = jax.jit(
    nav_metrics.episode_metrics,
    static_argnames=("dt_s", "timeout_s", "robot_radius_m", "person_radius_m", "goal_tolerance_m"),
)


def _metrics(robot_xy, speed=None, yaw=None, people_xy=None, people_v=None, present=None, goal=None, reached_at=None,
             group=None, tolerance=0.0):  # fmt: skip
    robot_xy = np.asarray(robot_xy, np.float32)
    t = robot_xy.shape[0]
    if people_xy is None:
        people_xy, present = np.full((t, 1, 2), 100.0), np.zeros((t, 1), bool)
    p = people_xy.shape[1]
    if yaw is None:
        d = np.diff(robot_xy, axis=0, append=robot_xy[-1:] + (robot_xy[-1:] - robot_xy[-2:-1]))
        yaw = np.arctan2(d[:, 1], d[:, 0])
    if speed is None:
        speed = np.linalg.norm(np.diff(robot_xy, axis=0, prepend=robot_xy[:1]), axis=1) / DT
    reached = np.zeros(t, bool) if reached_at is None else np.arange(t) >= reached_at
    return _episode_metrics(
        jnp.asarray(robot_xy),
        jnp.asarray(yaw, jnp.float32),
        jnp.asarray(speed, jnp.float32),
        jnp.asarray(people_xy, jnp.float32),
        jnp.zeros((t, p, 2)) if people_v is None else jnp.asarray(people_v, jnp.float32),
        jnp.asarray(present if present is not None else np.ones((t, p), bool)),
        jnp.asarray(reached),
        jnp.asarray(robot_xy[-1] if goal is None else goal, jnp.float32),
        jnp.asarray(robot_xy[0]),
        jnp.full(p, -1, jnp.int32) if group is None else jnp.asarray(group, jnp.int32),
        DT,
        t * DT,
        0.275,
        0.25,
        jnp.array(True),
        tolerance,
    )


def _line(n, speed=0.5, y=0.0):
    x = np.arange(n) * speed * DT
    return np.stack([x, np.full(n, y)], 1)


@pytest.mark.slow
def test_speed_acceleration_and_jerk_of_a_ramp_then_a_cruise():
    # Accelerates at 0.5 m/s^2 for 10 steps from rest, then cruises at 0.5 m/s for 40.
    speed = np.concatenate([0.05 * np.arange(11), np.full(40, 0.5)])
    xy = np.stack([np.cumsum(speed) * DT, np.zeros_like(speed)], 1)
    m = _metrics(xy, speed=speed, yaw=np.zeros_like(speed))
    n = len(speed)
    assert float(m["speed_mean_mps"]) == pytest.approx(speed.mean(), abs=1e-6)
    assert float(m["accel_mean_mps2"]) == pytest.approx(10 * 0.5 / n, abs=1e-5)  # 10 steps at 0.5
    assert float(m["jerk_mean_mps3"]) == pytest.approx(2 * 0.5 / DT / n, abs=1e-3)  # two jumps of 0.5 m/s^2
    assert float(m["turn_rate_mean_rps"]) == 0.0


def test_turn_rate_of_a_constant_turn():
    yaw = 0.3 * DT * np.arange(50)  # 0.3 rad/s
    xy = np.stack([np.cos(yaw), np.sin(yaw)], 1)
    m = _metrics(xy, speed=np.full(50, 0.3), yaw=yaw)
    assert float(m["turn_rate_mean_rps"]) == pytest.approx(0.3 * 49 / 50, abs=1e-5)  # the first step has no rate


@pytest.mark.slow
def test_path_irregularity_and_length_ratio_of_a_detour():
    side = np.linspace(0, 1, 11)[1:]
    square = np.concatenate(
        [np.zeros((1, 2)), np.stack([side, 0 * side], 1), np.stack([1 + 0 * side, side], 1),
         np.stack([1 - side, 1 + 0 * side], 1)]
    )  # fmt: skip
    yaw = np.concatenate([[0.0], np.zeros(10), np.full(10, math.pi / 2), np.full(10, math.pi)])
    m = _metrics(square, yaw=yaw, reached_at=len(square) - 1)
    # Goal (0, 1) from (0, 0) facing +x: a quarter turn is needed, a half turn was made over 3 m.
    assert float(m["path_irregularity_rad_per_m"]) == pytest.approx((math.pi - math.pi / 2) / 3.0, abs=1e-5)
    assert float(m["path_length_ratio"]) == pytest.approx(3.0, abs=1e-5)
    straight = _metrics(_line(41), yaw=np.zeros(41), reached_at=40)
    assert float(straight["path_irregularity_rad_per_m"]) == 0.0
    assert float(straight["path_length_ratio"]) == pytest.approx(1.0, abs=1e-5)
    # With a goal tolerance the straight line ends on its circle: ratio 1 again, not 2 m / 1.7 m.
    short = _metrics(_line(41)[:35], yaw=np.zeros(35), goal=_line(41)[-1], reached_at=34, tolerance=0.3)
    assert float(short["path_length_ratio"]) == pytest.approx(1.7 / 1.7, abs=1e-4)


@pytest.mark.slow
def test_deadlock_is_told_apart_from_a_slow_timeout():
    goal = np.array([10.0, 0.0])
    stuck = np.concatenate([_line(21), np.repeat(_line(21)[-1:], 80, axis=0)])  # 1 m, then 8 s still
    m = _metrics(stuck, goal=goal)
    assert bool(m["deadlock"]) and not bool(m["timeout"]) and not bool(m["goal_success"])
    assert float(m["no_progress_max_s"]) == pytest.approx(8.0, abs=0.11)
    slow = _line(101, speed=0.05)  # 0.25 m of progress in every 5 s: slow, not stuck
    m = _metrics(slow, goal=goal)
    assert not bool(m["deadlock"]) and bool(m["timeout"])
    assert float(m["no_progress_max_s"]) == 0.0


@pytest.mark.slow
def test_near_misses_and_body_edge_clearance():
    robot = _line(121, speed=0.5)  # x from 0 to 6 m
    person = np.tile([[[3.0, 0.6]]], (121, 1, 1))  # centre 0.6 m off the line: gap 0.075 m
    m = _metrics(robot, people_xy=person)
    assert int(m["near_misses"]) == 1 and int(m["collisions"]) == 0
    assert float(m["clearance_min_m"]) == pytest.approx(0.6 - 0.525, abs=1e-5)
    touching = _metrics(robot, people_xy=np.tile([[[3.0, 0.3]]], (121, 1, 1)))
    assert int(touching["near_misses"]) == 0 and int(touching["collisions"]) == 1  # a contact is not a miss
    assert float(touching["clearance_min_m"]) == pytest.approx(0.3 - 0.525, abs=1e-5)
    wide = _metrics(robot, people_xy=np.tile([[[3.0, 0.8]]], (121, 1, 1)))
    assert int(wide["near_misses"]) == 0


@pytest.mark.slow
def test_intrusions_are_split_by_who_closed_in():
    # The robot drives past a standing person: the robot intrudes.
    robot = _line(121, speed=0.5)
    m = _metrics(robot, people_xy=np.tile([[[3.0, 1.0]]], (121, 1, 1)))
    assert int(m["intrusions_robot"]) == 1 and int(m["intrusions_person"]) == 0
    # A person walks up to a standing robot and stops 0.8 m away: the person intrudes.
    still = np.zeros((60, 2))
    walk = np.stack([np.maximum(4.0 - 0.1 * np.arange(60), 0.8), np.zeros(60)], 1)[:, None, :]
    v = np.stack([np.where(walk[:, 0, 0] > 0.8, -1.0, 0.0), np.zeros(60)], 1)[:, None, :]
    m = _metrics(still, speed=np.zeros(60), yaw=np.zeros(60), people_xy=walk, people_v=v, goal=np.array([5.0, 5.0]))
    assert int(m["intrusions_person"]) == 1 and int(m["intrusions_robot"]) == 0


@pytest.mark.slow
def test_group_intrusions_count_entries_into_the_groups_circle():
    robot = _line(121, speed=0.5)  # along y = 0 through x = 3
    members = np.tile([[[3.0, 0.8], [3.0, -0.8], [10.0, 10.0]]], (121, 1, 1))  # a pair facing across the line
    m = _metrics(robot, people_xy=members, group=[0, 0, -1])
    assert int(m["group_intrusions"]) == 1
    around = _metrics(_line(121, speed=0.5, y=2.0), people_xy=members, group=[0, 0, -1])
    assert int(around["group_intrusions"]) == 0


@pytest.mark.slow
def test_people_effect_of_hand_made_runs():
    t = np.arange(50) * DT
    without = np.stack([t * 1.0, np.zeros(50)], 1)[:, None, :]  # 1 m/s along x
    with_robot = np.stack([t * 0.8, np.where(t > 2.0, 0.3, 0.0)], 1)[:, None, :]  # slowed, stepped aside
    present = np.ones((50, 1), bool)
    e = nav_metrics.people_effect(jnp.asarray(with_robot), present, jnp.asarray(without), present, DT)
    # The speed: 0.8 m/s, except the side step (0.3 m in one step) inflates one step.
    speeds = np.linalg.norm(np.diff(with_robot[:, 0], axis=0), axis=1) / DT
    assert float(e["people_speed_drop_mps"]) == pytest.approx(1.0 - speeds.mean(), abs=1e-5)
    apart = np.linalg.norm(with_robot[:, 0] - without[:, 0], axis=1)
    assert float(e["people_deviation_m"]) == pytest.approx(apart.mean(), abs=1e-5)
    assert float(e["people_deviation_max_m"]) == pytest.approx(apart.max(), abs=1e-5)
    same = nav_metrics.people_effect(jnp.asarray(without), present, jnp.asarray(without), present, DT)
    assert all(float(v) == 0.0 for v in same.values())
    standing = np.zeros((50, 1, 2))  # a standing person's speed drop is not averaged in
    nobody = nav_metrics.people_effect(jnp.asarray(standing), present, jnp.asarray(standing), present, DT)
    assert float(nobody["people_speed_drop_mps"]) == 0.0


def _one_walker(setup, robot_xy):
    v = sample_variants(setup.spec, 0, 1, 0, False, setup.n_slots)
    v = v.replace(robot_xy=np.asarray(robot_xy, np.float32)[None])
    return jax.tree_util.tree_map(jnp.asarray, v)


@pytest.mark.slow
def test_the_counterfactual_is_nil_far_from_the_robot_and_positive_in_its_way():
    """snape_walking's person walks (0.5-1 m/s) from about (-1.25, -0.45) to (3, 1.5) and avoids the
    robot. A robot standing in a far corner changes nothing; one standing on the person's line
    makes them go around it: they pass at least a body width aside at some moment."""
    setup = arena.setup_scene(load_scene(SCENES_DIR / "snape_walking.json"))
    without = arena.counterfactual_function(setup)
    stand = arena.actor_function(setup, arena.STAND_STILL, ())
    far = _one_walker(setup, (-4.5, 2.8))
    line = np.asarray(far.end_xy[0, 0]) - np.asarray(far.start_xy[0, 0])
    middle = np.asarray(far.start_xy[0, 0]) + 0.5 * line
    near = _one_walker(setup, middle)

    def effect(variants):
        tr, wo = stand(variants), without(variants)
        return {
            k: float(v[0])
            for k, v in jax.vmap(nav_metrics.people_effect, in_axes=(0, 0, 0, 0, None))(
                tr.people_xy_m, tr.people_present, wo.people_xy_m, wo.people_present, 0.1
            ).items()
        }, wo

    nil, wo = effect(far)
    assert nil["people_deviation_max_m"] < 1e-3 and abs(nil["people_speed_drop_mps"]) < 1e-3
    # The counterfactual person walks straight through the robot's spot (they ignore it).
    d = np.linalg.norm(np.asarray(wo.people_xy_m[0, :, 0]) - middle, axis=1)
    assert d.min() < 0.1
    hit, _ = effect(near)
    assert hit["people_deviation_max_m"] > 0.3  # at least around the robot's body
    assert hit["people_deviation_m"] > 0.01


@pytest.mark.slow
def test_the_counterfactual_equals_a_run_whose_people_ignore_the_robot_bit_for_bit():
    """casn_head_on's walker ignores the robot: the run with any robot and the counterfactual (the
    robot far away) move them by the same arithmetic, so their tracks agree to the bit and every
    effect is exactly 0 (the old counterfactual by ``ignore_robot`` differed by rounding, which a
    crowd's dynamics grew to centimetres)."""
    setup = arena.setup_scene(load_scene(SCENES_DIR / "casn_head_on.json"))
    variants = jax.tree_util.tree_map(jnp.asarray, sample_variants(setup.spec, 0, 4, 0, False, setup.n_slots))
    assert bool(np.asarray(variants.ignore_robot)[:, 0].all())
    tr = arena.baseline_function(setup, "orca", arena.crowd_params())(variants)
    wo = arena.counterfactual_function(setup)(variants)
    np.testing.assert_array_equal(np.asarray(tr.people_xy_m), np.asarray(wo.people_xy_m))
    assert np.abs(np.asarray(wo.robot_xy_m) - arena.FAR_AWAY_M).max() < 1.0  # it stood far away
