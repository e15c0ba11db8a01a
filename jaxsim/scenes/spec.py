"""Social-navigation scenes as data: the file format, its validation, and variants drawn from it.

A scene file (``data/scenes/<name>.json``) holds the walls, objects with their interaction
spaces, people each with a behaviour, the robot's start and goal, a timeout, the scene's social
rule, and a range for every number that varies: one scene and a seed give one variant
(:func:`sample_variants`). Every error is a :class:`~jaxsim.scenario.errors.ScenarioError`
naming the file and the field.

Format (``N``: a number or ``[lo, hi]``, drawn uniformly per variant; ``P``: ``[N, N]``, a point)::

    {"name": "...", "source": "seed 001 Sec. 4.1",
     "bounds_m": [xmin, xmax, ymin, ymax],
     "walls": [[xmin, xmax, ymin, ymax], ...],                  # boxes
     "objects": [{"name": "table", "polygon": [[x, y], ...], "cost": 30}],   # convex, counter-clockwise
     "robot": {"start": P, "yaw_deg": N, "goal": P},
     "timeout_s": 40,
     "people": [
       {"behaviour": "standing", "position": P, "heading_deg": N},
       {"behaviour": "walk", "from": P, "to": P, "speed_mps": N, "start_s": N,
        "back_and_forth": false, "ignore_robot": true, "walks_with": 2},
       {"behaviour": "group", "centre": P, "size": N, "radius_m": N, "facing": "in" | "out",
        "rotation_deg": N, "turn_inward_at_s": N},
       {"behaviour": "queue", "head": P, "towards_deg": N, "length": N, "spacing_m": N,
        "advance_every_s": N, "exit": P},
       {"behaviour": "stream", "from": P, "to": P, "count": 2, "start_s": N, "interval_s": N, "speed_mps": N}
     ],
     "rule": {"type": "min_distance", "distance_m": 1.2},
     "held_out_rule": {...},                                    # optional, see below
     "stop_and_go_m": 0.9,                                      # optional, see below
     "people_in_global_plan": true,                             # optional, see below
     "variants_of": "gscl_crowded_entrance",                    # optional, see below
     "recording": {"run": "biwi_hotel", "playback": "replayed" | "reactive",
                   "window_within_s": [0, 480]}}                # optional, see below ("file", "frames_per_s" for "run")

Every key of the file is one of these, where it stands (a ``walks_with`` on a stream, or a
misspelt ``start_S``, is an error naming the field, not a default used in silence); a key that
starts with ``_`` is a note for people (``"_comment": "..."``) and is not read.

Behaviours: a **standing** person stays put; a **walker** goes from ``from`` to ``to`` at
``speed_mps`` from ``start_s`` on (back and forth if asked), by the run's human model, round the
walls by the corners of the shortest way where its straight line crosses one
(:mod:`jaxsim.scenes.routes`; a walker no body can get through to its end is refused,
:func:`jaxsim.scenes.reachable.people_problem`); a **group** is
``size`` (2-6) standing people on a circle of ``radius_m`` facing its centre (``in``) or away
(``out``), turning inward at ``turn_inward_at_s`` if given (seed 002's lab scene), neighbours at
least two bodies apart; a **queue** is ``length`` people behind ``head`` facing ``towards_deg``,
spaced ``spacing_m``, no wall across its line: every ``advance_every_s`` its first person leaves
for ``exit`` and the rest step up; a **stream** is ``count`` walkers entering at
``from`` every ``interval_s`` from ``start_s``, leaving the scene at ``to``. ``ignore_robot``
(walkers, streams): the person does not avoid the robot, as the seeds' test subjects walked their
course. ``walks_with`` (walkers): the index in ``people`` of another walker this one walks
with, a walking group (Moussaïd et al. 2010's group terms, :mod:`jaxsim.groups`, on top of the
run's human model); pairs chain into larger groups.

Rules (what "socially successful" means in the scene, checked on the trajectory by
:func:`evaluation.arena.nav_metrics.rule_satisfied`, and step by step by
:mod:`jaxsim.scenes.rule_monitor`): ``min_distance`` (never closer than ``distance_m`` to anyone,
centre to centre), ``avoid_group`` (never inside group ``group``'s circle), ``avoid_circle`` (never
within ``radius_m`` of ``centre``: a corner taken wide), ``keep_right``
(inside ``box``, travelling along ``direction_deg``, at least ``min_share`` of the time on the right
half of the box), ``visit`` (pass through ``box`` before the goal), ``pass_behind`` (cross walker
``person``'s line behind them), ``queue`` (join a line at its tail and never cut in: see below),
``all`` (every rule in ``rules``).

``queue``: ``{"type": "queue", "head": [x, y], "direction_deg": N, "half_width_m": 0.6,
"length_m": 5, "ahead_m": 1.2}``. The line's lane runs from ``length_m`` behind ``head`` to
``ahead_m`` in front of it (the way the queue faces is ``direction_deg``), ``half_width_m`` either
side of its axis. The robot cuts in when its centre is in the lane ahead, along the axis, of a
person still in the lane: entering the lane from the side ahead of someone in line, or reaching a
goal in front of the head while people still wait. Joining behind the last person and advancing
with the line obeys it (seed 002 Sec. 5.3.5: "enter the queue from the beginning and wait for its
turn").

``held_out_rule`` (optional; default ``rule``): the rule of the held-out layout (:func:`mirror`),
written in this file's frame and mirrored with the layout, for a scene where mirroring changes
what a person would do. The L-hallway's left turn becomes a right turn there: keeping right then
puts the blind inner corner on the robot's own side, so "take the corner wide" would mean leaving
its lane, and the two rules together are ones no walker satisfies; its held-out rule keeps right
in both legs and keeps the distance to people, without the wide corner.

``stop_and_go_m`` (optional; default none): every method's robot in the scene stops while a seen
person is ahead of it (within 60 deg of its heading) closer than this, centre to centre, and goes
on when the gap opens: seed 002 Sec. 4.3's "simple stop-and-go mechanism based on the distance to
the next person in line", which its robot used in the queue scene only. It wraps every method's
actor (:func:`planners.actors.with_stop_and_go`), so the methods stay comparable.

``people_in_global_plan`` (optional; default true): whether the stacks' global planner sees the
people as obstacles (Nav2's obstacle layer in the global costmap, this arena's default). false:
the global costmap is the walls, their inflation and the social layer, as seed 002 Sec. 4.4 lists
it ("the static and the inflation layer"); the people then shape the global path only through
the social layer, and the local planner, the safety stop and the stop-and-go keep the robot off
them. A queue needs it: the way to the head is through the line, behind the people in it.

``variants_of`` (optional; default the scene's ``name``): the name whose random stream draws the
scene's variants (:func:`jaxsim.scenes.variant.sample_variant`). A copy of a scene that changes
one number (``scripts/scene_sweep.py``: the crowded entrance's walkers starting later) names the
scene it copies, so its variant ``k`` draws the same numbers as the scene's own variant ``k``
(common random numbers across the copies) and a copy that changes nothing gives the scene's own
episodes.

``recording`` (optional): the scene's people are a recorded crowd, a window of ``timeout_s``
seconds of the shipped run ``run`` (:func:`socialnav.data.recorded.run_names`: the ETH/UCY
scenes, the Jülich corridors; positions in the run's own frame) or of the user's own ``file``
instead (the toolkit's tracks file, :mod:`socialnav.data.track_file`: ``frame, id, x, y`` rows in
metres, its path relative to the scene file's folder, with ``frames_per_s``, the frame numbers'
rate; ``socialnav arena-scene`` writes a scene for one) per variant, drawn from the
run's ``window_within_s``; a held-out variant's window lies wholly outside it, in the rest of the
run (:mod:`jaxsim.scenes.recording`); the recording's people must walk inside ``bounds_m``, at
most :data:`MAX_PEOPLE_SLOTS` at once. Such a scene has no scripted ``people`` (``[]``). Two
``playback`` modes: ``replayed``, everyone moves exactly as recorded and ignores the robot (as
SocNavBench replays ETH/UCY: a collision is then the robot's by construction); ``reactive``, each
person heads for where they are recorded 1 s ahead, by the run's human model, so they yield to
the robot and go back to their recorded path after. The robot's start is redrawn (with the
window) until nobody recorded stands within 0.775 m of it when the episode begins.
"""

