"""Waypoint planners of seed 000: the shortest-path baseline and the causal cost (Eq. 8-10).

The causal cost of the arc ``u -> v`` in slot ``s`` (Eq. 9) is

    lambda_dist * delta(u, v) + lambda_density * D_hat(s, u) + lambda_battery * |L_hat(u, v)|

with ``delta`` the Euclidean length, ``D_hat(s, u) = E[D | do(S = s), W = u]`` from the engine's
table and ``L_hat(u, v) = E[L | do(V = v_nav), C = 0] * delta / v_nav``, the battery use of the
arc at the navigation speed (seed 000 Sec. 4.3). Weights (Sec. 5.2): 1 for distance, 10 for
density, 5 for battery. Eq. (9) prints ``lambda_D`` twice; the text names the density weight
``lambda_C = 10``; this reads the first as the distance weight and the second as the density
weight.

A* (Eq. 8) with the admissible heuristic ``lambda_dist * euclid(w, goal)`` finds the same paths as
an all-pairs search on these non-negative costs; the batched simulator takes the all-pairs
result as a :class:`~jaxsim.world.RobotPlan` table per slot (:func:`planners.warehouse.routes.plan_from_costs`,
the one function that builds the shortest and the causal tables), and :func:`astar` serves
single queries and the check that both agree.

The abort decision (Eq. 10): refuse a task when ``battery - C_L(path) < B_min`` (20 %), with
``C_L`` the summed ``|L_hat|`` along the path (:func:`battery_cost_table`). :func:`refuse_task`
is the one implementation: the evaluation protocol calls it inside its JAX step.
"""

from __future__ import annotations

import dataclasses
import heapq

import jax
import numpy as np

from socialnav.jaxsim.scenario import Scenario
from socialnav.jaxsim.world import RobotPlan
from socialnav.planners.warehouse.routes import arc_lengths_m, plan_from_costs
from socialnav.planners.warehouse.tables import CausalTables

# B_min of Eq. (10), the critical battery level (seed 000 Sec. 5.2).
MIN_BATTERY_PCT = 20.0


@dataclasses.dataclass(frozen=True)
class CausalWeights:
    """Eq. (9) weights: distance (m), density (people/m^2), battery (%)."""

    distance: float = 1.0
    density: float = 10.0
    battery: float = 5.0


def battery_rate_pct_per_s(battery_pct_per_s: np.ndarray, speed_edges_mps: np.ndarray, speed_mps: float) -> float:
    """E[L | do(V = v), C = 0] per second for the speed bin holding ``speed_mps`` (negative).

    Raises:
      ValueError: the engine has no finite estimate for that bin.
    """
    k = int(np.clip(np.searchsorted(speed_edges_mps, speed_mps, side="right") - 1, 0, len(speed_edges_mps) - 2))
    rate = float(battery_pct_per_s[k, 0])
    if not np.isfinite(rate):
        raise ValueError(f"the engine has no E[L | do(V), C=0] for the speed bin of {speed_mps} m/s")
    return rate


def causal_arc_costs(
    scenario: Scenario,
    density_ppm2: np.ndarray,
    battery_pct_per_s: float,
    speed_mps: float = 0.5,
    weights: CausalWeights = CausalWeights(),
) -> np.ndarray:
    """(S, W, W) directed arc costs of Eq. (9) per slot (inf where there is no arc).

    Args:
      density_ppm2: (S, W) E[D | do(S), W]; NaN (waypoints the engine never saw) counts as 0.
      battery_pct_per_s: E[L | do(V = speed), C = 0] per second (negative when discharging).
    """
    length = arc_lengths_m(scenario)
    density = np.nan_to_num(np.asarray(density_ppm2, np.float64), nan=0.0)
    if density.shape != (scenario.n_slots, scenario.n_waypoints):
        raise ValueError(f"density table shape {density.shape}, expected {(scenario.n_slots, scenario.n_waypoints)}")
    battery = abs(battery_pct_per_s) * length / speed_mps
    base = weights.distance * length + weights.battery * battery
    return base[None] + weights.density * density[:, :, None]  # density at the arc's source waypoint


def causal_plan(
    scenario: Scenario, tables: CausalTables, speed_mps: float = 0.5, weights: CausalWeights = CausalWeights()
) -> tuple[RobotPlan, np.ndarray]:
    """The causal planner's routes and their battery cost, from the engine's tables.

    Args:
      tables: the engine's tables (:meth:`CausalTables.load` of ``engine_tables.npz``), checked
        against the scenario's waypoints and slots here.

    Returns:
      (plan, battery cost C_L in % per (slot, start, goal)).
    """
    tables.check_against(scenario.waypoint_ids, scenario.slot_names)
    rate = battery_rate_pct_per_s(tables.battery_pct_per_s, tables.speed_edges_mps, speed_mps)
    costs = causal_arc_costs(scenario, tables.density_ppm2, rate, speed_mps, weights)
    plan = plan_from_costs(scenario, costs)
    return plan, battery_cost_table(plan, rate, speed_mps)


def battery_cost_table(plan: RobotPlan, battery_pct_per_s: float, speed_mps: float) -> np.ndarray:
    """C_L (Eq. 10) of every planned route: ``|L_hat|`` summed along it, in % (S, W, W)."""
    return np.asarray(plan.length_m, np.float64) / speed_mps * abs(battery_pct_per_s)


def refuse_task(
    battery_pct: jax.Array | np.ndarray | float,
    path_cost_pct: jax.Array | np.ndarray | float,
    min_battery_pct: float = MIN_BATTERY_PCT,
):
    """Eq. (10): refuse when the battery left after the path would fall below ``B_min``.

    Elementwise on JAX or numpy arrays of any broadcastable shapes (a bool for two floats); the
    evaluation protocol calls it inside its jitted step.
    """
    return battery_pct - path_cost_pct < min_battery_pct


def astar(costs: np.ndarray, xy_m: np.ndarray, start: int, goal: int, distance_weight: float = 1.0) -> list[int]:
    """A* over a (W, W) directed cost matrix (Eq. 8), heuristic ``distance_weight * euclid``.

    Returns:
      the waypoints from ``start`` to ``goal`` inclusive.

    Raises:
      ValueError: ``goal`` is unreachable.
    """
    h = distance_weight * np.linalg.norm(xy_m - xy_m[goal], axis=1)
    best = {start: 0.0}
    parent = {start: start}
    heap = [(h[start], 0.0, start)]
    done = set()
    while heap:
        _, g, node = heapq.heappop(heap)
        if node in done:
            continue
        if node == goal:
            path = [goal]
            while path[-1] != start:
                path.append(parent[path[-1]])
            return path[::-1]
        done.add(node)
        for nxt in np.flatnonzero(np.isfinite(costs[node])):
            nxt = int(nxt)
            cand = g + costs[node, nxt]
            if nxt != node and cand < best.get(nxt, np.inf) - 1e-12:
                best[nxt] = cand
                parent[nxt] = node
                heapq.heappush(heap, (cand + h[nxt], cand, nxt))
    raise ValueError(f"waypoint {goal} is unreachable from {start}")
