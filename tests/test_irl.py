"""Learning costs through the planner (models.irl): the implicit gradient equals the unrolled one
and finite differences, the likelihood's known properties, a demonstrated corridor becomes
cheaper, a known cost map is recovered well enough to plan on it."""

import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest

from socialnav.models import grid
from socialnav.planners.global_planners import grid_planner, smooth_planner
from socialnav.planners.learning import irl


def _two_corridor_map(h=9, w=13):
    """A block in the middle: from the left end to the right end the way is over it or under it,
    the two corridors equally long."""
    maps = np.zeros((h, w), np.uint8)
    maps[2 : h - 2, 3 : w - 3] = grid.WALL
    return maps


def _demo(path_cells, shape):
    path = jnp.asarray(path_cells, jnp.int32)
    starts = jnp.zeros(shape, jnp.float32).at[path[0, 0], path[0, 1]].add(1.0)
    return irl.Demonstrations(irl.path_moves(path, shape), starts, path[-1], jnp.float32(1.0))


def _corridor_path(row, h=9, w=13):
    """From (h // 2, 0) up or down to ``row``, along it, and back to (h // 2, w - 1)."""
    mid = h // 2
    step = -1 if row < mid else 1
    down = [(r, 0) for r in range(mid, row, step)]
    along = [(row, c) for c in range(0, w)]
    back = [(r, w - 1) for r in range(row - step, mid - step, -step)]
    return down + along + back


@pytest.mark.slow
def test_implicit_gradient_equals_the_unrolled_one_and_finite_differences():
    rng = np.random.default_rng(3)
    with jax.enable_x64(True):
        t = jnp.asarray(50 + 200 * rng.random((8, 10)))
        t = t.at[4, 2:7].set(smooth_planner.BLOCKED)
        weights = smooth_planner.soft_weights(t, 0.4)
        goal, start, tau = (1, 8), (6, 1), 3.0

        def unrolled(w):
            return smooth_planner._iterate(w, smooth_planner._goal_mask((8, 10), goal), tau, 1e9, 8, 300)[start]

        def implicit(w):
            return smooth_planner.soft_potential_implicit(w, goal, tau, 300, 1e9)[start]

        assert float(unrolled(weights)) == pytest.approx(float(implicit(weights)), rel=1e-12)
        g_unrolled, g_implicit = jax.grad(unrolled)(weights), jax.grad(implicit)(weights)
        np.testing.assert_allclose(g_implicit, g_unrolled, atol=1e-10)
        # The weights' gradient is the soft policy's expected moves: one unit of flow leaves the
        # start, and every unit arrives at the goal.
        assert float(jnp.sum(g_implicit)) > 1.0  # a path takes more than one move
        out_of_start = float(jnp.sum(g_implicit[:, start[0], start[1]]))
        assert out_of_start == pytest.approx(1.0, abs=1e-9)


@pytest.mark.slow
def test_path_likelihood_gradient_equals_finite_differences():
    rng = np.random.default_rng(4)
    maps = _two_corridor_map()
    path = _corridor_path(0)
    with jax.enable_x64(True):
        costs = jnp.asarray(rng.uniform(0.05, 0.6, maps.shape))
        demo = _demo(path, maps.shape)

        def nll(c):
            return irl.path_nll(c, maps, demo, temperature=3.0, iterations=300)

        value = float(nll(costs))
        assert value > 0  # the soft-min lies below every path's cost
        grad = np.asarray(jax.grad(nll)(costs))
        assert np.all(grad[maps == grid.WALL] == 0)
        eps = 1e-5
        cells = [(0, 5), (8, 5), (4, 0), (1, 2), (7, 11), (4, 12)]
        for i, j in cells:
            fd = (float(nll(costs.at[i, j].add(eps))) - float(nll(costs.at[i, j].add(-eps)))) / (2 * eps)
            assert grad[i, j] == pytest.approx(fd, rel=1e-5, abs=1e-8)
        # Demonstrated cells (not the start, which no expected visit outweighs) are pushed down in
        # cost, the other corridor up.
        assert grad[0, 6] > 0 and grad[8, 6] < 0


