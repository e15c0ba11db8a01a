"""Waypoint planners: the causal cost avoids crowds the engine predicts, and refuses tasks
the battery cannot finish (seed 000 Eq. 8-10)."""

from __future__ import annotations

import numpy as np
import pytest

from jaxsim import world as world_lib
from jaxsim.rollout import rollout, to_numpy
from jaxsim.scenario import load_scenario
from planners import waypoint as wp

RATE = -0.0069  # % per s at 0.5 m/s, about the simulator's


def _tables(scenario, density=None):
    return {"density_ppm2": np.zeros((scenario.n_slots, scenario.n_waypoints)) if density is None else density,
            "battery_pct_per_s": np.array([[-0.0056, 0.014], [RATE, np.nan]]),
            "speed_edges_mps": np.array([0.0, 0.3, 0.5])}


def _route(plan, slot, start, goal):
    hops = int(plan.hops[slot, start, goal])
    return [start] + np.asarray(plan.routes[slot, start, goal, :hops]).tolist()


def test_without_crowds_the_causal_routes_are_the_shortest(warehouse):
    plan, _ = wp.causal_plan(warehouse, _tables(warehouse))
    base = world_lib.shortest_path_plan(warehouse)
    np.testing.assert_allclose(np.asarray(plan.length_m), np.asarray(base.length_m), rtol=1e-5)
    top, bottom = warehouse.waypoint("target-2"), warehouse.waypoint("target-5")
    assert _route(plan, 0, top, bottom) == _route(base, 0, top, bottom)


def test_the_causal_planner_avoids_a_predicted_crowd_and_takes_it_when_empty(warehouse):
    s = warehouse
    base = world_lib.shortest_path_plan(s)
    top, bottom = s.waypoint("target-2"), s.waypoint("target-5")
    shortest = _route(base, 2, top, bottom)
    crowded = shortest[len(shortest) // 2]
    density = np.zeros((s.n_slots, s.n_waypoints))
    density[2, crowded] = 2.0  # people / m^2 at one waypoint of the shortest route, in slot S3 only
    plan, cost = wp.causal_plan(s, _tables(s, density))
    detour = _route(plan, 2, top, bottom)
    assert crowded not in detour and detour[0] == top and detour[-1] == bottom
    assert float(plan.length_m[2, top, bottom]) > float(base.length_m[2, top, bottom])
    assert _route(plan, 3, top, bottom) == shortest  # another slot: the waypoint is empty, take it
    assert cost[2, top, bottom] > cost[3, top, bottom] > 0


def test_astar_agrees_with_the_all_pairs_plan(warehouse):
    s = warehouse
    rng = np.random.default_rng(0)
    density = rng.random((s.n_slots, s.n_waypoints)) * 0.5
    costs = wp.causal_arc_costs(s, density, RATE)
    plan = wp.plan_from_costs(s, costs)
    allowed = np.flatnonzero(s.robot_allowed)
    robot_costs = np.where(s.robot_allowed[:, None] & s.robot_allowed[None, :], costs[4], np.inf)
    for a, b in rng.choice(allowed, size=(40, 2)):
        if a == b:
            continue
        path = wp.astar(robot_costs, s.waypoint_xy_m, int(a), int(b))
        total = sum(robot_costs[u, v] for u, v in zip(path, path[1:]))
        ref = _route(plan, 4, int(a), int(b))
        ref_total = sum(robot_costs[u, v] for u, v in zip(ref, ref[1:]))
        assert total == pytest.approx(ref_total, rel=1e-9)


def test_refuses_tasks_the_battery_cannot_finish(warehouse):
    s = warehouse
    plan, cost = wp.causal_plan(s, _tables(s))
    top, bottom = s.waypoint("target-2"), s.waypoint("target-5")
    c = cost[0, top, bottom]
    assert c == pytest.approx(float(plan.length_m[0, top, bottom]) / 0.5 * abs(RATE))
    assert not wp.refuse_task(20.0 + c + 0.01, c)
    assert wp.refuse_task(20.0 + c - 0.01, c)
    assert wp.refuse_task(np.array([100.0, 20.5]), np.array([c, c])).tolist() == [False, c > 0.5]


def test_bad_tables_are_rejected(warehouse):
    t = _tables(warehouse)
    with pytest.raises(ValueError, match="speed bin"):
        wp.battery_rate_pct_per_s(np.full((2, 2), np.nan), t["speed_edges_mps"], 0.5)
    with pytest.raises(ValueError, match="density table shape"):
        wp.causal_arc_costs(warehouse, np.zeros((3, 3)), RATE)


def test_a_causal_plan_drives_the_simulator():
    s = load_scenario(slot_length_s=30.0, n_workers=4)
    plan, _ = wp.causal_plan(s, _tables(s))
    _, rec = rollout(s.params, world_lib.build_world(s), plan, seed=0, n_worlds=2, n_steps=600,
                     sample_every_steps=10)
    assert (to_numpy(rec).tasks_started[:, -1] >= 1).all()
