"""Cost layers (planners.layers.costmap, snl, casn, snape, gscl_layer): known values, shapes, batching."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from flax import nnx
from scipy import ndimage

from socialnav.models import social_costs as sc
from socialnav.models import unet
from socialnav.planners.layers import casn_layer as casn
from socialnav.planners.layers import costmap, gscl_layer
from socialnav.planners.layers import snape_layer as snape
from socialnav.planners.layers import snl_layer as snl
from socialnav.planners.layers.scene import make_scene

SPEC = costmap.GridSpec(height=60, width=80, resolution_m=0.1, origin_x_m=-4.0, origin_y_m=-3.0)
X, Y = SPEC.cell_centres()


def value_at(layer, x_m, y_m):
    i, j = np.asarray(SPEC.cell_of(np.array([x_m, y_m])))
    return float(layer[i, j]), (X[i, j], Y[i, j])


# ---------------------------------------------------------------- conventions and inflation


def test_obstacle_distance_equals_scipy_edt_within_its_reach():
    rng = np.random.default_rng(0)
    occupied = rng.uniform(size=(50, 70)) < 0.02
    d = np.asarray(costmap.obstacle_distance_m(occupied, 0.05, 0.6))
    ref = ndimage.distance_transform_edt(~occupied) * 0.05
    near = ref <= 0.6
    np.testing.assert_allclose(d[near], ref[near], atol=1e-6)
    assert np.all(d[~near] > 0.6)


def test_inflation_layer_follows_nav2s_formula():
    occupancy = np.zeros(SPEC.shape, np.float32)
    occupancy[30, 40] = 1.0
    layer = np.asarray(costmap.obstacle_layer(occupancy, SPEC, inscribed_radius_m=0.2))
    assert layer[30, 40] == costmap.LETHAL
    assert layer[30, 42] == costmap.INSCRIBED  # 0.2 m away
    assert layer[30, 43] == pytest.approx(252 * math.exp(-10 * (0.3 - 0.2)), rel=1e-5)
    assert layer[30, 45] == pytest.approx(252 * math.exp(-10 * (0.5 - 0.2)), rel=1e-5)
    assert layer[30, 46] == costmap.FREE  # 0.6 m: past the 0.55 m radius
    assert np.all(np.diff(layer[30, 40:50]) <= 0)
    # Compiled as one program, the same bits as its operations run one by one.
    eager = costmap.obstacle_layer.__wrapped__(occupancy, SPEC, inscribed_radius_m=0.2)
    np.testing.assert_array_equal(layer, np.asarray(eager))


def test_combine_max_and_uint8_conversion():
    a = jnp.array([[0.0, 100.5], [253.0, 10.0]])
    b = jnp.array([[5.0, 20.0], [0.0, 254.0]])
    np.testing.assert_array_equal(costmap.combine_max(a, b), [[5.0, 100.5], [253.0, 254.0]])
    np.testing.assert_array_equal(costmap.to_uint8(a), [[0, 100], [253, 10]])
    t = np.asarray(costmap.navfn_traversal(jnp.array([0.0, 252.0, 253.0, 254.0])))
    np.testing.assert_allclose(t, [50.0, 50 + 0.8 * 252, np.inf, np.inf])


def test_a_sampled_field_is_the_grid_centred_on_its_samples_and_finds_the_cell_a_point_is_in():
    """Grid.of_samples puts every cell's centre on a sample (its origin half a cell below and to
    the left of the first), and a lookup finds the same cell as GridSpec.cell_of, the planners'."""
    from socialnav.jaxsim.grid import Grid

    grid = Grid.of_samples(jnp.arange(35.0).reshape(5, 7), -1.3, 2.1, 0.25)
    spec = grid.spec
    assert spec.shape == (5, 7) and spec.resolution_m == 0.25
    assert (spec.origin_x_m, spec.origin_y_m) == pytest.approx((-1.425, 1.975))
    assert grid.first_centre_m == pytest.approx((-1.3, 2.1))
    x, y = spec.cell_centres()
    np.testing.assert_allclose(x[0], -1.3 + 0.25 * np.arange(7), atol=1e-6)
    np.testing.assert_allclose(y[:, 0], 2.1 + 0.25 * np.arange(5), atol=1e-6)
    points = np.array([[-1.3, 2.1], [-1.2, 2.2], [0.2, 3.05], [-0.45, 2.62]], np.float32)
    row, col = grid.index(points[:, 0], points[:, 1])
    np.testing.assert_array_equal(np.asarray(spec.cell_of(points)), np.stack([row, col], axis=-1))
    np.testing.assert_array_equal(np.asarray(grid.lookup(points[:, 0], points[:, 1])), [0.0, 0.0, 34.0, 17.0])
    # Off the grid: the lookup clamps to the border cell, nearest_cell says how far off it is.
    assert np.asarray(grid.index(np.float32(-9.0), np.float32(9.0))).tolist() == [4, 0]
    assert np.asarray(grid.nearest_cell(np.float32(-9.0), np.float32(9.0))).tolist() == [28.0, -31.0]
    # The spec's clamp moves cells off the grid to the nearest border cell and keeps the rest.
    cells = spec.cell_of(np.array([[-9.0, 9.0], [0.2, 3.05], [9.0, -9.0]], np.float32))
    assert np.asarray(spec.clamp(cells)).tolist() == [[4, 0], [4, 6], [0, 6]]
    assert np.asarray(spec.contains(cells)).tolist() == [False, True, False]


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(height=1, width=5, resolution_m=0.1),
        dict(height=5, width=5, resolution_m=0.0),
        dict(height=5, width=5, resolution_m=float("nan")),
    ],
)
def test_grid_spec_rejects_nonsense(kwargs):
    with pytest.raises(ValueError, match="GridSpec"):
        costmap.GridSpec(**kwargs)


