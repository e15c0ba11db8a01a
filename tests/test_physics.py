"""Social force, battery (Eq. 1-2 by hand), routes and the distance field: known answers."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.sparse.csgraph import shortest_path

from socialnav.jaxsim import battery, geometry, graph
from socialnav.jaxsim import social_force as sf


def test_two_walkers_head_on_repel(warehouse):
    p = warehouse.params
    x, y = jnp.array([0.0, 1.0]), jnp.array([0.0, 0.0])
    vx, vy = jnp.array([1.0, -1.0]), jnp.zeros(2)
    ax, ay = sf.social_force(p, x, y, vx, vy, jnp.ones(2))
    assert ax[0] < 0 < ax[1]  # pushed apart along x
    np.testing.assert_allclose(ax[0], -ax[1], rtol=1e-5)  # mirror symmetry
    # An absent agent (weight 0) exerts nothing.
    ax0, ay0 = sf.social_force(p, x, y, vx, vy, jnp.array([1.0, 0.0]))
    assert float(ax0[0]) == 0.0 and float(ay0[0]) == 0.0
    # Farther is weaker.
    far, _ = sf.social_force(p, jnp.array([0.0, 3.0]), y, vx, vy, jnp.ones(2))
    assert abs(far[0]) < abs(ax[0])


def test_desired_force_relaxes_to_desired_velocity(warehouse):
    p = warehouse.params
    ax, ay = sf.desired_force(p, jnp.float32(3.0), jnp.float32(4.0), jnp.float32(0.0), jnp.float32(0.0), 1.0)
    np.testing.assert_allclose(
        [ax, ay], [0.6 / p.worker_relaxation_time_s, 0.8 / p.worker_relaxation_time_s], rtol=1e-5
    )


def test_wall_field_and_obstacle_force(warehouse):
    boxes = np.array([[0.0, 1.0, 0.0, 1.0]])
    sd, nx, ny = geometry.box_signed_distance(np.array([2.0, 0.5, 0.5]), np.array([0.5, 0.6, 3.0]), boxes)
    np.testing.assert_allclose(sd, [1.0, -0.4, 2.0])
    np.testing.assert_allclose(nx, [1.0, 0.0, 0.0])
    np.testing.assert_allclose(ny, [0.0, 1.0, 1.0])
    p = warehouse.params
    near = sf.obstacle_force(p, 0.3, 1.0, 0.0)[0]
    far = sf.obstacle_force(p, 1.0, 1.0, 0.0)[0]
    assert near > far > 0
    np.testing.assert_allclose(near / far, np.exp(0.7 / p.worker_obstacle_sigma_m), rtol=1e-5)


def test_the_distance_field_is_box_distance_at_every_cell_centre_bit_for_bit(warehouse):
    """The field (and the host's signed distance at any point) is built one box at a time with x
    and y apart; it must hold what the one formula
    (:func:`geometry.box_distance`, every box at once) gives: on the warehouse, and on touching
    and overlapping boxes where two boxes tie (the earlier one's normal is kept, as argmin does)
    and cells lie inside two boxes at once."""
    from socialnav.jaxsim.world import world_bounds

    ties = np.array([[0.0, 1.0, 0.0, 1.0], [1.0, 2.0, 0.0, 1.0], [0.5, 1.5, 0.5, 2.0], [-1.0, 3.0, -0.5, -0.25]])
    for boxes, bounds, resolution in (
        (warehouse.boxes_m, world_bounds(warehouse), 0.05),
        (ties, (-1.5, 3.5, -1.0, 2.5), 0.125),  # cell centres on the boxes' edges
    ):
        field = geometry.build_distance_field(boxes, bounds, resolution)
        xs = np.arange(bounds[0], bounds[1] + resolution / 2, resolution)  # the cell centres
        ys = np.arange(bounds[2], bounds[3] + resolution / 2, resolution)
        assert field.sdf_m.shape == (len(ys), len(xs))
        rows = slice(None, None, 7)  # every 7th row: the whole warehouse at once needs 1 GB here
        gx, gy = np.meshgrid(xs, ys[rows])
        sd, normal = geometry.box_distance(np.stack([gx, gy], -1), np.asarray(boxes, np.float64))
        for built, direct in ((field.sdf_m, sd), (field.normal_x, normal[..., 0]), (field.normal_y, normal[..., 1])):
            np.testing.assert_array_equal(built[rows], direct.astype(np.float32))
        # The host form for any points (the tests' wall checks): the same float64 bits, off the grid too.
        px, py = gx + 0.0137, gy - 0.0071
        host = geometry.box_signed_distance(px, py, boxes)
        sd, normal = geometry.box_distance(np.stack([px, py], -1), np.asarray(boxes, np.float64))
        for got, want in zip(host, (sd, normal[..., 0], normal[..., 1]), strict=True):
            np.testing.assert_array_equal(got, want)
    assert (field.sdf_m < 0).any() and (field.sdf_m == 0).any()  # insides and edges were compared
    with pytest.raises(ValueError, match="at least one box"):
        geometry.build_distance_field(np.zeros((0, 4)), (0, 1, 0, 1))


def test_segment_hits_boxes():
    boxes = np.array([[0.0, 1.0, 0.0, 1.0]])
    p0 = np.array([[-1.0, 0.5], [-1.0, 2.0], [0.5, -1.0], [2.0, 2.0]])
    p1 = np.array([[2.0, 0.5], [2.0, 2.0], [0.5, -0.5], [0.5, 0.5]])
    assert geometry.segment_hits_boxes(p0, p1, boxes).tolist() == [True, False, False, True]
    # Axis-parallel and degenerate segments (a direction component exactly 0): along the box's
    # edge touches it, a point inside hits, a point outside does not.
    p0 = np.array([[0.0, -1.0], [1.5, -1.0], [0.5, 0.5], [1.5, 1.5]])
    p1 = np.array([[0.0, 2.0], [1.5, 2.0], [0.5, 0.5], [1.5, 1.5]])
    assert geometry.segment_hits_boxes(p0, p1, boxes).tolist() == [True, False, True, False]


def test_segment_hits_boxes_is_one_formula_in_numpy_and_jax():
    """The arena's line of sight (jax.numpy, float32) and the warehouse's grid (numpy, float64)
    agree on random and grid-aligned segments, where exact zeros and edge contacts are common."""
    rng = np.random.default_rng(0)
    boxes = np.round(rng.uniform(-5, 5, (12, 2, 2)), 1)
    boxes = np.concatenate([np.sort(boxes[:, :, 0], 1), np.sort(boxes[:, :, 1], 1)], axis=1).astype(np.float32)
    ends = np.round(rng.uniform(-6, 6, (2, 20000, 2)), 1).astype(np.float32)
    ends[1, :5000, 0] = ends[0, :5000, 0]  # vertical
    ends[1, 5000:10000, 1] = ends[0, 5000:10000, 1]  # horizontal
    numpy_says = geometry.segment_hits_boxes(ends[0], ends[1], boxes)
    jax_says = jax.jit(lambda a, b, w: geometry.segment_hits_boxes(a, b, w, xp=jnp))(ends[0], ends[1], boxes)
    np.testing.assert_array_equal(np.asarray(jax_says), numpy_says)
    assert 0.1 < numpy_says.mean() < 0.9


def test_battery_hand_computed(warehouse):
    """120 s at 0.5 m/s without and with an obstacle, then 120 s charging (Eq. 1-2)."""
    p = warehouse.params
    ks, kd, ko, kc = (
        p.battery_static_pct_per_s,
        p.battery_dynamic_pct_per_m,
        p.battery_obstacle_factor,
        p.battery_charge_pct_per_s,
    )
    steps = int(round(120 / p.dt_s))

    def run(b0, speed, charging, obstacle):
        def body(b, _):
            change = battery.battery_change_pct(p, jnp.float32(speed), charging, obstacle)
            return battery.next_battery_pct(b, change), change

        return jax.lax.scan(body, jnp.float32(b0), None, length=steps)

    b1, l1 = run(100.0, 0.5, False, False)
    np.testing.assert_allclose(l1, -p.dt_s * (ks + kd * 0.5), rtol=1e-6)  # Eq. (1), every step
    expected1 = 100.0 - 120 * (ks + 0.5 * kd)  # = 100 - 120 * 100 / 14400
    assert expected1 == pytest.approx(100 - 120 / 144)
    b2, l2 = run(b1, 0.5, False, True)
    np.testing.assert_allclose(l2, -p.dt_s * (ks + kd * 0.5) * ko, rtol=1e-6)
    expected2 = expected1 - 120 * (ks + 0.5 * kd) * ko
    b3, l3 = run(b2, 0.0, True, False)
    np.testing.assert_allclose(l3, p.dt_s * kc, rtol=1e-6)
    expected3 = expected2 + 120 * kc
    # Eq. (2) summed in float32: at most half an ulp of 100 lost per step.
    tol = steps * np.spacing(np.float32(100.0))
    for got, want in [(b1, expected1), (b2, expected2), (b3, expected3)]:
        assert abs(float(got) - want) <= tol
    assert float(battery.next_battery_pct(jnp.float32(99.99), jnp.float32(1.0))) == 100.0
    assert float(battery.next_battery_pct(jnp.float32(0.01), jnp.float32(-1.0))) == 0.0


def test_all_pairs_next_hops_match_scipy(warehouse):
    s = warehouse
    w = graph.edge_lengths_m(s.waypoint_xy_m, s.edges)
    dist, nxt = graph.all_pairs_shortest(s.n_waypoints, s.edges, w, s.robot_allowed)
    keep = np.flatnonzero(s.robot_allowed)
    m = np.zeros((s.n_waypoints, s.n_waypoints))
    for (u, v), length in zip(s.edges, w):
        if s.robot_allowed[u] and s.robot_allowed[v]:
            m[u, v] = m[v, u] = length
    ref = shortest_path(m, directed=False)
    np.testing.assert_allclose(dist[np.ix_(keep, keep)], ref[np.ix_(keep, keep)], rtol=1e-9)
    # next_hop walks a shortest path: each hop is an edge and the hop lengths add up to dist.
    edge_set = {tuple(e) for e in s.edges} | {tuple(e[::-1]) for e in s.edges}
    rng = np.random.default_rng(0)
    for i, j in rng.choice(keep, size=(200, 2)):
        path = [int(i)]
        while path[-1] != j:
            path.append(int(nxt[path[-1], j]))
            assert (path[-2], path[-1]) in edge_set or path[-2] == path[-1] == j
        assert s.parking not in path
        length = sum(np.linalg.norm(s.waypoint_xy_m[a] - s.waypoint_xy_m[b]) for a, b in zip(path, path[1:]))
        assert length == pytest.approx(dist[i, j])
    assert not np.isfinite(dist[s.parking]).any()


def test_fast_atan2_matches_arctan2():
    angles = np.linspace(-np.pi, np.pi, 10001)
    radius = np.linspace(0.01, 10, 10001)
    y, x = radius * np.sin(angles), radius * np.cos(angles)
    got = np.asarray(sf.fast_atan2(jnp.asarray(y, jnp.float32), jnp.asarray(x, jnp.float32)))
    err = np.abs(np.angle(np.exp(1j * (got - np.arctan2(y, x)))))
    assert err.max() < 3e-4
    assert float(sf.fast_atan2(jnp.float32(0), jnp.float32(0))) == 0.0


def test_cos_sin_of_turns_matches_numpy_within_the_stated_bound():
    u = np.concatenate([np.linspace(0.0, 1.0, 200_001), [-1.3, -0.75, -0.25, 0.25, 0.5, 0.75, 1.0, 2.6]])
    cos, sin = sf.cos_sin_turns(jnp.asarray(u, jnp.float32))
    angle = 2.0 * np.pi * u  # float64 truth
    assert np.max(np.abs(np.asarray(cos) - np.cos(angle))) < 6e-7 * 2  # float32 input rounding of u
    assert np.max(np.abs(np.asarray(sin) - np.sin(angle))) < 6e-7 * 2
    # The quarter turns land on the axes.
    c, s = sf.cos_sin_turns(jnp.asarray([0.0, 0.25, 0.5, 0.75], jnp.float32))
    np.testing.assert_allclose(np.asarray(c), [1, 0, -1, 0], atol=1e-6)
    np.testing.assert_allclose(np.asarray(s), [0, 1, 0, -1], atol=1e-6)


def test_random_force_is_gaussian_with_the_configured_spread(warehouse):
    p = warehouse.params
    k1, k2 = jax.random.split(jax.random.key(3))
    u1 = jax.random.uniform(k1, (200_000,), minval=1e-7, maxval=1.0)
    u2 = jax.random.uniform(k2, (200_000,))
    ax, ay = sf.random_force(p, u1, u2)
    sigma = float(p.worker_random_force_std_mps2)
    for a in (np.asarray(ax), np.asarray(ay)):
        assert abs(a.mean()) < 0.01 * sigma and abs(a.std() / sigma - 1) < 0.01
    assert abs(np.corrcoef(np.asarray(ax), np.asarray(ay))[0, 1]) < 0.01


@pytest.mark.slow
@pytest.mark.parametrize("force", [sf.social_force, sf.social_force_xla], ids=["default", "xla"])
@pytest.mark.parametrize("n", [1, 2, 7, 8, 51])
def test_pairwise_social_force_equals_dense(warehouse, n, force):
    """Each pair once (Newton's third law) gives the full-matrix result, in the CPU kernel
    (:mod:`jaxsim.native`, the default here) and in JAX."""
    p = warehouse.params
    k = jax.random.split(jax.random.key(n), 5)
    x, y = jax.random.uniform(k[0], (n,)) * 6, jax.random.uniform(k[1], (n,)) * 6
    vx, vy = jax.random.normal(k[2], (n,)), jax.random.normal(k[3], (n,))
    w = (jax.random.uniform(k[4], (n,)) > 0.3).astype(jnp.float32)
    got = force(p, x, y, vx, vy, w)
    want = sf.social_force_dense(p, x, y, vx, vy, w)
    scale = float(jnp.max(jnp.abs(jnp.stack(want)))) + 1.0
    np.testing.assert_allclose(np.stack(got), np.stack(want), atol=2e-5 * scale)


@pytest.mark.slow
def test_hash_uniforms_are_uniform_and_independent():
    from socialnav.jaxsim.rng import hash_uniform16

    draws = jax.vmap(lambda s: hash_uniform16(jnp.uint32(12345), s, (6, 51)))(jnp.arange(2000))
    u = np.asarray(draws)  # (steps, streams, agents)
    assert ((u > 0) & (u < 1)).all()
    assert abs(u.mean() - 0.5) < 0.005 and abs(u.var() - 1 / 12) < 0.002
    hist, _ = np.histogram(u, bins=16, range=(0, 1))
    assert hist.min() > 0.95 * u.size / 16
    for a, b in [(u[1:], u[:-1]), (u[:, 1:], u[:, :-1]), (u[:, :, 1:], u[:, :, :-1])]:  # steps, streams, agents
        assert abs(np.corrcoef(a.ravel(), b.ravel())[0, 1]) < 0.01
    other = np.asarray(hash_uniform16(jnp.uint32(12346), jnp.int32(0), (6, 51)))
    assert abs(np.corrcoef(other.ravel(), u[0].ravel())[0, 1]) < 0.2
    np.testing.assert_array_equal(u[3], np.asarray(hash_uniform16(jnp.uint32(12345), jnp.int32(3), (6, 51))))


def _box_distance_m(boxes_m, x, y):
    """(P,) exact distance from points to the nearest axis-aligned box (0 inside one)."""
    dx = np.maximum(np.maximum(boxes_m[None, :, 0] - x[:, None], 0), x[:, None] - boxes_m[None, :, 1])
    dy = np.maximum(np.maximum(boxes_m[None, :, 2] - y[:, None], 0), y[:, None] - boxes_m[None, :, 3])
    return np.sqrt(dx**2 + dy**2).min(axis=1)


def test_no_robot_waypoint_within_the_robots_radius_of_a_wall(warehouse):
    """What keep_body_clear relies on to never hold the robot off a goal."""
    x, y = warehouse.waypoint_xy_m[warehouse.robot_allowed].T
    assert _box_distance_m(warehouse.boxes_m, x, y).min() >= warehouse.params.robot_radius_m


@pytest.mark.slow
def test_robot_body_stays_out_of_walls(short_day):
    """A whole short day of 4 worlds: the robot's body (its radius, not only its centre) never
    overlaps a wall box, to the field's first-order error (1 mm), and it still does its tasks."""
    from socialnav.jaxsim.rollout import rollout

    scenario, world, controller = short_day
    _, rec = rollout(scenario.params, world, controller, 3, 4, scenario.n_slots * 600, 5)
    x, y = np.asarray(rec.robot_x_m).ravel(), np.asarray(rec.robot_y_m).ravel()
    clearance = _box_distance_m(scenario.boxes_m, x, y)
    assert clearance.min() >= scenario.params.robot_radius_m - 1e-3
    assert np.asarray(rec.tasks_succeeded)[:, -1].min() > 0
