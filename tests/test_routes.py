"""Walkers round the walls: the corners of the shortest way a body fits through (jaxsim.scenes.routes),
walked by the scene's people (jaxsim.scenes.people), a walker with no way refused with the scene's
file and field, and every shipped scene's people left walking in the open as before."""

import json
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from socialnav.data import DATA_DIR
from socialnav.jaxsim import geometry
from socialnav.jaxsim.scenario.errors import ScenarioError
from socialnav.jaxsim.scenes import routes
from socialnav.jaxsim.scenes.people import ARRIVED_M
from socialnav.jaxsim.scenes.reachable import people_problem
from socialnav.jaxsim.scenes.spec import load_scene, mirror, turn, turn_bounds_m, turn_points
from socialnav.jaxsim.scenes.variant import sample_variant, sample_variants

BOUNDS = (-5.0, 5.0, -5.0, 5.0)
# A wall across the room at y = 0 with a 1 m door at x in [2, 3]: from (-3, 3) to (-3, -3) the
# straight line crosses the wall, the way goes through the door.
DOOR_WALLS = np.array([[-5.0, 2.0, -0.1, 0.1], [3.0, 5.0, -0.1, 0.1]])


def _legs(start, corners, end):
    return np.vstack([start, corners, end])


def _clearance_along(points, walls, step_m=0.01):
    """The least distance to a wall box along the polyline ``points``."""
    least = np.inf
    for a, b in zip(points[:-1], points[1:], strict=True):
        t = np.linspace(0, 1, max(2, int(np.linalg.norm(b - a) / step_m)))
        xy = a + t[:, None] * (b - a)
        least = min(least, float(geometry.box_signed_distance(xy[:, 0], xy[:, 1], walls)[0].min()))
    return least


def test_the_way_through_a_door_turns_at_its_post_and_keeps_the_body_off_the_walls():
    start, end = np.array([-3.0, 3.0]), np.array([-3.0, -3.0])
    corners = routes.waypoints(start, end, DOOR_WALLS, BOUNDS)
    assert 1 <= len(corners) <= 3 and corners.dtype == np.float32
    path = _legs(start, corners, end)
    length = float(np.sum(np.linalg.norm(np.diff(path, axis=0), axis=-1)))
    # Round the door's post (2, 0) at a body's clearance: longer than the line hugging the post,
    # shorter than the way through the door's middle.
    hugging = 2 * math.hypot(2.0 + 3.0, 3.0)
    through_middle = 2 * math.hypot(2.5 + 3.0, 3.0)
    assert hugging < length < through_middle
    assert all(2.0 < x < 3.0 for x, y in corners if abs(y) <= 0.1)  # any corner in the wall's band is in the door
    # The taut legs may cut ROUTE_MARGIN_M inside the free cells' clearance, never into the body.
    assert _clearance_along(path, DOOR_WALLS) >= routes.ROUTE_MARGIN_M
    # The way back is the same way.
    back = routes.waypoints(end, start, DOOR_WALLS, BOUNDS)
    back_length = float(np.sum(np.linalg.norm(np.diff(_legs(end, back, start), axis=0), axis=-1)))
    assert back_length == pytest.approx(length, abs=0.1)


def test_a_line_in_the_open_has_no_corners_and_a_closed_wall_or_a_maze_has_no_way():
    assert len(routes.waypoints([-3.0, 3.0], [4.0, 3.0], DOOR_WALLS, BOUNDS)) == 0
    closed = np.array([[-5.0, 5.0, -0.1, 0.1]])
    with pytest.raises(routes.NoRoute, match="no way from \\(-3, 3\\) to \\(-3, -3\\)"):
        routes.waypoints([-3.0, 3.0], [-3.0, -3.0], closed, BOUNDS)
    narrow = np.array([[-5.0, 2.0, -0.1, 0.1], [2.4, 5.0, -0.1, 0.1]])  # a 0.4 m door: no body fits
    with pytest.raises(routes.NoRoute):
        routes.waypoints([-3.0, 3.0], [-3.0, -3.0], narrow, BOUNDS)
    # A zigzag of ten walls, each open at the other end: more corners than a variant holds.
    zigzag = [[-5.0, 4.0, y - 0.05, y + 0.05] if k % 2 else [-4.0, 5.0, y - 0.05, y + 0.05]
              for k, y in enumerate(np.linspace(-4.5, 4.5, 10))]  # fmt: skip
    with pytest.raises(routes.NoRoute, match=f"more than {routes.MAX_WAYPOINTS}"):
        routes.waypoints([0.0, -4.9], [0.0, 4.9], np.array(zigzag), BOUNDS)


def _people_problem(spec):
    return people_problem(spec.people, spec.bounds_m, spec.walls_m)


