"""A robot route table for the simulator's tests, built with scipy, not with ``planners``.

The simulator's tests need some :class:`~jaxsim.world.RobotPlan` to follow; building it here from
``scipy.sparse.csgraph.shortest_path`` keeps them independent of the planners (whose own tests
compare their tables against scipy).
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from scipy.sparse.csgraph import shortest_path

from socialnav.jaxsim.world import RobotPlan


def scipy_shortest_plan(scenario) -> RobotPlan:
    """Euclidean shortest routes over the robot's graph, the same every slot."""
    n = scenario.n_waypoints
    xy = scenario.waypoint_xy_m
    weights = np.zeros((n, n))
    for u, v in scenario.edges:
        if scenario.robot_allowed[u] and scenario.robot_allowed[v]:
            weights[u, v] = weights[v, u] = np.linalg.norm(xy[u] - xy[v])
    dist, pred = shortest_path(weights, directed=False, return_predecessors=True)
    paths = {}
    for i in range(n):
        for j in range(n):
            if i != j and np.isfinite(dist[i, j]):
                path, here = [], j
                while here != i:
                    path.append(here)
                    here = pred[i, here]
                paths[i, j] = path[::-1]
    width = max(len(p) for p in paths.values())
    routes = np.repeat(np.arange(n, dtype=np.int32)[None, :, None], n, 0).repeat(width, 2)
    hops = np.zeros((n, n), np.int32)
    for (i, j), p in paths.items():
        routes[i, j, : len(p)] = p
        hops[i, j] = len(p)
    length = np.where(np.isfinite(dist), dist, 0.0)
    s = scenario.n_slots
    return RobotPlan(
        routes=jnp.asarray(np.broadcast_to(routes, (s, *routes.shape))),
        hops=jnp.asarray(np.broadcast_to(hops, (s, n, n))),
        length_m=jnp.asarray(np.broadcast_to(length, (s, n, n)), jnp.float32),
    )