@pytest.mark.slow
def test_likelihood_is_zero_only_for_a_certain_choice_and_ignores_empty_demonstrations():
    maps = _two_corridor_map()
    cheap_top = np.ones(maps.shape, np.float32)
    cheap_top[:2, :] = 0.0
    t = np.where(maps == grid.WALL, np.inf, np.asarray(irl.traversal_per_m(maps, cheap_top)))
    best = grid_planner.plan(t, (4, 0), (4, 12), grid.CELL_M)
    demo = _demo(np.asarray(best.path_ij)[: int(best.path_length)], maps.shape)
    assert np.asarray(best.path_ij)[:, 0].min() <= 1  # over the block
    even = np.full(maps.shape, 0.3, np.float32)
    sharp = float(irl.path_nll(jnp.asarray(cheap_top), maps, demo, temperature=0.5))
    tie = float(irl.path_nll(jnp.asarray(even), maps, demo, temperature=0.5))
    # On an even map the path and its mirror image under the block tie: the demonstrated one has
    # probability 1/2 at most.
    assert tie >= np.log(2) - 1e-4
    assert -1e-3 < sharp < 1e-2  # 0 up to float32 rounding of costs near 500
    empty = irl.Demonstrations(demo.moves * 0, demo.starts * 0, demo.goal_ij, jnp.float32(0.0))
    assert float(irl.path_nll(jnp.asarray(even), maps, empty)) == 0.0


def test_path_moves_counts_each_step_once_and_ignores_repeats():
    path = [(2, 2), (2, 3), (3, 4), (3, 4), (3, 4)]
    moves = np.asarray(irl.path_moves(jnp.asarray(path), (6, 6)))
    assert moves.sum() == 2
    k_right = grid_planner.moves(8).index((0, 1))
    k_diag = grid_planner.moves(8).index((1, 1))
    assert moves[k_right, 2, 2] == 1 and moves[k_diag, 2, 3] == 1


def test_a_demonstrated_corridor_becomes_the_cheaper_one():
    maps = _two_corridor_map()
    demo = _demo(_corridor_path(0), maps.shape)
    theta = jnp.zeros(maps.shape)
    opt = optax.adam(0.05)
    state = opt.init(theta)

    @jax.jit
    def step(theta, state):
        grad = jax.grad(lambda th: irl.path_nll(jax.nn.sigmoid(th), maps, demo))(theta)
        updates, state = opt.update(grad, state)
        return optax.apply_updates(theta, updates), state

    for _ in range(30):
        theta, state = step(theta, state)
    learned = np.asarray(jax.nn.sigmoid(theta))
    top, bottom = learned[0, 3:10].mean(), learned[-1, 3:10].mean()
    assert top < 0.5 < bottom


def _walled_map_with_goal(seed):
    """A 40 x 40 map with one wall and a goal pixel at (30, 8), random costs in [0, 1], and the
    exact potential to the goal with the move weights it descends: (maps, costs, phi, weights)."""
    maps = np.zeros((grid.GRID, grid.GRID), np.uint8)
    maps[10, 5:30] = grid.WALL
    maps[30, 8] = grid.GOAL
    costs = np.random.default_rng(seed).uniform(0, 1, maps.shape).astype(np.float32)
    t = np.asarray(irl.traversal_per_m(maps, costs))
    t = np.where(t >= smooth_planner.BLOCKED, np.inf, t)
    phi = np.asarray(grid_planner.potential(t, (30, 8), grid.CELL_M))
    weights = np.stack(list(grid_planner.move_costs(t, grid.CELL_M).values()))
    return maps, costs, phi, weights


@pytest.mark.slow
def test_planned_demonstrations_follow_the_exact_plan_on_the_known_map():
    maps, costs, phi, weights = _walled_map_with_goal(5)
    demo = irl.planned_demonstration(jax.random.key(0), jnp.asarray(maps), jnp.asarray(costs), paths_per_map=3)
    assert float(demo.n_paths) == 3 and tuple(np.asarray(demo.goal_ij)) == (30, 8)
    robot = tuple(int(v) for v in grid.cell_of(0.0, 0.0))
    assert demo.starts[robot] >= 1  # the first path leaves from the robot's cell
    # Every path costs its exact optimum: the demonstrations' total cost equals the sum of the
    # exact potentials at their starts.
    moves = np.asarray(demo.moves)
    total = float(np.sum(moves * np.where(moves > 0, weights, 0.0)))
    assert total == pytest.approx(float(np.sum(np.asarray(demo.starts) * phi)), rel=1e-5)
    assert np.all(moves[:, maps == grid.WALL] == 0)
    # Flow is conserved: at every cell but the goal, moves out = moves in + starts.
    out_flow = moves.sum(0)
    in_flow = np.zeros_like(out_flow)
    for k, (di, dj) in enumerate(grid_planner.moves(8)):
        in_flow += np.roll(np.roll(moves[k], di, 0), dj, 1)
    balance = out_flow - in_flow - np.asarray(demo.starts)
    balance[30, 8] += 3
    np.testing.assert_allclose(balance, 0, atol=1e-6)