# ---------------------------------------------------------------- SNL


def test_snl_radius_at_cutoff_matches_the_ros_formula():
    assert snl.radius_at_cutoff_m(0.25) == pytest.approx(1.0104, abs=1e-3)
    assert snl.radius_at_cutoff_m(0.25 * 6) == pytest.approx(2.475, abs=1e-3)  # in front at 1 m/s
    assert snl.radius_at_cutoff_m(snl.covariance_for_radius(1.2)) == pytest.approx(1.2)


def test_snl_proxemic_costs_at_hand_computed_points():
    standing = make_scene([[0.05, 0.05]])
    layer = np.asarray(snl.proxemic_layer(standing, X, Y))
    for dx, dy in [(0.5, 0.0), (0.0, -0.7), (-0.9, 0.0)]:
        cost, (cx, cy) = value_at(layer, 0.05 + dx, 0.05 + dy)
        r2 = (cx - 0.05) ** 2 + (cy - 0.05) ** 2
        assert cost == pytest.approx(77 * math.exp(-r2 / 0.5), rel=1e-4)
    assert value_at(layer, 0.05 + 1.1, 0.05)[0] == 0.0  # past 1.01 m: below the cutoff
    assert value_at(layer, 0.05 + 0.95, 0.05)[0] > 10.0

    walking = make_scene([[0.05, 0.05]], people_velocity_mps=[[1.0, 0.0]])
    layer = np.asarray(snl.proxemic_layer(walking, X, Y))
    front, (fx, _) = value_at(layer, 1.05, 0.05)
    behind, (bx, _) = value_at(layer, -0.95, 0.05)
    assert front == pytest.approx(77 * math.exp(-((fx - 0.05) ** 2) / (2 * 0.25 * 6)), rel=1e-4)
    assert behind == pytest.approx(77 * math.exp(-((bx - 0.05) ** 2) / (2 * 0.25)), rel=1e-4)
    assert value_at(layer, 2.3, 0.05)[0] > 10.0 > value_at(layer, -1.2, 0.05)[0]  # reach 2.47 m ahead, 1.01 behind


def test_snl_passing_lobe_is_on_the_persons_right():
    walking = make_scene([[0.05, 0.05]], people_velocity_mps=[[1.0, 0.0]])
    layer = np.asarray(snl.passing_layer(walking, X, Y))
    right, _ = value_at(layer, 0.05, -0.6)
    left, _ = value_at(layer, 0.05, 0.7)
    assert right > 10.0 and left == 0.0
    mirrored = np.asarray(snl.passing_layer(walking, X, Y, passing_side=+1.0))
    assert value_at(mirrored, 0.05, 0.7)[0] > 10.0 and value_at(mirrored, 0.05, -0.6)[0] == 0.0


