"""Shortest routes over the waypoint graph (host side, numpy; 73 nodes, so all pairs at once).

The simulator never searches a graph inside ``jit``: workers look up ``next_hop[here, goal]``,
built here once; the robot follows a route table that a planner builds with the same search
(``planners.warehouse.routes``).
"""

from __future__ import annotations

import numpy as np

UNREACHABLE = -1


def edge_lengths_m(waypoint_xy_m: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """(E,) Euclidean length of each edge."""
    return np.linalg.norm(waypoint_xy_m[edges[:, 0]] - waypoint_xy_m[edges[:, 1]], axis=-1)


def all_pairs_shortest(
    n: int, edges: np.ndarray, weights: np.ndarray, allowed: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Floyd-Warshall over an undirected graph.

    Args:
      n: number of nodes.
      edges: (E, 2) int node pairs.
      weights: (E,) non-negative edge costs.
      allowed: (n,) bool; nodes that are False are neither used nor reachable.

    Returns:
      dist: (n, n) path cost (inf when unreachable).
      next_hop: (n, n) int32 first node after ``i`` on a shortest path ``i -> j``
        (``j`` itself for neighbours, ``i`` for ``i == j``, -1 when unreachable).
    """
    allowed = np.ones(n, bool) if allowed is None else np.asarray(allowed, bool)
    cost = np.full((n, n), np.inf)
    for (u, v), w in zip(edges, weights):
        if allowed[u] and allowed[v] and w < cost[u, v]:
            cost[u, v] = cost[v, u] = w
    return floyd_warshall(cost, allowed)


def floyd_warshall(cost: np.ndarray, allowed: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """All-pairs shortest paths over a dense, possibly directed cost matrix.

    Args:
      cost: (n, n) cost of the arc ``i -> j`` (inf where there is none); the diagonal is ignored.
      allowed: (n,) bool; nodes that are False are neither used nor reachable.

    Returns:
      (dist, next_hop) as in :func:`all_pairs_shortest`.
    """
    n = len(cost)
    allowed = np.ones(n, bool) if allowed is None else np.asarray(allowed, bool)
    dist = np.where(allowed[:, None] & allowed[None, :], np.asarray(cost, np.float64), np.inf)
    next_hop = np.where(np.isfinite(dist), np.arange(n, dtype=np.int32)[None, :], UNREACHABLE).astype(np.int32)
    idx = np.flatnonzero(allowed)
    dist[idx, idx] = 0.0
    next_hop[idx, idx] = idx
    for k in range(n):
        via = dist[:, k : k + 1] + dist[k : k + 1, :]
        better = via < dist - 1e-12
        dist = np.where(better, via, dist)
        next_hop = np.where(better, next_hop[:, k : k + 1], next_hop)
    return dist, next_hop