@pytest.mark.slow
def test_every_cell_demonstration_is_the_exact_plans_each_step_once():
    maps, costs, phi, weights = _walled_map_with_goal(6)
    demo = irl.policy_demonstration(jax.random.key(0), jnp.asarray(maps), jnp.asarray(costs))
    moves, starts = np.asarray(demo.moves), np.asarray(demo.starts)
    free = maps == grid.FREE
    # One move out of every free cell but the goal, none out of a wall, and as many steps.
    np.testing.assert_array_equal(moves.sum(0), free.astype(np.float32))
    assert float(demo.n_paths) == free.sum() and tuple(np.asarray(demo.goal_ij)) == (30, 8)
    # Each step is +1 where it leaves and -1 where it lands: the starts sum to 0 and the moves'
    # cost equals the potential they descend (each step is the exact plan's step).
    assert float(starts.sum()) == pytest.approx(0.0, abs=1e-6)
    total = float(np.sum(moves * np.where(moves > 0, weights, 0.0)))
    assert total == pytest.approx(float(np.sum(starts * np.where(np.isfinite(phi), phi, 0.0))), rel=1e-5)
    # The paths planned to the same goal take the same move at every cell they cross.
    paths = irl.planned_demonstration(jax.random.key(1), jnp.asarray(maps), jnp.asarray(costs), paths_per_map=4)
    crossed = np.asarray(paths.moves) > 0
    assert crossed.sum() > 20 and np.all(moves[crossed] == 1)
    # Its likelihood is the mean of the steps' one-step likelihoods under the soft policy.
    tau = 2.0
    soft_w = smooth_planner.soft_weights(irl.traversal_per_m(maps, costs), grid.CELL_M)
    soft = np.asarray(smooth_planner.soft_potential_implicit(soft_w, demo.goal_ij, tau, irl.ITERATIONS, irl.CEILING))
    padded = np.pad(soft, 1, constant_values=np.inf)
    steps = [
        (float(soft_w[k, i, j]) + padded[1 + i + di, 1 + j + dj] - soft[i, j]) / tau
        for k, (di, dj) in enumerate(grid_planner.moves(8))
        for i, j in zip(*np.nonzero(moves[k]), strict=True)
    ]
    nll = float(irl.path_nll(jnp.asarray(costs), jnp.asarray(maps), demo, tau))
    assert nll == pytest.approx(np.mean(steps), rel=2e-3) and nll > 0  # float32 sums of potentials
    # The "cells" objective prepares the same demonstrations for each map of a batch.
    objective = irl.PathObjective(tau, demonstrations="cells")
    batch = objective.prepare(jax.random.key(2), jnp.stack([maps, maps]), jnp.stack([costs, costs]))
    np.testing.assert_array_equal(np.asarray(batch.moves[1]), moves)
    np.testing.assert_allclose(
        np.asarray(objective.loss(jnp.stack([costs, costs]), jnp.stack([maps, maps]), batch)), nll, rtol=1e-5
    )


@pytest.mark.slow
def test_a_known_cost_map_is_recovered_from_its_exact_plans():
    """Known answer: learn a free cost grid from exact plans on a known one; held-out start and
    goal pairs planned on the learned grid cost, under the true grid, within 5 % of the optimum
    (the all-zero grid is further off), and the learned grid correlates with the true one."""
    h = 16
    maps = np.zeros((h, h), np.uint8)
    maps[5, 2:11] = grid.WALL
    yy, xx = np.mgrid[0:h, 0:h]
    true = np.maximum(np.exp(-((yy - 10) ** 2 + (xx - 6) ** 2) / 8.0), np.exp(-((yy - 3) ** 2 + (xx - 12) ** 2) / 6.0))
    true = jnp.asarray(true, jnp.float32)
    maps_j = jnp.asarray(maps)

    def demos(key, n):
        def one(k):
            kg, ks = jax.random.split(k)
            free = maps_j != grid.WALL
            goal = irl._random_cell(kg, free)
            start = irl._random_cell(ks, free & ~((jnp.arange(h)[:, None] == goal[0]) & (jnp.arange(h) == goal[1])))
            t = irl.traversal_per_m(maps_j, true)
            t = jnp.where(t >= smooth_planner.BLOCKED, jnp.inf, t)
            p = grid_planner.plan(t, start, goal, grid.CELL_M)
            starts = jnp.zeros((h, h)).at[start[0], start[1]].add(1.0)
            return irl.Demonstrations(irl.path_moves(p.path_ij, (h, h)), starts, goal, jnp.float32(1.0)), start

        return jax.vmap(one)(jax.random.split(key, n))

    train, _ = demos(jax.random.key(1), 96)
    test, test_starts = demos(jax.random.key(2), 32)
    opt = optax.adam(0.1)
    theta = jnp.full((h, h), -2.0)
    state = opt.init(theta)

    @jax.jit
    def step(theta, state):
        def loss(th):
            return jnp.mean(
                jax.vmap(lambda d: irl.path_nll(jax.nn.sigmoid(th), maps_j, d, temperature=2.0, iterations=64))(train)
            )

        grad = jax.grad(loss)(theta)
        updates, state = opt.update(grad, state)
        return optax.apply_updates(theta, updates), state

    for _ in range(300):
        theta, state = step(theta, state)
    learned = jax.nn.sigmoid(theta)

    def excess(plan_costs):
        cost, best = jax.vmap(lambda s, g: irl.exact_path_cost(true, maps_j, plan_costs, s, g))(
            test_starts, test.goal_ij
        )
        return float(jnp.mean(cost / best - 1))

    assert excess(learned) < 0.05
    assert excess(learned) < excess(jnp.zeros_like(true))
    visited = np.asarray(train.moves.sum((0, 1))) > 0
    assert np.corrcoef(np.asarray(learned)[visited], np.asarray(true)[visited])[0, 1] > 0.5


