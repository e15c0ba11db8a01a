"""What the robot senses and how its base moves in the arena's scenes: line of sight, velocities
estimated from tracks, the exact wall distance, a body that never enters a wall, and the step
bound (shorter than the body's radius) that keeps it so."""

import jax.numpy as jnp
import numpy as np
import pytest

from socialnav.data import DATA_DIR
from socialnav.jaxsim.scenes import perception
from socialnav.jaxsim.scenes import robot as robot_lib
from socialnav.jaxsim.scenes import world as world_lib
from socialnav.jaxsim.scenes.spec import load_scene


def test_the_l_hallways_person_is_hidden_until_the_corner():
    spec = load_scene(DATA_DIR / "scenes" / "gscl_l_hallway.json")
    world = world_lib.build_scene_world(spec.walls_m, spec.bounds_m)
    person = jnp.array([[1.4, 2.3]])
    present = jnp.array([True])
    assert not bool(perception.visible(world, jnp.array([-5.0, 0.0]), person, present)[0])
    assert not bool(perception.visible(world, jnp.array([-3.0, 0.0]), person, present)[0])
    assert bool(perception.visible(world, jnp.array([1.0, 0.0]), person, present)[0])


def test_velocity_is_estimated_from_the_window_of_positions():
    tracks = perception.init_tracks(1)
    for k in range(perception.WINDOW):
        tracks, v = perception.observe(tracks, jnp.array([[0.1 * k, 0.0]]), jnp.array([True]), 0.1)
    np.testing.assert_allclose(v[0], [1.0, 0.0], atol=1e-5)
    tracks, v = perception.observe(tracks, jnp.array([[9.0, 9.0]]), jnp.array([False]), 0.1)
    np.testing.assert_array_equal(v[0], [0.0, 0.0])  # not seen now: no estimate


@pytest.mark.slow
def test_wall_distance_is_exact():
    walls = jnp.array([[0.0, 1.0, 0.0, 1.0]])
    d, n = world_lib.wall_distance(jnp.array([[2.0, 0.5], [1.3, 1.4], [0.5, 0.4]]), walls)
    np.testing.assert_allclose(d, [1.0, 0.5, -0.4], atol=1e-6)
    np.testing.assert_allclose(n[0], [1.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(n[1], [0.6, 0.8], atol=1e-6)


@pytest.mark.slow
def test_wall_clearance_is_the_wall_distance_in_both_layouts():
    spec = load_scene(DATA_DIR / "scenes" / "snape_static_table_fridge.json")  # 7 boxes, one inside
    walls = world_lib.build_scene_world(spec.walls_m, spec.bounds_m).walls_m
    xmin, xmax, ymin, ymax = spec.bounds_m
    rng = np.random.default_rng(0)
    points = jnp.asarray(
        np.stack([rng.uniform(xmin - 1, xmax + 1, (50, 14)), rng.uniform(ymin - 1, ymax + 1, (50, 14))], -1),
        jnp.float32,
    )
    expected = np.asarray(world_lib.wall_distance(points, walls)[0])
    assert (expected < 0).any() and (expected > 0.5).any()  # inside and well outside boxes
    per_box = np.asarray(world_lib.wall_clearance(points, walls))
    at_once = np.asarray(world_lib.wall_clearance(points, walls, per_box=False))
    assert per_box.shape == at_once.shape == (50, 14)
    np.testing.assert_allclose(per_box, expected, atol=1e-6)
    np.testing.assert_allclose(at_once, expected, atol=1e-6)
    corner = world_lib.wall_clearance(jnp.array([[1.3, 1.4]]), jnp.array([[0.0, 1.0, 0.0, 1.0]]))
    np.testing.assert_allclose(corner, [0.5], atol=1e-6)  # 0.3-0.4-0.5 off the corner


@pytest.mark.slow
def test_the_base_never_puts_its_body_into_a_wall():
    spec = load_scene(DATA_DIR / "scenes" / "gscl_l_hallway.json")
    world = world_lib.build_scene_world(spec.walls_m, spec.bounds_m)
    params = robot_lib.RobotParams()
    state = robot_lib.init_robot(jnp.array([-3.0, 0.0]), jnp.float32(1.2))  # heading into the wall
    for _ in range(80):
        state = robot_lib.step_robot(params, world, state, 0.5, 0.0, 0.1)
        assert float(world_lib.wall_distance(state.xy, world.walls_m)[0]) >= params.radius_m - 1e-4
    assert int(state.wall_contacts) > 0


def _crosses(step_radii: float, thickness_m: float, radius_m: float = 0.275) -> int:
    """How many of 10 starts (one radius or more clear of a long wall at x = 1, headings 0-0.6
    rad towards it) end past the wall's middle, the base driven at full speed for 3 m, a step of
    ``step_radii`` radii."""
    import jax

    world = world_lib.SceneWorld(walls_m=jnp.array([[1.0, 1.0 + thickness_m, -100.0, 100.0]]), wall_field=None)
    step_m = step_radii * radius_m
    params = robot_lib.RobotParams(max_speed_mps=step_m / 0.1, max_accel_mps2=1e4, radius_m=radius_m)
    starts = [(x, yaw) for x in np.linspace(-1.0, 1.0 - radius_m, 5) for yaw in (0.0, 0.6)]

    def drive(x, yaw):
        state = robot_lib.init_robot(jnp.array([x, 0.0]), yaw)
        step = lambda s, _: (robot_lib.step_robot(params, world, s, 1e3, 0.0, 0.1), None)
        return jax.lax.scan(step, state, None, length=int(3.0 / step_m) + 3)[0].xy[0]

    ends = jax.jit(jax.vmap(drive))(*map(jnp.asarray, zip(*starts)))
    return int(jnp.sum(ends > 1.0 + thickness_m / 2))


@pytest.mark.parametrize("thickness_m", [0.0, 0.01, 0.2])
def test_a_step_shorter_than_the_radius_never_crosses_a_wall_and_the_env_refuses_a_longer_one(thickness_m):
    """The base checks where a move ends: below one radius a step cannot cross a wall of any
    thickness; at 1.2 radii it crosses a thin one, at 3 a 0.2 m one (so the bound is needed)."""
    for below in (0.9, 0.99):
        assert _crosses(below, thickness_m) == 0
    assert _crosses(3.0, thickness_m) > 0
    if thickness_m < 0.05:
        assert _crosses(1.2, thickness_m) > 0
    assert robot_lib.step_length_problem(robot_lib.RobotParams(), 0.1) is None  # 0.05 m a step
    too_far = robot_lib.step_length_problem(robot_lib.RobotParams(max_speed_mps=3.0), 0.1)
    assert "0.3 m" in too_far and "0.275 m" in too_far and "below 2.75 m/s" in too_far