def test_snl_half_plane_is_the_ros_angle_test():
    # The ROS layers' |atan2(dy, dx) - direction| < pi / 2, wrapped, as the sign of a dot product.
    rng = np.random.default_rng(3)
    dx, dy = rng.uniform(-3, 3, (2, 20000)).astype(np.float32)
    direction = rng.uniform(-4 * np.pi, 4 * np.pi, 20000).astype(np.float32)
    angle = np.arctan2(dy, dx).astype(np.float64) - direction
    ros = np.abs((angle + np.pi) % (2 * np.pi) - np.pi) < np.pi / 2
    margin = np.abs(np.abs((angle + np.pi) % (2 * np.pi) - np.pi) - np.pi / 2) > 1e-4  # off the boundary
    ours = np.asarray(snl._ahead(jnp.asarray(dx), jnp.asarray(dy), jnp.asarray(direction)))
    assert margin.mean() > 0.99 and ros[margin].any() and (~ros[margin]).any()
    np.testing.assert_array_equal(ours[margin], ros[margin])


@pytest.mark.slow
def test_snl_ignores_padding_and_takes_the_max_over_people():
    one = make_scene([[0.0, 0.0]])
    padded = make_scene([[0.0, 0.0]], max_people=5)
    np.testing.assert_array_equal(snl.snl_layer(one, X, Y), snl.snl_layer(padded, X, Y))
    two = make_scene([[0.0, 0.0], [2.0, 0.0]])
    each = [snl.snl_layer(make_scene([p]), X, Y) for p in ([0.0, 0.0], [2.0, 0.0])]
    np.testing.assert_allclose(snl.snl_layer(two, X, Y), np.maximum(*each))


# ---------------------------------------------------------------- CASN


def circle(n, radius, inward=True, centre=(0.0, 0.0)):
    angles = np.linspace(0, 2 * np.pi, n, endpoint=False) + 0.3
    xy = np.stack([centre[0] + radius * np.cos(angles), centre[1] + radius * np.sin(angles)], axis=1)
    heading = angles + (np.pi if inward else 0.0)
    return xy, heading


detect_groups = jax.jit(casn.detect_groups)


@pytest.mark.parametrize("n", [2, 3, 4, 5, 6])
def test_casn_finds_a_group_facing_inward_and_none_facing_outward(n):
    xy, heading = circle(n, 1.2)
    labels = np.asarray(detect_groups(make_scene(xy, heading, max_people=8)))
    assert np.all(labels[:n] == labels[0]) and labels[0] >= 0
    assert np.all(labels[n:] == -1)
    xy, heading = circle(n, 1.2, inward=False)
    assert np.all(np.asarray(detect_groups(make_scene(xy, heading, max_people=8))) == -1)


def test_casn_no_group_beyond_three_metres_or_while_walking():
    far = make_scene([[0.0, 0.0], [3.5, 0.0]], people_heading_rad=[0.0, np.pi])
    assert np.all(np.asarray(casn.detect_groups(far)) == -1)
    near = make_scene([[0.0, 0.0], [2.5, 0.0]], people_heading_rad=[0.0, np.pi])
    assert np.all(np.asarray(casn.detect_groups(near)) == 0)
    walking = make_scene([[0.0, 0.0], [2.5, 0.0]], [0.0, np.pi], people_velocity_mps=[[0.5, 0.0], [0.0, 0.0]])
    assert np.all(np.asarray(casn.detect_groups(walking)) == -1)


def test_casn_group_spaces_cover_the_inside_of_the_formation():
    xy, heading = circle(4, 1.5, centre=(1.0, 0.0))
    layer = jax.jit(lambda s: casn.casn_layer(s, X, Y)[0])
    assert value_at(np.asarray(layer(make_scene(xy, heading))), 1.0, 0.0)[0] == costmap.MAX_GRADED  # o-space centre
    lone = make_scene(xy[:1], heading[:1], max_people=4)
    assert value_at(np.asarray(layer(lone)), 1.0, 0.0)[0] == 0.0


@pytest.mark.slow
def test_casn_static_person_discs():
    layer, _ = casn.casn_layer(make_scene([[0.05, 0.05]]), X, Y)
    layer = np.asarray(layer)
    assert value_at(layer, 0.35, 0.05)[0] == 252.0  # intimate + personal
    assert value_at(layer, 1.0, 0.05)[0] == 100.0  # personal
    assert value_at(layer, 1.35, 0.05)[0] == 0.0


def test_casn_head_on_point_lies_between_robot_and_person():
    scene = make_scene([[4.0, 0.0]], people_velocity_mps=[[-1.0, 0.0]], robot_xy_m=(0.0, 0.0), robot_yaw_rad=0.0)
    point, state = casn.collision_points(scene, casn.initial_state(1))
    p = 1.0 / (1.0 + 0.5)  # |v_h| / (|v_h| + v_robot)
    np.testing.assert_allclose(point[0], [4.0 - p * 4.0, 0.0], atol=1e-6)
    assert 0.0 < float(point[0, 0]) < 4.0
    assert bool(state.frozen[0])  # 1.33 m from the robot: inside the 2 m freeze distance
    faster = make_scene([[4.0, 0.0]], people_velocity_mps=[[-1.3, 0.0]])
    assert float(casn.collision_points(faster, casn.initial_state(1))[0][0, 0]) < float(point[0, 0])


