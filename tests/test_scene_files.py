"""Scene files and their variants: every shipped scene loads and draws, draws are seeded, a bad file
is refused in one line naming file and field, held-out draws leave the ranges, the mirror keeps
the rule."""

import dataclasses
import json

import jax.numpy as jnp
import numpy as np
import pytest

from socialnav.data import DATA_DIR
from socialnav.evaluation.arena import nav_metrics
from socialnav.jaxsim.scenario.errors import ScenarioError
from socialnav.jaxsim.scenes.spec import load_scene
from socialnav.jaxsim.scenes.variant import sample_variant, sample_variants

SCENES = sorted((DATA_DIR / "scenes").glob("*.json"))


def test_every_scene_loads_and_draws_variants():
    assert len(SCENES) == 14
    for file in SCENES:
        spec = load_scene(file)
        v = sample_variants(spec, 0, 3)
        assert v.valid.shape == (3, spec.n_people_slots)
        assert np.all(v.valid.sum(axis=1) >= 1)
        xmin, xmax, ymin, ymax = spec.bounds_m
        assert np.all((v.robot_xy[:, 0] > xmin) & (v.robot_xy[:, 0] < xmax))


def test_variants_are_seeded_and_do_not_depend_on_how_many_are_drawn():
    spec = load_scene(DATA_DIR / "scenes" / "gscl_group.json")
    a = sample_variants(spec, 7, 5)
    b = sample_variant(spec, 7, 3)
    np.testing.assert_array_equal(a.xy0[3], b.xy0)
    assert not np.array_equal(a.xy0[0], a.xy0[1])
    assert not np.array_equal(sample_variant(spec, 8, 3).xy0, b.xy0)


def _mutated(tmp_path, mutate):
    obj = json.loads((DATA_DIR / "scenes" / "gscl_group.json").read_text())
    mutate(obj)
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(obj))
    return path


@pytest.mark.parametrize(
    "mutate, field",
    [
        (lambda o: o.pop("timeout_s"), "timeout_s"),
        (lambda o: o.update(timeout_s="long"), "timeout_s"),
        (lambda o: o["people"][0].update(behaviour="dancing"), "people[0].behaviour"),
        (lambda o: o["people"][0].update(size=[5, 3]), "people[0].size"),
        (lambda o: o["people"][0].update(size=9), "people[0].size"),
        (lambda o: o["people"][1].update(speed_mps=-1), "people[1].speed_mps"),
        (lambda o: o["people"][1].update(to=[100, 0]), "people[1].to"),
        (lambda o: o["robot"].update(goal=[1]), "robot.goal"),
        (lambda o: o.update(walls=[[0, -1, 0, 1]]), "walls[0]"),
        (lambda o: o.update(rule={"type": "avoid_group", "group": 3}), "rule.group"),
        (lambda o: o.update(rule={"type": "teleport"}), "rule.type"),
        (lambda o: o.update(held_out_rule={"type": "all", "rules": []}), "held_out_rule.rules"),
        (lambda o: o.update(rule={"type": "queue", "head": [1], "direction_deg": 0, "length_m": 3}), "rule.head"),
        (lambda o: o.update(rule={"type": "queue", "head": [1, 0], "direction_deg": 0}), "rule.length_m"),
        (
            lambda o: o.update(
                rule={"type": "queue", "head": [1, 0], "direction_deg": 0, "length_m": 3, "half_width_m": 0}
            ),
            "rule.half_width_m",
        ),
        (lambda o: o["people"][1].update(walks_with=1), "people[1].walks_with"),  # itself
        (lambda o: o["people"][1].update(walks_with=0), "people[1].walks_with"),  # a standing group
        (lambda o: o["people"][1].update(walks_with="the others"), "people[1].walks_with"),
        (lambda o: o.update(stop_and_go_m=0), "stop_and_go_m"),
        (lambda o: o.update(people_in_global_plan="no"), "people_in_global_plan"),
        (lambda o: o.update(objects=[{"polygon": [[0, 0], [1, 1], [1, 0]], "cost": 10}]), "objects[0].polygon"),
        (lambda o: o.update(bounds_m=[0, 100, 0, 100]), "bounds_m"),
        (
            lambda o: o.update(walls=o["walls"] + [[o["robot"]["goal"][0] - 0.1, o["robot"]["goal"][0] + 0.1, -9, 9]]),
            "robot.goal",
        ),
    ],
)
def test_a_bad_scene_file_gives_one_error_naming_file_and_field(tmp_path, mutate, field):
    path = _mutated(tmp_path, mutate)
    with pytest.raises(ScenarioError) as e:
        load_scene(path)
    assert e.value.field == field and str(path) in str(e.value)


