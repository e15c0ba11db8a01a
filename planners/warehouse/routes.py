"""Route tables of the waypoint planners: every start-goal route of every slot, as the
simulator's :class:`~jaxsim.world.RobotPlan`.

One function builds them from arc costs (:func:`plan_from_costs`): the shortest-path baseline
is that function on Euclidean arc lengths (:func:`shortest_path_plan`), the causal planner on
Eq. (9)'s costs (:func:`planners.warehouse.waypoint.causal_plan`). On the warehouse's 73 waypoints an
all-pairs search per slot (Floyd-Warshall) is instant and gives the same routes as A* per query
(``tests/test_planners.py`` checks it), so the batched simulator never searches inside ``jit``.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from socialnav.jaxsim import graph
from socialnav.jaxsim.scenario import Scenario
from socialnav.jaxsim.world import RobotPlan

UNREACHABLE = graph.UNREACHABLE


def arc_lengths_m(scenario: Scenario) -> np.ndarray:
    """(W, W) Euclidean arc lengths, inf where there is no edge."""
    n = scenario.n_waypoints
    length = np.full((n, n), np.inf)
    lengths = graph.edge_lengths_m(scenario.waypoint_xy_m, scenario.edges)
    for (u, v), w in zip(scenario.edges, lengths, strict=True):
        length[u, v] = length[v, u] = w
    return length


def route(next_hop: np.ndarray, start: int, goal: int) -> list[int]:
    """Waypoints from ``start`` (excluded) to ``goal`` (included); empty if start == goal.

    Raises:
      ValueError: when ``goal`` cannot be reached from ``start``.
    """
    path, here = [], start
    while here != goal:
        here = int(next_hop[here, goal])
        if here == UNREACHABLE or len(path) > len(next_hop):
            raise ValueError(f"waypoint {goal} is unreachable from {start}")
        path.append(here)
    return path


def route_table(next_hop: np.ndarray, dist: np.ndarray, max_len: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Every shortest route as a padded table, the robot's plan format.

    Returns:
      routes: (n, n, L) int32; ``routes[i, j, :k]`` are the waypoints after ``i`` up to ``j``,
        padded with ``j`` (so a route can be followed without a length check).
      hops: (n, n) int32 number of real hops ``k`` (0 for unreachable pairs or ``i == j``).
    """
    n = len(next_hop)
    paths = {}
    for i in range(n):
        for j in range(n):
            if np.isfinite(dist[i, j]):
                paths[i, j] = route(next_hop, i, j)
    longest = max((len(p) for p in paths.values()), default=1)
    max_len = max(longest, 1) if max_len is None else max_len
    if longest > max_len:
        raise ValueError(f"a route has {longest} hops, more than max_len={max_len}")
    routes = np.repeat(np.arange(n, dtype=np.int32)[None, :, None], n, 0).repeat(max_len, 2)
    hops = np.zeros((n, n), np.int32)
    for (i, j), p in paths.items():
        routes[i, j, : len(p)] = p
        hops[i, j] = len(p)
    return routes, hops


def _route_lengths_m(routes: np.ndarray, hops: np.ndarray, length_m: np.ndarray) -> np.ndarray:
    """(n, n) metres along each route (arc lengths summed in route order)."""
    n = len(hops)
    start = np.arange(n)[:, None, None]
    prev = np.concatenate([np.broadcast_to(start, (n, n, 1)), routes[..., :-1]], -1)
    steps = length_m[prev, routes] * (np.arange(routes.shape[-1]) < hops[..., None])
    return steps.sum(-1)


def plan_from_costs(scenario: Scenario, costs: np.ndarray, allowed: np.ndarray | None = None) -> RobotPlan:
    """The :class:`RobotPlan` of least-cost routes under ``costs``.

    Args:
      costs: (S, W, W) directed arc costs per slot, or (W, W) for every slot; inf where there is
        no arc. Non-negative.
      allowed: (W,) bool waypoints the routes may use (default: the robot's graph).

    Returns:
      routes, hops and ``length_m`` (metres along each route, for placing obstacles) per slot.
    """
    costs = np.asarray(costs, np.float64)
    n_w = scenario.n_waypoints
    if costs.ndim == 2:
        costs = np.broadcast_to(costs, (scenario.n_slots, *costs.shape))
    if costs.shape != (scenario.n_slots, n_w, n_w):
        raise ValueError(f"arc costs of shape {costs.shape}, expected {(scenario.n_slots, n_w, n_w)}")
    if (costs < 0).any():
        raise ValueError("arc costs must be >= 0")
    allowed = scenario.robot_allowed if allowed is None else allowed
    arcs = arc_lengths_m(scenario)
    length = np.where(np.isfinite(arcs), arcs, 0.0)
    tables = {}  # slots with equal costs share one search
    routes, hops, metres = [], [], []
    for s in range(len(costs)):
        key = costs[s].tobytes()
        if key not in tables:
            dist, next_hop = graph.floyd_warshall(costs[s], allowed)
            r, h = route_table(next_hop, dist)
            tables[key] = (r, h, _route_lengths_m(r, h, length))
        r, h, m = tables[key]
        routes.append(r)
        hops.append(h)
        metres.append(m)
    width = max(r.shape[-1] for r in routes)
    routes = [np.concatenate([r, np.repeat(r[..., -1:], width - r.shape[-1], -1)], -1) for r in routes]
    return RobotPlan(
        routes=jnp.asarray(np.stack(routes)),
        hops=jnp.asarray(np.stack(hops)),
        length_m=jnp.asarray(np.stack(metres), jnp.float32),
    )


def shortest_path_plan(scenario: Scenario) -> RobotPlan:
    """The baseline: Euclidean shortest routes over the robot's graph, the same every slot."""
    return plan_from_costs(scenario, arc_lengths_m(scenario))