from __future__ import annotations

import dataclasses
import json
import math
import pathlib
from typing import Any

import numpy as np

from socialnav.common import strict_json
from socialnav.common.names import SAFE_NAME_RULE, is_safe_name, name_problem
from socialnav.jaxsim import geometry
from socialnav.jaxsim.params import PERSON_RADIUS_M
from socialnav.jaxsim.scenario.errors import ScenarioError

BEHAVIOURS = ("standing", "walk", "group", "queue", "stream")
KIND = {"standing": 0, "walk": 1, "queue": 2, "stream": 3, "recorded": 4}  # a group's members are standing
PLAYBACKS = ("replayed", "reactive")
RULES = ("min_distance", "avoid_group", "avoid_circle", "keep_right", "visit", "pass_behind", "queue", "all")
MAX_GROUP = 6
MAX_OBJECT_VERTICES = 8


@dataclasses.dataclass(frozen=True)
class SceneSpec:
    """A validated scene file (the raw numbers and ranges; :func:`sample_variants` draws from it)."""

    file: pathlib.Path
    name: str
    source: str
    bounds_m: tuple[float, float, float, float]
    walls_m: np.ndarray  # (K, 4)
    objects: tuple[tuple[str, np.ndarray, float], ...]
    robot: dict
    timeout_s: float
    people: tuple[dict, ...]
    rule: dict
    n_people_slots: int
    held_out_rule: dict | None = None  # the mirrored layout's rule, in this frame (None: ``rule``)
    stop_and_go_m: float | None = None  # every robot stops for a person ahead closer than this
    people_in_global_plan: bool = True  # the seen people are obstacles for the global planner
    recording: dict | None = None  # the recorded people (:func:`_recording`); None: scripted people only
    variants_of: str | None = None  # the name whose stream draws the variants (None: ``name``)
    turned_from: SceneSpec | None = None  # the scene this one is a quarter turn of (:func:`turn`); None: as in its file


# ------------------------------------------------------------------ typed reads


class _Reader:
    """Typed reads of one file's JSON, each failure a :class:`ScenarioError` naming the field.

    Every object's keys that were asked for are noted, so :meth:`check_every_field_read` can
    refuse a key nothing reads: a misspelt optional field (``"start_S"``, ``"distanse_m"``) or one
    that means nothing where it stands (``"walks_with"`` on a stream) would otherwise be dropped
    without a word and its default used. A key starting with ``_`` is a note for the reader of
    the file (``"_comment"``, as the warehouse's files' ``"_source"``) and is never read.
    """

    def __init__(self, file: pathlib.Path):
        self.file = file
        self.asked: dict[int, tuple[dict, str, set[str]]] = {}  # id(object) -> (object, where, keys asked)

    def fail(self, where: str, message: str):
        raise ScenarioError(self.file, where, message)

    def get(self, obj: dict, where: str, key: str, default: Any = ...):
        if not isinstance(obj, dict):
            self.fail(where, f"expected an object, got {type(obj).__name__}")
        self.asked.setdefault(id(obj), (obj, where, set()))[2].add(key)
        if key not in obj:
            if default is ...:
                self.fail(f"{where}.{key}" if where else key, "missing field")
            return default
        return obj[key]

    def number(self, value: Any, where: str, low: float = -math.inf, high: float = math.inf, integer=False):
        """A number or a [lo, hi] range within [low, high]: returns (lo, hi)."""
        if isinstance(value, list) and len(value) == 2:
            lo, hi = (self.number(v, f"{where}[{i}]", low, high, integer)[0] for i, v in enumerate(value))
            if lo > hi:
                self.fail(where, f"range [lo, hi] needs lo <= hi, got [{lo}, {hi}]")
            return lo, hi
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            self.fail(where, f"expected a finite number or a [lo, hi] range, got {value!r}")
        if integer and int(value) != value:
            self.fail(where, f"expected a whole number, got {value!r}")
        if not low <= value <= high:
            self.fail(where, f"expected a value in [{low}, {high}], got {value!r}")
        return float(value), float(value)

    def point(self, value: Any, where: str):
        if not isinstance(value, list) or len(value) != 2:
            self.fail(where, f"expected a point [x, y], got {value!r}")
        return tuple(self.number(v, f"{where}[{i}]") for i, v in enumerate(value))

    def exact_point(self, value: Any, where: str) -> np.ndarray:
        """A rule's point ``[x, y]`` (numbers, no ranges): (2,) float array."""
        if not isinstance(value, list) or len(value) != 2:
            self.fail(where, f"expected [x, y], got {value!r}")
        return np.array([self.number(c, f"{where}[{i}]")[0] for i, c in enumerate(value)])

    def box(self, value: Any, where: str) -> np.ndarray:
        if not isinstance(value, list) or len(value) != 4:
            self.fail(where, f"expected [xmin, xmax, ymin, ymax], got {value!r}")
        b = np.array([self.number(v, f"{where}[{i}]")[0] for i, v in enumerate(value)])
        if b[0] >= b[1] or b[2] >= b[3]:
            self.fail(where, f"expected xmin < xmax and ymin < ymax, got {value!r}")
        return b

    def check_every_field_read(self) -> None:
        """Refuse a key that no read asked for, of any object read so far (the first such key of the
        first object read that has one)."""
        for obj, where, asked in self.asked.values():
            key = strict_json.unknown_key(obj, asked)
            if key is not None:
                hint = strict_json.did_you_mean(key, sorted(asked))
                self.fail(
                    f"{where}.{key}" if where else key,
                    f"unknown field ({hint}the fields here: {', '.join(sorted(asked))})",
                )

    def flag(self, obj: dict, where: str, key: str, default: bool) -> bool:
        value = self.get(obj, where, key, default)
        if not isinstance(value, bool):
            self.fail(f"{where}.{key}" if where else key, f"expected true or false, got {value!r}")
        return value


def _inside_bounds(r: _Reader, bounds, point, where):
    xmin, xmax, ymin, ymax = bounds
    (x0, x1), (y0, y1) = point
    if x0 < xmin or x1 > xmax or y0 < ymin or y1 > ymax:
        r.fail(where, f"lies outside bounds_m {[float(b) for b in bounds]}")


