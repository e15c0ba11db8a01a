"""GSCL's held-out rule suite: does a cost model keep each family's rule on scenes no generator drew?

Seed 002's claim (Sec. 4.1, last paragraphs) is that one network "recognizes a given scenario,
or multiple scenarios when they co-occur, and generalizes the cost to similar unseen
scenarios". A low MSE on samples drawn like the training data does not show that, so this suite
builds its own scenes, outside the generator's layouts (:mod:`models.families`): any
orientation (the people's cells on lines and circles at any angle, not only the 8 directions a
heading pixel can draw), lengths, spacings, group sizes and radii at and beyond the generator's
ranges, walls near people (closer than the generator's clearances), the goal at several
distances, L hallways turning either way, and composite scenes where two rules co-occur (a group
beside a hallway, a queue near a blind corner, two groups, a queue and a group), whose expected
cost is the cell-wise max of the two rules' costs. It never calls a family's sampler and draws
from its own seed, so training never sees its scenes.

Every rule is one number, a **contrast**: the mean cost over region A of one map minus the mean
cost over region B of the same or a paired map (the same scene with one thing changed):

=================  ===================================================================================
rule               contrast (A minus B)
=================  ===================================================================================
``queue_u``        beside the queue (0.7-1.3 m from its line, along its length) with the goal at its
                   head, minus the same cells with the goal elsewhere (same people, same walls)
``group_zone``     the inner part of a group's circle (within 0.55 of its radius, 0.5 m at least) with the people
                   facing in, minus the same cells with them facing out
``keep_right``     the left part of a hallway (from a quarter of the half-width to the wall) relative
                   to the way to the goal, minus the right part (cells near walkers left out)
``corner_wide``    an L hallway's inner (blind) corner minus its outer corner: within 1 m of each,
                   inside the corridor
``blind_corner``   the free side within 1 m of a blind corner minus the free side 3-4.5 m from it
                   (beside a queue: both regions 2 m clear of its people, and a cell clear of
                   its U, which the ``queue_u`` check scores)
``pass_left``      beside a person on their right (0.6-1.4 m, 0-1.6 m ahead) minus the same on their
                   left (the passing layer: the robot passes on their left)
=================  ===================================================================================

A case **passes** when the model's contrast ``c`` is at least ``c_blind + PASS_FRACTION * (c_expected -
c_blind)``: it keeps at least half (:data:`PASS_FRACTION`) of what the rule adds. ``c_expected`` is
the contrast of the scene's expected map, ``c_blind`` that of its rule-blind map, the expected
map without the rule's own cost (a group's people facing in put some cost into the circle's
middle by their proxemics alone; a model must add the interaction zone to pass). The expected
map is built with the same cost shapes as the training targets (:mod:`models.social_costs`):
people at the cell they are drawn in, facing the drawn (8-direction) heading, because the input
shows no more; the queue's U along the line from its tail's cell to its head's
(:func:`models.social_costs.drawn_line`), as the generator draws it, and the group's zone over
its own circle, which the people's cells show at any angle. Every case's rule adds at least
:data:`MIN_EXPECTED_CONTRAST` (tested), so a model that draws nothing, or only people, fails.

:func:`build_suite` makes the cases (numpy arrays, deterministic by seed); :func:`evaluate`
scores a prediction function on them: pass share and mean contrast per (scene, rule), and the
MSE against the expected maps.
"""

from __future__ import annotations

import dataclasses
import functools

import jax
import jax.numpy as jnp
import numpy as np

from socialnav.common.intervals import wilson
from socialnav.models import grid
from socialnav.models import social_costs as sc
from socialnav.models.families import QUEUE_BODY_M, dilate

PASS_FRACTION = 0.5  # a case passes when the model's contrast is >= this share of the expected one
MIN_EXPECTED_CONTRAST = 0.1  # every case's expected contrast is at least this (checked when built)
MIN_REGION_CELLS = 3
SUITE_SEED = 20_161  # the suite's own seed: no training stream folds from it
MAX_PEOPLE = 24
MAX_WALLS = 6
LONG_M = 24.0  # a wall that crosses the whole 16 m window

RULES = ("queue_u", "group_zone", "keep_right", "corner_wide", "blind_corner", "pass_left")
SCENES = (
    "queue",
    "group",
    "hallway",
    "hallway_l",
    "corner",
    "person",
    "hallway+group",
    "queue+corner",
    "two_groups",
    "queue+group",
)


@dataclasses.dataclass(frozen=True)
class Case:
    """One rule checked on one scene (two maps: a single-map rule repeats its map).

    Attributes:
      scene / rule: names (:data:`SCENES`, :data:`RULES`).
      images: (2, 40, 40) uint8 input maps; expected: (2, 40, 40) float32 expected costs; blind:
        (2, 40, 40) the expected costs without the rule's own (what a model blind to the rule
        but right about everything else would draw).
      region_a: (40, 40) bool cells of map 0; region_b: (40, 40) bool cells of map 1.
      params: the scene's parameters (for the record and the picture's title).
    """

    scene: str
    rule: str
    images: np.ndarray
    expected: np.ndarray
    blind: np.ndarray
    region_a: np.ndarray
    region_b: np.ndarray
    params: dict


# ---------------------------------------------------------------------------------------------
# Drawing a scene: walls, people, a goal -> input map; rule costs -> expected map.