TINY_PATHS = dict(
    features=(4, 4, 8, 8),
    epochs=1,
    batch_size=16,
    train_fraction=0.012,
    test_fraction=0.002,
    composites=0,
    warmup_steps=2,
    checkpoint_every_steps=50,
    learning_rate=1e-2,
    objective="paths",
)


@pytest.mark.slow
def test_a_paths_run_lowers_the_demonstrations_likelihood_and_loads_as_a_gscl_model(tmp_path):
    from socialnav.models import dataset, steps, train
    from socialnav.models.config import TrainConfig
    from socialnav.models.inference import SocialCostModel

    config = TrainConfig(**TINY_PATHS)
    objective = irl.PathObjective.of(config)
    with pytest.raises(ValueError, match="PathObjective"):
        train.train(config, tmp_path / "no", progress=False)  # a paths run needs its objective
    data = dataset.generate(7, {"hallway_l": 8, "queue": 8})
    demos = jax.jit(objective.prepare)(jax.random.key(3), data["inputs"], data["targets"])
    assert float(demos.n_paths.min()) >= 1

    def held_out_nll(params, batch_stats):
        costs = steps.make_predict(steps.compiled(config, objective)[0])(params, batch_stats, data["inputs"])
        return float(jnp.mean(objective.loss(costs, data["inputs"], demos)))

    before = steps.initial_state(config)
    line = train.train(config, tmp_path / "run", progress=False, objective=objective)
    assert line["epoch"] == 1 and np.isfinite(line["test_mse"])
    model = SocialCostModel.load(tmp_path / "run")
    after = held_out_nll(*model.weights)
    # About 20 steps of a 4-8 channel network: 38.1 -> 36.4 nats per path on these held-out maps
    # (a wrong-signed gradient raises it).
    assert after < 0.97 * held_out_nll(before["params"], before["batch_stats"])
    assert model(data["inputs"][:2]).shape == (2, grid.GRID, grid.GRID)