def _door_scene(tmp_path, door=(2.0, 3.0), walls=None):
    """The door room with a walker through the door, one going back and forth through it and a
    stream of two, and the robot's start and goal on the walker's side (the robot stands aside in
    the people-only run)."""
    obj = {
        "name": "door_room",
        "bounds_m": list(BOUNDS),
        "walls": [[-5, door[0], -0.1, 0.1], [door[1], 5, -0.1, 0.1]] if walls is None else walls,
        "robot": {"start": [-4, 4], "yaw_deg": 0, "goal": [4, 4]},
        "timeout_s": 60,
        "people": [
            {"behaviour": "walk", "from": [-3, 3], "to": [-3, -3], "speed_mps": 1.0},
            {"behaviour": "walk", "from": [0, 3.5], "to": [0, -3.5], "speed_mps": 1.2, "back_and_forth": True},
            {
                "behaviour": "stream",
                "from": [4, 3],
                "to": [-4, -3],
                "count": 2,
                "start_s": 1,
                "interval_s": 3,
                "speed_mps": 1.0,
            },
        ],
        "rule": {"type": "min_distance", "distance_m": 0.5},
    }
    path = tmp_path / "door_room.json"
    path.write_text(json.dumps(obj))
    return path


def test_people_walk_through_the_door_and_back_where_without_their_corners_the_wall_holds_them(tmp_path):
    from socialnav.evaluation.arena import episodes as arena

    spec = load_scene(_door_scene(tmp_path))
    setup = arena.setup_scene(spec)
    assert routes.may_route(spec.people, spec.walls_m) and setup.env.routed  # the corners' bookkeeping is compiled in
    routed = sample_variants(spec, 0, 1, n_slots=setup.n_slots)
    assert routed.n_waypoints[0, :4].tolist() and (routed.n_waypoints[0, :4] > 0).all()
    straight = routed.replace(n_waypoints=np.zeros_like(routed.n_waypoints))  # the people as they walked before
    people_only = arena.counterfactual_function(setup)
    both = jax.tree_util.tree_map(lambda a, b: jnp.concatenate([a, b]), routed, straight)
    trajectory = people_only(jax.tree_util.tree_map(jnp.asarray, both))
    xy, present = np.asarray(trajectory.people_xy_m), np.asarray(trajectory.people_present)
    dt_s = 0.1
    # Routed: the walker reaches its end and stays; the stream's members reach theirs and leave.
    end = spec.people[0]["end"]
    assert np.linalg.norm(xy[0, -1, 0] - [end[0][0], end[1][0]]) < ARRIVED_M
    assert not present[0, -1, 2:4].any() and (xy[0, :, 2:4, 1] < -2.5).any(axis=0).all()
    # The back-and-forth walker crosses the wall's line both ways, each time through the door.
    y, x = xy[0, :, 1, 1], xy[0, :, 1, 0]
    crossings = np.flatnonzero(np.sign(y[1:]) != np.sign(y[:-1]))
    assert len(crossings) >= 2 and (np.diff(np.sign(y[crossings + 1])) != 0).any()
    assert ((x[crossings] > 2.0) & (x[crossings] < 3.0)).all()
    # No body inside a wall at any step.
    walls = np.asarray(spec.walls_m)
    moving = present[0] & np.isfinite(xy[0, ..., 0])
    sd = geometry.box_signed_distance(xy[0, ..., 0][moving], xy[0, ..., 1][moving], walls)[0]
    assert sd.min() > 0.0
    # Straight (no corners): the walkers stay on their side of the wall for the whole minute.
    assert (xy[1, :, :2, 1] > 0.0).all() and int(60 / dt_s) == xy.shape[1]


def test_a_walker_with_no_way_is_refused_naming_its_field_and_shipped_people_walk_in_the_open(tmp_path):
    spec = load_scene(_door_scene(tmp_path, door=(2.0, 2.4)))  # a 0.4 m door
    assert _people_problem(spec)[0] == "people[0].to"
    with pytest.raises(ScenarioError, match=r"people\[0\]\.to"):
        sample_variant(spec, 0, 0)
    from socialnav.evaluation.arena import episodes as arena

    with pytest.raises(ScenarioError, match=r"door_room\.json.*people\[0\]\.to.*no way from \(-3, 3\) to \(-3, -3\)"):
        arena.setup_scene(spec)
    # A way of more corners than a variant holds is refused when the scene is read too.
    zigzag = [[-5, 4, y - 0.05, y + 0.05] if k % 2 else [-4, 5, y - 0.05, y + 0.05]
              for k, y in enumerate(np.linspace(-2.5, 2.5, 10).tolist())]  # fmt: skip
    problem = _people_problem(load_scene(_door_scene(tmp_path, walls=zigzag)))
    assert problem[0] == "people[0].to" and f"more than {routes.MAX_WAYPOINTS}" in problem[1]
    # Every shipped scene: its walkers' straight lines cross no wall, in its variants, held out
    # and turned, so their people walk as they did before there were routes.
    for file in sorted((DATA_DIR / "scenes").rglob("*.json")):
        shipped = load_scene(file)
        assert _people_problem(shipped) is None, file.name
        for each in (shipped, turn(shipped)):
            assert not sample_variants(each, 0, 10).n_waypoints.any(), file.name
        assert not sample_variants(mirror(shipped), 0, 10, held_out=True).n_waypoints.any(), file.name


