"""A walker's way round the walls: the corners of the shortest path a person's body fits through.

The human models steer a person towards a point (:class:`jaxsim.walkers.Aims`). A scene's walker
(or a stream's member) whose straight line from ``from`` to ``to`` crosses a wall would be held
against that wall for the rest of the episode, the wall's push against the drive, with nothing
said. Pedestrian simulators route their agents instead (JuPedSim steers each agent along the
shortest path through the walkable area to its next waypoint; Vadere follows a floor field, the
geodesic distance to the target): here such a walker walks the corners of the shortest way round
the walls (waypoints), each passed when reached or when the point after it comes into sight
(:func:`jaxsim.scenes.people.step_people`). A queue's served member leaves the head for the exit
the same way (:data:`WAYS`). A walker whose straight line crosses no wall walks it as before, so
scenes whose people walk in the open (every shipped one) are unchanged, bit for bit.

How (:func:`waypoints`): the free space is the cells of :func:`free_regions`'
grid (0.05 m) where a person's body fits, with :data:`ROUTE_MARGIN_M` to spare where the way is
wide enough and without it where it is not; scipy's Dijkstra over its 8-connected cells gives the
shortest path of cells from the start's to the end's; the path is then pulled taut (from each
corner, the farthest path cell in straight sight of it: the segment between them over free cells
only, as Theta*'s line of sight on a grid).
A way with more than :data:`MAX_WAYPOINTS` corners, or none, raises :class:`NoRoute`, which the
scene's reader turns into a :class:`~jaxsim.scenario.errors.ScenarioError` naming the walker's
field, or the queue's (:func:`jaxsim.scenes.reachable.people_problem`). Written here because no
maintained library in the toolkit's dependencies routes a body through axis-aligned boxes; the
shortest path itself is scipy's.
"""

from __future__ import annotations

import functools

import numpy as np
import scipy.ndimage
import scipy.sparse
import scipy.sparse.csgraph

from socialnav.jaxsim import geometry
from socialnav.jaxsim.params import PERSON_RADIUS_M

# The people who may need a way round the walls, by behaviour: the spec's fields their way runs
# between, and the scene file's field an error about it names. A walker or stream member walks
# from its start to its end; a queue's served member leaves from the head for the exit.
WAYS = {"walk": ("start", "end", "to"), "stream": ("start", "end", "to"), "queue": ("head", "exit", "exit")}

# The free space's cells (m): the robot's way to its goal (:mod:`jaxsim.scenes.reachable`) and a
# walker's way round the walls.
RESOLUTION_M = 0.05
# Corners a walker's way may turn at: the variant's waypoint arrays have this many slots whatever
# the scene (the compiled programs do not depend on a scene's routes).
MAX_WAYPOINTS = 8
# Room kept between a routed walker's body and the walls where the way is wide enough (the human
# models' wall force pushes a body off a wall from about this distance).
ROUTE_MARGIN_M = 0.1


class NoRoute(ValueError):
    """A walker's end cannot be reached from its start by a person's body, or only round more than
    :data:`MAX_WAYPOINTS` corners (the message says which)."""


