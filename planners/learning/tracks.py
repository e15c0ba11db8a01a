"""People's tracks as demonstrations for learning costs through the planner (:mod:`planners.learning.irl`).

Three sources: a user's files (below), the real pedestrians shipped with the package
(:func:`recorded_tracks`: an ETH/UCY file or a Jülich run, with the walls where the data has
them), and the arena's own people (:func:`simulated_tracks`: the crowd model walking a scene's
variants with no robot among them). Each gives the tracks and the occupancy in the same form
as a file's.

**The file formats** (a user's own data):

* Tracks: CSV or Parquet with one row per person and frame and at least the columns ``frame``
  (integer), ``id`` (any label), ``x`` and ``y`` (metres, in the map's frame), read by
  :func:`socialnav.data.track_file.read_tracks` (the arena's recorded crowds read the same files).
  Other columns are ignored; rows may come in any order. The frame rate does not matter here
  (only the order of a person's positions is used).
* The walls: a ROS ``map_server`` map, the format every ROS and Nav2 user has (a YAML file and
  its image), read by :func:`planners.learning.ros_map.read_ros_map` with Nav2's meaning of each
  field and pixel.

**What a track becomes** (:func:`track_demonstrations`): the GSCL network's view of the scene
from where the person starts, as the robot sees it from the centre of its 16 m window
(:func:`models.inference.input_map`, in the world's axes like the GSCL layer's default): the
walls, the other people present at that frame with their headings (from their next position),
and as the goal the last position of the track before it first leaves the window. The
demonstrated path is the chain of 0.4 m cells the person crossed up to there (segments between
positions sampled every 5 cm, so consecutive cells are 8-neighbours; two straight steps around a
cell corner become the diagonal move, as the planner would make it). A track is left out, and
counted in the report by reason, when it crosses fewer than two cells, enters a wall cell, or
moves diagonally past a wall's corner (a move the planner cannot make).
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from socialnav.data.track_file import REQUIRED_COLUMNS, TrackFileError, read_tracks  # noqa: F401  (re-exported)
from socialnav.models import grid
from socialnav.models.inference import input_map
from socialnav.planners.learning.irl import Demonstrations, K, path_moves

SAMPLE_M = 0.05  # spacing of the points a segment between two positions is sampled at


# The least share of a file's positions that must lie on its map (inside the image's extent) for
# the two to be taken as one frame. Positions of another frame (the map's origin forgotten, the
# tracks in centimetres or pixels, x and y swapped) put next to none of them on the map, and a
# window with no walls teaches nothing of walls; a recording whose people sometimes walk past the
# mapped area still passes. A choice, not a measurement: ``--min-on-map`` sets another.
MIN_ON_MAP_SHARE = 0.8


def check_on_map(
    tracks: dict,
    occupancy,
    resolution_m: float,
    origin_xy_m,
    tracks_file="tracks",
    map_file="map",
    min_share: float = MIN_ON_MAP_SHARE,
) -> float:
    """The share of the tracks' positions that lie on the map (inside the image's extent).

    Raises:
      TrackFileError: below ``min_share``, naming both files, the share and where the positions
        and the map lie (so a frame mismatch can be seen at once).
    """
    h, w = np.shape(occupancy)
    x0, y0 = float(origin_xy_m[0]), float(origin_xy_m[1])
    x1, y1 = x0 + w * resolution_m, y0 + h * resolution_m
    xy = np.concatenate([t[:, 1:] for t in tracks.values()])
    on = (xy[:, 0] >= x0) & (xy[:, 0] <= x1) & (xy[:, 1] >= y0) & (xy[:, 1] <= y1)
    share = float(on.mean())
    if share < min_share:
        lo, hi = xy.min(axis=0), xy.max(axis=0)
        raise TrackFileError(
            f"{tracks_file}: columns 'x', 'y': {100 * share:.0f} % of the positions lie on the map {map_file} "
            f"(at least {100 * min_share:.0f} % needed): the positions span x {lo[0]:.4g}..{hi[0]:.4g}, "
            f"y {lo[1]:.4g}..{hi[1]:.4g} m, the map x {x0:.4g}..{x1:.4g}, y {y0:.4g}..{y1:.4g} m; "
            "are both in metres, in the same frame?"
        )
    return share


def without_specks(occupied, resolution_m: float, min_area_m2: float) -> np.ndarray:
    """``occupied`` (H, W) less its connected pieces (cells touching at a side or a corner) of
    less than ``min_area_m2``: a map's speckle (a SLAM map's stray hits), not walls. 0 keeps
    every occupied cell."""
    occupied = np.asarray(occupied) > 0
    if min_area_m2 <= 0:
        return occupied
    from scipy import ndimage

    labels, _ = ndimage.label(occupied, structure=np.ones((3, 3), bool))
    keep = np.bincount(labels.ravel()) * resolution_m**2 >= min_area_m2
    keep[0] = False  # the free cells
    return keep[labels]


def map_walls(tracks_file, map_file, rows, bounds_m, min_wall_m2: float = 0.0) -> tuple[list, float]:
    """``(walls, in_walls)``: the walls of the ROS map ``map_file`` inside ``bounds_m`` (boxes,
    :func:`jaxsim.scenes.from_recording.walls_from_occupancy`; pieces under ``min_wall_m2`` left
    out, :func:`without_specks`) and the share of the recorded positions of ``rows`` that lie in a
    wall (people the map does not know of). Raises ``TrackFileError`` where under 80 % of the
    positions lie on the map (another frame, other units: :func:`check_on_map`); ``MapFileError``
    for a map that cannot be read."""
    from socialnav.jaxsim.scenes import from_recording
    from socialnav.planners.learning.ros_map import read_ros_map

    occupancy, resolution_m, origin = read_ros_map(map_file)
    tracks = {p: g[["frame", "x_m", "y_m"]].to_numpy() for p, g in rows.groupby("person")}
    check_on_map(tracks, occupancy, resolution_m, origin, tracks_file, map_file)
    occupancy = without_specks(occupancy, resolution_m, min_wall_m2)
    walls = from_recording.walls_from_occupancy(occupancy, resolution_m, origin, bounds_m)
    xy = rows[["x_m", "y_m"]].to_numpy()
    col = np.floor((xy[:, 0] - origin[0]) / resolution_m).astype(int)
    row = np.floor((xy[:, 1] - origin[1]) / resolution_m).astype(int)
    on = (row >= 0) & (row < occupancy.shape[0]) & (col >= 0) & (col < occupancy.shape[1])
    in_wall = np.zeros(len(xy), bool)
    in_wall[on] = np.asarray(occupancy)[row[on], col[on]] > 0
    return walls, float(in_wall.mean()) if len(xy) else 0.0


def _dense(points_local_m: np.ndarray) -> np.ndarray:
    """(K, 2) points along the polyline of local points (M, 2), at most ``SAMPLE_M`` apart."""
    dense = [points_local_m[:1]]
    for a, b in zip(points_local_m[:-1], points_local_m[1:], strict=True):
        n = max(1, math.ceil(np.linalg.norm(b - a) / SAMPLE_M))
        dense.append(a + (b - a) * (np.arange(1, n + 1) / n)[:, None])
    return np.concatenate(dense)


def _cells_of_paths(paths: list[np.ndarray]) -> list[np.ndarray]:
    """Each polyline's (N, 2) int cells crossed (:func:`models.grid.cell_of`), consecutive repeats
    dropped. Every path's points go through ``cell_of`` in one call: called per path, each path's
    length was a new shape and a new compiled program (one track file has hundreds)."""
    dense = [_dense(p) for p in paths]
    xy = np.concatenate(dense)
    row, col = (np.asarray(v) for v in grid.cell_of(xy[:, 0], xy[:, 1]))
    out = []
    for cells in np.split(np.stack([row, col], axis=1), np.cumsum([len(d) for d in dense])[:-1]):
        keep = np.concatenate([[True], np.any(cells[1:] != cells[:-1], axis=1)])
        out.append(cells[keep])
    return out


def _shortcut(cells: np.ndarray, walls: np.ndarray) -> np.ndarray:
    """The chain with each corner step made a diagonal move where the planner has it: a track
    crossing a cell corner (exactly, or by a few centimetres) becomes one diagonal move instead
    of two straight ones through a side cell."""
    out = [cells[0]]
    i = 0
    while i < len(cells) - 1:
        a = out[-1]
        if i + 2 < len(cells):
            c = cells[i + 2]
            d = c - a
            if np.abs(d).max() == 1 and d.all() and not (walls[a[0] + d[0], a[1]] or walls[a[0], a[1] + d[1]]):
                out.append(c)
                i += 2
                continue
        out.append(cells[i + 1])
        i += 1
    return np.stack(out)


def _feasible(cells: np.ndarray, walls: np.ndarray) -> str | None:
    """None when the planner's graph has every move of the chain, else why not."""
    if len(cells) < 2:
        return "fewer than 2 cells"
    if walls[cells[:, 0], cells[:, 1]].any():
        return "enters a wall cell"
    step = cells[1:] - cells[:-1]
    if np.abs(step).max() > 1:
        return "jumps a cell"  # cannot happen with SAMPLE_M < CELL_M; kept as a guard
    diag = (step[:, 0] != 0) & (step[:, 1] != 0)
    a = cells[:-1][diag]
    s = step[diag]
    if (walls[a[:, 0] + s[:, 0], a[:, 1]] | walls[a[:, 0], a[:, 1] + s[:, 1]]).any():
        return "cuts a wall's corner"
    return None


