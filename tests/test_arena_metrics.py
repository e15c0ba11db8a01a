"""The arena's metrics on hand-made trajectories: CHC, path length, clearance, collisions per
encounter, the scenes' rules, Wilson intervals."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pandas as pd
import pytest

from socialnav.evaluation.arena import nav_metrics
from socialnav.evaluation.arena import report as arena_report

# One compiled program a trajectory's shape, as the arena runs it (op by op, each new shape cost ~100 programs).
_episode_metrics = jax.jit(
    nav_metrics.episode_metrics,
    static_argnames=("dt_s", "timeout_s", "robot_radius_m", "person_radius_m", "goal_tolerance_m"),
)


def _metrics(robot_xy, people_xy=None, present=None, dt=0.1, reached_at=None, yaw=None, group=None, people_v=None):
    t = robot_xy.shape[0]
    if people_xy is None:
        people_xy = np.full((t, 1, 2), 100.0)
        present = np.zeros((t, 1), bool)
    if yaw is None:
        d = np.diff(robot_xy, axis=0, prepend=robot_xy[:1])
        yaw = np.arctan2(d[:, 1], d[:, 0])
    speed = np.linalg.norm(np.diff(robot_xy, axis=0, prepend=robot_xy[:1]), axis=1) / dt
    reached = np.zeros(t, bool) if reached_at is None else np.arange(t) >= reached_at
    p = people_xy.shape[1]
    return _episode_metrics(
        jnp.asarray(robot_xy, jnp.float32),
        jnp.asarray(yaw, jnp.float32),
        jnp.asarray(speed, jnp.float32),
        jnp.asarray(people_xy, jnp.float32),
        jnp.zeros((t, p, 2)) if people_v is None else jnp.asarray(people_v),
        jnp.asarray(present),
        jnp.asarray(reached),
        jnp.asarray(robot_xy[-1]),
        jnp.asarray(robot_xy[0]),
        jnp.full(p, -1, jnp.int32) if group is None else jnp.asarray(group),
        dt,
        100.0,
        0.275,
        0.25,
        jnp.array(True),
    )


@pytest.mark.slow
def test_chc_of_a_square_path_and_its_length():
    side = np.linspace(0, 1, 11)[1:]
    square = np.concatenate(
        [
            np.zeros((1, 2)),
            np.stack([side, 0 * side], 1),
            np.stack([1 + 0 * side, side], 1),
            np.stack([1 - side, 1 + 0 * side], 1),
        ]
    )
    m = _metrics(square, reached_at=len(square) - 1)
    assert float(m["chc_rad"]) == pytest.approx(math.pi, abs=1e-5)  # two quarter turns
    assert float(m["path_length_m"]) == pytest.approx(3.0, abs=1e-5)
    assert bool(m["goal_success"])
    assert float(m["spl"]) == pytest.approx(1.0 / 3.0, abs=1e-5)  # straight line 1 m, driven 3 m
    np.testing.assert_allclose(m["zone_share"], [0.0, 0.0, 0.0, 1.0])  # nobody present: public


@pytest.mark.slow
def test_a_straight_pass_at_a_known_distance():
    x = np.linspace(-5, 5, 101)
    robot = np.stack([x, np.zeros_like(x)], 1)
    person = np.tile([[[0.0, 1.0]]], (101, 1, 1))
    present = np.ones((101, 1), bool)
    m = _metrics(robot, person, present)
    assert float(m["d_min_m"]) == pytest.approx(1.0, abs=1e-6)
    assert int(m["intrusions"]) == 1  # one entry into the 1.2 m
    inside_personal = np.sum(np.hypot(x, 1.0) < 1.2) / 101
    share = np.asarray(m["zone_share"])
    assert share[0] == 0.0 and share[1] == pytest.approx(inside_personal, abs=1e-6)
    assert share.sum() == pytest.approx(1.0, abs=1e-6)
    # Body to body (less the radii, 0.275 + 0.25 m): the gap is 0.475 m at the closest, so the
    # robot is in the personal zone while the centres are within 1.2 + 0.525 m, never intimate.
    body = np.asarray(m["zone_share_body"])
    assert body[0] == 0.0 and body[1] == pytest.approx(np.sum(np.hypot(x, 1.0) - 0.525 < 1.2) / 101, abs=1e-6)
    assert body[1] > share[1] and body.sum() == pytest.approx(1.0, abs=1e-6)
    assert int(m["collisions"]) == 0


@pytest.mark.slow
def test_a_trial_intrudes_once_however_many_entries_as_seed_001_counts():
    """Two people 1 m beside the line: two personal-space entries, one trial with an intrusion;
    1.5 m beside it: none."""
    x = np.linspace(-5, 5, 101)
    robot = np.stack([x, np.zeros_like(x)], 1)
    present = np.ones((101, 2), bool)
    near = _metrics(robot, np.tile([[[-2.0, 1.0], [2.0, -1.0]]], (101, 1, 1)), present)
    assert int(near["intrusions"]) == 2 and bool(near["intruded"])
    far = _metrics(robot, np.tile([[[-2.0, 1.5], [2.0, -1.5]]], (101, 1, 1)), present)
    assert int(far["intrusions"]) == 0 and not bool(far["intruded"])


@pytest.mark.slow
def test_a_collision_is_counted_once_per_encounter():
    x = np.linspace(-3, 3, 61)
    robot = np.stack([x, np.zeros_like(x)], 1)
    person = np.tile([[[0.0, 0.3]]], (61, 1, 1))  # closer than 0.525 m for several steps
    m = _metrics(robot, person, np.ones((61, 1), bool))
    assert int(m["collisions"]) == 1 and int(m["collisions_robot"]) == 1
    assert float(m["ttc_min_s"]) == 0.0


@pytest.mark.slow
def test_a_collision_before_arrival_fails_the_run_where_a_collision_ends_it_and_one_after_does_not():
    """Seed 002's reading (a collision ends the run): reached, but through a person, is a goal
    success and not a goal without collision; a person met only after arrival does not count."""
    x = np.linspace(-3, 3, 61)
    robot = np.stack([x, np.zeros_like(x)], 1)
    person = np.tile([[[0.0, 0.3]]], (61, 1, 1))  # met at step 30
    through = _metrics(robot, person, np.ones((61, 1), bool), reached_at=50)
    assert bool(through["goal_success"]) and not bool(through["goal_no_collision"])
    assert not bool(through["social_no_collision"])
    before = _metrics(robot, person, np.ones((61, 1), bool), reached_at=20)
    assert bool(before["goal_no_collision"]) and int(before["collisions"]) == 0


@pytest.mark.slow
def test_rules_on_hand_made_trajectories():
    x = np.linspace(-3, 3, 61)
    robot = jnp.asarray(np.stack([x, -0.5 + 0 * x], 1), jnp.float32)
    reached = jnp.zeros(61, bool)
    none = jnp.zeros((61, 1, 2)), jnp.zeros((1, 2)), jnp.zeros((1, 2)), jnp.zeros((61, 1), bool), jnp.full(1, -1)
    keep_right = {"type": "keep_right", "box": [-3, 3, -1, 1], "direction_deg": 0.0, "min_share": 0.6}
    assert bool(nav_metrics.rule_satisfied(keep_right, robot, reached, *none))
    assert not bool(nav_metrics.rule_satisfied(keep_right, -robot, reached, *none))  # left side, other way
    visit = {"type": "visit", "box": [1, 2, -1, 0]}
    assert bool(nav_metrics.rule_satisfied(visit, robot, reached, *none))
    corner = {"type": "avoid_circle", "centre": np.array([0.0, 0.0]), "radius_m": 0.4}
    assert bool(nav_metrics.rule_satisfied(corner, robot, reached, *none))
    assert not bool(nav_metrics.rule_satisfied(corner, robot * 0.5, reached, *none))


def test_summary_gives_wilson_intervals():
    episodes = pd.DataFrame(
        {"scene": "s", "method": "m", "goal_success": [True] * 9 + [False], "social_success": [True] * 5 + [False] * 5}
    )
    row = arena_report.summary(episodes).iloc[0]
    assert row["goal_success_pct"] == 90.0 and row["social_success_pct"] == 50.0
    lo, hi = arena_report.wilson(9, 10)
    assert lo == pytest.approx(0.5958, abs=1e-3) and hi == pytest.approx(0.9821, abs=1e-3)
