"""Grid planners: potentials equal scipy's Dijkstra, paths descend them, the smooth planner's
gradient equals finite differences, a layer moves the path where it should."""

import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from socialnav.planners.global_planners import grid_planner, smooth_planner
from socialnav.planners.layers import costmap
from socialnav.planners.layers import snl_layer as snl
from socialnav.planners.layers.scene import make_scene


def scipy_potential(traversal, goal, resolution_m, connectivity=8):
    """Cost-to-goal by scipy's Dijkstra on the grid graph built independently of the planner:
    moves to the 8 (4) neighbours cost length x the entered cell's cost, no corner cutting."""
    h, w = traversal.shape
    blocked = np.isinf(traversal)
    offsets = [(di, dj) for di in (-1, 0, 1) for dj in (-1, 0, 1) if (di, dj) != (0, 0)]
    if connectivity == 4:
        offsets = [(di, dj) for di, dj in offsets if di == 0 or dj == 0]
    rows, cols, vals = [], [], []
    for i in range(h):
        for j in range(w):
            for di, dj in offsets:
                a, b = i + di, j + dj
                if not (0 <= a < h and 0 <= b < w) or blocked[a, b]:
                    continue
                if di and dj and (blocked[i + di, j] or blocked[i, j + dj]):
                    continue
                # Reversed edge: Dijkstra from the goal over it gives the cost of reaching the goal.
                rows.append(a * w + b)
                cols.append(i * w + j)
                vals.append(resolution_m * np.hypot(di, dj) * traversal[a, b])
    graph = sp.csr_matrix((vals, (rows, cols)), shape=(h * w, h * w))
    return dijkstra(graph, directed=True, indices=goal[0] * w + goal[1]).reshape(h, w)


def random_grid(rng, h, w, wall_share):
    costs = rng.uniform(0, 252, (h, w)).astype(np.float32)
    costs[rng.uniform(size=(h, w)) < wall_share] = costmap.LETHAL
    return costs


@pytest.mark.parametrize("solver", ["sweeps", "dijkstra"])
@pytest.mark.parametrize("connectivity", [8, 4])
def test_potentials_equal_scipy_dijkstra_on_random_walled_grids(connectivity, solver):
    rng = np.random.default_rng(connectivity)
    batch, h, w = 6, 23, 31
    costs = np.stack([random_grid(rng, h, w, share) for share in np.linspace(0.0, 0.35, batch)])
    # A maze-like wall with one gap in half of them: paths that turn back.
    costs[::2, 8, 2:] = costmap.LETHAL
    costs[::2, 16, :-2] = costmap.LETHAL
    goals = np.stack([rng.integers(0, h, batch), rng.integers(0, w, batch)], axis=1)
    costs[np.arange(batch), goals[:, 0], goals[:, 1]] = 0.0
    traversal = np.asarray(costmap.navfn_traversal(costs))
    potentials = jax.jit(grid_planner.potentials, static_argnames=("resolution_m", "connectivity", "solver"))
    phi = np.asarray(potentials(traversal, goals, resolution_m=0.05, connectivity=connectivity, solver=solver))
    for k in range(batch):
        ref = scipy_potential(traversal[k], goals[k], 0.05, connectivity)
        reachable = np.isfinite(ref)
        np.testing.assert_array_equal(np.isfinite(phi[k]), reachable)
        np.testing.assert_allclose(phi[k][reachable], ref[reachable], rtol=1e-5, atol=1e-4)


@pytest.mark.slow
def test_paths_descend_the_potential_and_avoid_impassable_cells():
    rng = np.random.default_rng(7)
    batch, h, w = 8, 30, 30
    costs = np.stack([random_grid(rng, h, w, 0.2) for _ in range(batch)])
    starts = np.tile([[1, 1]], (batch, 1))
    goals = np.tile([[h - 2, w - 2]], (batch, 1))
    costs[:, 1, 1] = costs[:, h - 2, w - 2] = 0.0
    traversal = costmap.navfn_traversal(costs)
    plan = grid_planner.plans(traversal, starts, goals, 0.1, max_steps=4 * (h + w))
    reachable = [k for k in range(batch) if np.isfinite(np.asarray(plan.potential[k])[1, 1])]
    assert len(reachable) >= batch // 2  # the paths' checks below are not vacuous
    for k in range(batch):
        n = int(plan.path_length[k])
        path = np.asarray(plan.path_ij[k, :n])
        phi = np.asarray(plan.potential[k])
        if k not in reachable:
            assert not bool(plan.reached[k]) and np.isinf(float(plan.cost[k]))
            continue
        assert bool(plan.reached[k]) and tuple(path[-1]) == (h - 2, w - 2)
        assert np.all(costs[k][path[1:, 0], path[1:, 1]] < costmap.INSCRIBED)
        assert np.all(np.diff(phi[path[:, 0], path[:, 1]]) < 0)
        assert np.all(np.abs(np.diff(path, axis=0)).max(axis=1) == 1)  # neighbours
        assert float(plan.cost[k]) == pytest.approx(phi[1, 1])