@pytest.mark.parametrize(
    "mutate, field, hint",
    [
        (lambda o: o["people"][1].update(back_and_fourth=True), "people[1].back_and_fourth", "back_and_forth"),
        (lambda o: o["people"][0].update(walks_with=1), "people[0].walks_with", None),  # a group's, not a walker's
        (lambda o: o["robot"].update(yaw=90), "robot.yaw", "yaw_deg"),
        (lambda o: o["rule"].update(distance_m=1.2), "rule.distance_m", None),  # not an avoid_group rule's
        (lambda o: o.update(stop_and_go=0.9), "stop_and_go", "stop_and_go_m"),
        (lambda o: o.update(recording=None, held_out=None), "held_out", None),
    ],
)
def test_a_field_nothing_reads_is_refused_not_dropped_for_its_default(tmp_path, mutate, field, hint):
    """A misspelt optional field, or one that means nothing where it stands, would otherwise run
    the scene with the default in its place and say nothing."""
    path = _mutated(tmp_path, mutate)
    with pytest.raises(ScenarioError, match="unknown field") as e:
        load_scene(path)
    assert e.value.field == field and str(path) in str(e.value)
    assert (f"did you mean {hint!r}" in str(e.value)) == (hint is not None)


@pytest.mark.parametrize("key", ["timeout_s", "speed_mps"])  # the file's top level; its walker
def test_a_key_given_twice_is_refused_not_the_last_one_kept(tmp_path, key):
    """``json.loads`` would keep the second value and drop the first without a word."""
    text = (DATA_DIR / "scenes" / "gscl_group.json").read_text()
    first = text.index(f'"{key}"')
    path = tmp_path / "scene.json"
    path.write_text(text[:first] + f'"{key}": 1.0,\n' + text[first:])
    with pytest.raises(ScenarioError, match="given twice") as e:
        load_scene(path)
    assert e.value.field == key and str(path) in str(e.value)


def test_a_note_in_an_underscore_field_is_not_read(tmp_path):
    def annotate(o):
        o["_comment"] = "the lab scene of seed 002"
        o["people"][1]["_why"] = "a walker passing the group"

    annotated = load_scene(_mutated(tmp_path, annotate))
    plain = load_scene(DATA_DIR / "scenes" / "gscl_group.json")
    assert annotated.people == plain.people and annotated.rule == plain.rule
    np.testing.assert_array_equal(sample_variant(annotated, 0, 3).xy0, sample_variant(plain, 0, 3).xy0)


def test_a_person_standing_on_the_robots_start_is_refused_with_both_radii(tmp_path):
    from socialnav.jaxsim.params import PERSON_RADIUS_M
    from socialnav.jaxsim.scenes.robot import RobotParams

    def on_the_robot(o):
        o["people"] = [{"behaviour": "standing", "position": o["robot"]["start"], "heading_deg": [0, 0]}]
        o["rule"] = {"type": "min_distance", "distance_m": 0.45}

    with pytest.raises(ScenarioError) as e:
        load_scene(_mutated(tmp_path, on_the_robot))
    assert e.value.field == "people[0].position"
    assert f"radii {PERSON_RADIUS_M} m and {RobotParams().radius_m} m" in str(e.value)


