"""The Sec. 5.2 protocol in the batched simulator: task outcomes, resets, refusals, collisions,
and both methods identical where there is nobody to avoid (S11)."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest

from socialnav.evaluation import protocol as ex
from socialnav.evaluation.outcomes import BATTERY, CONGESTION, NOT_RUN, SUCCESS
from socialnav.evaluation.warehouse import build_methods, method_plans
from socialnav.jaxsim.route_follower import route_follower
from socialnav.jaxsim.scenario import load_scenario
from socialnav.jaxsim.world import build_world
from socialnav.planners.warehouse.actors import causal_planner
from socialnav.planners.warehouse.routes import shortest_path_plan
from socialnav.planners.warehouse.tables import CausalTables

N_TASKS = 8
CFG = dict(warmup_s=20.0, arrival_spread_s=10.0)


def _short(world, n_tasks=N_TASKS):
    """The world with every slot's task list cut to its first ``n_tasks`` tasks."""
    return world.replace(robot_goal_count=jnp.minimum(world.robot_goal_count, n_tasks))


def _run(scenario, world, method, slots, replicas=None, **cfg):
    slots = np.asarray(slots)
    replicas = np.arange(len(slots)) if replicas is None else np.asarray(replicas)
    keys = ex.experiment_keys(0, slots, replicas)
    config = ex.ProtocolConfig.for_params(scenario.params, **{**CFG, **cfg})
    return ex.run_experiments(scenario.params, world, method, slots, keys, config, segment_s=60.0)


def _tables(scenario):
    rng = np.random.default_rng(0)
    density = rng.uniform(0.0, 1.0, (scenario.n_slots, scenario.n_waypoints))
    density[~scenario.slot_working] = 0.0  # what the engine learns: nobody there off hours
    return CausalTables.from_arrays(
        {
            "density_ppm2": density,
            "battery_pct_per_s": np.array([[-0.0056, 0.014], [-0.0069, np.nan]]),
            "speed_edges_mps": np.array([0.0, 0.3, 0.5]),
        }
    )


@pytest.fixture(scope="module")
def setup(warehouse):
    """The scenario, its world with short task lists, the two methods' drivers and their plans."""
    world = _short(build_world(warehouse))
    plans = method_plans(warehouse, _tables(warehouse))
    return warehouse, world, build_methods(plans, world), {name: plan for name, (plan, _) in plans.items()}


@pytest.mark.slow
def test_off_slot_both_methods_take_the_same_routes_and_get_the_same_results(setup):
    scenario, world, methods, plans = setup
    off = int(np.flatnonzero(~scenario.slot_working)[0])
    base, causal = plans["baseline"], plans["causal"]
    np.testing.assert_array_equal(np.asarray(base.routes[off]), np.asarray(causal.routes[off]))
    working = int(np.flatnonzero(scenario.slot_working)[0])
    assert not np.array_equal(np.asarray(base.routes[working]), np.asarray(causal.routes[working]))

    logs = {name: _run(scenario, world, m, [off, off]).log for name, m in methods.items()}
    for field in ("outcome", "time_s", "stalled_s", "distance_m", "battery_used_pct", "collisions", "goal_wp"):
        np.testing.assert_array_equal(getattr(logs["baseline"], field), getattr(logs["causal"], field), field)
    assert (logs["baseline"].outcome[:, :N_TASKS] == SUCCESS).all()
    assert (logs["baseline"].outcome[:, N_TASKS:] == NOT_RUN).all()


@pytest.mark.slow
def test_protocol_invariants_in_working_slots(setup):
    scenario, world, methods, plans = setup
    p = scenario.params
    state = _run(scenario, world, methods["baseline"], [0, 5])
    log = state.log
    ran = log.outcome != NOT_RUN
    assert ran.sum(axis=1).tolist() == [N_TASKS, N_TASKS]
    assert np.isin(log.outcome[ran], [SUCCESS, CONGESTION, BATTERY]).all()
    assert (log.stalled_s <= log.time_s + 1e-4).all()
    assert (log.distance_m <= p.robot_max_speed_mps * log.time_s + 1e-3).all()
    ok = log.outcome == SUCCESS
    # A success drives the planned route, short by at most the tolerance at each waypoint, long
    # by what its body slides round wall ends (jaxsim.robot.keep_body_clear; under 1 % here).
    hops = np.asarray(plans["baseline"].hops)[state.slot[:, None], log.start_wp, log.goal_wp]
    assert (log.distance_m[ok] >= log.planned_m[ok] - p.robot_goal_tolerance_m * hops[ok] - 1e-3).all()
    assert (log.distance_m[ok] <= 1.01 * log.planned_m[ok] + 1e-3).all()
    failed = log.outcome == CONGESTION
    assert (log.time_s[failed] >= p.robot_leg_deadline_s - 1e-3).all()
    # Task k starts where task k - 1 was to end, whatever happened to it.
    np.testing.assert_array_equal(log.start_wp[:, 1:N_TASKS], log.goal_wp[:, : N_TASKS - 1])
    assert (state.task == N_TASKS).all() and (state.end_step > 0).all()
    assert (log.collisions >= 0).all() and (state.distance_hist.sum(axis=1) > 0).all()
    assert not log.refused.any()