def free_regions(bounds_m, walls_m: np.ndarray, radius_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(labels, xs, ys)``: (H, W) int over ``bounds_m``, 0 where a body's centre cannot be
    (closer than ``radius_m``, less one cell, to a wall box (K, 4) or the bounds), else the number of
    the connected region the cell belongs to; the cells' centres (W,) and (H,) in metres."""
    xmin, xmax, ymin, ymax = bounds_m
    xs = xmin + (np.arange(int(np.ceil((xmax - xmin) / RESOLUTION_M))) + 0.5) * RESOLUTION_M
    ys = ymin + (np.arange(int(np.ceil((ymax - ymin) / RESOLUTION_M))) + 0.5) * RESOLUTION_M
    gx, gy = np.meshgrid(xs, ys)
    clearance = np.minimum.reduce([gx - xmin, xmax - gx, gy - ymin, ymax - gy])
    if len(walls_m):
        clearance = np.minimum(clearance, geometry.box_signed_distance(gx, gy, walls_m)[0])
    labels, _ = scipy.ndimage.label(clearance >= radius_m - RESOLUTION_M, structure=np.ones((3, 3)))
    return labels, xs, ys


def may_route(people, walls_m: np.ndarray) -> bool:
    """Whether the straight line of a walker, a stream member or a queue's served member
    (:data:`WAYS`) can cross a wall box (K, 4) in any variant of a scene with these ``people``
    (:attr:`~jaxsim.scenes.spec.SceneSpec.people`), held out ones included: some wall box meets
    the box that holds both of its ranges,
    each widened by half its width (a held-out draw lies at most that far outside its range). False
    means no variant has a corner to walk (a segment stays in any box holding both its ends), so
    the scene's people step without the corners' bookkeeping (:attr:`jaxsim.scenes.env.Env.routed`),
    as fast as before (all shipped scenes but ``snape_two_walking``, whose corridor wall meets a
    walker's box; its people walk the same steps either way, no line of theirs crossing a wall)."""
    walls_m = np.asarray(walls_m, np.float64).reshape(-1, 4)
    if len(walls_m) == 0:
        return False
    for person in people:
        if person["behaviour"] not in WAYS:
            continue
        start, end, _ = WAYS[person["behaviour"]]
        (ax, ay), (bx, by) = person[start], person[end]
        x0, x1 = min(_widened(ax)[0], _widened(bx)[0]), max(_widened(ax)[1], _widened(bx)[1])
        y0, y1 = min(_widened(ay)[0], _widened(by)[0]), max(_widened(ay)[1], _widened(by)[1])
        meets = (walls_m[:, 0] <= x1) & (walls_m[:, 1] >= x0) & (walls_m[:, 2] <= y1) & (walls_m[:, 3] >= y0)
        if meets.any():
            return True
    return False


def _widened(interval) -> tuple[float, float]:
    lo, hi = (float(v) for v in interval)
    return lo - (hi - lo) / 2, hi + (hi - lo) / 2


def crosses_walls(start_xy, end_xy, walls_m: np.ndarray) -> bool:
    """Whether the straight line from ``start_xy`` to ``end_xy`` (2,) crosses a wall box (K, 4)."""
    if len(walls_m) == 0:
        return False
    return bool(geometry.segment_hits_boxes(np.asarray(start_xy)[None], np.asarray(end_xy)[None], walls_m)[0])


def waypoints(start_xy, end_xy, walls_m: np.ndarray, bounds_m, radius_m: float = PERSON_RADIUS_M) -> np.ndarray:
    """(k, 2) float32 the corners between ``start_xy`` and ``end_xy`` (2,) of the shortest way round
    the walls (K, 4) within ``bounds_m`` for a body of ``radius_m`` (0 <= k <= :data:`MAX_WAYPOINTS`;
    neither end included; none where the straight line crosses no wall). Raises :class:`NoRoute`."""
    walls_m = np.asarray(walls_m, np.float64).reshape(-1, 4)
    if not crosses_walls(start_xy, end_xy, walls_m):
        return np.zeros((0, 2), np.float32)
    keys = (tuple(map(tuple, walls_m.tolist())), tuple(float(b) for b in bounds_m), float(radius_m))
    start, end = (tuple(np.asarray(xy, np.float64).tolist()) for xy in (start_xy, end_xy))
    return _corners(start, end, *keys).copy()


@functools.lru_cache(maxsize=1024)
def _corners(start: tuple, end: tuple, walls_key: tuple, bounds_key: tuple, radius_m: float) -> np.ndarray:
    """:func:`waypoints` of a way that crosses a wall, cached (a scene's checks and its variants ask
    for the same ways again)."""
    start_xy, end_xy = np.asarray(start, np.float64), np.asarray(end, np.float64)
    for clearance_m in (radius_m + ROUTE_MARGIN_M, radius_m):  # with room to spare, then without
        free, xs, ys, graph = _free_graph(walls_key, bounds_key, float(clearance_m))
        path = _cell_path(free, xs, ys, graph, start_xy, end_xy, clearance_m)
        if path is not None:
            # The legs between corners may cut ROUTE_MARGIN_M closer to a wall than the path's
            # cells keep: round a wall's corner the free cells' edge is an arc, which a taut line
            # of sight at the same clearance would follow corner by corner.
            sight = _free_graph(walls_key, bounds_key, float(clearance_m - ROUTE_MARGIN_M))[0]
            corners = _pulled_taut(np.vstack([start_xy, path, end_xy]), sight, xs, ys, clearance_m)
            if len(corners) > MAX_WAYPOINTS:
                raise NoRoute(
                    f"the way round the walls turns at {len(corners)} corners, more than {MAX_WAYPOINTS}: "
                    "bring its ends (a queue's head and exit) nearer, or split a walk into walkers with ends "
                    "in sight of each other"
                )
            return corners.astype(np.float32)
    raise NoRoute(
        f"no way from ({start_xy[0]:g}, {start_xy[1]:g}) to ({end_xy[0]:g}, {end_xy[1]:g}) round the walls "
        f"for a person ({radius_m:g} m body, a way {2 * radius_m:g} m wide)"
    )


def _pulled_taut(points: np.ndarray, free: np.ndarray, xs: np.ndarray, ys: np.ndarray, clearance_m: float):
    """The corners of the polyline ``points`` (n, 2) (start, path cells, end) pulled taut: from each
    corner the farthest point in straight sight over the free cells (:func:`_in_sight`), or the next
    point where none further is; the start and end left out."""
    corners, i, last = [], 0, len(points) - 1
    while True:
        clear = _in_sight(points[i], points[i + 1 :], free, xs, ys, clearance_m, i == 0, last - i - 1)
        j = i + 1 + (int(np.flatnonzero(clear)[-1]) if clear.any() else 0)
        if j >= last:
            return np.asarray(corners, np.float64).reshape(-1, 2)
        corners.append(points[j])
        i = j


def _in_sight(a, bs, free, xs, ys, clearance_m: float, a_is_start: bool, end_index: int) -> np.ndarray:
    """(m,) bool: the segments from ``a`` (2,) to each of ``bs`` (m, 2) run over free cells only,
    sampled every quarter cell; near a walker's own start and end (``a_is_start``, ``bs[end_index]``),
    which may lie closer to a wall than the free cells do, within ``clearance_m`` of that point
    anything goes."""
    step = RESOLUTION_M
    length = np.linalg.norm(bs - a, axis=-1)
    n = int(np.ceil(length.max() / (step / 4))) + 2
    t = np.linspace(0.0, 1.0, n)
    points = a[None, None, :] + t[None, :, None] * (bs - a)[:, None, :]  # (m, n, 2)
    col = np.clip(np.rint((points[..., 0] - xs[0]) / step).astype(np.int64), 0, len(xs) - 1)
    row = np.clip(np.rint((points[..., 1] - ys[0]) / step).astype(np.int64), 0, len(ys) - 1)
    ok = free[row, col]
    along = t[None, :] * length[:, None]  # (m, n) metres from a
    if a_is_start:
        ok |= along <= clearance_m
    ok[end_index] |= (length[end_index] - along[end_index]) <= clearance_m
    return ok.all(axis=1)


@functools.lru_cache(maxsize=32)
def _free_graph(walls_key: tuple, bounds_key: tuple, clearance_m: float):
    """``(free (H, W) bool, xs (W,), ys (H,), graph)``: the cells where a body keeps ``clearance_m``
    from the walls and bounds (:func:`free_regions`: up to one cell
    short of it) and the 8-connected graph over them, each edge the distance between the cells'
    centres (a scene's walkers share it)."""
    walls_m = np.asarray(walls_key, np.float64).reshape(-1, 4)
    labels, xs, ys = free_regions(bounds_key, walls_m, clearance_m)
    free = labels > 0
    h, w = free.shape
    index = np.arange(h * w).reshape(h, w)
    step = RESOLUTION_M
    rows, cols, weights = [], [], []
    ya, xa = np.nonzero(free)
    for dy, dx in ((0, 1), (1, 0), (1, 1), (1, -1)):
        yb, xb = ya + dy, xa + dx
        inside = (yb < h) & (xb >= 0) & (xb < w)
        y0, x0, y1, x1 = ya[inside], xa[inside], yb[inside], xb[inside]
        both = free[y1, x1]
        rows.append(index[y0[both], x0[both]])
        cols.append(index[y1[both], x1[both]])
        weights.append(np.full(int(both.sum()), step * np.hypot(dx, dy)))
    graph = scipy.sparse.csr_matrix(
        (np.concatenate(weights), (np.concatenate(rows), np.concatenate(cols))), shape=(h * w, h * w)
    )
    return free, xs, ys, graph


def _nearest_free(free: np.ndarray, xs: np.ndarray, ys: np.ndarray, xy: np.ndarray, within_m: float) -> int | None:
    """The flat index of the free cell nearest ``xy`` within ``within_m``, or None."""
    d2 = (xs[None, :] - xy[0]) ** 2 + (ys[:, None] - xy[1]) ** 2
    d2 = np.where(free, d2, np.inf)
    k = int(np.argmin(d2))
    return k if d2.flat[k] <= within_m**2 else None


def _cell_path(free, xs, ys, graph, start_xy, end_xy, clearance_m: float) -> np.ndarray | None:
    """(n, 2) the centres of the cells of the shortest 8-connected path between the free cells
    nearest the two ends (within ``clearance_m`` of them), or None where there is none."""
    source = _nearest_free(free, xs, ys, start_xy, clearance_m)
    target = _nearest_free(free, xs, ys, end_xy, clearance_m)
    if source is None or target is None:
        return None
    distance, previous = scipy.sparse.csgraph.dijkstra(graph, directed=False, indices=source, return_predecessors=True)
    if not np.isfinite(distance[target]):
        return None
    cells = [target]
    while cells[-1] != source:
        cells.append(int(previous[cells[-1]]))
    rows, cols = np.divmod(np.asarray(cells[::-1]), free.shape[1])
    return np.stack([xs[cols], ys[rows]], axis=-1)