def test_unreachable_goal_and_goal_off_the_grid():
    costs = np.zeros((10, 10), np.float32)
    costs[:, 5] = costmap.LETHAL
    walled = grid_planner.plan(costmap.navfn_traversal(costs), (2, 2), (2, 8), 0.1)
    assert not bool(walled.reached) and np.isinf(float(walled.cost))
    assert int(walled.path_length) == 1
    off = grid_planner.plan(costmap.navfn_traversal(np.zeros((10, 10))), (2, 2), (20, 3), 0.1)
    assert not bool(off.reached) and np.all(np.isinf(np.asarray(off.potential)))


def test_free_grid_potential_is_the_octile_distance():
    h = w = 15
    phi = np.asarray(grid_planner.potential(np.full((h, w), 50.0), (7, 7), 0.1))
    i, j = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    di, dj = np.abs(i - 7), np.abs(j - 7)
    octile = 0.1 * 50.0 * (np.maximum(di, dj) + (np.sqrt(2) - 1) * np.minimum(di, dj))
    np.testing.assert_allclose(phi, octile, rtol=1e-5)


@pytest.mark.slow
def test_a_standing_person_moves_the_path_further_with_a_larger_covariance():
    spec = costmap.GridSpec(40, 100, 0.1, origin_x_m=-5.0, origin_y_m=-2.0)
    x, y = spec.cell_centres()
    start, goal = np.array([-4.5, 0.05]), np.array([4.5, 0.05])
    person = np.array([0.0, 0.05])
    clearances = []
    for params in (None, snl.SIGMA_SMALL, snl.SIGMA_LARGE):
        if params is None:
            costs = jnp.zeros(spec.shape)
        else:
            costs = snl.snl_layer(make_scene([person], [0.0]), x, y, params, passing=False)
        plan = grid_planner.navfn_plans(costs[None], start[None], goal[None], spec)
        path = np.asarray(grid_planner.path_xy_m(plan, spec))[0, : int(plan.path_length[0])]
        assert bool(plan.reached[0])
        clearances.append(np.min(np.linalg.norm(path - person, axis=1)))
    assert clearances[0] < 0.1  # straight through without a social layer
    assert 0.5 < clearances[1] < clearances[2]


@pytest.mark.slow
def test_smooth_planner_tends_to_the_exact_potential_and_its_gradient_is_right():
    rng = np.random.default_rng(1)
    costs = rng.uniform(0, 200, (12, 14))
    costs[3:9, 6] = costmap.LETHAL
    exact = np.asarray(grid_planner.potential(costmap.navfn_traversal(costs), (2, 12), 0.1))
    gaps = []
    for temperature in (1.0, 0.1, 0.01):
        soft = np.asarray(
            smooth_planner.soft_potential(smooth_planner.smooth_traversal(costs), (2, 12), 0.1, temperature, 200)
        )
        assert np.all(soft <= exact + 1e-3)
        gaps.append(np.max(exact - soft))
    assert gaps[0] > gaps[1] > gaps[2] and gaps[2] < 1e-2

    spec = costmap.GridSpec(12, 14, 0.1)
    with jax.enable_x64(True):
        c64 = jnp.asarray(costs, jnp.float64)

        def cost(c):
            return smooth_planner.soft_path_cost(c, (0.15, 1.05), (1.25, 0.25), spec, 1.0, 200)

        grad = np.asarray(jax.grad(cost)(c64))
        assert np.all(grad >= 0) and grad[3:9, 6].max() == 0.0  # walls are not on any path
        top = np.argsort(grad.ravel())[::-1][:5]
        for flat in list(top) + [0, 50]:
            i, j = np.unravel_index(flat, costs.shape)
            if costs[i, j] >= costmap.INSCRIBED:
                continue
            eps = 1e-3
            plus, minus = c64.at[i, j].add(eps), c64.at[i, j].add(-eps)
            fd = (float(cost(plus)) - float(cost(minus))) / (2 * eps)
            assert grad[i, j] == pytest.approx(fd, rel=1e-5, abs=1e-9)