@pytest.mark.parametrize("gap_m, refused", [(0.50, True), (0.55, False)])
def test_the_placement_check_uses_the_body_the_arena_measures_contacts_with(tmp_path, gap_m, refused):
    """The env's person (0.25 m) and the robot (0.275 m) touch below 0.525 m: a person standing
    0.5 m from the robot's start is refused (the warehouse workers' 0.2 m let it through)."""

    def beside(o):
        x, (y0, y1) = o["robot"]["start"]
        o["people"] = [{"behaviour": "standing", "position": [x + gap_m, [y1, y1]], "heading_deg": [0, 0]}]
        o["robot"]["start"] = [x, [y1, y1]]
        o["rule"] = {"type": "min_distance", "distance_m": 0.45}

    path = _mutated(tmp_path, beside)
    if refused:
        with pytest.raises(ScenarioError, match="would stand on the robot"):
            load_scene(path)
    else:
        assert load_scene(path).people[0]["behaviour"] == "standing"


def _standing(xy):
    return {"behaviour": "standing", "position": [[v, v] for v in xy], "heading_deg": [0, 0]}


def _small_group(centre):
    return {"behaviour": "group", "centre": list(centre), "size": 3, "radius_m": 0.5, "facing": "in", "rotation_deg": 0}


def _queue_person(obj):
    (queue,) = [p for p in obj["people"] if p["behaviour"] == "queue"]
    return queue


@pytest.mark.parametrize(
    "mutate, field, words",
    [  # the queue's line, placed from its head back against towards_deg: every place checked
        (lambda o: _queue_person(o).update(length=20, spacing_m=3.0), "people[0].length", "the line's place 3"),
        (lambda o: _queue_person(o).update(towards_deg=180), "people[0].length", "walls["),
        (lambda o: _queue_person(o).update(towards_deg=[-10, 100]), "people[0].length", "towards_deg"),
        # someone placed on the line, or the robot's start on it: two in one place (a place 1.2-2.0 m)
        (lambda o: o["people"].append(_standing((1.6, 0.0))), "people[1].position", "of people[0]: two people"),
        (lambda o: o["robot"].update(start=[1.6, 0.0]), "people[0].length", "would stand on the robot"),
        # a thin wall across the line: the people waiting step straight up through it
        (lambda o: o["walls"].append([2.65, 2.7, -1.0, 1.0]), "people[0].length", "walls[5] stands between"),
        # the rules' geometry: a queue rule's head outside the scene or inside a wall is never broken
        (lambda o: o["rule"]["rules"][0].update(head=[300, 0]), "rule.rules[0].head", "outside bounds_m"),
        (lambda o: o["rule"]["rules"][0].update(head=[5.0, 0.0]), "rule.rules[0].head", "inside walls[4]"),
        (lambda o: o.update(rule={"type": "visit", "box": [50, 60, 0, 1]}), "rule.box", "wholly outside"),
        (lambda o: o.update(rule={"type": "avoid_circle", "centre": [0, 40], "radius_m": 1}), "rule.centre", "outside"),
        (
            lambda o: o.update(
                rule={"type": "all", "rules": [{"type": "keep_right", "box": [7, 9, 0, 1], "direction_deg": 0}]}
            ),
            "rule.rules[0].box",
            "wholly outside",
        ),
    ],
)
def test_a_queue_line_or_rule_outside_the_scene_is_refused(tmp_path, mutate, field, words):
    obj = json.loads((DATA_DIR / "scenes" / "gscl_queue.json").read_text())
    mutate(obj)
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(obj))
    with pytest.raises(ScenarioError) as e:
        load_scene(path)
    assert e.value.field == field and words in str(e.value), str(e.value)


def test_a_group_whose_circle_reaches_a_wall_or_out_of_the_scene_is_refused(tmp_path):
    path = _mutated(tmp_path, lambda o: o["people"][0].update(radius_m=5.0))
    with pytest.raises(ScenarioError, match="a member at .* lies (inside walls|outside bounds_m)") as e:
        load_scene(path)
    assert e.value.field == "people[0].radius_m"