def _clear_of_walls(r: _Reader, walls_m: np.ndarray, point, where):
    """A point's whole range must lie outside every wall box (a centre inside a wall)."""
    (x0, x1), (y0, y1) = point
    for k, (wx0, wx1, wy0, wy1) in enumerate(walls_m):
        if x0 <= wx1 and wx0 <= x1 and y0 <= wy1 and wy0 <= y1:
            r.fail(
                where,
                f"range x {[x0, x1]}, y {[y0, y1]} reaches into walls[{k}] {[float(v) for v in (wx0, wx1, wy0, wy1)]}",
            )


def _extremes(value, legal=(-math.inf, math.inf)) -> list[float]:
    """The values a range ``(lo, hi)`` can be drawn at, in the evaluation's draws and the held-out
    ones (up to half its width beyond either end, clipped to ``legal``:
    :class:`jaxsim.scenes.variant._Drawer`), at its ends and middle."""
    lo, hi = value
    half = (hi - lo) / 2
    lo, hi = max(lo - half, legal[0]), min(hi + half, legal[1])
    return sorted({lo, (lo + hi) / 2, hi})


def _check_queue_line(r: _Reader, queue: dict, where: str, bounds, walls_m: np.ndarray) -> None:
    """Every place of a queue's line (``head`` moved back ``m * spacing_m`` against
    ``towards_deg``, for m up to ``length - 1``) inside ``bounds_m`` and outside every wall, and
    no wall between a place and the next one up the line (the people waiting in line step
    straight up to their place, :func:`jaxsim.scenes.people.step_people`: they would walk through
    it), for the head's corners and the ends and middle of the direction's and spacing's ranges
    (held-out draws included; between the directions checked, every 45 degrees as well). The exit
    and the head are checked as points already."""
    (hx0, hx1), (hy0, hy1) = queue["head"]
    angles = _queue_angles(queue)
    spacings = _extremes(queue["spacing_m"], (0.3, 3.0))
    last = int(queue["length"][1]) - 1
    xmin, xmax, ymin, ymax = bounds
    for angle in angles:
        for spacing in spacings:
            back = -spacing * np.array([math.cos(math.radians(angle)), math.sin(math.radians(angle))])
            for m in range(1, last + 1):
                for hx, hy in ((hx0, hy0), (hx0, hy1), (hx1, hy0), (hx1, hy1)):
                    x, y = hx + m * back[0], hy + m * back[1]
                    place = (
                        f"the line's place {m} at ({x:.2f}, {y:.2f}) m (towards_deg {angle:g}, spacing_m {spacing:g})"
                    )
                    if not (xmin <= x <= xmax and ymin <= y <= ymax):
                        r.fail(f"{where}.length", f"{place} lies outside bounds_m {[float(b) for b in bounds]}")
                    for k, (wx0, wx1, wy0, wy1) in enumerate(walls_m):
                        if wx0 <= x <= wx1 and wy0 <= y <= wy1:
                            r.fail(f"{where}.length", f"{place} lies inside walls[{k}]")
                    ahead = (x - back[0], y - back[1])
                    if not len(walls_m) or not geometry.segment_hits_boxes(ahead, (x, y), walls_m):
                        continue
                    for k, wall in enumerate(walls_m):  # the wall in the way, for the message
                        if geometry.segment_hits_boxes(ahead, (x, y), wall[None]):
                            r.fail(
                                f"{where}.length",
                                f"walls[{k}] stands between {place} and the place ahead of it at "
                                f"({ahead[0]:.2f}, {ahead[1]:.2f}) m: the people in line step straight "
                                "up to their places and would walk through it",
                            )


def _check_group_circle(r: _Reader, group: dict, where: str, bounds, walls_m: np.ndarray) -> None:
    """Every member of a group (on its circle of ``radius_m`` about ``centre``, ``size`` of them
    spaced evenly from ``rotation_deg``) inside ``bounds_m`` and outside every wall, for the
    centre's corners, the radius's and rotation's ends and middle (held-out draws included; a
    rotation range every 10 degrees) and every size drawn; and neighbours on the circle at least two
    bodies apart (:data:`~socialnav.jaxsim.params.PERSON_RADIUS_M`) at the largest size and the
    smallest radius drawn, as two people placed at the start are (:func:`_check_placements`): the
    members stand where they are put, so closer they would stand inside each other all episode."""
    (cx0, cx1), (cy0, cy1) = group["centre"]
    radii = _extremes(group["radius_m"], (0.3, 5.0))
    largest = int(group["size"][1])
    apart_m = 2 * radii[0] * math.sin(math.pi / largest)  # the chord between neighbours
    if apart_m < 2 * PERSON_RADIUS_M - 1e-9:
        needed_m = PERSON_RADIUS_M / math.sin(math.pi / largest)
        r.fail(
            f"{where}.radius_m",
            f"{largest} members on a circle of radius_m {radii[0]:g} stand {apart_m:.2f} m apart, closer than "
            f"two bodies ({2 * PERSON_RADIUS_M:g} m): two people in one place; for {largest} members the smallest "
            f"radius drawn (held-out draws included) must be at least {needed_m:.2f} m",
        )
    lo, hi = _extremes(group["rotation_deg"])[0], _extremes(group["rotation_deg"])[-1]
    rotations = np.linspace(lo, hi, max(2, math.ceil((hi - lo) / 10.0) + 1)) if hi > lo else [lo]
    sizes = range(2, int(group["size"][1]) + 1)
    xmin, xmax, ymin, ymax = bounds
    for size in sizes:
        for rotation in rotations:
            for m in range(size):
                angle = math.radians(rotation) + 2 * math.pi * m / size
                for radius in radii:
                    for cx, cy in ((cx0, cy0), (cx0, cy1), (cx1, cy0), (cx1, cy1)):
                        x, y = cx + radius * math.cos(angle), cy + radius * math.sin(angle)
                        member = f"a member at ({x:.2f}, {y:.2f}) m (size {size}, radius_m {radius:g})"
                        if not (xmin <= x <= xmax and ymin <= y <= ymax):
                            r.fail(f"{where}.radius_m", f"{member} lies outside bounds_m {[float(b) for b in bounds]}")
                        for k, (wx0, wx1, wy0, wy1) in enumerate(walls_m):
                            if wx0 <= x <= wx1 and wy0 <= y <= wy1:
                                r.fail(f"{where}.radius_m", f"{member} lies inside walls[{k}]")


def _rule_point(r: _Reader, point: np.ndarray, where: str, bounds, walls_m: np.ndarray) -> np.ndarray:
    """A rule's point inside ``bounds_m`` and outside every wall (a rule anchored where no robot
    can go can never be broken: it would score every method as following it)."""
    x, y = float(point[0]), float(point[1])
    xmin, xmax, ymin, ymax = bounds
    if not (xmin <= x <= xmax and ymin <= y <= ymax):
        r.fail(where, f"({x:g}, {y:g}) lies outside bounds_m {[float(b) for b in bounds]}")
    for k, (wx0, wx1, wy0, wy1) in enumerate(walls_m):
        if wx0 < x < wx1 and wy0 < y < wy1:
            r.fail(where, f"({x:g}, {y:g}) lies inside walls[{k}]")
    return point


