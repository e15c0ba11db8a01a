"""Waypoint planners: route tables equal scipy's shortest paths, the causal cost avoids crowds
the engine predicts, Eq. 10 refuses tasks the battery cannot finish (seed 000 Eq. 8-10), and the
engine's tables are read with one clear error per kind of bad file."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest
from scipy.sparse.csgraph import shortest_path

from socialnav.planners.warehouse import routes as routes_lib
from socialnav.planners.warehouse import waypoint as wp
from socialnav.planners.warehouse.tables import CausalTables, TablesError

RATE = -0.0069  # % per s at 0.5 m/s, about the simulator's


def _tables(scenario, density=None, **extra):
    return CausalTables.from_arrays(
        {
            "density_ppm2": np.zeros((scenario.n_slots, scenario.n_waypoints)) if density is None else density,
            "battery_pct_per_s": np.array([[-0.0056, 0.014], [RATE, np.nan]]),
            "speed_edges_mps": np.array([0.0, 0.3, 0.5]),
            **extra,
        }
    )


def test_shortest_routes_match_scipy(warehouse):
    s = warehouse
    plan = routes_lib.shortest_path_plan(s)
    lengths = routes_lib.arc_lengths_m(s)
    weights = np.where(np.isfinite(lengths) & s.robot_allowed[:, None] & s.robot_allowed[None, :], lengths, 0.0)
    ref = shortest_path(weights, directed=False)
    keep = np.flatnonzero(s.robot_allowed)
    np.testing.assert_allclose(np.asarray(plan.length_m[0])[np.ix_(keep, keep)], ref[np.ix_(keep, keep)], rtol=1e-6)
    edge_set = {tuple(e) for e in s.edges} | {tuple(e[::-1]) for e in s.edges}
    routes, hops = np.asarray(plan.routes[0]), np.asarray(plan.hops[0])
    rng = np.random.default_rng(0)
    for i, j in rng.choice(keep, size=(200, 2)):
        path = [i] + routes[i, j, : hops[i, j]].tolist()
        assert path[-1] == j and all((a, b) in edge_set for a, b in zip(path, path[1:], strict=False))
        assert s.parking not in path  # excluded for the robot
        assert (routes[i, j, hops[i, j] :] == j).all()  # padded with the goal
    assert (np.asarray(plan.routes) == routes[None]).all()  # the same every slot


def test_plan_from_costs_rejects_bad_costs(warehouse):
    with pytest.raises(ValueError, match="arc costs of shape"):
        routes_lib.plan_from_costs(warehouse, np.zeros((3, 3)))
    with pytest.raises(ValueError, match=">= 0"):
        routes_lib.plan_from_costs(warehouse, -routes_lib.arc_lengths_m(warehouse))


def _route(plan, slot, start, goal):
    hops = int(plan.hops[slot, start, goal])
    return [start] + np.asarray(plan.routes[slot, start, goal, :hops]).tolist()


def test_without_crowds_the_causal_routes_are_the_shortest(warehouse):
    plan, _ = wp.causal_plan(warehouse, _tables(warehouse))
    base = routes_lib.shortest_path_plan(warehouse)
    np.testing.assert_allclose(np.asarray(plan.length_m), np.asarray(base.length_m), rtol=1e-5)
    top, bottom = warehouse.waypoint("target-2"), warehouse.waypoint("target-5")
    assert _route(plan, 0, top, bottom) == _route(base, 0, top, bottom)


def test_the_causal_planner_avoids_a_predicted_crowd_and_takes_it_when_empty(warehouse):
    s = warehouse
    base = routes_lib.shortest_path_plan(s)
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
    plan = routes_lib.plan_from_costs(s, costs)
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
    # The same rule on JAX arrays, as the evaluation protocol calls it inside its jitted step.
    assert np.asarray(wp.refuse_task(jnp.array([100.0, 20.5]), jnp.float32(c))).tolist() == [False, c > 0.5]


def test_bad_tables_are_rejected(warehouse):
    t = _tables(warehouse)
    with pytest.raises(ValueError, match="speed bin"):
        wp.battery_rate_pct_per_s(np.full((2, 2), np.nan), t.speed_edges_mps, 0.5)
    with pytest.raises(ValueError, match="density table shape"):
        wp.causal_arc_costs(warehouse, np.zeros((3, 3)), RATE)


def test_tables_file_errors_name_the_file_and_key(warehouse, tmp_path):
    good = {
        "density_ppm2": np.zeros((11, 73)),
        "battery_pct_per_s": np.array([[-0.006, 0.01], [-0.007, 0.0]]),
        "speed_edges_mps": np.array([0.0, 0.3, 0.5]),
        "waypoints": np.array(warehouse.waypoint_ids),
        "slots": np.array(warehouse.slot_names),
    }
    f = tmp_path / "t.npz"
    np.savez(f, **good)
    tables = CausalTables.load(f)
    tables.check_against(warehouse.waypoint_ids, warehouse.slot_names)
    assert tables.density_ppm2.shape == (11, 73) and tables.waypoints == warehouse.waypoint_ids
    cases = {
        "missing key": ({k: v for k, v in good.items() if k != "battery_pct_per_s"}, "missing key"),
        "edges": ({**good, "speed_edges_mps": np.array([0.0, 0.5])}, "speed_edges_mps"),
        "decreasing": ({**good, "speed_edges_mps": np.array([0.5, 0.3, 0.0])}, "strictly increasing"),
        "negative density": ({**good, "density_ppm2": -np.ones((11, 73))}, "density_ppm2"),
        "names": ({**good, "waypoints": np.array(warehouse.waypoint_ids[:5])}, "names 5 waypoints"),
    }
    for name, (arrays, message) in cases.items():
        bad = tmp_path / f"{name.replace(' ', '_')}.npz"
        np.savez(bad, **arrays)
        with pytest.raises(TablesError, match=message) as err:
            CausalTables.load(bad)
        assert str(bad) in str(err.value), name
    swapped = list(warehouse.waypoint_ids)
    swapped[3], swapped[4] = swapped[4], swapped[3]
    np.savez(f, **{**good, "waypoints": np.array(swapped)})
    with pytest.raises(TablesError, match="differ from the scenario's at index 3"):
        CausalTables.load(f).check_against(warehouse.waypoint_ids, warehouse.slot_names)
    with pytest.raises(TablesError, match="not found"):
        CausalTables.load(tmp_path / "none.npz")
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(TablesError, match="not an .npz archive"):
        CausalTables.load(tmp_path / "junk.npz")
