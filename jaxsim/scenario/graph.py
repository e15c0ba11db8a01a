"""``graph.json``: undirected ``edges`` as ``[u, v]`` waypoint-id pairs, and the ids excluded for
humans (``humans_exclude``) and for the robot (``robot_exclude``)."""

from __future__ import annotations

import pathlib

import numpy as np

from jaxsim.scenario.errors import ScenarioError
from jaxsim.scenario.jsonio import list_field, read_json

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