def _rule_box(r: _Reader, box: np.ndarray, where: str, bounds) -> np.ndarray:
    """A rule's box overlapping ``bounds_m`` (a box wholly outside the scene can never be entered)."""
    xmin, xmax, ymin, ymax = bounds
    if box[1] <= xmin or box[0] >= xmax or box[3] <= ymin or box[2] >= ymax:
        r.fail(where, f"{[float(v) for v in box]} lies wholly outside bounds_m {[float(b) for b in bounds]}")
    return box


def _person(r: _Reader, p: dict, where: str, bounds, walls_m: np.ndarray) -> tuple[dict, int]:
    behaviour = r.get(p, where, "behaviour")
    if behaviour not in BEHAVIOURS:
        r.fail(f"{where}.behaviour", f"expected one of {', '.join(BEHAVIOURS)}, got {behaviour!r}")
    out: dict = {"behaviour": behaviour}

    def pt(key):
        value = r.point(r.get(p, where, key), f"{where}.{key}")
        _inside_bounds(r, bounds, value, f"{where}.{key}")
        _clear_of_walls(r, walls_m, value, f"{where}.{key}")
        return value

    def num(key, low=-math.inf, high=math.inf, default=..., integer=False):
        value = r.get(p, where, key, default)
        return value if value is None else r.number(value, f"{where}.{key}", low, high, integer)

    if behaviour == "standing":
        out.update(position=pt("position"), heading_deg=num("heading_deg"))
        return out, 1
    if behaviour == "walk":
        out.update(
            start=pt("from"),
            end=pt("to"),
            speed_mps=num("speed_mps", 0.05, 3.0),
            start_s=num("start_s", 0.0, default=0.0),
            back_and_forth=r.flag(p, where, "back_and_forth", False),
            ignore_robot=r.flag(p, where, "ignore_robot", False),
            walks_with=r.get(p, where, "walks_with", None),
        )
        return out, 1
    if behaviour == "group":
        facing = r.get(p, where, "facing")
        if facing not in ("in", "out"):
            r.fail(f"{where}.facing", f"expected 'in' or 'out', got {facing!r}")
        size = num("size", 2, MAX_GROUP, integer=True)
        turn = r.get(p, where, "turn_inward_at_s", None)
        out.update(
            centre=pt("centre"),
            size=size,
            radius_m=num("radius_m", 0.3, 5.0),
            facing=facing,
            rotation_deg=num("rotation_deg", default=0.0),
            turn_inward_at_s=None if turn is None else r.number(turn, f"{where}.turn_inward_at_s", 0.0),
        )
        _check_group_circle(r, out, where, bounds, walls_m)
        return out, int(size[1])
    if behaviour == "queue":
        length = num("length", 1, 20, integer=True)
        out.update(
            head=pt("head"),
            towards_deg=num("towards_deg"),
            length=length,
            spacing_m=num("spacing_m", 0.3, 3.0),
            advance_every_s=num("advance_every_s", 1.0),
            exit=pt("exit"),
        )
        _check_queue_line(r, out, where, bounds, walls_m)
        return out, int(length[1])
    # stream
    count = r.get(p, where, "count")
    if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= 20:
        r.fail(f"{where}.count", f"expected a whole number in [1, 20], got {count!r}")
    out.update(
        start=pt("from"),
        end=pt("to"),
        count=count,
        start_s=num("start_s", 0.0, default=0.0),
        interval_s=num("interval_s", 0.1),
        speed_mps=num("speed_mps", 0.05, 3.0),
        ignore_robot=r.flag(p, where, "ignore_robot", False),
    )
    return out, count


def _range_points(value) -> list[tuple[float, float]]:
    """A point range's corners and middle (``((x0, x1), (y0, y1))``)."""
    (x0, x1), (y0, y1) = value
    return [(x0, y0), (x0, y1), (x1, y0), (x1, y1), ((x0 + x1) / 2, (y0 + y1) / 2)]


def _check_straight_walk(r: _Reader, walker: dict, where: str, i: int, walls_m: np.ndarray) -> None:
    """A ``pass_behind`` rule's walker walks straight from ``from`` to ``to``: the rule judges the
    robot against that line (:func:`evaluation.arena.nav_metrics.rule_satisfied`), and a walker
    whose line crosses a wall walks round it instead (:mod:`jaxsim.scenes.routes`), so the rule
    would judge a way nobody walks. Checked at the ranges' corners and middles."""
    if not len(walls_m):
        return
    starts, ends = np.array(_range_points(walker["start"])), np.array(_range_points(walker["end"]))
    starts, ends = np.repeat(starts, len(ends), axis=0), np.tile(ends, (len(starts), 1))  # every pair
    hits = geometry.segment_hits_boxes(starts, ends, walls_m)
    if hits.any():
        start, end = starts[np.argmax(hits)], ends[np.argmax(hits)]
        r.fail(
            where,
            f"person {i}'s straight line from ({start[0]:g}, {start[1]:g}) to ({end[0]:g}, {end[1]:g}) m "
            "crosses a wall: the walker walks round it, and pass_behind judges the robot against that "
            "straight line; give the rule a walker whose way crosses no wall",
        )


def _rule(r: _Reader, rule: Any, where: str, people: list[dict], bounds, walls_m: np.ndarray) -> dict:
    kind = r.get(rule, where, "type")
    if kind not in RULES:
        r.fail(f"{where}.type", f"expected one of {', '.join(RULES)}, got {kind!r}")
    if kind == "min_distance":
        return {"type": kind, "distance_m": r.number(r.get(rule, where, "distance_m"), f"{where}.distance_m", 0.0)[0]}
    if kind == "avoid_group":
        g = r.get(rule, where, "group", 0)
        groups = [p for p in people if p["behaviour"] == "group"]
        if isinstance(g, bool) or not isinstance(g, int) or not 0 <= g < len(groups):
            r.fail(f"{where}.group", f"expected the index of one of the scene's {len(groups)} group(s), got {g!r}")
        return {"type": kind, "group": g}
    if kind == "avoid_circle":
        return {
            "type": kind,
            "centre": _rule_point(
                r,
                r.exact_point(r.get(rule, where, "centre"), f"{where}.centre"),
                f"{where}.centre",
                bounds,
                np.zeros((0, 4)),
            ),
            "radius_m": r.number(r.get(rule, where, "radius_m"), f"{where}.radius_m", 0.0)[0],
        }
    if kind == "keep_right":
        return {
            "type": kind,
            "box": _rule_box(r, r.box(r.get(rule, where, "box"), f"{where}.box"), f"{where}.box", bounds),
            "direction_deg": r.number(r.get(rule, where, "direction_deg"), f"{where}.direction_deg")[0],
            "min_share": r.number(r.get(rule, where, "min_share", 0.5), f"{where}.min_share", 0.0, 1.0)[0],
        }
    if kind == "visit":
        return {
            "type": kind,
            "box": _rule_box(r, r.box(r.get(rule, where, "box"), f"{where}.box"), f"{where}.box", bounds),
        }
    if kind == "pass_behind":
        i = r.get(rule, where, "person")
        if isinstance(i, bool) or not isinstance(i, int) or not 0 <= i < len(people):
            r.fail(f"{where}.person", f"expected a person index in [0, {len(people)}), got {i!r}")
        if people[i]["behaviour"] != "walk":
            r.fail(f"{where}.person", f"person {i} is a {people[i]['behaviour']!r}, not a walker")
        _check_straight_walk(r, people[i], f"{where}.person", i, walls_m)
        return {"type": kind, "person": i}
    if kind == "queue":
        return {
            "type": kind,
            "head": _rule_point(
                r, r.exact_point(r.get(rule, where, "head"), f"{where}.head"), f"{where}.head", bounds, walls_m
            ),
            "direction_deg": r.number(r.get(rule, where, "direction_deg"), f"{where}.direction_deg")[0],
            "half_width_m": r.number(r.get(rule, where, "half_width_m", 0.6), f"{where}.half_width_m", 0.05, 5.0)[0],
            "length_m": r.number(r.get(rule, where, "length_m"), f"{where}.length_m", 0.0, 100.0)[0],
            "ahead_m": r.number(r.get(rule, where, "ahead_m", 1.2), f"{where}.ahead_m", 0.0, 20.0)[0],
        }
    rules = r.get(rule, where, "rules")
    if not isinstance(rules, list) or not rules:
        r.fail(f"{where}.rules", "expected a non-empty list of rules")
    return {
        "type": kind,
        "rules": [_rule(r, sub, f"{where}.rules[{i}]", people, bounds, walls_m) for i, sub in enumerate(rules)],
    }