def test_casn_freeze_holds_the_point_until_the_robot_has_passed():
    params = casn.CASNParams()
    first = make_scene([[7.0, 0.0]], people_velocity_mps=[[-1.0, 0.0]])
    point, state = casn.collision_points(first, casn.initial_state(1), params)
    assert not bool(state.frozen[0])  # h_hat 2.33 m from the robot: not yet
    closer = make_scene([[2.4, 0.0]], people_velocity_mps=[[-1.0, 0.0]], robot_xy_m=(0.6, 0.0))
    frozen_point, state = casn.collision_points(closer, state, params)
    assert bool(state.frozen[0])
    later = make_scene([[1.8, 0.3]], people_velocity_mps=[[-1.0, 0.0]], robot_xy_m=(0.8, 0.0))
    point, state = casn.collision_points(later, state, params)
    np.testing.assert_array_equal(point, frozen_point)
    passed = make_scene([[0.5, 0.5]], people_velocity_mps=[[-1.0, 0.0]], robot_xy_m=(1.0, 0.0))
    _, state = casn.collision_points(passed, state, params)
    assert not bool(state.frozen[0])


def test_casn_crossing_point_sends_the_robot_behind_the_person():
    # Robot at the origin heading +x; the person 3 m ahead, 2 m to the left, walking across (-y).
    scene = make_scene([[3.0, 2.0]], people_velocity_mps=[[0.0, -0.4]], robot_yaw_rad=0.0)
    point, _ = casn.collision_points(scene, casn.initial_state(1))
    np.testing.assert_allclose(point[0], [0.8 * 3.0, -0.6], atol=1e-6)  # shifted the way the person walks
    # The cheaper way round the disc is on the side the person comes from (behind them).
    layer, _ = casn.casn_layer(scene, X, Y)
    column = np.asarray(layer)[:, np.argmin(np.abs(X[0] - 2.4))]
    free_y = Y[:, 0][column == 0]
    assert free_y[free_y > 0].min() < -free_y[free_y < 0].max()


# ---------------------------------------------------------------- SNAPE


def test_snape_intimate_is_lethal_personal_dearer_than_social():
    scene = make_scene([[0.05, 0.05]], people_heading_rad=[0.0])
    layer = np.asarray(snape.snape_layer(scene, X, Y))
    assert value_at(layer, 0.05, 0.35)[0] == costmap.LETHAL  # 0.3 m to the side
    personal = value_at(layer, 0.05, 0.95)[0]  # 0.9 m to the side
    social = value_at(layer, 0.05, 2.05)[0]  # 2 m to the side
    assert personal == 50.0 and social == 10.0 and personal > social
    # Longer in front than behind: 1.5 m ahead is personal, 1.5 m behind is social.
    assert value_at(layer, 1.55, 0.05)[0] == 50.0
    assert value_at(layer, -1.45, 0.05)[0] == 10.0


def test_snape_objects_interaction_space():
    table = ([[1.0, -1.0], [2.0, -1.0], [2.0, 0.0], [1.0, 0.0]], 30.0)
    scene = make_scene([[-3.0, 2.0]], objects=[table], max_objects=2)
    layer = np.asarray(snape.snape_layer(scene, X, Y))
    assert value_at(layer, 1.5, -0.5)[0] == 30.0
    assert value_at(layer, 2.5, -0.5)[0] == 0.0


# ---------------------------------------------------------------- GSCL layer


def small_unet_predict():
    model = unet.UNet((4, 4, 8, 8), rngs=nnx.Rngs(0))
    model.eval()
    return lambda maps: model(maps)