# ---------------------------------------------------------------- the C++ Dijkstra against the sweeps


def _random_batch(rng, batch, h, w, wall_share, low=1.0, high=5.0):
    t = rng.uniform(low, high, (batch, h, w)).astype(np.float32)
    t[rng.uniform(size=t.shape) < wall_share] = np.inf
    ij = lambda: np.stack([rng.integers(0, h, batch), rng.integers(0, w, batch)], axis=1).astype(np.int32)
    return t, ij(), ij()


@pytest.mark.slow
@pytest.mark.parametrize("connectivity", [8, 4])
def test_dijkstra_plans_are_the_sweeps_plans_bit_for_bit(connectivity):
    """Both solvers reach the same float32 fixed point (Dijkstra settles each cell as the min of
    the same sums), so potentials, paths (the same moves and ties), lengths and costs are equal
    bit for bit, also for a goal off the grid, a start on the goal and cut paths."""
    if not grid_planner.dijkstra_available():
        pytest.skip("no C++ compiler: the sweeps are the only solver")
    rng = np.random.default_rng(connectivity)
    t, start, goal = _random_batch(rng, 8, 37, 29, 0.25)
    goal[0] = (-1, 3)
    start[1] = goal[1]
    for max_steps in (0, 12):
        a = grid_planner.plans(t, start, goal, 0.2, connectivity, max_steps, solver="sweeps")
        b = jax.jit(grid_planner.plans, static_argnums=(3, 4, 5, 6))(
            t, start, goal, 0.2, connectivity, max_steps, "dijkstra"
        )
        for field in ("potential", "path_ij", "path_length", "reached", "cost"):
            np.testing.assert_array_equal(np.asarray(getattr(b, field)), np.asarray(getattr(a, field)), err_msg=field)
        assert np.asarray(a.reached).any() and not np.asarray(a.reached).all()
    # A vmap over single grids (the arena's stacks) gives the batch's paths.
    one = jax.vmap(
        lambda tt, s, g: grid_planner.plans(tt[None], s[None], g[None], 0.2, connectivity, solver="dijkstra")
    )
    whole = grid_planner.plans(t, start, goal, 0.2, connectivity, solver="sweeps")
    np.testing.assert_array_equal(np.asarray(one(t, start, goal).path_ij[:, 0]), np.asarray(whole.path_ij))


@pytest.mark.slow
@pytest.mark.parametrize("low,high", [(0.0, 5.0), (1.0, 1e6)])
def test_dijkstra_falls_back_to_a_heap_where_buckets_do_not_fit(low, high):
    """Free moves (cost 0: no bucket width) and costs spread over a million-fold range (too many
    buckets) use the heap: the same answers."""
    if not grid_planner.dijkstra_available():
        pytest.skip("no C++ compiler: the sweeps are the only solver")
    t, _, goal = _random_batch(np.random.default_rng(7), 4, 25, 25, 0.2, low, high)
    t[:, :5, :5] = low
    sweeps = grid_planner.potentials(t, goal, 0.1, solver="sweeps")
    np.testing.assert_array_equal(
        np.asarray(grid_planner.potentials(t, goal, 0.1, solver="dijkstra")), np.asarray(sweeps)
    )


@pytest.mark.slow
def test_the_solver_is_checked_and_the_sweeps_keep_their_options(monkeypatch):
    t = np.ones((1, 5, 5), np.float32)
    with pytest.raises(ValueError, match="solver must be one of"):
        grid_planner.potentials(t, [[0, 0]], 0.1, solver="bfs")
    phi, rounds = grid_planner.potentials(t, [[0, 0]], 0.1, return_rounds=True)  # auto: the sweeps
    monkeypatch.setenv("SOCIALNAV_GRID_SOLVER", "dijstra")  # a typo in the user's environment: named as such
    said = "SOCIALNAV_GRID_SOLVER=dijstra: not a solver (one of auto, sweeps, dijkstra; unset: auto)"
    assert grid_planner.solver_variable_problem() == said
    with pytest.raises(ValueError, match=re.escape(said)):
        grid_planner.potentials(t, [[0, 0]], 0.1)
    monkeypatch.setenv("SOCIALNAV_GRID_SOLVER", "sweeps")
    assert grid_planner.solver_variable_problem() is None
    assert int(rounds) >= 1 and float(phi[0, 4, 4]) == pytest.approx(4 * 0.1 * np.sqrt(2), rel=1e-6)