# Bodies for the placement checks of :func:`load_scene`: a person's is the arena's
# (:data:`jaxsim.params.PERSON_RADIUS_M`, 0.25 m, the body the env measures contacts with; it was
# the warehouse workers' 0.2 m here, so a person the check let stand 0.45 m from the robot's
# start touched the robot in the env), the robot's :class:`jaxsim.scenes.robot.RobotParams` radius
# (0.275 m, TIAGo's footprint).
# A goal closer to the start than this is reached before the robot moves (the arena's goal
# tolerance is 0.3 m): an episode that tests nothing.
MIN_START_GOAL_M = 0.5


def range_gap_m(a, b) -> float:
    """The smallest distance between two points drawn from ranges ``((x0, x1), (y0, y1))``."""
    (ax0, ax1), (ay0, ay1) = a
    (bx0, bx1), (by0, by1) = b
    dx = max(0.0, bx0 - ax1, ax0 - bx1)
    dy = max(0.0, by0 - ay1, ay0 - by1)
    return math.hypot(dx, dy)


def range_span_m(a, b) -> float:
    """The largest distance between two points drawn from ranges ``((x0, x1), (y0, y1))``."""
    (ax0, ax1), (ay0, ay1) = a
    (bx0, bx1), (by0, by1) = b
    return math.hypot(max(abs(bx1 - ax0), abs(ax1 - bx0)), max(abs(by1 - ay0), abs(ay1 - by0)))


def _circles_can_meet(gap_m: float, span_m: float, radii_a, radii_b, within_m: float) -> bool:
    """Whether two circles, their centres ``gap_m .. span_m`` apart and their radii drawn from
    ``radii_a`` and ``radii_b`` (``(lo, hi)``; a point is a circle of radius 0), can pass within
    ``within_m`` of each other: the nearest points of circles of radii r1, r2 whose centres are d
    apart are ``max(d - r1 - r2, |r1 - r2| - d, 0)`` apart."""
    (lo_a, hi_a), (lo_b, hi_b) = radii_a, radii_b
    least_difference = max(0.0, lo_a - hi_b, lo_b - hi_a)
    return gap_m < hi_a + hi_b + within_m and span_m > least_difference - within_m


def _queue_angles(queue: dict) -> list[float]:
    """The directions (deg) a queue's line is checked at: the ends and middle of ``towards_deg``'s
    draws (held-out ones included) and every multiple of 45 degrees between them (so a box over
    them bounds the arc: its extremes lie at the ends or at multiples of 90)."""
    lo, hi = _extremes(queue["towards_deg"])[0], _extremes(queue["towards_deg"])[-1]
    return sorted({lo, hi, (lo + hi) / 2, *(45.0 * k for k in range(math.ceil(lo / 45), math.floor(hi / 45) + 1))})


def _queue_places(queue: dict) -> list[tuple[str, tuple]]:
    """Where a queue's people stand at the start: ``(what, point range)`` of its head and of each
    place m behind it (``head`` moved back ``m * spacing_m`` against ``towards_deg``), each place's
    range the box over the head's range and the direction's and spacing's draws."""
    (hx0, hx1), (hy0, hy1) = queue["head"]
    spacings = _extremes(queue["spacing_m"], (0.3, 3.0))
    backs = [
        (-sp * math.cos(math.radians(a)), -sp * math.sin(math.radians(a)))
        for a in _queue_angles(queue)
        for sp in spacings
    ]
    places = [("head", queue["head"])]
    for m in range(1, int(queue["length"][1])):
        xs, ys = [m * bx for bx, _ in backs], [m * by for _, by in backs]
        places.append((f"the line's place {m}", ((hx0 + min(xs), hx1 + max(xs)), (hy0 + min(ys), hy1 + max(ys)))))
    return places


def _placed_at_start(person: dict) -> list[tuple[str, str, tuple]]:
    """Where a person (a queue: each of its people) stands when the episode starts: ``(field, what,
    point range)``, ``what`` naming it in a message."""
    b = person["behaviour"]
    if b == "standing":
        return [("position", "position", person["position"])]
    if b in ("walk", "stream"):
        starts_at_once = person["start_s"][0] == 0.0
        return [("from", "from", person["start"])] if starts_at_once else []
    if b == "queue":
        return [("head" if what == "head" else "length", what, point) for what, point in _queue_places(person)]
    return []


