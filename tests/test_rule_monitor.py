"""The streaming rule monitor (jaxsim/scenes/rule_monitor.py) against the batch check the arena
uses (evaluation.arena.nav_metrics.rule_satisfied): the same verdict on random trajectories of every
built-in scene, mirrored ones included, and on hand-made ones for each rule kind; and the batch
check with the rule's numbers as arguments (the arena's compiled form) against it with constants."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from socialnav.data import SCENES_DIR
from socialnav.evaluation.arena import nav_metrics
from socialnav.jaxsim.scenes import rule_monitor
from socialnav.jaxsim.scenes.spec import load_scene, mirror
from socialnav.jaxsim.scenes.variant import sample_variants

T = 80


def _streamed(rule, robot_xy, reached, people_xy, present, start_xy, end_xy, group):
    init, update, verdict = rule_monitor.monitor(rule)
    episode = rule_monitor.Episode(start_xy, end_xy, group)

    def step(state, xs):
        return update(state, rule_monitor.Step(*xs), episode), None

    state, _ = jax.lax.scan(step, init(), (robot_xy, reached, people_xy, present))
    return verdict(state)


def _batch(rule, robot_xy, reached, people_xy, present, start_xy, end_xy, group):
    return nav_metrics.rule_satisfied(rule, robot_xy, reached, people_xy, start_xy, end_xy, present, group)


def _random_episodes(rng, variants, n):
    """Trajectories (n, T, ...) from each variant's start towards its goal with a random sideways
    swing (so boxes are crossed on both halves), people drifting from their start, the goal
    reached at a random step or never."""
    s = np.linspace(0, 1.1, T)[:, None]
    start, goal = variants.robot_xy[:, None], variants.goal_xy[:, None]
    line = goal - start
    length = np.maximum(np.linalg.norm(line, axis=-1, keepdims=True), 1e-6)
    normal = np.stack([-line[..., 1], line[..., 0]], -1) / length
    swing = rng.uniform(-1.5, 1.5, (n, 1, 1)) * np.sin(np.pi * s * rng.uniform(0.5, 2, (n, 1, 1)))
    robot = start + s * line + swing * normal + rng.normal(0, 0.05, (n, T, 2))
    drift = np.cumsum(rng.normal(0, 0.08, (n, T) + variants.xy0.shape[1:]), axis=1)
    people = variants.xy0[:, None] + drift
    present = (rng.uniform(size=people.shape[:-1]) < 0.95) & variants.valid[:, None]
    first = rng.integers(T // 2, T + 20, n)  # >= T: never reached
    reached = np.arange(T)[None] >= first[:, None]
    return [jnp.asarray(a, jnp.float32) for a in (robot, people)], jnp.asarray(reached), jnp.asarray(present)


SCENES = sorted(p.stem for p in SCENES_DIR.glob("*.json"))


@pytest.mark.parametrize("name", SCENES)
def test_monitor_equals_the_batch_check_on_every_scene(name):
    spec = load_scene(SCENES_DIR / f"{name}.json")
    rng = np.random.default_rng(abs(hash(name)) % 2**32)
    n = 48
    for s in (spec, mirror(spec)):
        variants = sample_variants(s, 0, n)
        (robot, people), reached, present = _random_episodes(rng, variants, n)
        args = (robot, reached, people, present, jnp.asarray(variants.start_xy), jnp.asarray(variants.end_xy))
        group = jnp.asarray(variants.group)
        streamed = jax.jit(jax.vmap(lambda *a, rule=s.rule: _streamed(rule, *a)))(*args, group)
        batch = jax.jit(jax.vmap(lambda *a, rule=s.rule: _batch(rule, *a)))(*args, group)
        np.testing.assert_array_equal(np.asarray(streamed), np.asarray(batch), err_msg=f"{s.name}: {s.rule}")
        # The arena's form: the rule's numbers as arguments of one program per rule structure.
        structure, numbers = nav_metrics.split_rule(s.rule)
        # A scene and its mirror share it, unless the file gives the mirror its own rule.
        if s.held_out_rule is None:
            assert nav_metrics.split_rule(mirror(s).rule)[0] == structure
        else:
            assert nav_metrics.split_rule(mirror(s).rule)[0] == nav_metrics.split_rule(s.held_out_rule)[0]
        check = lambda nums, *a, st=structure: _batch(nav_metrics.join_rule(st, nums), *a)
        traced = jax.jit(jax.vmap(check, in_axes=(None,) + (0,) * 7))(numbers, *args, group)
        np.testing.assert_array_equal(np.asarray(traced), np.asarray(batch), err_msg=f"{s.name}: split")


def _line(y0, y1, n=T):
    x = np.linspace(-4, 4, n)
    return np.stack([x, np.linspace(y0, y1, n)], -1)


@pytest.mark.parametrize(
    "rule, robot, want",
    [
        ({"type": "keep_right", "box": [-3, 3, -1, 1], "direction_deg": 0, "min_share": 0.6}, _line(-0.5, -0.5), True),
        ({"type": "keep_right", "box": [-3, 3, -1, 1], "direction_deg": 0, "min_share": 0.6}, _line(0.5, 0.5), False),
        ({"type": "keep_right", "box": [-3, 3, -1, 1], "direction_deg": 0, "min_share": 0.6}, _line(5, 5), True),
        ({"type": "visit", "box": [-0.5, 0.5, 1.5, 2.5]}, _line(0, 4), True),
        ({"type": "visit", "box": [-0.5, 0.5, 1.5, 2.5]}, _line(0, 0), False),
        ({"type": "avoid_circle", "centre": [0, 0], "radius_m": 1.0}, _line(-2, -2), True),
        ({"type": "avoid_circle", "centre": [0, 0], "radius_m": 1.0}, _line(-2, 2), False),
        (
            {
                "type": "all",
                "rules": [{"type": "visit", "box": [-0.5, 0.5, -0.5, 0.5]}, {"type": "min_distance", "distance_m": 1}],
            },
            _line(0, 0),
            True,
        ),
    ],
)
def test_hand_made_verdicts(rule, robot, want):
    people = jnp.full((T, 1, 2), 50.0)  # far away, present
    args = (jnp.asarray(robot, jnp.float32), jnp.zeros(T, bool), people, jnp.ones((T, 1), bool))
    legs = (jnp.zeros((1, 2)), jnp.ones((1, 2)), jnp.full((1,), -1, jnp.int32))
    assert bool(_streamed(rule, *args, *legs)) == want
    assert bool(_batch(rule, *args, *legs)) == want


def test_steps_after_the_goal_do_not_count():
    rule = {"type": "avoid_circle", "centre": [3.5, 0], "radius_m": 1.0}
    robot = jnp.asarray(_line(0, 0), jnp.float32)  # reaches x = 3.5 only at the end
    reached = jnp.arange(T) >= T // 2  # at the goal halfway, before the circle
    people, present = jnp.full((T, 1, 2), 50.0), jnp.ones((T, 1), bool)
    legs = (jnp.zeros((1, 2)), jnp.ones((1, 2)), jnp.full((1,), -1, jnp.int32))
    assert bool(_streamed(rule, robot, reached, people, present, *legs))
    assert not bool(_streamed(rule, robot, jnp.zeros(T, bool), people, present, *legs))


def test_pass_behind_streamed():
    # A walker crossing y = 0 going up along x = 0 from (0, -3) at 0.1 m per step; the robot
    # crosses the walker's line (x = 0) from left to right along y = 0, early (ahead of the
    # walker: wrong) or late (behind: right).
    legs = (jnp.array([[0.0, -3.0]]), jnp.array([[0.0, 3.0]]), jnp.full((1,), -1, jnp.int32))
    walker = jnp.stack([jnp.zeros(T), -3.0 + 0.1 * jnp.arange(T)], -1)[:, None]
    present = jnp.ones((T, 1), bool)
    for cross_at, want in ((10, False), (60, True)):
        x = jnp.where(jnp.arange(T) < cross_at, -1.0, 1.0)
        robot = jnp.stack([x, jnp.zeros(T)], -1)
        args = (robot, jnp.zeros(T, bool), walker, present, *legs)
        assert bool(_streamed({"type": "pass_behind", "person": 0}, *args)) == want
        assert bool(_batch({"type": "pass_behind", "person": 0}, *args)) == want


QUEUE_RULE = {
    "type": "queue",
    "head": [3.0, 0.0],
    "direction_deg": 0,
    "half_width_m": 0.6,
    "length_m": 4.5,
    "ahead_m": 1.2,
}


def _queue_episode(robot_points, served_every=None):
    """Three people in line facing +x at x = 3.0, 2.2, 1.4 (y = 0); the head leaves (absent from
    then on) every ``served_every`` steps and the others step up 0.8 m; the robot walks through
    ``robot_points`` at even steps."""
    t = np.arange(T)
    served = np.zeros(T, int) if served_every is None else t // served_every
    place = np.arange(3)[None] - served[:, None]  # (T, 3) place in line, < 0 once served
    people = np.stack([3.0 - 0.8 * np.maximum(place, 0), np.zeros((T, 3))], -1)
    present = place >= 0
    pts = np.asarray(robot_points, float)
    s = np.linspace(0, len(pts) - 1, T)
    robot = np.stack([np.interp(s, np.arange(len(pts)), pts[:, k]) for k in range(2)], -1)
    return robot, people, present


@pytest.mark.parametrize(
    "robot_points, served_every, want",
    [
        ([(0.0, -2.0), (0.0, 0.0), (0.4, 0.0)], None, True),  # joins behind the tail and waits
        ([(3.5, -2.0), (3.8, 0.0)], None, False),  # straight to the goal in front of the head
        ([(2.6, -2.0), (2.6, 0.0)], None, False),  # steps into the line between two people
        ([(2.0, -2.0), (2.0, -0.8), (3.8, -0.8)], None, True),  # walks past beside the line, never in it
        # joins at the tail and reaches the goal only after all three were served
        ([(0.0, -2.0), (0.6, 0.0), (0.6, 0.0), (3.8, 0.0)], 20, True),
        # the same walk, but the last person is still in line when the robot reaches the goal
        ([(0.0, -2.0), (0.6, 0.0), (0.6, 0.0), (3.8, 0.0)], 30, False),
    ],
)
def test_queue_rule_on_hand_made_walks(robot_points, served_every, want):
    robot, people, present = _queue_episode(robot_points, served_every)
    legs = (jnp.zeros((3, 2)), jnp.ones((3, 2)), jnp.full((3,), -1, jnp.int32))
    args = (jnp.asarray(robot, jnp.float32), jnp.zeros(T, bool), jnp.asarray(people, jnp.float32), jnp.asarray(present))
    rule = {**QUEUE_RULE, "head": np.asarray(QUEUE_RULE["head"])}
    assert bool(_streamed(rule, *args, *legs)) == want
    assert bool(_batch(rule, *args, *legs)) == want
    # The same walk in a queue facing the other way, with the rule turned with it.
    flipped = dict(rule, head=np.array([-3.0, 0.0]), direction_deg=180)
    turned = [a * jnp.array([-1.0, 1.0]) if a.ndim and a.shape[-1] == 2 else a for a in args]
    assert bool(_batch(flipped, *turned, *legs)) == want