def track_demonstrations(tracks: dict, occupancy, resolution_m: float, origin_xy_m, min_cells: int = 2):
    """Input maps and demonstrations of every usable track.

    Args:
      tracks: ``{id: (T, 3) [frame, x, y]}`` (:func:`read_tracks`).
      occupancy, resolution_m, origin_xy_m: the walls (:func:`planners.learning.ros_map.read_ros_map`,
        or any OccupancyGrid layout array in [0, 1]).
      min_cells: the fewest cells a track must cross inside its window.

    Returns:
      ``(maps (N, 40, 40) uint8, Demonstrations with axis N, report)``; ``report`` counts the
      tracks used and those left out by reason, and lists the ids used in order.
    """
    ids = list(tracks)
    heading, present_at = {}, {}
    for pid in ids:
        t = tracks[pid]
        d = np.diff(t[:, 1:], axis=0)
        h = np.arctan2(d[:, 1], d[:, 0]) if len(d) else np.zeros(1)
        heading[pid] = np.append(h, h[-1])  # a position's heading: towards the next one (the last: as before it)
        for i, f in enumerate(t[:, 0].astype(int)):
            present_at.setdefault(f, []).append((pid, i))

    # Each track's window: its centre (the first position), how far it stays inside, the others then.
    views = []
    for pid in ids:
        t = tracks[pid]
        local = t[:, 1:] - t[0, 1:]
        inside = np.all(np.abs(local) < grid.HALF_M - 1e-6, axis=1)
        last = len(t) if inside.all() else int(np.argmin(inside))
        others = [(q, i) for q, i in present_at[int(t[0, 0])] if q != pid]
        views.append((local[:last], others))
    # Positions from the map's origin, taken in float64 before the float32 the windows are drawn in:
    # a map in a world frame far from zero (UTM: y ~ 5e6 m, where float32 steps by 0.5 m) would
    # otherwise put walls and people a cell or more from where they are.
    origin64 = np.asarray(origin_xy_m, np.float64)
    p_max = max(1, max(len(others) for _, others in views))
    people = np.zeros((len(ids), p_max, 2), np.float32)
    headings = np.zeros((len(ids), p_max), np.float32)
    valid = np.zeros((len(ids), p_max), bool)
    for n, (_, others) in enumerate(views):
        for k, (q, i) in enumerate(others):
            people[n, k], headings[n, k], valid[n, k] = tracks[q][i, 1:] - origin64, heading[q][i], True
    centres = np.stack([tracks[pid][0, 1:] for pid in ids]) - origin64
    goals = np.stack([tracks[pid][len(path) - 1, 1:] for pid, (path, _) in zip(ids, views, strict=True)]) - origin64
    occupancy = jnp.asarray(occupancy, jnp.float32)
    at_zero = jnp.zeros(2, jnp.float32)
    images = np.asarray(
        jax.jit(
            jax.vmap(lambda c, p, h, v, g: input_map(occupancy, resolution_m, at_zero, c, p, h, g, people_valid=v))
        )(centres.astype(np.float32), people, headings, valid, goals.astype(np.float32))
    )

    chains, used = [], []
    skipped: dict[str, int] = {}
    crossed = _cells_of_paths([path for path, _ in views])
    for n in range(len(views)):
        walls = images[n] == grid.WALL
        cells = _shortcut(crossed[n], walls)
        why = _feasible(cells, walls) if len(cells) >= min_cells else f"fewer than {min_cells} cells"
        if why:
            skipped[why] = skipped.get(why, 0) + 1
            continue
        chains.append(cells)
        used.append(n)
    report = {"tracks": len(ids), "used": len(used), "left_out": skipped, "ids": [ids[n] for n in used]}
    length = max((len(c) for c in chains), default=1)
    padded = np.zeros((len(chains), length, 2), np.int32)
    for n, c in enumerate(chains):
        padded[n] = np.concatenate([c, np.repeat(c[-1:], length - len(c), axis=0)])  # a repeated cell is no move
    moves = np.asarray(jax.vmap(path_moves)(padded)) if chains else np.zeros((0, K, grid.GRID, grid.GRID), np.float32)
    starts = np.zeros((len(chains), grid.GRID, grid.GRID), np.float32)
    starts[np.arange(len(chains)), padded[:, 0, 0], padded[:, 0, 1]] = 1.0
    demos = Demonstrations(moves, starts, padded[:, -1], np.ones(len(chains), np.float32))
    return images[used], demos, report