@pytest.mark.parametrize(
    "size, radius_m, refused",
    [
        ([6, 6], [0.3, 0.3], True),  # neighbours 0.30 m apart: refused, naming the radius needed (0.50 m)
        ([6, 6], [0.5, 0.5], False),  # exactly two bodies apart
        ([3, 5], [0.5, 0.9], True),  # five at the held-out draw's 0.3 m: 0.35 m apart
        ([3, 5], [0.8, 0.9], False),  # five at 0.75 m: 0.88 m apart
    ],
)
def test_a_group_whose_members_would_stand_inside_each_other_is_refused(tmp_path, size, radius_m, refused):
    """Neighbours on a group's circle at least two bodies apart at its largest size and smallest
    radius (held-out draws included), as two people placed at the start are: the members stand
    where they are put."""
    path = _mutated(tmp_path, lambda o: o["people"][0].update(size=size, radius_m=radius_m))
    if not refused:
        assert load_scene(path).people[0]["radius_m"] == tuple(radius_m)
        return
    with pytest.raises(ScenarioError, match=r"stand 0\.\d\d m apart, closer than two bodies") as e:
        load_scene(path)
    assert e.value.field == "people[0].radius_m"
    if size == [6, 6]:
        assert "at least 0.50 m" in str(e.value)


@pytest.mark.parametrize(
    "added, field, words",
    [  # gscl_group's group: centre (1-2, -0.3-0.3), radius 1.0-1.5 (0.75-1.75 held out)
        (_standing((2.75, 0.0)), "people[2].position", "of the circle of people[0]"),  # on the circle
        # inside the circle but 0.58 m from a centre it can be drawn at, a member 0.75 m out: 0.17 m apart
        (_standing((1.5, 0.0)), "people[2].position", "a member could stand where this person does"),
        (_standing((4.5, 0.0)), None, None),  # 0.75 m past the widest circle
        (_small_group((1.5, 0.0)), "people[2].centre", "the circle of people[2] can pass within 0.5 m"),
        (_small_group((4.5, -2.8)), None, None),  # 3.5 m from the first's nearest centre
    ],
)
def test_a_person_or_a_group_where_a_groups_member_could_stand_is_refused(tmp_path, added, field, words):
    """A group's members stand anywhere on its circle (the rotation and size drawn), so a person
    placed at the start, or another group's circle, within two bodies of that circle is two
    people in one place."""
    path = _mutated(tmp_path, lambda o: o["people"].append(added))
    if field is None:
        assert len(load_scene(path).people) == 3
        return
    with pytest.raises(ScenarioError) as e:
        load_scene(path)
    assert e.value.field == field and words in str(e.value), str(e.value)


@pytest.mark.parametrize("pillar, refused", [([0.3, 0.7, -0.2, 0.2], True), ([2.0, 2.4, -0.2, 0.2], False)])
def test_pass_behind_a_walker_whose_line_crosses_a_wall_is_refused(tmp_path, pillar, refused):
    """seed 001's crossing (the walker from x 0-1 at y 2.7 to x 0-1 at y -2.7) with a pillar: on
    the walker's line the walker is routed round it and pass_behind would judge the robot against
    a line nobody walks; beside it the scene reads as before."""
    obj = json.loads((DATA_DIR / "scenes" / "casn_crossing.json").read_text())
    obj["walls"].append(pillar)
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(obj))
    if not refused:
        assert load_scene(path).rule == {"type": "pass_behind", "person": 0}
        return
    with pytest.raises(ScenarioError, match="person 0's straight line from .* crosses a wall") as e:
        load_scene(path)
    assert e.value.field == "rule.person"


def test_every_generated_queue_place_lies_inside_the_scene_and_clear_of_walls():
    """The check's promise, measured on the generator: every queue place of 200 variants of the
    shipped queue, evaluation and held-out draws alike, lies inside the bounds and no wall."""
    spec = load_scene(DATA_DIR / "scenes" / "gscl_queue.json")
    xmin, xmax, ymin, ymax = spec.bounds_m
    for held_out in (False, True):
        v = sample_variants(spec, 0, 200, 0, held_out)
        xy = v.xy0[v.valid & (v.kind == 2)]
        assert len(xy) > 200
        assert np.all((xy[:, 0] >= xmin) & (xy[:, 0] <= xmax) & (xy[:, 1] >= ymin) & (xy[:, 1] <= ymax))
        for wx0, wx1, wy0, wy1 in spec.walls_m:
            assert not np.any((xy[:, 0] > wx0) & (xy[:, 0] < wx1) & (xy[:, 1] > wy0) & (xy[:, 1] < wy1))