@jax.jit
def _render(segments, wall_valid, px, py, pheading, pvalid, goal, has_goal):
    image = jnp.where(grid.wall_mask(segments, wall_valid), jnp.uint8(grid.WALL), jnp.uint8(grid.FREE))
    image = grid.draw_people(image, px, py, pheading, pvalid)
    drawn = grid.draw_goal(image, goal[0], goal[1])
    return jnp.where(has_goal, drawn, image)


_people_cost = jax.jit(sc.people_cost)
# The scene builders' cost pieces, each compiled once (per queue length for the U): called
# eagerly, each is dozens of JAX dispatches a scene, most of the suite's building time. Compiled,
# their maps differ from the eager ones in the last bits (expected maps by up to 2e-6); the scenes
# drawn, their images and regions do not change.
_queue_u_cost = jax.jit(lambda x, y, heading, valid: sc.queue_u_cost(*sc.drawn_line(x, y, heading, valid)))
_disc_plateau = jax.jit(sc.disc_plateau)
_corner_cost = jax.jit(sc.corner_cost)
_left_of_path = jax.jit(sc.left_of_path)
_dilate = jax.jit(dilate, static_argnums=1)


@dataclasses.dataclass
class _Scene:
    """Mutable while a scene is built; :meth:`render` gives (image, expected)."""

    walls: list = dataclasses.field(default_factory=list)  # (x0, y0, x1, y1)
    people: list = dataclasses.field(default_factory=list)  # (x, y, heading) as drawn
    goal: tuple | None = None
    costs: list = dataclasses.field(default_factory=list)  # (rule, (40, 40) cost), combined by max

    def add_person(self, x, y, heading):
        self.people.append(grid.snap_person(x, y, heading))

    def render(self):
        """(image (40, 40) uint8, maps): ``maps[""]`` the expected costs, ``maps[rule]`` the same
        without that rule's own cost (the rule-blind map; for ``pass_left`` people without the
        passing layer and front stretch, as if standing)."""
        seg, wv = np.zeros((MAX_WALLS, 4), np.float32), np.arange(MAX_WALLS) < len(self.walls)
        if self.walls:
            seg[: len(self.walls)] = self.walls
        ppl, pv = np.zeros((MAX_PEOPLE, 3), np.float32), np.arange(MAX_PEOPLE) < len(self.people)
        if self.people:
            ppl[: len(self.people)] = self.people
        goal = np.zeros(2, np.float32) if self.goal is None else np.asarray(self.goal, np.float32)
        image = np.asarray(_render(seg, wv, ppl[:, 0], ppl[:, 1], ppl[:, 2], pv, goal, self.goal is not None))
        people = np.asarray(_people_cost(ppl[:, 0], ppl[:, 1], ppl[:, 2], pv))
        standing = np.asarray(_people_cost(ppl[:, 0], ppl[:, 1], ppl[:, 2], pv, 0.0))

        def combined(without: str | None):
            cost = standing if without == "pass_left" else people
            for tag, extra in self.costs:
                if tag != without:
                    cost = np.maximum(cost, np.asarray(extra))
            return np.where(image == grid.WALL, 0.0, cost).astype(np.float32)

        return image, {"": combined(None), **{rule: combined(rule) for rule in RULES}}


def _local(x0, y0, angle):
    """Cell centres in the frame at (x0, y0) turned by ``angle`` (x along it)."""
    dx, dy = grid.CELL_X_M - x0, grid.CELL_Y_M - y0
    c, s = np.cos(angle), np.sin(angle)
    return dx * c + dy * s, -dx * s + dy * c


def _world(x0, y0, angle, lx, ly):
    c, s = np.cos(angle), np.sin(angle)
    return x0 + lx * c - ly * s, y0 + lx * s + ly * c


def _segment_distance(px, py, seg) -> float:
    x0, y0, x1, y1 = seg
    dx, dy = x1 - x0, y1 - y0
    t = np.clip(((px - x0) * dx + (py - y0) * dy) / max(dx * dx + dy * dy, 1e-12), 0, 1)
    return float(np.hypot(x0 + t * dx - px, y0 + t * dy - py))


def _free(*images):
    """Cells free in every image."""
    return np.all([im == grid.FREE for im in images], axis=0)


def _on_grid(x, y, margin_m=0.0):
    return abs(x) < grid.HALF_M - margin_m and abs(y) < grid.HALF_M - margin_m


def _near(points, radius_m):
    """(40, 40) bool: cells within ``radius_m`` of any of the (x, y) points."""
    mask = np.zeros((grid.GRID, grid.GRID), bool)
    for x, y in points:
        mask |= np.hypot(grid.CELL_X_M - x, grid.CELL_Y_M - y) < radius_m
    return mask


# ---------------------------------------------------------------------------------------------
# Scene parts. Each returns what a rule needs to place its regions.


@dataclasses.dataclass
class _Queue:
    hx: float
    hy: float
    phi: float
    spacing: float
    n: int
    people: list
    elsewhere_goal: tuple | None = None

    @property
    def tail(self):
        return (self.n - 1) * self.spacing