def _check_placements(r: _Reader, robot: dict, people: list[dict]) -> None:
    """Refuse what no episode can use: the goal at the start, a person on the robot's start
    (or on its circle, for a group), two people in one place at the start (a person placed at the
    start within two bodies of another, or of a group's circle, or two groups' circles)."""
    from socialnav.jaxsim.scenes.robot import RobotParams

    robot_radius = RobotParams().radius_m
    if range_gap_m(robot["start"], robot["goal"]) < MIN_START_GOAL_M:
        r.fail(
            "robot.goal",
            f"within {MIN_START_GOAL_M} m of robot.start: the goal would be reached before the robot moves",
        )
    placed = []
    for i, person in enumerate(people):
        for key, what, point in _placed_at_start(person):
            here = "" if what == key else f"{what}: "
            if range_gap_m(point, robot["start"]) < robot_radius + PERSON_RADIUS_M:
                r.fail(
                    f"people[{i}].{key}",
                    f"{here}can be within {robot_radius + PERSON_RADIUS_M:.3f} m of robot.start: the person would "
                    f"stand on the robot (radii {PERSON_RADIUS_M} m and {robot_radius} m)",
                )
            placed.append((i, key, what, point))
        if person["behaviour"] == "group":
            (cx0, cx1), (cy0, cy1) = person["centre"]
            sx, sy = (sum(robot["start"][0]) / 2, sum(robot["start"][1]) / 2)
            gap = math.hypot(sx - (cx0 + cx1) / 2, sy - (cy0 + cy1) / 2)
            r_lo, r_hi = person["radius_m"]
            if r_lo - robot_radius - PERSON_RADIUS_M < gap < r_hi + robot_radius + PERSON_RADIUS_M:
                r.fail(f"people[{i}].centre", "the group's circle passes over robot.start: a member would stand on it")
    for a in range(len(placed)):
        for b in range(a + 1, len(placed)):
            (i, ki, wi, pi), (j, kj, wj, pj) = placed[a], placed[b]
            if i == j:  # a queue's own places: its spacing_m (legal from 0.3 m) sets them
                continue
            if range_gap_m(pi, pj) < 2 * PERSON_RADIUS_M:
                here = "" if wj == kj else f"{wj}: "
                other = f"people[{i}].{ki}" if wi == ki else f"{wi} of people[{i}]"
                r.fail(
                    f"people[{j}].{kj}",
                    f"{here}can be within {2 * PERSON_RADIUS_M} m of {other}: two people in one place at the start",
                )
    # A group's members stand anywhere on its circle (the rotation and size drawn): a person placed
    # at the start, or another group's circle, that it can pass within two bodies of is refused.
    groups = [(i, p) for i, p in enumerate(people) if p["behaviour"] == "group"]
    for g, (i, group) in enumerate(groups):
        radii = _extremes(group["radius_m"], (0.3, 5.0))
        ring = (radii[0], radii[-1])
        for j, key, what, point in placed:
            gap, span = range_gap_m(group["centre"], point), range_span_m(group["centre"], point)
            if _circles_can_meet(gap, span, ring, (0.0, 0.0), 2 * PERSON_RADIUS_M):
                here = "" if what == key else f"{what}: "
                r.fail(
                    f"people[{j}].{key}",
                    f"{here}can be within {2 * PERSON_RADIUS_M} m of the circle of people[{i}] (a group, radius_m "
                    f"{ring[0]:g}-{ring[1]:g} with held-out draws): a member could stand where this person does",
                )
        for j, other in groups[g + 1 :]:
            other_radii = _extremes(other["radius_m"], (0.3, 5.0))
            gap, span = range_gap_m(group["centre"], other["centre"]), range_span_m(group["centre"], other["centre"])
            if _circles_can_meet(gap, span, ring, (other_radii[0], other_radii[-1]), 2 * PERSON_RADIUS_M):
                r.fail(
                    f"people[{j}].centre",
                    f"the circle of people[{j}] can pass within {2 * PERSON_RADIUS_M} m of the circle of people[{i}] "
                    "(both groups, held-out draws included): members of the two could stand in one place",
                )


# The most people a scene holds at once (scripted, or a recording's peak with each slot's gaps):
# every shipped recording fits (the densest, the Jülich corridor uo-180-180-070, needs 77 slots;
# ETH/UCY's students001 76), run padded to 128. What a step costs grows with the people:
# docs/performance.md, "Human models at crowd scale".
MAX_PEOPLE_SLOTS = 128


def _recording(r: _Reader, rec: Any, timeout_s: float, people: list, bounds: tuple) -> dict:
    """The ``recording`` block: the shipped run or the user's file (known, readable, its people
    inside ``bounds_m``), the playback mode, the windows' range (room for an evaluated window
    inside it and a held-out one outside), the slots it needs."""
    from socialnav.data.recorded import RecordedDataError
    from socialnav.data.track_file import TrackFileError
    from socialnav.jaxsim.scenes import recording as recording_lib

    run = r.get(rec, "recording", "run", None)
    file_name = r.get(rec, "recording", "file", None)
    if (run is None) == (file_name is None):
        r.fail("recording", "expected either 'run' (a shipped recording) or 'file' (your own), not both or neither")
    where = "recording.run" if file_name is None else "recording.file"
    file = None
    if file_name is None:
        if not isinstance(run, str):
            r.fail(where, f"expected a run's name, got {run!r}")
    else:
        if not isinstance(file_name, str) or not file_name:
            r.fail(where, f"expected a file's path (relative to the scene file's folder), got {file_name!r}")
        file = (r.file.parent / file_name).resolve()
        if not file.is_file():
            r.fail(where, f"{file}: {'not a file' if file.exists() else 'no such file'}")
        frames_per_s = r.get(rec, "recording", "frames_per_s")
        if isinstance(frames_per_s, list):
            r.fail("recording.frames_per_s", f"expected the frame numbers' rate (one number), got {frames_per_s!r}")
        frames_per_s = r.number(frames_per_s, "recording.frames_per_s", 1e-3, 1e6)[0]
    try:
        if file is None:
            data = recording_lib.load_recording(run)
        else:
            data = recording_lib.load_recording_file(file, frames_per_s)
    except KeyError as e:
        r.fail(where, e.args[0])
    except (RecordedDataError, TrackFileError) as e:
        r.fail(where, str(e))
    run = data.run
    lo, hi = data.xy.min(0), data.xy.max(0)
    if lo[0] < bounds[0] or hi[0] > bounds[1] or lo[1] < bounds[2] or hi[1] > bounds[3]:
        r.fail(
            where,
            f"its people walk x {lo[0]:.2f} to {hi[0]:.2f} m, y {lo[1]:.2f} to {hi[1]:.2f} m, outside bounds_m "
            f"[{', '.join(f'{b:g}' for b in bounds)}]: widen the bounds or give the positions in the scene's frame",
        )
    slots = recording_lib.slots_needed(data)
    if slots > MAX_PEOPLE_SLOTS:
        r.fail(where, f"{run} has up to {slots} people at once: {MAX_PEOPLE_SLOTS} allowed")
    playback = r.get(rec, "recording", "playback")
    if playback not in PLAYBACKS:
        r.fail("recording.playback", f"expected one of {', '.join(PLAYBACKS)}, got {playback!r}")
    within = r.number(r.get(rec, "recording", "window_within_s"), "recording.window_within_s", 0.0, data.duration_s)
    if not recording_lib.window_starts_s(within, timeout_s, data.duration_s, held_out=False):
        r.fail("recording.window_within_s", f"{list(within)} is shorter than one window (timeout_s {timeout_s:g} s)")
    if not recording_lib.window_starts_s(within, timeout_s, data.duration_s, held_out=True):
        r.fail(
            "recording.window_within_s",
            f"{list(within)} leaves no held-out window of timeout_s {timeout_s:g} s outside it "
            f"(the run lasts {data.duration_s:.1f} s)",
        )
    if people:
        r.fail("people", "a scene with a recording has no scripted people (expected [])")
    recording = {"run": run, "playback": playback, "within_s": within, "slots": slots, "mirror_y_m": None}
    return recording if file is None else {**recording, "file": str(file), "frames_per_s": frames_per_s}