def test_not_json_and_missing_file(tmp_path):
    (tmp_path / "bad.json").write_text("{oops")
    with pytest.raises(ScenarioError, match="invalid JSON"):
        load_scene(tmp_path / "bad.json")
    with pytest.raises(ScenarioError, match="missing"):
        load_scene(tmp_path / "none.json")


def test_held_out_variants_leave_the_ranges_and_the_mirror_keeps_the_rule():
    from socialnav.jaxsim.scenes.spec import mirror

    spec = load_scene(DATA_DIR / "scenes" / "casn_head_on.json")
    inside = sample_variants(spec, 0, 40)
    outside = sample_variants(spec, 0, 40, held_out=True)
    assert np.all((inside.speed_mps[:, 0] >= 0.4) & (inside.speed_mps[:, 0] <= 1.35))
    assert np.all((outside.speed_mps[:, 0] < 0.4) | (outside.speed_mps[:, 0] > 1.35))
    assert np.all(outside.speed_mps[:, 0] >= 0.05)
    hall = load_scene(DATA_DIR / "scenes" / "gscl_l_hallway.json")
    flipped = mirror(hall)
    c = hall.bounds_m[2] + hall.bounds_m[3]
    np.testing.assert_allclose(flipped.walls_m[:, 2], c - hall.walls_m[:, 3])
    assert mirror(flipped).rule["rules"][0]["direction_deg"] == hall.rule["rules"][0]["direction_deg"]
    # A path keeping right in the original keeps right in the mirror image of the hallway.
    x = np.linspace(-5.5, -0.5, 30)
    right = jnp.asarray(np.stack([x, -0.5 + 0 * x], 1), jnp.float32)
    mirrored_path = right.at[:, 1].set(c - right[:, 1])
    rule = hall.rule["rules"][0]
    none = jnp.zeros((30, 1, 2)), jnp.zeros((1, 2)), jnp.zeros((1, 2)), jnp.zeros((30, 1), bool), jnp.full(1, -1)
    assert bool(nav_metrics.rule_satisfied(rule, right, jnp.zeros(30, bool), *none))
    assert not bool(nav_metrics.rule_satisfied(flipped.rule["rules"][0], mirrored_path, jnp.zeros(30, bool), *none))


def test_the_l_hallways_held_out_rule_is_one_a_right_turn_can_keep():
    """The mirrored L-hallway turns right: its rule is the file's held_out_rule (keep right in both
    legs, no wide corner), mirrored; a walk keeping right round the right turn, 0.35 m off the inner
    walls, obeys it, where the left turn's rule mirrored refused it (the wide corner lies across the
    lane one keeps to). Mirroring twice gives the file's rules back."""
    from socialnav.jaxsim.scenes.spec import mirror

    hall = load_scene(DATA_DIR / "scenes" / "gscl_l_hallway.json")
    assert [r["type"] for r in hall.held_out_rule["rules"]] == ["keep_right", "keep_right", "min_distance"]
    flipped = mirror(hall)
    c = hall.bounds_m[2] + hall.bounds_m[3]
    assert [r["type"] for r in flipped.rule["rules"]] == ["keep_right", "keep_right", "min_distance"]
    box = np.asarray(hall.held_out_rule["rules"][1]["box"])
    np.testing.assert_allclose(flipped.rule["rules"][1]["box"], [box[0], box[1], c - box[3], c - box[2]])
    twice = mirror(flipped)
    assert [r["type"] for r in twice.rule["rules"]] == [r["type"] for r in hall.rule["rules"]]
    np.testing.assert_allclose(twice.rule["rules"][2]["centre"], hall.rule["rules"][2]["centre"])
    np.testing.assert_allclose(twice.held_out_rule["rules"][1]["box"], box)

    # The mirrored hallway: along +x at y in [c - 1, c + 1], then down x in [0, 2]; the inner corner at (0, c - 1).
    inner_y = c - 1.0
    first = np.stack([np.linspace(-5.5, 0.35, 40), np.full(40, inner_y + 0.35)], 1)
    second = np.stack([np.full(40, 0.35), np.linspace(inner_y + 0.35, -0.8, 40)], 1)
    walk = jnp.asarray(np.concatenate([first, second]), jnp.float32)
    t = walk.shape[0]
    none = jnp.zeros((t, 1, 2)), jnp.zeros((1, 2)), jnp.zeros((1, 2)), jnp.zeros((t, 1), bool), jnp.full(1, -1)
    assert bool(nav_metrics.rule_satisfied(flipped.rule, walk, jnp.zeros(t, bool), *none))
    left_turn_rule_mirrored = mirror(dataclasses.replace(hall, held_out_rule=None)).rule
    assert not bool(nav_metrics.rule_satisfied(left_turn_rule_mirrored, walk, jnp.zeros(t, bool), *none))