def _queue(rng, length=(1.5, 13.0), gap=(0.15, 1.1), head_box=3.5) -> _Queue:
    """A queue at any angle, lengths and gaps at and beyond the generator's (first 3-10 m and
    0.3-0.8 m, then 2-12 m and 0.2-1.0 m)."""
    phi = rng.uniform(-np.pi, np.pi)
    spacing = QUEUE_BODY_M + rng.uniform(*gap)
    n = int(rng.uniform(*length) // spacing) + 1
    hx, hy = rng.uniform(-head_box, head_box, 2)
    people = [_world(hx, hy, phi, -i * spacing, rng.uniform(-0.05, 0.05)) for i in range(n)]
    return _Queue(hx, hy, phi, spacing, n, people)  # n >= 2: length >= 1.5 m >= spacing


def _draw_queue(scene: _Scene, q: _Queue, goal: str, rng):
    """People facing the head; goal ``"head"`` (0.5-1.1 m ahead, with the U) or ``"elsewhere"``
    (2.5-7 m to a side of the queue, proxemics only)."""
    for x, y in q.people:
        scene.add_person(x, y, q.phi)
    if goal == "head":
        d = rng.uniform(0.5, 1.1)
        scene.goal = _world(q.hx, q.hy, q.phi, d, 0.0)
        # The U along the line the people's cells show, as the generator draws it.
        x, y, heading = (np.asarray(v, np.float32) for v in zip(*scene.people[-q.n :], strict=True))
        scene.costs.append(("queue_u", _queue_u_cost(x, y, heading, np.ones(q.n, bool))))
    else:
        scene.goal = q.elsewhere_goal


def _queue_goal_elsewhere(q: _Queue, rng, obstacles=()):
    """A goal to a side of the queue, 2.5-7 m from its middle and >= 2.5 m from every member."""
    for _ in range(100):
        along = -rng.uniform(0, q.tail)
        lateral = rng.choice([-1, 1]) * rng.uniform(2.5, 7.0)
        gx, gy = _world(q.hx, q.hy, q.phi, along, lateral)
        far = all(np.hypot(gx - x, gy - y) >= 2.5 for x, y in q.people)
        if far and _on_grid(gx, gy, 0.4) and all(_segment_distance(gx, gy, w) > 0.8 for w in obstacles):
            return gx, gy
    return None


def _beside_queue(q: _Queue):
    lx, ly = _local(q.hx, q.hy, q.phi)
    return (lx >= -q.tail + 0.2) & (lx <= -0.2) & (np.abs(ly) >= 0.7) & (np.abs(ly) <= 1.3)


def _queue_pair(rng, walls=(), costs=(), extra_people=(), queue=None):
    """Maps 0 (goal at the head) and 1 (goal elsewhere) of one queue, and its 'beside' region."""
    q = queue or _queue(rng)
    q.elsewhere_goal = _queue_goal_elsewhere(q, rng, walls)
    if q.elsewhere_goal is None:
        return None
    maps = []
    for goal in ("head", "elsewhere"):
        s = _Scene(walls=list(walls), costs=list(costs))
        for p in extra_people:
            s.add_person(*p)
        _draw_queue(s, q, goal, rng)
        maps.append(s.render())
    images, expected = _stack(maps)
    region = _beside_queue(q) & _free(*images) & ~_near([q.elsewhere_goal], 0.8)
    return q, images, expected, region


@dataclasses.dataclass
class _Group:
    cx: float
    cy: float
    radius: float
    people: list  # (x, y, angle from the centre)


def _group(rng, n=(2, 8), radius=(0.9, 2.2), centre_box=4.0, centre=None) -> _Group:
    """2-8 people (generator: 2-6, then 2-7) on a circle of radius 0.9-2.2 m (generator: 1-1.5 m,
    then 0.8-1.8 m), any rotation, centred in a box of +-``centre_box`` m (or at ``centre``).

    Smaller circles are not drawn: below about 0.9 m the people's own cost (1 at each of them)
    covers the circle's middle, the zone adds less than :data:`MIN_EXPECTED_CONTRAST` there, and
    no model could be told apart from one blind to the rule (measured: 27 of 28 such groups)."""
    k = int(rng.integers(n[0], n[1] + 1))
    r = rng.uniform(*radius)
    cx, cy = rng.uniform(-centre_box, centre_box, 2) if centre is None else centre
    full = np.pi if k == 2 else 2 * np.pi * (k - 1) / k
    arc = rng.uniform(0.5, 1.0) * full
    start = rng.uniform(-np.pi, np.pi)
    angles = start + arc * np.arange(k) / (k - 1)
    return _Group(cx, cy, r, [(cx + r * np.cos(a), cy + r * np.sin(a), a) for a in angles])


def _draw_group(scene: _Scene, g: _Group, inward: bool):
    for x, y, a in g.people:
        scene.add_person(x, y, a + (np.pi if inward else 0.0))
    if inward:
        scene.costs.append(("group_zone", _disc_plateau(g.cx, g.cy, g.radius)))


def _group_zone_region(g: _Group, images):
    d = np.hypot(grid.CELL_X_M - g.cx, grid.CELL_Y_M - g.cy)
    return (d < max(0.55 * g.radius, 0.5)) & _free(*images)


def _group_pair(rng, walls=(), costs=(), other=None, group=None):
    """Maps 0 (facing in) and 1 (facing out) of one group; ``other(scene)`` draws the rest."""
    g = group or _group(rng)
    maps = []
    for inward in (True, False):
        s = _Scene(walls=list(walls), costs=list(costs))
        if other is not None:
            other(s)
        _draw_group(s, g, inward)
        maps.append(s.render())
    images, expected = _stack(maps)
    return g, images, expected, _group_zone_region(g, images)


def _tangent_wall(cx, cy, distance_m, angle):
    """A long wall whose nearest point to (cx, cy) is ``distance_m`` away in direction ``angle``."""
    px, py = cx + distance_m * np.cos(angle), cy + distance_m * np.sin(angle)
    tx, ty = -np.sin(angle) * LONG_M / 2, np.cos(angle) * LONG_M / 2
    return (px - tx, py - ty, px + tx, py + ty)


@dataclasses.dataclass
class _Hallway:
    phi: float  # direction of travel (towards the goal)
    half_m: float
    back_m: float
    front_m: float


def _hallway_cost(h: _Hallway, inside, left_m):
    return np.where(inside, sc.HALLWAY_LEFT_COST * np.asarray(sc.smoothstep(left_m / h.half_m)), 0.0)


def _straight_hallway(rng, half=(0.65, 2.5), goal_m=(1.5, 7.5), walkers=True):
    """A hallway through the robot, 1.3-5 m wide (generator: 1.6-4, then 1.4-4.6), goal 1.5-7.5 m ahead (3-7)."""
    h = _Hallway(rng.uniform(-np.pi, np.pi), rng.uniform(*half), rng.uniform(2.0, 14.0), rng.uniform(2.0, 14.0))
    lx, ly = _local(0.0, 0.0, h.phi)
    s = _Scene()
    for y in (-h.half_m, h.half_m):
        s.walls.append((*_world(0, 0, h.phi, -h.back_m, y), *_world(0, 0, h.phi, h.front_m, y)))
    inside = (np.abs(ly) < h.half_m) & (lx >= -h.back_m) & (lx <= h.front_m)
    s.costs.append(("keep_right", _hallway_cost(h, inside, np.maximum(ly, 0.0))))
    s.goal = _world(0, 0, h.phi, min(rng.uniform(*goal_m), h.front_m - 0.5), 0.0)
    walker_xy = []
    if walkers and rng.random() < 0.5:
        for _ in range(int(rng.integers(1, 4))):
            wx, wy = rng.uniform(-6, 6), rng.uniform(-0.6, 0.6) * h.half_m
            if -h.back_m <= wx <= h.front_m:
                x, y = _world(0, 0, h.phi, wx, wy)
                s.add_person(x, y, h.phi + (0.0 if rng.random() < 0.5 else np.pi))
                walker_xy.append((x, y))
    return h, s, inside, lx, ly, walker_xy


# ---------------------------------------------------------------------------------------------
# Scene kinds: each returns a list of cases (or None to draw again).


def _stack(rendered):
    """Two rendered maps -> images (2, 40, 40) and their expected maps {key: (2, 40, 40)}."""
    images = np.stack([image for image, _ in rendered])
    return images, {k: np.stack([maps[k] for _, maps in rendered]) for k in rendered[0][1]}


def _first(maps):
    return {k: v[0] for k, v in maps.items()}


def _case(scene, rule, images, maps, a, b, **params):
    """A case from a scene's images ((2, 40, 40), or (40, 40) for a one-map rule) and expected maps."""
    expected, blind = maps[""], maps[rule]
    if images.ndim == 2:
        images, expected, blind = (np.stack([x, x]) for x in (images, expected, blind))
    return Case(
        scene, rule, images.astype(np.uint8), expected.astype(np.float32), blind.astype(np.float32), a, b, params
    )


def _scene_queue(rng):
    walls = []
    if rng.random() < 0.5:  # a wall 0.9-1.5 m beside the queue (the generator keeps them 1.5 m away)
        q = _queue(rng, length=(1.5, 9.0))
        side = rng.choice([-1, 1])
        w = rng.uniform(0.9, 1.5)
        walls.append((*_world(q.hx, q.hy, q.phi, 4.0, side * w), *_world(q.hx, q.hy, q.phi, -q.tail - 4.0, side * w)))
    else:
        q = None
    out = _queue_pair(rng, walls, queue=q)
    if out is None:
        return None
    q, images, expected, region = out
    if walls:
        lx, ly = _local(q.hx, q.hy, q.phi)
        region &= (side * ly) < w - 0.3
    return [_case("queue", "queue_u", images, expected, region, region, length_m=q.tail, spacing_m=q.spacing)]


def _scene_group(rng):
    walls = []
    g = _group(rng)
    if rng.random() < 0.5:  # a wall 0.4-0.9 m outside the circle (the generator's groups have none)
        walls.append(_tangent_wall(g.cx, g.cy, g.radius + rng.uniform(0.4, 0.9), rng.uniform(-np.pi, np.pi)))
    g, images, expected, region = _group_pair(rng, walls, group=g)
    return [_case("group", "group_zone", images, expected, region, region, n=len(g.people), radius_m=g.radius)]


def _keep_right_regions(h: _Hallway, inside, lx, ly, images, keep_out):
    base = inside & _free(*images[:1]) & ~keep_out & (np.abs(lx) < 6.0)
    return base & (ly > 0.25 * h.half_m), base & (ly < -0.25 * h.half_m)


def _scene_hallway(rng):
    h, s, inside, lx, ly, walkers = _straight_hallway(rng)
    image, expected = s.render()
    a, b = _keep_right_regions(h, inside, lx, ly, image[None], _near(walkers + [s.goal], 1.2))
    return [_case("hallway", "keep_right", image, expected, a, b, width_m=2 * h.half_m, walkers=len(walkers))]


def _scene_hallway_l(rng):
    """An L hallway turning left or right (the generator's right turns are its left ones mirrored),
    the turn 1-6 m ahead (generator: 1.5-5), 1.3-5 m wide."""
    half = rng.uniform(0.65, 2.5)
    a = rng.uniform(max(1.0, half + 0.3), 6.0)
    phi = rng.uniform(-np.pi, np.pi)
    turn = 1.0 if rng.random() < 0.5 else -1.0
    lx, ly = _local(0.0, 0.0, phi)
    ly_m = ly * turn  # mirrored so that the turn is towards +y
    back = rng.uniform(2.0, 12.0)

    def world(x, y):
        return _world(0.0, 0.0, phi, x, y * turn)

    walls = [
        (*world(-back, -half), *world(a + half, -half)),
        (*world(a + half, -half), *world(a + half, LONG_M)),
        (*world(-back, half), *world(a - half, half)),
        (*world(a - half, half), *world(a - half, LONG_M)),
    ]
    in1 = (lx <= a + half) & (np.abs(ly_m) < half) & (lx >= -back)
    in2 = (np.abs(lx - a) < half) & (ly_m >= -half)
    inside = in1 | in2
    left = np.asarray(_left_of_path(lx, ly_m, a, turn > 0))
    s = _Scene(walls=walls)
    s.costs.append(("keep_right", np.where(inside, sc.HALLWAY_LEFT_COST * np.asarray(sc.smoothstep(left / half)), 0)))
    inner = world(a - half, half)
    outer = world(a + half, -half)
    s.costs.append(("corner_wide", np.asarray(_corner_cost(*inner, inside))))
    s.goal = world(a, rng.uniform(1.5, 6.0))
    image, expected = s.render()
    free = inside & _free(image)
    r = min(1.0, 1.2 * half)
    near_inner, near_outer = free & _near([inner], r), free & _near([outer], r)
    # Keep right in leg 1 (before the inner corner): left of travel is +y for a left turn, -y for a right one.
    leg1 = free & (lx < a - half - 0.3) & (np.abs(lx) < 6.0) & ~_near([s.goal], 1.2)
    left_cells, right_cells = leg1 & (ly_m * turn > 0.25 * half), leg1 & (ly_m * turn < -0.25 * half)
    params = dict(turn="left" if turn > 0 else "right", width_m=2 * half, turn_at_m=a)
    return [
        _case("hallway_l", "keep_right", image, expected, left_cells, right_cells, **params),
        _case("hallway_l", "corner_wide", image, expected, near_inner, near_outer, **params),
    ]


CORNER_WEDGE_DEG = (35.0, 150.0)  # the wall block's angle at the suite's corners (generator: 45-135)


def _corner_walls(rng, distance=(1.0, 6.5), wedge_deg=CORNER_WEDGE_DEG):
    """Two walls meeting at a corner 1-6.5 m from the robot, the wall block's angle
    :data:`CORNER_WEDGE_DEG`, the robot on the free side. Returns walls, corner, free-side mask."""
    d = rng.uniform(*distance)
    bearing = rng.uniform(-np.pi, np.pi)
    cx, cy = d * np.cos(bearing), d * np.sin(bearing)
    beta = np.deg2rad(rng.uniform(*wedge_deg))
    # The wedge points away from the robot: centred on the direction from the robot to the corner.
    theta0 = np.arctan2(cy, cx) + rng.uniform(-0.3, 0.3) * (np.pi - beta) - beta / 2
    walls = [(cx, cy, cx + LONG_M * np.cos(t), cy + LONG_M * np.sin(t)) for t in (theta0, theta0 + beta)]
    rel = (np.arctan2(grid.CELL_Y_M - cy, grid.CELL_X_M - cx) - theta0) % (2 * np.pi)
    return walls, (cx, cy), rel > beta, {"corner_m": d, "wedge_deg": float(np.rad2deg(beta))}


def _blind_corner_regions(corner, free_side, image, keep_out):
    d = np.hypot(grid.CELL_X_M - corner[0], grid.CELL_Y_M - corner[1])
    free = free_side & _free(image) & ~keep_out
    return free & (d < 1.0), free & (d >= 3.0) & (d <= 4.5)


def _scene_corner(rng):
    walls, corner, free_side, geometry = _corner_walls(rng)
    s = _Scene(walls=walls)
    s.costs.append(("blind_corner", np.asarray(_corner_cost(*corner, free_side))))
    people = []
    if rng.random() < 0.5:  # somebody standing 1.5-3 m from the corner, on the free side
        for _ in range(50):
            ang, dist = rng.uniform(-np.pi, np.pi), rng.uniform(1.5, 3.0)
            x, y = corner[0] + dist * np.cos(ang), corner[1] + dist * np.sin(ang)
            r, c = grid.cell_of_point(x, y)
            if grid.inside(r, c) and free_side[r, c] and all(_segment_distance(x, y, w) > 0.8 for w in walls):
                s.add_person(x, y, rng.uniform(-np.pi, np.pi))
                people.append((x, y))
                break
    image, expected = s.render()
    a, b = _blind_corner_regions(corner, free_side, image, _near(people, 1.5))
    return [_case("corner", "blind_corner", image, expected, a, b, person=bool(people), **geometry)]


def _pass_regions(x, y, heading, image):
    lx, ly = _local(x, y, heading)
    ahead = (lx >= 0.0) & (lx <= 1.6) & _free(image)
    return ahead & (ly <= -0.6) & (ly >= -1.4), ahead & (ly >= 0.6) & (ly <= 1.4)


def _scene_person(rng):
    """One person at any heading (drawn as the nearest of 8), sometimes a wall 0.7-1.1 m behind them
    or 1.8-2.6 m on their left (the generator keeps walls 1.2 m away)."""
    x, y = rng.uniform(-4.5, 4.5, 2)
    heading = rng.uniform(-np.pi, np.pi)
    s = _Scene()
    s.add_person(x, y, heading)
    px, py, drawn = s.people[0]
    u = rng.random()
    if u < 0.33:
        s.walls.append(_tangent_wall(px, py, rng.uniform(0.7, 1.1), drawn + np.pi))
    elif u < 0.66:
        s.walls.append(_tangent_wall(px, py, rng.uniform(1.8, 2.6), drawn + np.pi / 2))
    image, expected = s.render()
    a, b = _pass_regions(px, py, drawn, image)
    off = float(np.rad2deg(abs((heading - drawn + np.pi) % (2 * np.pi) - np.pi)))
    return [_case("person", "pass_left", image, expected, a, b, heading_off_drawn_deg=off, walls=len(s.walls))]


def _scene_hallway_group(rng):
    """A straight hallway with a group standing just outside one of its walls."""
    h, s, inside, lx, ly, walkers = _straight_hallway(rng, half=(1.0, 2.0), walkers=False)
    side = rng.choice([-1, 1])
    radius = rng.uniform(0.8, 1.6)
    centre = _world(0, 0, h.phi, rng.uniform(-3, 3), side * (h.half_m + radius + rng.uniform(0.7, 1.5)))
    g = _group(rng, n=(2, 6), radius=(radius, radius), centre=centre)

    def hallway(scene):
        scene.walls, scene.goal = list(s.walls), s.goal
        scene.costs.extend(s.costs)

    g, images, expected, zone = _group_pair(rng, group=g, other=hallway)
    a, b = _keep_right_regions(
        h, inside, lx, ly, images, _near([s.goal, (g.cx, g.cy)], 1.2) | _near([(g.cx, g.cy)], g.radius + 1.2)
    )
    return [
        _case("hallway+group", "keep_right", images[0], _first(expected), a, b),
        _case("hallway+group", "group_zone", images, expected, zone, zone),
    ]


def _scene_queue_corner(rng):
    """A queue on the free side of a blind corner, 1.5-3 m from its walls."""
    walls, corner, free_side, geometry = _corner_walls(rng, distance=(1.5, 5.0))
    q = _queue(rng, length=(2.0, 6.0), head_box=5.0)
    clear = [min(_segment_distance(x, y, w) for w in walls) for x, y in q.people]
    cells = [grid.cell_of_point(x, y) for x, y in q.people]
    if not (all(1.5 <= c <= 3.0 for c in clear[:1]) and min(clear) >= 1.5):
        return None
    if not all(grid.inside(r, c) and free_side[r, c] for r, c in cells):
        return None
    out = _queue_pair(rng, walls, costs=[("blind_corner", np.asarray(_corner_cost(*corner, free_side)))], queue=q)
    if out is None:
        return None
    q, images, expected, region = out
    # The corner's regions leave out the queue: its people and, with the goal at its head, its U
    # and a cell round it (the U is forbidden, above every graded cost: in a region it would
    # decide the corner's contrast; the queue_u check scores it).
    head = _first(expected)
    u_cells = np.asarray(_dilate(jnp.asarray(head[""] > head["queue_u"] + 1e-3), 1))
    a, b = _blind_corner_regions(corner, free_side, images[0], _near(q.people + [q.elsewhere_goal], 2.0) | u_cells)
    return [
        _case("queue+corner", "queue_u", images, expected, region, region),
        _case("queue+corner", "blind_corner", images[0], _first(expected), a, b, **geometry),
    ]


def _apart(g: _Group, points, gap_m):
    return all(np.hypot(x - g.cx, y - g.cy) >= g.radius + gap_m for x, y in points)


def _scene_two_groups(rng):
    g1, g2 = _group(rng, n=(2, 6), radius=(0.8, 1.6)), _group(rng, n=(2, 6), radius=(0.8, 1.6))
    if np.hypot(g1.cx - g2.cx, g1.cy - g2.cy) < g1.radius + g2.radius + 1.5:
        return None
    inward2 = rng.random() < 0.5
    _, images1, expected1, zone1 = _group_pair(rng, group=g1, other=lambda s: _draw_group(s, g2, inward2))
    inward1 = rng.random() < 0.5
    _, images2, expected2, zone2 = _group_pair(rng, group=g2, other=lambda s: _draw_group(s, g1, inward1))
    return [
        _case("two_groups", "group_zone", images1, expected1, zone1, zone1),
        _case("two_groups", "group_zone", images2, expected2, zone2, zone2),
    ]


def _scene_queue_group(rng):
    q = _queue(rng, length=(2.0, 7.0))
    g = _group(rng, n=(2, 6), radius=(0.8, 1.6), centre_box=5.0)
    if not _apart(g, q.people, 2.0):
        return None
    # The queue's pair with the group facing in (its zone in both maps).
    facing_in = [(x, y, a + np.pi) for x, y, a in g.people]
    out = _queue_pair(
        rng, costs=[("group_zone", np.asarray(_disc_plateau(g.cx, g.cy, g.radius)))], extra_people=facing_in, queue=q
    )
    if out is None or not _apart(g, [q.elsewhere_goal], 1.5):
        return None
    _, q_images, q_expected, q_region = out
    q_region &= ~_near([(g.cx, g.cy)], g.radius + 1.0)

    def queue_at_head(scene):
        _draw_queue(scene, q, "head", rng)

    _, g_images, g_expected, zone = _group_pair(rng, group=g, other=queue_at_head)
    return [
        _case("queue+group", "queue_u", q_images, q_expected, q_region, q_region),
        _case("queue+group", "group_zone", g_images, g_expected, zone, zone),
    ]


_BUILDERS = {
    "queue": _scene_queue,
    "group": _scene_group,
    "hallway": _scene_hallway,
    "hallway_l": _scene_hallway_l,
    "corner": _scene_corner,
    "person": _scene_person,
    "hallway+group": _scene_hallway_group,
    "queue+corner": _scene_queue_corner,
    "two_groups": _scene_two_groups,
    "queue+group": _scene_queue_group,
}


def expected_contrast(case: Case, blind: bool = False) -> float:
    """The contrast of the case's expected map (or of its rule-blind map)."""
    maps = case.blind if blind else case.expected
    return float(contrasts(maps[None], case.region_a[None], case.region_b[None])[0])


def _usable(case: Case) -> bool:
    return (
        case.region_a.sum() >= MIN_REGION_CELLS
        and case.region_b.sum() >= MIN_REGION_CELLS
        and expected_contrast(case) - expected_contrast(case, blind=True) >= MIN_EXPECTED_CONTRAST
    )


def draw_suite(
    scenes_per_kind: int = 100, seed: int = SUITE_SEED, kinds: tuple[str, ...] = SCENES, report=None
) -> tuple[Case, ...]:
    """The suite's cases: ``scenes_per_kind`` scenes of each kind (a scene may check two rules),
    deterministic by ``seed``. A drawn scene whose regions hold fewer than
    :data:`MIN_REGION_CELLS` cells or whose expected contrast is below
    :data:`MIN_EXPECTED_CONTRAST` is drawn again (so every case can tell a rule from its absence).
    ``report(done, total)``, if given, is called with the scenes drawn after each one.
    :func:`build_suite` keeps the last few suites drawn."""
    unknown = sorted(set(kinds) - set(_BUILDERS))
    if unknown:
        raise ValueError(f"unknown scene kinds {unknown}; known: {list(_BUILDERS)}")
    cases = []
    for k, kind in enumerate(kinds):
        rng = np.random.default_rng([seed, k])
        made, tries = 0, 0
        while made < scenes_per_kind:
            tries += 1
            if tries > 50 * scenes_per_kind:
                raise RuntimeError(f"rule suite: could not place {scenes_per_kind} '{kind}' scenes")
            drawn = _BUILDERS[kind](rng)
            if drawn is None or not all(_usable(c) for c in drawn):
                continue
            cases.extend(drawn)
            made += 1
            if report is not None:
                report(k * scenes_per_kind + made, len(kinds) * scenes_per_kind)
    return tuple(cases)


@functools.lru_cache(maxsize=4)
def build_suite(
    scenes_per_kind: int = 100, seed: int = SUITE_SEED, kinds: tuple[str, ...] = SCENES
) -> tuple[Case, ...]:
    """:func:`draw_suite`'s cases, kept for the same arguments (training scores the same suite
    after every epoch)."""
    return draw_suite(scenes_per_kind, seed, kinds)


def cases_per_scene(kinds: tuple[str, ...] = SCENES) -> int:
    """The cases one scene of each kind makes (a kind's scenes check the same rules every time)."""
    return len(build_suite(1, kinds=kinds))


def contrasts(costs, region_a, region_b) -> np.ndarray:
    """(N,) mean of ``costs[:, 0]`` over ``region_a`` minus mean of ``costs[:, 1]`` over ``region_b``.

    Args:
      costs: (N, 2, 40, 40) cost maps (the two maps of each case); region_a / region_b: (N, 40, 40) bool.
    """
    costs = np.asarray(costs, np.float64)
    a = (costs[:, 0] * region_a).sum((1, 2)) / region_a.sum((1, 2))
    b = (costs[:, 1] * region_b).sum((1, 2)) / region_b.sum((1, 2))
    return a - b


def evaluate(predict, cases, batch: int = 256) -> dict:
    """Score ``predict`` ((B, 40, 40) uint8 -> (B, 40, 40) costs) on the cases.

    Returns ``{"by_check": {"scene/rule": {...}}, "by_rule": {...}, "mse": float, "cases": int,
    "contrast": (N,) model contrasts, "expected_contrast": (N,), "blind_contrast": (N,), "passed":
    (N,) bool, "predictions": (N, 2, 40, 40)}``: for each (scene, rule) and each rule, the number
    of cases, the share that pass with its 95 % Wilson interval (what a suite of this size can
    tell), the mean model and expected contrasts; the MSE of the predictions against the expected
    maps over every map.
    """
    images = np.stack([c.images for c in cases])  # (N, 2, 40, 40)
    flat = images.reshape(-1, grid.GRID, grid.GRID)
    pad = -len(flat) % batch  # every call the same shape: one compilation
    flat = np.concatenate([flat, np.zeros((pad, grid.GRID, grid.GRID), np.uint8)])
    out = np.concatenate([np.asarray(predict(jnp.asarray(flat[i : i + batch]))) for i in range(0, len(flat), batch)])
    return score(out[: len(flat) - pad].reshape(images.shape), cases)


def score(costs, cases) -> dict:
    """:func:`evaluate`'s report of given cost maps: ``costs`` (N, 2, 40, 40), the two maps of each
    of the N cases (e.g. maps fitted to each case by another route than a network)."""
    costs = np.asarray(costs, np.float64)
    if costs.shape != (len(cases), 2, grid.GRID, grid.GRID):
        raise ValueError(f"costs: expected shape {(len(cases), 2, grid.GRID, grid.GRID)}, got {costs.shape}")
    expected = np.stack([c.expected for c in cases]).astype(np.float64)
    region_a, region_b = np.stack([c.region_a for c in cases]), np.stack([c.region_b for c in cases])
    model, want = contrasts(costs, region_a, region_b), contrasts(expected, region_a, region_b)
    blind = contrasts(np.stack([c.blind for c in cases]), region_a, region_b)
    passed = model >= blind + PASS_FRACTION * (want - blind)
    keys = [f"{c.scene}/{c.rule}" for c in cases]

    def summary(mask):
        return {
            "cases": int(mask.sum()),
            "pass_share": float(passed[mask].mean()),
            "pass_share_ci95": list(wilson(int(passed[mask].sum()), int(mask.sum()))),
            "contrast": float(model[mask].mean()),
            "expected_contrast": float(want[mask].mean()),
            "blind_contrast": float(blind[mask].mean()),
        }

    return {
        "cases": len(cases),
        "by_check": {k: summary(np.array([kk == k for kk in keys])) for k in dict.fromkeys(keys)},
        "by_rule": {
            r: summary(np.array([c.rule == r for c in cases])) for r in RULES if any(c.rule == r for c in cases)
        },
        "mse": float(np.mean((costs - expected) ** 2)),
        "contrast": model,
        "expected_contrast": want,
        "blind_contrast": blind,
        "passed": passed,
        "predictions": costs.astype(np.float32),
    }


RULES_BAR = 0.95  # the goal: every (scene, rule) check passing on at least 95 % of its cases


def passes(report: dict, share: float = RULES_BAR) -> bool:
    """Every (scene, rule) check passes on at least ``share`` of its cases."""
    return all(v["pass_share"] >= share for v in report["by_check"].values())


def table(report: dict) -> str:
    """The per-check table (markdown): cases, pass share, mean contrasts."""
    lines = [
        "| scene | rule | cases | pass | 95 % interval | contrast: model | expected | rule-blind |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for key, v in report["by_check"].items():
        scene, rule = key.split("/")
        lo, hi = v["pass_share_ci95"]
        lines.append(
            f"| {scene} | {rule} | {v['cases']} | {100 * v['pass_share']:.0f} % | {100 * lo:.0f}-{100 * hi:.0f} % "
            f"| {v['contrast']:.3f} "
            f"| {v['expected_contrast']:.3f} | {v['blind_contrast']:.3f} |"
        )
    lines.append(f"\nMSE against the expected maps: {report['mse']:.5f} over {2 * report['cases']} maps")
    return "\n".join(lines)


def plot(cases, report: dict, path):
    """A PNG with one row per (scene, rule): its first failing case (else its first case), input /
    expected / prediction of map 0 and of map 1, region A outlined on map 0 and region B on map 1."""
    from socialnav.common import figures
    from socialnav.common.atomic import write_atomic
    from socialnav.models.plots import input_rgb

    keys = list(report["by_check"])
    fig = figures.figure(figsize=(9.5, 1.6 * len(keys)))
    axes = fig.subplots(len(keys), 6, squeeze=False)
    for row, key in enumerate(keys):
        idx = [i for i, c in enumerate(cases) if f"{c.scene}/{c.rule}" == key]
        failing = [i for i in idx if not report["passed"][i]]
        i = (failing or idx)[0]
        case = cases[i]
        for m, region in ((0, case.region_a), (1, case.region_b)):
            ax = axes[row, 3 * m : 3 * m + 3]
            ax[0].imshow(input_rgb(case.images[m]), interpolation="nearest")
            ax[1].imshow(case.expected[m], vmin=0, vmax=1, cmap="magma", interpolation="nearest")
            ax[2].imshow(report["predictions"][i, m], vmin=0, vmax=1, cmap="magma", interpolation="nearest")
            for a in ax:
                a.contour(region, levels=[0.5], colors="c", linewidths=0.6)
                a.set_xticks([])
                a.set_yticks([])
        verdict = "passes" if report["passed"][i] else "FAILS"
        axes[row, 0].set_ylabel(key.replace("/", "\n"), fontsize=7)
        axes[row, 2].set_title(
            f"contrast {report['contrast'][i]:.2f} / {report['expected_contrast'][i]:.2f}: {verdict}", fontsize=7
        )
    for col, title in enumerate(("map A", "expected", "model", "map B", "expected", "model")):
        axes[0, col].set_xlabel(title, fontsize=7)
        axes[0, col].xaxis.set_label_position("top")
    fig.tight_layout()
    return write_atomic(path, lambda tmp: fig.savefig(tmp, dpi=72, format="png"))