@pytest.mark.slow
def test_gscl_layer_reproduces_the_model_where_window_and_grid_align():
    predict = small_unet_predict()
    robot = np.array([3.0, 2.0], np.float32)
    spec = costmap.GridSpec(40, 40, 0.4, origin_x_m=float(robot[0] - 8.0), origin_y_m=float(robot[1] - 8.0))
    occupancy = np.zeros(spec.shape, np.float32)
    occupancy[5, :] = 1.0
    scene = make_scene([[4.0, 3.5]], people_heading_rad=[1.0], robot_xy_m=robot, goal_xy_m=(8.0, 5.0))
    # Jitted as the stacks run them (op by op, this test compiled ~150 programs).
    layer = np.asarray(jax.jit(lambda o, s: gscl_layer.gscl_layer(predict, o, spec, s))(occupancy, scene))
    window = np.asarray(jax.jit(lambda o, s: predict(gscl_layer.window_input(o, spec, s)[None]))(occupancy, scene))[0]
    # The window's row 0 is the top (y up); the planner grid's row 0 is the bottom.
    np.testing.assert_allclose(layer, gscl_layer.read_cost(np.flipud(window)), rtol=1e-6)


def test_gscl_costs_read_graded_up_to_the_graded_top_and_lethal_from_the_forbidden_level():
    top, forbidden_from = sc.GRADED_TOP, sc.FORBIDDEN_FROM
    values = np.array([0.0, 0.5 * top, top, 0.5 * (top + forbidden_from), forbidden_from, 1.0, -0.1], np.float32)
    want = [0.0, 126.0, costmap.MAX_GRADED, costmap.MAX_GRADED, costmap.LETHAL, costmap.LETHAL, 0.0]
    np.testing.assert_allclose(np.asarray(gscl_layer.read_cost(values)), want, rtol=1e-6)


@pytest.mark.slow
def test_gscl_layers_batch_equals_one_by_one():
    predict = small_unet_predict()
    scenes = [
        make_scene([[0.5, 0.5]], [0.3], robot_xy_m=(0.0, 0.0), goal_xy_m=(3.0, 0.0)),
        make_scene([[-1.0, 1.0]], [2.0], robot_xy_m=(1.0, -1.0), goal_xy_m=(-3.0, 0.0)),
    ]
    occupancy = np.zeros(SPEC.shape, np.float32)
    batch = jax.tree_util.tree_map(lambda *a: jnp.stack(a), *scenes)
    together = np.asarray(jax.jit(lambda o, b: gscl_layer.gscl_layers(predict, o, SPEC, b))(occupancy, batch))
    alone = jax.jit(lambda o, s: gscl_layer.gscl_layer(predict, o, SPEC, s))
    for k, scene in enumerate(scenes):
        # Costs reach 252: a batch of two and a batch of one may pick different convolution
        # orders in XLA, a few float32 ulps apart (2.9e-6 at 12.0 seen on CI's processor).
        one = alone(occupancy, scene)
        np.testing.assert_allclose(together[k], one, rtol=1e-6, atol=1e-6)
    far = np.hypot(X - 0.0, Y - 0.0) > 8 * math.sqrt(2) + 0.1
    assert np.all(together[0][far] == 0.0)


# ---------------------------------------------------------------- batching


@pytest.mark.slow
def test_layers_vmap_over_scenes():
    rng = np.random.default_rng(3)
    scenes = [
        make_scene(rng.uniform(-3, 3, (4, 2)), rng.uniform(-3, 3, 4), rng.uniform(-1, 1, (4, 2)), max_people=6)
        for _ in range(3)
    ]
    batch = jax.tree_util.tree_map(lambda *a: jnp.stack(a), *scenes)
    layers = {
        "snl": lambda s: snl.snl_layer(s, X, Y),
        "casn": lambda s: casn.casn_layer(s, X, Y)[0],
        "snape": lambda s: snape.snape_layer(s, X, Y),
    }
    for name, fn in layers.items():
        together = jax.jit(jax.vmap(fn))(batch)
        for k, scene in enumerate(scenes):
            np.testing.assert_allclose(together[k], fn(scene), atol=1e-4, err_msg=name)


# ---------------------------------------------------------------- the pictures' command


def test_layers_command_rejects_a_run_without_checkpoints(tmp_path, capsys):
    from socialnav import cli

    assert cli.main(["layers", "--out", str(tmp_path / "img"), "--gscl-run", str(tmp_path)]) == 2
    assert "neither a GSCL training run" in capsys.readouterr().err
    assert not (tmp_path / "img").exists()


@pytest.mark.slow
def test_layers_command_writes_one_picture_per_scene_type(tmp_path):
    from socialnav import cli
    from socialnav.planners import plots

    assert cli.main(["layers", "--out", str(tmp_path)]) == 0
    written = sorted(p.name for p in tmp_path.glob("*.png"))
    assert written == sorted(f"layers_{name}.png" for name in plots.demo_scenes())
    assert not list(tmp_path.glob(".socialnav-tmp-*"))