def _turned_back(xy, bounds_m):
    """Points turned a quarter turn clockwise about ``bounds_m``'s centre: the inverse of the turn."""
    cx, cy = (bounds_m[0] + bounds_m[1]) / 2, (bounds_m[2] + bounds_m[3]) / 2
    xy = np.asarray(xy, np.float64)
    return np.stack([cx + (xy[..., 1] - cy), cy - (xy[..., 0] - cx)], axis=-1)


@pytest.mark.parametrize("file", SCENES, ids=[f.stem for f in SCENES])
def test_a_turned_scene_is_the_scene_a_quarter_turn_on(file):
    """``turn``: the walls' signed distance at a point is the turned walls' at the turned point;
    the turned planner grid, rasterised at the turned scene's own cells, holds a wall wherever the
    turned walls put one (every cell not on a tie, a face exactly half a cell off its centre); the
    turned scene's variant k is variant k turned (positions, headings; start-goal distance kept)."""
    from socialnav.jaxsim import geometry
    from socialnav.jaxsim.scenes import world as world_lib
    from socialnav.jaxsim.scenes.spec import turn, turn_bounds_m, turn_points

    spec = load_scene(file)
    turned = turn(spec)
    about = turn_bounds_m(spec.bounds_m)
    (x0, x1, y0, y1), (u0, u1, w0, w1) = about, turned.bounds_m
    assert (u1 - u0, w1 - w0) == pytest.approx((y1 - y0, x1 - x0))

    rng = np.random.default_rng(0)
    points = np.stack([rng.uniform(x0, x1, 500), rng.uniform(y0, y1, 500)], 1)
    walls = world_lib.wall_boxes(spec.walls_m, spec.bounds_m)
    turned_walls = world_lib.wall_boxes(turned.walls_m, turned.bounds_m)
    before = geometry.box_signed_distance(points[:, 0], points[:, 1], walls)[0]
    moved = turn_points(points, about)
    after = geometry.box_signed_distance(moved[:, 0], moved[:, 1], turned_walls)[0]
    np.testing.assert_allclose(after, before, atol=1e-6)

    occ, (ox, oy) = world_lib.occupancy(turned.walls_m, turned.bounds_m, 0.2, (spec.walls_m, spec.bounds_m))
    rows, cols = np.meshgrid(np.arange(occ.shape[0]), np.arange(occ.shape[1]), indexing="ij")
    cx, cy = ox + (cols + 0.5) * 0.2, oy + (rows + 0.5) * 0.2
    sd = geometry.box_signed_distance(cx, cy, turned_walls)[0]
    inner = np.zeros(occ.shape, bool)
    inner[1:-1, 1:-1] = True  # the border cells are walls by rule
    clear = inner & (np.abs(sd - 0.1) > 1e-6)
    np.testing.assert_array_equal(occ[clear] == 1.0, sd[clear] <= 0.1)
    assert (occ[~inner] == 1.0).all()

    v, vt = sample_variants(spec, 0, 4), sample_variants(turned, 0, 4)
    for name in ("xy0", "start_xy", "end_xy", "queue_head", "exit_xy", "robot_xy", "goal_xy"):
        np.testing.assert_allclose(_turned_back(getattr(vt, name), about), getattr(v, name), atol=1e-5, err_msg=name)
    np.testing.assert_allclose(np.cos(vt.heading0), -np.sin(v.heading0), atol=1e-6)
    np.testing.assert_allclose(np.sin(vt.robot_yaw), np.cos(v.robot_yaw), atol=1e-6)
    np.testing.assert_allclose(
        np.linalg.norm(vt.goal_xy - vt.robot_xy, axis=-1), np.linalg.norm(v.goal_xy - v.robot_xy, axis=-1), rtol=1e-6
    )
    np.testing.assert_array_equal(vt.speed_mps, v.speed_mps)
    with pytest.raises(ValueError, match="already turned"):
        turn(turned)