def concatenate(parts):
    """One ``(maps, demonstrations, report)`` from several :func:`track_demonstrations` results
    (the reports' counts summed, their ids listed in order)."""
    maps = np.concatenate([p[0] for p in parts])
    demos = jax.tree.map(lambda *a: np.concatenate(a), *[p[1] for p in parts])
    left: dict[str, int] = {}
    for p in parts:
        for why, n in p[2]["left_out"].items():
            left[why] = left.get(why, 0) + n
    report = {
        "tracks": sum(p[2]["tracks"] for p in parts),
        "used": sum(p[2]["used"] for p in parts),
        "left_out": left,
        "ids": [i for p in parts for i in p[2]["ids"]],
    }
    return maps, demos, report


RECORDED_MARGIN_M = 8.0  # free space around a recording's people: a track's 16 m window stays on the map


def recorded_tracks(run: str, resolution_m: float = 0.1):
    """The tracks of a shipped recorded run (:mod:`data.recorded`) and its walls.

    ETH/UCY ships no map of its walls, so its map is free everywhere (the people's extent and
    :data:`RECORDED_MARGIN_M` around it): what a cost learnt from it can show is how people keep
    clear of each other, not of the buildings they walked past. A Jülich run's map is its
    corridor: occupied outside the walkable polygon and inside its obstacles.

    Returns:
      ``(tracks, occupancy, resolution_m, origin_xy_m)`` as :func:`read_tracks` and
      :func:`~planners.learning.ros_map.read_ros_map` give them, ids ``"<run>:<person>"``, frames the
      run's own numbers.

    Raises:
      KeyError: no shipped run of that name (naming the ones shipped).
    """
    from matplotlib.path import Path as Polygon

    from socialnav.data import recorded

    info = recorded.run_info(run)
    rows = recorded.trajectories(run)
    out = {
        f"{run}:{person}": g[["frame", "x_m", "y_m"]].to_numpy(np.float64)
        for person, g in rows.groupby("person", sort=True)
    }
    xy = rows[["x_m", "y_m"]].to_numpy()
    lo, hi = xy.min(0) - RECORDED_MARGIN_M, xy.max(0) + RECORDED_MARGIN_M
    shape = np.ceil((hi - lo) / resolution_m).astype(int)[::-1]  # (rows along y, columns along x)
    occupancy = np.zeros(shape, np.float32)
    geometry = info.get("geometry")
    if geometry is not None:
        row, col = np.mgrid[: shape[0], : shape[1]]
        centres = np.column_stack(
            [lo[0] + (col.ravel() + 0.5) * resolution_m, lo[1] + (row.ravel() + 0.5) * resolution_m]
        )
        blocked = ~Polygon(np.asarray(geometry["walkable_polygon_m"])).contains_points(centres)
        for obstacle in geometry.get("obstacles_m", []):
            blocked |= Polygon(np.asarray(obstacle)).contains_points(centres)
        occupancy = blocked.reshape(shape).astype(np.float32)
    return out, occupancy, resolution_m, (float(lo[0]), float(lo[1]))