@pytest.mark.slow
def test_demo_paths_reach_the_goal_and_keep_off_lethal_cells():
    from socialnav.planners import plots

    demo = plots.demo_scenes()["group_facing_in"]
    for name, costs, path, reached in plots.plan_panels(demo, plots.layer_functions()):
        assert reached, name
        ij = np.asarray(plots.SPEC.cell_of(path))
        assert np.all(costs[ij[1:, 0], ij[1:, 1]] < costmap.INSCRIBED), name


# ---------------------------------------------------------------- one shape for every layer (planners.layers)


@pytest.mark.slow
def test_every_layer_in_one_shape_equals_its_own_function():
    """``layer(scene, grid, state) -> (costs, state)`` gives each paper's layer exactly, CASN's state
    carried (its frozen points), the others' ``()``; under jit with the grid static too. Two
    layers of one kind are equal whatever their parameters (an actor built on one is cached)."""
    from socialnav.planners import layers

    scene = make_scene([[1.0, 0.5], [-1.0, -0.5]], people_velocity_mps=[[-1.0, 0.0], [0.0, 0.0]], goal_xy_m=(3, 0))
    x, y = jnp.asarray(X), jnp.asarray(Y)
    expected = {
        "snl": snl.snl_layer(scene, x, y),
        "casn": casn.casn_layer(scene, x, y)[0],
        "snape": snape.snape_layer(scene, x, y),
        "none": jnp.zeros(SPEC.shape, jnp.float32),
    }
    for name, make in layers.BY_NAME.items():
        layer = make()
        costs, state = layer(scene, SPEC)
        np.testing.assert_array_equal(np.asarray(costs), np.asarray(expected[name]))
        assert costs.shape == SPEC.shape and costs.dtype == jnp.float32
        jitted = jax.jit(layer.apply, static_argnums=2)(layer.params, scene, SPEC, layer.init(scene.n_people), None)
        np.testing.assert_allclose(np.asarray(jitted[0]), np.asarray(costs), atol=1e-4)
        if name == "casn":
            assert isinstance(state, casn.CASNState)
        else:
            assert state == ()
    # Parameters are traced: another radius changes the costs through the same function.
    wider_layer = layers.casn(casn.CASNParams(personal_radius_m=1.5))
    wider = wider_layer(scene, SPEC)[0]
    assert float(jnp.sum(wider > 0)) > float(jnp.sum(expected["casn"] > 0))
    assert wider_layer == layers.casn() and hash(wider_layer) == hash(layers.casn())
    assert layers.snl(passing=False) != layers.snl() and layers.casn() != layers.snape()


@pytest.mark.slow
def test_the_gscl_layer_in_one_shape_equals_gscl_layer():
    from socialnav.planners import layers

    predict = small_unet_predict()
    scene = make_scene([[1.0, 0.5]], people_heading_rad=[math.pi], robot_xy_m=(0.0, 0.0), goal_xy_m=(3.0, 0.0))
    occupancy = np.zeros(SPEC.shape, np.float32)
    occupancy[:, :3] = 1.0
    costs, state = layers.gscl(predict)(scene, SPEC, occupancy=occupancy)
    np.testing.assert_array_equal(np.asarray(costs), np.asarray(gscl_layer.gscl_layer(predict, occupancy, SPEC, scene)))
    assert state == () and float(costs.max()) > 0.0
    with pytest.raises(ValueError, match="occupancy"):
        layers.gscl(predict)(scene, SPEC)
    with pytest.raises(TypeError, match="SocialCostModel"):
        layers.gscl("runs/gscl")


def test_a_stack_takes_a_layer_of_its_own_kind_and_gscl_only_with_a_model():
    from socialnav.planners import actors, layers, stack

    with pytest.raises(ValueError, match="trained GSCL model"):
        actors.stack_actor(stack.METHODS["gscl"], SPEC, 0.275)
    with pytest.raises(ValueError, match="'casn', the layer given is 'snl'"):
        actors.stack_actor(stack.METHODS["casn"], SPEC, 0.275, layer=layers.snl())
    assert (
        actors.stack_actor(stack.METHODS["snl_large"], SPEC, 0.275, layer=layers.snl(snl.SIGMA_LARGE)).name
        == "snl_large"
    )
    assert stack.cost_layer(stack.METHODS["snl_large"]).params == snl.SIGMA_LARGE
    with pytest.raises(ValueError, match="gscl_model"):
        stack.cost_layer(stack.METHODS["gscl"])