def test_the_turned_l_hallway_keeps_its_rule():
    """The L-hallway's rules turned with it: a walk keeping right along the first leg obeys the
    turned rule turned, one keeping left breaks it, as in the file's own frame."""
    from socialnav.jaxsim.scenes.spec import mirror, turn, turn_bounds_m, turn_points

    hall = load_scene(DATA_DIR / "scenes" / "gscl_l_hallway.json")
    turned = turn(hall)
    about = turn_bounds_m(hall.bounds_m)
    x = np.linspace(-5.5, -0.5, 30)
    t = len(x)
    none = jnp.zeros((t, 1, 2)), jnp.zeros((1, 2)), jnp.zeros((1, 2)), jnp.zeros((t, 1), bool), jnp.full(1, -1)
    for y, keeps in ((-0.5, True), (0.5, False)):
        walk = np.stack([x, np.full(t, y)], 1)
        walk_xy = jnp.asarray(walk, jnp.float32)
        here = nav_metrics.rule_satisfied(hall.rule["rules"][0], walk_xy, jnp.zeros(t, bool), *none)
        there = nav_metrics.rule_satisfied(
            turned.rule["rules"][0], jnp.asarray(turn_points(walk, about), jnp.float32), jnp.zeros(t, bool), *none
        )
        assert bool(here) == bool(there) == keeps
    assert turned.rule["rules"][0]["direction_deg"] == hall.rule["rules"][0]["direction_deg"] + 90.0
    with pytest.raises(ValueError, match="not mirrored"):
        mirror(turned)


def test_the_crossings_at_other_angles_are_the_crossing_turned_about_its_crossing_point():
    """data/scenes/geometry: the crossing's walker at 60 and 120 deg to the robot's path (the
    centres of its ranges), meeting the robot's line where the original's does (x in [0, 1]), the
    rest of the scene the original's; the arena finds them by name and by 'geometry'."""
    from socialnav.cli.arena import GEOMETRY, _scene_files
    from socialnav.data import GEOMETRY_SCENES_DIR, RECORDED_SCENES_DIR, SCENES_DIR

    original = load_scene(SCENES_DIR / "casn_crossing.json")
    files = _scene_files([GEOMETRY], SCENES_DIR, RECORDED_SCENES_DIR, GEOMETRY_SCENES_DIR)
    assert [f.stem for f in files] == ["casn_crossing_120", "casn_crossing_60"]
    assert _scene_files(["casn_crossing_60"], SCENES_DIR, RECORDED_SCENES_DIR, GEOMETRY_SCENES_DIR) == [files[1]]
    for file, angle in zip(files, (120, 60), strict=True):
        spec = load_scene(file)
        walker = spec.people[0]
        start = np.array([np.mean(walker["start"][0]), np.mean(walker["start"][1])])
        end = np.array([np.mean(walker["end"][0]), np.mean(walker["end"][1])])
        step = end - start
        assert np.degrees(np.arccos(step[0] / np.linalg.norm(step))) == pytest.approx(angle, abs=0.05)
        crossing_x = start[0] + step[0] * (start[1] / (start[1] - end[1]))
        assert crossing_x == pytest.approx(0.5, abs=1e-3)  # the original's range [0, 1], its centre
        np.testing.assert_array_equal(spec.walls_m, original.walls_m)
        assert spec.rule == original.rule and spec.robot == original.robot
        v = sample_variants(spec, 0, 20)
        assert np.all(np.abs(v.xy0[:, 0, 1] - 2.7) < 1e-6) and np.all(np.abs(v.end_xy[:, 0, 1] + 2.7) < 1e-6)