ROBOT_AWAY_M = 1.0e4  # where the robot is while people walk alone: too far for any force
TRACK_PERIOD_S = 0.4  # one position per person this often (a 0.4 m cell at a walker's 1 m/s)


def simulated_tracks(spec, seed: int = 0, variants: int = 20, seconds: float | None = None, resolution_m: float = 0.1):
    """People's tracks in ``variants`` variants of an arena scene (a ``jaxsim.scenes.spec.SceneSpec``),
    walked by the arena's crowd model (:func:`jaxsim.scenes.people.step_people`, social force)
    with the robot far away, for ``seconds`` (the scene's timeout by default).

    Returns:
      ``(tracks, occupancy, resolution_m, origin_xy_m)`` as :func:`read_tracks` and
      :func:`~planners.learning.ros_map.read_ros_map` give them: ids ``"variant:person"``, the
      frames of variant ``k`` offset by ``k`` times the frames per variant so that people of two variants never share a
      frame (each demonstration's map shows only its own variant's people).
    """
    from socialnav.data import WAREHOUSE_DIR
    from socialnav.jaxsim import humans
    from socialnav.jaxsim.params import TIAGO_RADIUS_M
    from socialnav.jaxsim.scenario.loader import load_scenario
    from socialnav.jaxsim.scenes import people as people_lib
    from socialnav.jaxsim.scenes.variant import sample_variants
    from socialnav.jaxsim.scenes.world import build_scene_world, occupancy
    from socialnav.jaxsim.walkers import RobotDisc

    params = load_scenario(WAREHOUSE_DIR).params
    world = build_scene_world(spec.walls_m, spec.bounds_m)
    stacked = jax.tree.map(jnp.asarray, sample_variants(spec, seed, variants))
    every = max(1, round(TRACK_PERIOD_S / float(params.dt_s)))
    frames = int((spec.timeout_s if seconds is None else seconds) / (every * float(params.dt_s)))
    away = RobotDisc.of(jnp.full(2, ROBOT_AWAY_M, jnp.float32), jnp.zeros(2), TIAGO_RADIUS_M)
    constants = humans.human_params("social_force", params)

    def walk(v):
        def tick(people, step):
            people = people_lib.step_people("social_force", constants, world, v, people, away, step)
            return people, None

        def frame(people, f):
            people, _ = jax.lax.scan(tick, people, f * every + jnp.arange(every, dtype=jnp.int32))
            return people, (people.xy, people.present & ~people.done)

        start = people_lib.init_people(v)
        _, (xy, present) = jax.lax.scan(frame, start, jnp.arange(frames, dtype=jnp.int32))
        return jnp.concatenate([start.xy[None], xy]), jnp.concatenate([start.present[None], present])

    xy, present = (np.asarray(a) for a in jax.jit(jax.vmap(walk))(stacked))
    out = {}
    per_variant = frames + 1
    for k in range(variants):
        for p in range(xy.shape[2]):
            on = np.flatnonzero(present[k, :, p])
            if len(on):
                out[f"{k}:{p}"] = np.column_stack([k * per_variant + on, xy[k, on, p]]).astype(np.float64)
    unturned = None if spec.turned_from is None else (spec.turned_from.walls_m, spec.turned_from.bounds_m)
    occ, origin = occupancy(spec.walls_m, spec.bounds_m, resolution_m, unturned)
    return out, occ, resolution_m, origin
