"""``graph.json``: undirected ``edges`` as ``[u, v]`` waypoint-id pairs, and the ids excluded for
humans (``humans_exclude``) and for the robot (``robot_exclude``)."""

from __future__ import annotations

import pathlib

import numpy as np

from socialnav.jaxsim.scenario.errors import ScenarioError
from socialnav.jaxsim.scenario.jsonio import list_field, only_fields, read_json

FILE = "graph.json"


def _exclusion_mask(graph: dict, file: pathlib.Path, key: str, index: dict[str, int]) -> np.ndarray:
    allowed = np.ones(len(index), bool)
    for name in list_field(graph, file, key):
        if name not in index:
            raise ScenarioError(file, key, f"unknown waypoint {name!r}")
        allowed[index[name]] = False
    return allowed


def load_graph(folder: pathlib.Path, index: dict[str, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(E, 2) int32 edges, (W,) human_allowed, (W,) robot_allowed."""
    file = folder / FILE
    graph = read_json(file)
    only_fields(graph, file, "", ("edges", "humans_exclude", "robot_exclude"))
    edges = []
    for i, e in enumerate(list_field(graph, file, "edges")):
        if not (isinstance(e, list) and len(e) == 2):
            raise ScenarioError(file, f"edges[{i}]", f"expected [u, v], got {e!r}")
        for end in e:
            if not isinstance(end, str) or end not in index:
                raise ScenarioError(file, f"edges[{i}]", f"edge to unknown waypoint {end!r}")
        if e[0] == e[1]:
            raise ScenarioError(file, f"edges[{i}]", f"self loop at {e[0]!r}")
        edges.append((index[e[0]], index[e[1]]))
    human_allowed = _exclusion_mask(graph, file, "humans_exclude", index)
    robot_allowed = _exclusion_mask(graph, file, "robot_exclude", index)
    return np.asarray(edges, np.int32).reshape(-1, 2), human_allowed, robot_allowed


def reachable(n_waypoints: int, edges: np.ndarray, allowed: np.ndarray, start: int) -> np.ndarray:
    """(W,) bool: the waypoints reachable from ``start`` along ``edges`` through ``allowed`` ones."""
    neighbours: list[list[int]] = [[] for _ in range(n_waypoints)]
    for u, v in edges:
        if allowed[u] and allowed[v]:
            neighbours[u].append(int(v))
            neighbours[v].append(int(u))
    seen = np.zeros(n_waypoints, bool)
    seen[start] = True
    frontier = [start]
    while frontier:
        nxt = [v for u in frontier for v in neighbours[u] if not seen[v]]
        seen[nxt] = True
        frontier = list(dict.fromkeys(nxt))
    return seen


def check_connected(
    file: pathlib.Path,
    ids: tuple[str, ...],
    edges: np.ndarray,
    allowed: np.ndarray,
    start: int,
    needed: dict[int, str],
    who: str,
) -> None:
    """Raise :class:`ScenarioError` on ``file`` naming the first waypoint of ``needed`` (index ->
    what it is for) that ``who`` cannot reach from ``start``."""
    seen = reachable(len(ids), edges, allowed, start)
    for wp, role in needed.items():
        if not seen[wp]:
            raise ScenarioError(
                file,
                "edges",
                f"{role} {ids[wp]!r} cannot be reached by {who} from {ids[start]!r} "
                f"(no path of edges through waypoints {who} may use)",
            )