@pytest.mark.slow
def test_the_layer_reading_prices_costs_as_the_gscl_layer_and_never_enters_a_forbidden_cell():
    from socialnav.models.social_costs import FORBIDDEN, FORBIDDEN_FROM, GRADED_TOP
    from socialnav.planners.layers import gscl_layer
    from socialnav.planners.layers.costmap import NAVFN_FACTOR, NAVFN_NEUTRAL

    # Below FORBIDDEN_FROM the exact planner prices a cost as NavFn prices the layer's Nav2 cost
    # (the graded top from GRADED_TOP up), and from there up it cannot enter. The soft one prices
    # the graded costs alike, goes on at the graded slope up to FORBIDDEN_FROM, and adds
    # LETHAL_PER_M over LETHAL_RAMP above it.
    costs = jnp.asarray([[0.0, 0.35, GRADED_TOP, 0.8, FORBIDDEN_FROM, FORBIDDEN]], jnp.float32)
    maps = jnp.zeros(costs.shape, jnp.uint8).at[0, 0].set(grid.WALL)
    exact = np.asarray(irl.traversal_per_m(maps, costs, jnp.inf, "layer"))
    soft = np.asarray(irl.traversal_per_m(maps, costs, smooth_planner.BLOCKED, "layer"))
    nav2 = np.asarray(gscl_layer.read_cost(costs))
    np.testing.assert_allclose(exact[0, 1:4], NAVFN_NEUTRAL + NAVFN_FACTOR * nav2[0, 1:4], rtol=1e-6)
    top = NAVFN_NEUTRAL + NAVFN_FACTOR * 252.0
    assert exact[0, 2] == pytest.approx(top) and exact[0, 3] == pytest.approx(top)
    assert np.isinf(exact[0, [0, 4, 5]]).all() and soft[0, 0] == smooth_planner.BLOCKED
    np.testing.assert_allclose(soft[0, 1:3], exact[0, 1:3], rtol=1e-6)
    slope = NAVFN_FACTOR * 252.0 / GRADED_TOP  # per unit of network cost
    rising = NAVFN_NEUTRAL + slope * np.array([0.8, FORBIDDEN_FROM, FORBIDDEN_FROM])
    np.testing.assert_allclose(soft[0, 3:], rising + irl.LETHAL_PER_M * np.array([0, 0, 1]), rtol=1e-5)
    assert soft[0, 3] < 1.2 * top  # below the threshold the soft price stays near the layer's
    price = jax.grad(lambda c: irl.traversal_per_m(jnp.zeros(()), c, reading="layer"))
    assert float(price(jnp.float32(0.8))) == pytest.approx(slope, rel=1e-4)  # no flat stretch to stall in
    step = float(price(jnp.float32(FORBIDDEN_FROM + irl.LETHAL_RAMP / 2)))
    assert step == pytest.approx(irl.LETHAL_PER_M / irl.LETHAL_RAMP, rel=1e-3)
    with pytest.raises(ValueError, match="reading must be one of"):
        irl.traversal_per_m(maps, costs, reading="lethal")

    # A forbidden band (the queue's U at FORBIDDEN) between the left half and the goal, open only
    # at the bottom: graded, it is 5 times a free cell and the exact moves cross it; read as the
    # layer reads it, no move enters it (a move still leaves each of its cells, as a robot inside
    # the U would get out).
    band = np.zeros((grid.GRID, grid.GRID), np.float32)
    band[:34, 20] = FORBIDDEN
    maps = np.zeros(band.shape, np.uint8)
    maps[5, 30] = grid.GOAL
    entered = {}
    for reading in ("graded", "layer"):
        demo = irl.policy_demonstration(jax.random.key(0), jnp.asarray(maps), jnp.asarray(band), reading)
        moves = np.asarray(demo.moves)
        landed = sum(np.roll(moves[k], (di, dj), axis=(0, 1)) for k, (di, dj) in enumerate(grid_planner.moves(8)))
        entered[reading] = int((landed[band == FORBIDDEN] > 0).sum())
        assert float(demo.n_paths) == (maps == grid.FREE).sum()
    assert entered["graded"] > 10 and entered["layer"] == 0
    # The objective read as the layer: its loss is finite, and lower with the band lethal than free.
    objective = irl.PathObjective(2.0, demonstrations="cells", reading="layer")
    demos = objective.prepare(jax.random.key(0), jnp.asarray(maps)[None], jnp.asarray(band)[None])
    lethal, free = (objective.loss(jnp.asarray(c)[None], jnp.asarray(maps)[None], demos) for c in (band, 0 * band))
    assert np.isfinite(float(lethal[0])) and float(lethal[0]) < float(free[0])


def test_the_command_line_refuses_bad_path_settings_in_one_line(tmp_path):
    from socialnav import cli

    for extra, message in (
        (["--temperature", "12"], "temperature must be in"),
        (["--objective", "demos"], "invalid choice"),
        (["--paths-per-map", "0"], "positive"),
        (["--demonstrations", "everywhere"], "invalid choice"),
        (["--reading", "lethal"], "invalid choice"),
    ):
        with pytest.raises(SystemExit) as err:
            cli.main(["gscl", "train", "--out", str(tmp_path / "r"), "--objective", "paths", *extra])
        assert message in str(err.value) or err.value.code == 2
    assert not (tmp_path / "r" / "checkpoints").exists()
    from socialnav.models.config import TrainConfig

    with pytest.raises(ValueError, match="demonstrations must be one of"):
        TrainConfig(objective="paths", demonstrations="everywhere")
    with pytest.raises(ValueError, match="reading must be one of"):
        TrainConfig(objective="paths", reading="lethal")
    with pytest.raises(ValueError, match="needs the 'paths' objective"):
        TrainConfig(objective="maps", reading="layer")