@pytest.mark.slow
def test_missed_deadlines_are_congestion_failures_and_the_robot_moves_on():
    scenario = load_scenario(robot_leg_deadline_s=1.0)
    world = _short(build_world(scenario), 4)
    state = _run(scenario, world, route_follower(shortest_path_plan(scenario), world), [1, 1])
    log = state.log
    assert (log.outcome[:, :4] == CONGESTION).all()
    np.testing.assert_allclose(log.time_s[:, :4], 1.0, atol=scenario.params.dt_s + 1e-4)
    assert (log.distance_m[:, :4] <= 0.5 + 1e-4).all()


def test_battery_failures_reset_the_battery_and_refusals_prevent_them():
    # A battery that empties in 25 s: every long enough task crosses 20 %.
    scenario = load_scenario(battery_static_pct_per_s=4.0)
    world = _short(build_world(scenario), 6)
    plan = shortest_path_plan(scenario)
    state = _run(scenario, world, route_follower(plan, world), [10, 10])
    log = state.log
    battery = log.outcome == BATTERY
    assert battery.any()
    # A task never drains more than from a full battery to just under 20 %; one that starts
    # full after a reset and fails drains exactly that.
    used = log.battery_used_pct[battery]
    assert (used <= 80.0 + 1.0).all() and abs(used.max() - 80.0) < 1.0
    assert (state.sim.robot.battery_pct >= 20.0 - 0.5).all()

    # Eq. (10) with a cost that always exceeds what is left above 20 %: every task is refused
    # (the battery reset first), so none fails on the battery... unless the task alone needs more.
    refusing = causal_planner(plan, world, np.full(plan.hops.shape, 85.0))
    log = _run(scenario, world, refusing, [10, 10]).log
    assert log.refused[:, :6].all()
    assert (log.outcome[:, :6] != NOT_RUN).all()
    never = causal_planner(plan, world, np.zeros(plan.hops.shape))
    assert not _run(scenario, world, never, [10, 10]).log.refused.any()
    # The threshold that runs is the one planners.warehouse.waypoint.refuse_task applies: B_min = 20 % by default.
    assert ex.ProtocolConfig().min_battery_pct == 20.0


def test_bad_input_is_rejected(setup):
    scenario, world, methods, plans = setup
    keys = ex.experiment_keys(0, np.array([0]), np.array([0]))
    with pytest.raises(ValueError, match="slots must be in"):
        ex.run_experiments(scenario.params, world, methods["baseline"], np.array([99]), keys)
    with pytest.raises(ValueError, match="one slot per key"):
        ex.run_experiments(scenario.params, world, methods["baseline"], np.array([0, 1]), keys)
    with pytest.raises(ValueError, match="battery cost table shape"):
        causal_planner(plans["baseline"], world, np.zeros((2, 2)))
    for field, value in (
        ("collision_radius_m", 0.0),
        ("min_battery_pct", 120.0),
        ("warmup_s", float("nan")),
        ("distance_bins", 0),
    ):
        with pytest.raises(ValueError, match=f"ProtocolConfig.{field}"):
            ex.ProtocolConfig(**{field: value})


@pytest.mark.slow
def test_compacting_the_batch_keeps_every_experiment_in_its_place(warehouse):
    """Seven short experiments end early; the three long ones go on in a smaller batch."""
    world = build_world(warehouse).replace(robot_goal_count=jnp.array([2] * 10 + [30], jnp.int32))
    method = route_follower(shortest_path_plan(warehouse), world)
    slots = np.array([10, 0, 0, 10, 0, 0, 0, 10, 0, 0])
    keys = ex.experiment_keys(0, slots, np.arange(len(slots)))
    cfg = ex.ProtocolConfig.for_params(warehouse.params, **CFG)
    runs = [
        ex.run_experiments(warehouse.params, world, method, slots, keys, cfg, segment_s=30.0, shrink_at=s)
        for s in (0.0, 0.5)
    ]
    for state in runs:
        np.testing.assert_array_equal(state.slot, slots)
        np.testing.assert_array_equal(state.task, np.where(slots == 10, 30, 2))
    # Without workers nothing depends on the batch: the moved experiments end bit for bit the same.
    off = slots == 10
    np.testing.assert_array_equal(runs[0].log.time_s[off], runs[1].log.time_s[off])
    np.testing.assert_array_equal(runs[0].end_step, runs[1].end_step)