def test_a_turned_scene_turns_its_walkers_corners_with_it(tmp_path):
    spec = load_scene(_door_scene(tmp_path))
    drawn, turned = sample_variant(spec, 0, 3), sample_variant(turn(spec), 0, 3)
    n = drawn.n_waypoints
    assert (turned.n_waypoints == n).all() and n[0] > 0
    expected = turn_points(drawn.waypoints_xy[0, : n[0]], turn_bounds_m(spec.bounds_m))
    np.testing.assert_allclose(turned.waypoints_xy[0, : n[0]], expected, atol=1e-6)
    first = drawn.waypoints_xy[0, 0] - drawn.start_xy[0]
    assert drawn.heading0[0] == pytest.approx(math.atan2(first[1], first[0]), abs=1e-6)  # faces its first corner


def _queue_scene(tmp_path, door=(2.0, 3.0)):
    """A queue of four at a counter below the wall of :data:`DOOR_WALLS`, its exit above it: served
    at the head (-3, -2), a person leaves through the door for (-3, 3)."""
    obj = {
        "name": "queue_room",
        "bounds_m": list(BOUNDS),
        "walls": [[-5, door[0], -0.1, 0.1], [door[1], 5, -0.1, 0.1]],
        "robot": {"start": [4, -4], "yaw_deg": 180, "goal": [0, -4]},
        "timeout_s": 60,
        "people": [
            {
                "behaviour": "queue",
                "head": [-3, -2],
                "towards_deg": 180,
                "length": 4,
                "spacing_m": 0.7,
                "advance_every_s": 5,
                "exit": [-3, 3],
            },
        ],  # fmt: skip
        "rule": {"type": "min_distance", "distance_m": 0.5},
    }
    path = tmp_path / "queue_room.json"
    path.write_text(json.dumps(obj))
    return path


def test_a_queues_served_people_leave_for_an_exit_round_the_walls_where_straight_they_stay(tmp_path):
    """Served at the head, a queue member walks to the exit by the corners of its way round the
    wall (the way is the queue's own: ``people[0].exit`` named where there is none)."""
    from socialnav.evaluation.arena import episodes as arena

    spec = load_scene(_queue_scene(tmp_path))
    setup = arena.setup_scene(spec)
    assert routes.may_route(spec.people, spec.walls_m) and setup.env.routed
    routed = sample_variants(spec, 0, 1, n_slots=setup.n_slots)
    assert (routed.n_waypoints[0, :4] > 0).all()  # each member has the head's way to the exit
    straight = routed.replace(n_waypoints=np.zeros_like(routed.n_waypoints))  # as they walked before
    both = jax.tree_util.tree_map(lambda a, b: jnp.concatenate([a, b]), routed, straight)
    trajectory = arena.counterfactual_function(setup)(jax.tree_util.tree_map(jnp.asarray, both))
    xy, present = np.asarray(trajectory.people_xy_m), np.asarray(trajectory.people_present)
    # Routed: all four served (every 5 s) and gone through the door by the end of the minute.
    assert present[0, 0, :4].all() and not present[0, -1, :4].any()
    crossed = np.sign(xy[0, 1:, :4, 1]) != np.sign(xy[0, :-1, :4, 1])
    assert all(((xy[0, 1:, p, 0][crossed[:, p]] > 2.0) & (xy[0, 1:, p, 0][crossed[:, p]] < 3.0)).all()
               for p in range(4))  # fmt: skip
    # Straight: the served stand against the wall's underside for the rest of the minute.
    assert present[1, -1, :4].all() and (xy[1, -1, :4, 1] < 0.0).all()
    closed = load_scene(_queue_scene(tmp_path, door=(2.0, 2.4)))  # a 0.4 m door
    assert _people_problem(closed)[0] == "people[0].exit"
    with pytest.raises(
        ScenarioError, match=r"queue_room\.json.*people\[0\]\.exit.*no way from \(-3, -2\) to \(-3, 3\)"
    ):
        arena.setup_scene(closed)