def load_scene(file: str | pathlib.Path) -> SceneSpec:
    """Read and validate a scene file (one :class:`ScenarioError` naming file and field on error)."""
    file = pathlib.Path(file)
    r = _Reader(file)
    if not file.is_file():
        r.fail("<file>", "file is missing")
    try:
        obj = strict_json.loads(file.read_text())
    except strict_json.DuplicateKeyError as e:
        r.fail(e.key, "given twice in one object: which one was meant?")
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        r.fail("<file>", f"invalid JSON: {e}")
    if not isinstance(obj, dict):
        r.fail("<file>", "top level must be a JSON object")
    name = r.get(obj, "", "name")
    if not is_safe_name(name):  # the name files its results: episodes/<name>.parquet
        r.fail("name", f"{name!r} cannot name the scene's result files ({name_problem(name)}): use {SAFE_NAME_RULE}")
    bounds = tuple(r.box(r.get(obj, "", "bounds_m"), "bounds_m"))
    if (bounds[1] - bounds[0]) * (bounds[3] - bounds[2]) > 2500:
        r.fail(
            "bounds_m",
            f"the scene is {(bounds[1] - bounds[0]):.0f} x {(bounds[3] - bounds[2]):.0f} m: at most 2500 m^2",
        )
    walls = r.get(obj, "", "walls")
    if not isinstance(walls, list):
        r.fail("walls", "expected a list of boxes")
    walls_m = np.array([r.box(w, f"walls[{i}]") for i, w in enumerate(walls)]).reshape(-1, 4)
    objects = []
    for i, o in enumerate(r.get(obj, "", "objects", [])):
        where = f"objects[{i}]"
        polygon = r.get(o, where, "polygon")
        if not isinstance(polygon, list) or not 3 <= len(polygon) <= MAX_OBJECT_VERTICES:
            r.fail(f"{where}.polygon", f"expected 3 to {MAX_OBJECT_VERTICES} points")
        vertices = []
        for k, v in enumerate(polygon):
            if not isinstance(v, list) or len(v) != 2:
                r.fail(f"{where}.polygon[{k}]", f"expected [x, y], got {v!r}")
            vertices.append([r.number(c, f"{where}.polygon[{k}]")[0] for c in v])
        poly = np.array(vertices)
        edges = np.roll(poly, -1, axis=0) - poly
        cross = edges[:, 0] * np.roll(edges, -1, axis=0)[:, 1] - edges[:, 1] * np.roll(edges, -1, axis=0)[:, 0]
        if np.any(cross <= 0):
            r.fail(f"{where}.polygon", "expected a convex polygon listed counter-clockwise")
        cost = r.number(r.get(o, where, "cost"), f"{where}.cost", 0.0, 252.0)[0]
        objects.append((str(r.get(o, where, "name", f"object{i}")), poly.astype(np.float32), cost))
    robot_obj = r.get(obj, "", "robot")
    robot = {
        "start": r.point(r.get(robot_obj, "robot", "start"), "robot.start"),
        "goal": r.point(r.get(robot_obj, "robot", "goal"), "robot.goal"),
        "yaw_deg": r.number(r.get(robot_obj, "robot", "yaw_deg", 0.0), "robot.yaw_deg"),
    }
    for key in ("start", "goal"):
        _inside_bounds(r, bounds, robot[key], f"robot.{key}")
        _clear_of_walls(r, walls_m, robot[key], f"robot.{key}")
    timeout = r.number(r.get(obj, "", "timeout_s"), "timeout_s", 1.0, 3600.0)[0]
    people_obj = r.get(obj, "", "people")
    if not isinstance(people_obj, list):
        r.fail("people", "expected a list")
    people, slots = [], 0
    for i, p in enumerate(people_obj):
        person, n = _person(r, p, f"people[{i}]", bounds, walls_m)
        people.append(person)
        slots += n
    if slots > MAX_PEOPLE_SLOTS:
        r.fail("people", f"{slots} people at most: {MAX_PEOPLE_SLOTS} allowed")
    for i, person in enumerate(people):
        mate = person.get("walks_with")
        if mate is None:
            continue
        walkers = [k for k, q in enumerate(people) if q["behaviour"] == "walk" and k != i]
        if isinstance(mate, bool) or not isinstance(mate, int) or mate not in walkers:
            r.fail(f"people[{i}].walks_with", f"expected the index of another walker (one of {walkers}), got {mate!r}")
    rule = _rule(r, r.get(obj, "", "rule"), "rule", people, bounds, walls_m)
    held_out = r.get(obj, "", "held_out_rule", None)
    held_out_rule = None if held_out is None else _rule(r, held_out, "held_out_rule", people, bounds, walls_m)
    stop_and_go = r.get(obj, "", "stop_and_go_m", None)
    if stop_and_go is not None:
        stop_and_go = r.number(stop_and_go, "stop_and_go_m", 0.3, 5.0)[0]
    people_in_global_plan = r.flag(obj, "", "people_in_global_plan", True)
    variants_of = r.get(obj, "", "variants_of", None)
    if variants_of is not None and not is_safe_name(variants_of):
        r.fail("variants_of", f"expected a scene's name, got {variants_of!r} ({name_problem(variants_of)})")
    _check_placements(r, robot, people)
    recording_obj = r.get(obj, "", "recording", None)
    recording = None if recording_obj is None else _recording(r, recording_obj, timeout, people, bounds)
    source = str(r.get(obj, "", "source", ""))
    r.check_every_field_read()
    spec = SceneSpec(
        file=file,
        name=name,
        source=source,
        bounds_m=bounds,
        walls_m=walls_m.astype(np.float32),
        objects=tuple(objects),
        robot=robot,
        timeout_s=timeout,
        people=tuple(people),
        rule=rule,
        n_people_slots=max(slots, 1) if recording is None else recording["slots"],
        held_out_rule=held_out_rule,
        stop_and_go_m=stop_and_go,
        people_in_global_plan=people_in_global_plan,
        recording=recording,
        variants_of=variants_of,
    )
    if recording is not None:
        from socialnav.jaxsim.scenes.variant import recorded_start_problem

        problem = recorded_start_problem(spec)
        if problem is not None:
            raise problem
    return spec


# A person's fields that are points (ranges per axis) and angles (degree ranges): what a mirror or
# a turn moves.
PERSON_POINTS = ("position", "start", "end", "centre", "head", "exit")
PERSON_ANGLES = ("heading_deg", "rotation_deg", "towards_deg")


def _moved_people(people, point, angle) -> tuple[dict, ...]:
    """``people`` with every point field moved by ``point`` and every angle by ``angle``."""
    moved = []
    for p in people:
        q = dict(p)
        q.update({key: point(q[key]) for key in PERSON_POINTS if key in q})
        q.update({key: angle(q[key]) for key in PERSON_ANGLES if key in q})
        moved.append(q)
    return tuple(moved)


def _moved_robot(robot: dict, point, angle) -> dict:
    return {"start": point(robot["start"]), "goal": point(robot["goal"]), "yaw_deg": angle(robot["yaw_deg"])}


def _moved_rule(r: dict, box, xy, direction) -> dict:
    """A rule's geometry moved: its ``box`` by ``box``, its ``centre`` and ``head`` points by ``xy``,
    its ``direction_deg`` by ``direction``, and every sub-rule of an ``all`` the same way."""
    r = dict(r)
    if "box" in r:
        r["box"] = box(r["box"])
    for key in ("centre", "head"):
        if key in r:
            r[key] = xy(r[key])
    if "direction_deg" in r:
        r["direction_deg"] = direction(r["direction_deg"])
    if "rules" in r:
        r["rules"] = [_moved_rule(sub, box, xy, direction) for sub in r["rules"]]
    return r


def mirror(spec: SceneSpec) -> SceneSpec:
    """The scene mirrored across the horizontal line through its bounds' centre (y -> c - y):
    walls, objects, people, the robot, headings and the rule's geometry; "keep right" stays keep
    right of the (mirrored) direction of travel. The rule is the file's ``held_out_rule`` where it
    gives one (mirrored the same way), and the original rule becomes the mirror's held-out rule, so
    that mirroring twice gives the scene back. Used for held-out variants: a method that learnt a
    layout's handedness rather than its rule shows it here."""
    if spec.turned_from is not None:
        raise ValueError(f"{spec.file}: a turned scene is not mirrored; mirror the file's scene")
    c = spec.bounds_m[2] + spec.bounds_m[3]

    def y_range(r):
        return (c - r[1], c - r[0])

    def point(p):
        return (p[0], y_range(p[1]))

    def angle(r):
        return (-r[1], -r[0])

    walls = spec.walls_m.copy()
    walls[:, 2], walls[:, 3] = c - spec.walls_m[:, 3], c - spec.walls_m[:, 2]
    objects = tuple(
        (name, np.stack([poly[::-1, 0], c - poly[::-1, 1]], axis=1).astype(np.float32), cost)
        for name, poly, cost in spec.objects
    )

    def box(b):
        b = np.asarray(b, float)
        return np.array([b[0], b[1], c - b[3], c - b[2]])

    def rule(r):
        return _moved_rule(r, box, lambda xy: np.array([xy[0], c - xy[1]]), lambda d: -d)

    recording = spec.recording
    if recording is not None:  # the recorded people mirrored too (twice: as recorded)
        recording = {**recording, "mirror_y_m": c if recording["mirror_y_m"] is None else None}
    return dataclasses.replace(
        spec,
        name=spec.name,
        walls_m=walls,
        objects=objects,
        robot=_moved_robot(spec.robot, point, angle),
        people=_moved_people(spec.people, point, angle),
        rule=rule(spec.rule if spec.held_out_rule is None else spec.held_out_rule),
        held_out_rule=None if spec.held_out_rule is None else rule(spec.rule),
        recording=recording,
    )


TURNED_DEG = 90.0  # the turned row's angle: a quarter turn, counter-clockwise
TURN_CELL_M = 0.2  # the grid a turn keeps whole: the arena planner's cell (ArenaConfig.grid_resolution_m)


def turn_bounds_m(bounds_m, cell_m: float = TURN_CELL_M) -> tuple[float, float, float, float]:
    """The box a scene is turned about: ``bounds_m`` grown at its top and right to whole cells of
    ``cell_m``, as a planner's grid over the bounds covers them (:func:`jaxsim.scenes.world.occupancy`),
    so that the turned grid's cells are the scene's own cells, turned."""
    xmin, xmax, ymin, ymax = (float(v) for v in bounds_m)
    width, height = (math.ceil(extent / cell_m - 1e-6) * cell_m for extent in (xmax - xmin, ymax - ymin))
    return xmin, round(xmin + width, 9), ymin, round(ymin + height, 9)


def turn_points(xy, bounds_m) -> np.ndarray:
    """Points (..., 2) turned a quarter turn counter-clockwise about the centre of ``bounds_m``
    (``xmin, xmax, ymin, ymax``: a scene's :func:`turn_bounds_m`): ``(x, y) -> (cx - (y - cy),
    cy + (x - cx))``."""
    xy = np.asarray(xy)
    cx, cy = (bounds_m[0] + bounds_m[1]) / 2, (bounds_m[2] + bounds_m[3]) / 2
    return np.stack([cx - (xy[..., 1] - cy), cy + (xy[..., 0] - cx)], axis=-1).astype(xy.dtype)


def turn(spec: SceneSpec) -> SceneSpec:
    """The scene turned a quarter turn (:data:`TURNED_DEG`) counter-clockwise about the centre of
    its :func:`turn_bounds_m` (its bounds in whole planner cells, which become its bounds): walls,
    objects, people, the robot and the rule's geometry, with headings and directions turned too.
    Its variants are the scene's own, turned (:func:`~jaxsim.scenes.variant.sample_variant` draws
    them from ``turned_from`` and turns them), and its planner grid is the scene's own grid, turned
    (:func:`jaxsim.scenes.world.occupancy`), so the turned row is a paired comparison that changes
    the orientation alone: the same people, timings and ranges (in distribution), the same cells.

    Why a quarter turn and not any angle: this simulator's walls are axis-aligned boxes (the
    people's wall field, the robot's contacts, line of sight and every planner's grid use them as
    such), and a quarter turn keeps a box a box, so the turned scene is exactly the scene; 30
    degrees would need oriented walls. What a turn can expose: a learnt cost map read in the
    world's axes (the GSCL window, :mod:`planners.layers.gscl_layer`) at an orientation the scene
    never had (the generator draws its own layouts at every orientation, :mod:`models.families`,
    so a rule learnt rather than a layout's look holds), and a grid planner whose choices depend
    on the grid's orientation (a point on a cell boundary falls in the cell on the other side once
    turned). A recorded crowd is turned with its variants. Raises ``ValueError`` for a scene
    already turned."""
    if spec.turned_from is not None:
        raise ValueError(f"{spec.file}: the scene is already turned; turn the file's scene")
    bounds = turn_bounds_m(spec.bounds_m)

    def point(p):  # a point's ranges ((xlo, xhi), (ylo, yhi)): the corners' box, turned
        corners = np.array([[x, y] for x in p[0] for y in p[1]], np.float64)
        t = turn_points(corners, bounds)
        lo, hi = np.round(t.min(axis=0), 9), np.round(t.max(axis=0), 9)
        return (float(lo[0]), float(hi[0])), (float(lo[1]), float(hi[1]))

    def angle(r):
        return (r[0] + TURNED_DEG, r[1] + TURNED_DEG)

    def box(b):  # xmin, xmax, ymin, ymax
        (x0, x1), (y0, y1) = point(((b[0], b[1]), (b[2], b[3])))
        return np.array([x0, x1, y0, y1], np.asarray(b).dtype)

    def rule(r):
        return _moved_rule(r, box, lambda xy: turn_points(np.asarray(xy, float), bounds), lambda d: d + TURNED_DEG)

    walls = np.stack([box(w) for w in spec.walls_m]).astype(np.float32) if len(spec.walls_m) else spec.walls_m
    objects = tuple(
        (name, turn_points(poly, bounds).astype(np.float32), cost) for name, poly, cost in spec.objects
    )  # a turn keeps a polygon counter-clockwise
    return dataclasses.replace(
        spec,
        bounds_m=tuple(float(v) for v in box(np.asarray(bounds, float))),
        walls_m=walls,
        objects=objects,
        robot=_moved_robot(spec.robot, point, angle),
        people=_moved_people(spec.people, point, angle),
        rule=rule(spec.rule),
        held_out_rule=None if spec.held_out_rule is None else rule(spec.held_out_rule),
        turned_from=spec,
    )
