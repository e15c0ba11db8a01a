"""Variants of a scene: every range of a :class:`~jaxsim.scenes.spec.SceneSpec` drawn, the people
expanded into fixed-size, masked arrays (:class:`Variant`), a batch stacked on a leading axis.

Variant ``k`` of a scene under seed ``s`` is drawn from ``numpy.random.default_rng((s, k,
crc32(name)))`` (the scene file's ``variants_of`` in place of its name where it gives one): the
same for every method (common random numbers) and independent of how many variants are drawn.
"""

from __future__ import annotations

import dataclasses
import math
import zlib
from collections.abc import Sequence

import numpy as np
from flax import struct

from socialnav.jaxsim.params import PERSON_RADIUS_M, TIAGO_RADIUS_M
from socialnav.jaxsim.scenario.errors import ScenarioError
from socialnav.jaxsim.scenes import recording as recording_lib
from socialnav.jaxsim.scenes import routes
from socialnav.jaxsim.scenes.spec import KIND, TURNED_DEG, SceneSpec, turn_bounds_m, turn_points

# A recorded scene's robot starts at least this far from everyone recorded there at time 0
# (centre to centre: the robot's and a person's radii and a quarter metre): its first step is
# not a contact it could not avoid.
RECORDED_START_CLEAR_M = TIAGO_RADIUS_M + PERSON_RADIUS_M + 0.25


@struct.dataclass
class Variant:
    """One drawn variant (P people slots; float32 unless said; a batch adds a leading axis).

    Attributes:
      kind: (P,) int32 behaviour (:data:`jaxsim.scenes.spec.KIND`; group members are standing).
      valid: (P,) bool, the slot holds a person of this variant.
      xy0: (P, 2) initial position (a stream's entry point); heading0: (P,) initial heading.
      start_xy, end_xy: (P, 2) a walker's or stream member's legs.
      waypoints_xy: (P, W, 2) the corners of a walker's or stream member's way round the walls
        from ``start_xy`` to ``end_xy`` (:func:`jaxsim.scenes.routes.waypoints`; W =
        :data:`~jaxsim.scenes.routes.MAX_WAYPOINTS`, the first ``n_waypoints`` used; a return leg
        walks them backwards); n_waypoints: (P,) int32, 0 where the straight line crosses no wall.
      speed_mps: (P,) desired speed; start_s: (P,) when a walker sets off or a stream member enters.
      back_and_forth, ignore_robot: (P,) bool.
      turn_at_s: (P,) when a group member turns inward (``inf``: never); heading_turned: (P,) after.
      queue_place: (P,) int32 place in the queue (0 at the head); queue_head: (P, 2); queue_step:
        (P, 2) from one place to the next one back; queue_interval_s: (P,); exit_xy: (P, 2).
      group: (P,) int32 standing group index (-1: none).
      walking_group: (P,) int32 walkers who walk together share one (-1: alone;
        :mod:`jaxsim.groups`).
      track_xy: (P, F, 2) a recorded scene's people sampled every
        :data:`jaxsim.scenes.recording.RECORD_DT_S` from the episode's start; track_present:
        (P, F) bool (a scene without a recording: F = 1, nobody); window_start_s: () where the
        window begins in its run (0 without one); reactive: () bool, the recorded crowd is played
        reactively (False: replayed, or no recording).
      robot_xy: (2,) start; robot_yaw: (); goal_xy: (2,).
      seed_u32: () uint32 seed of the people's random force.
      noise_turns: () float32 turns added to the angle of the social force's random push: 0, or a
        turned scene's quarter (:func:`turn_variant`), so a person's pushes turn with the scene.
    """

    kind: np.ndarray
    valid: np.ndarray
    xy0: np.ndarray
    heading0: np.ndarray
    start_xy: np.ndarray
    end_xy: np.ndarray
    waypoints_xy: np.ndarray
    n_waypoints: np.ndarray
    speed_mps: np.ndarray
    start_s: np.ndarray
    back_and_forth: np.ndarray
    ignore_robot: np.ndarray
    turn_at_s: np.ndarray
    heading_turned: np.ndarray
    queue_place: np.ndarray
    queue_head: np.ndarray
    queue_step: np.ndarray
    queue_interval_s: np.ndarray
    exit_xy: np.ndarray
    group: np.ndarray
    walking_group: np.ndarray
    track_xy: np.ndarray
    track_present: np.ndarray
    window_start_s: np.ndarray
    reactive: np.ndarray
    robot_xy: np.ndarray
    robot_yaw: np.ndarray
    goal_xy: np.ndarray
    seed_u32: np.ndarray
    noise_turns: np.ndarray


class _Drawer:
    """Draws a scene's ranges: inside them, or (``held_out``) just outside them.

    Held out, a range ``[lo, hi]`` of width ``w`` gives a value in ``[lo - w/2, lo)`` or ``(hi, hi +
    w/2]`` (clipped to what the field allows); a count (group size, queue length) only below ``lo``
    (its slots are reserved for ``hi``); positions stay inside their ranges (outside, they would
    fall into walls); a fixed number stays fixed.
    """

    def __init__(self, rng: np.random.Generator, held_out: bool):
        self.rng, self.held_out = rng, held_out

    def number(self, value, legal=(-np.inf, np.inf)) -> float:
        lo, hi = float(value[0]), float(value[1])
        if lo == hi:
            return lo
        if not self.held_out:
            return float(self.rng.uniform(lo, hi))
        half = (hi - lo) / 2
        below, above = (max(lo - half, legal[0]), lo), (hi, min(hi + half, legal[1]))
        side = below if (self.rng.uniform() < 0.5 and below[1] > below[0]) or above[1] <= above[0] else above
        return float(self.rng.uniform(*side)) if side[1] > side[0] else lo

    def count(self, value, legal_low: int) -> int:
        lo, hi = int(value[0]), int(value[1])
        if self.held_out and lo > legal_low:
            return int(self.rng.integers(legal_low, lo))
        return lo if lo == hi else int(self.rng.integers(lo, hi + 1))

    def point(self, value) -> np.ndarray:
        inside = _Drawer(self.rng, False)
        return np.array([inside.number(value[0]), inside.number(value[1])], np.float32)


def padded_slots(n_slots: int) -> int:
    """The people slots a scene with ``n_slots`` is run with: a power of two, at least 2.

    Scenes whose padded shapes agree share one compiled episode program (:mod:`evaluation.arena.episodes`);
    the rule depends on the scene alone, so a scene gives the same episodes whichever other scenes
    run beside it. Empty slots change nothing: a slot's random force is drawn by its index
    (:func:`jaxsim.rng.hash_uniform16`) and every sum over people masks absent ones."""
    return max(2, 1 << (max(int(n_slots), 1) - 1).bit_length())


def walking_groups(people: Sequence[dict], slot_of: list[int], n_slots: int) -> np.ndarray:
    """(n_slots,) int32: the walkers of a scene's ``people`` (its file's entries, person ``i`` in
    slot ``slot_of[i]``) linked by ``walks_with`` (chains joined) share the lowest slot among them
    as their id; everyone else -1."""
    label = np.arange(n_slots)
    mates = [(i, p.get("walks_with")) for i, p in enumerate(people)]
    links = [(slot_of[i], slot_of[k]) for i, k in mates if k is not None]
    for _ in range(len(links)):
        for a, b in links:
            label[a] = label[b] = min(label[a], label[b])
    linked = {s for pair in links for s in pair}
    return np.array([label[k] if k in linked else -1 for k in range(n_slots)], np.int32)


def sample_variant(
    spec: SceneSpec, seed: int, k: int, held_out: bool = False, n_slots: int = 0, training: bool = False
) -> Variant:
    """Variant ``k`` of ``spec`` under ``seed`` (numpy arrays); ``held_out`` draws every range just
    outside itself (:class:`_Drawer`); ``n_slots`` pads the people to that many slots (at least the
    scene's own; the draws do not depend on it).

    ``training`` draws from a stream of its own (the ranges as usual): the random generator's
    entropy gets a last word (2) that no evaluation draw has, so no training variant is ever a
    variant the benchmark evaluates on, whatever the seeds.

    A turned scene (:func:`~jaxsim.scenes.spec.turn`) gives the variant of the scene it was turned
    from, turned (:func:`turn_variant`): the same draw, paired with the scene's own variant ``k``."""
    if held_out and training:
        raise ValueError("a variant is drawn held out or for training, not both")
    if spec.turned_from is not None:
        drawn = sample_variant(spec.turned_from, seed, k, held_out, n_slots, training)
        return turn_variant(drawn, turn_bounds_m(spec.turned_from.bounds_m))
    # A recorded scene draws by its run's name: its replayed and reactive scenes play the same
    # windows from the same starts (a paired comparison of the two playbacks).
    # A copy of a scene (``variants_of``) draws by the name of the scene it copies.
    stream = (spec.variants_of or spec.name) if spec.recording is None else f"recording:{spec.recording['run']}"
    entropy = (int(seed), int(k), zlib.crc32(stream.encode())) + ((1,) if held_out else ()) + ((2,) if training else ())
    rng = np.random.default_rng(entropy)
    draw = _Drawer(rng, held_out)
    n = max(spec.n_people_slots, int(n_slots))
    f32 = lambda shape=(): np.zeros(shape, np.float32)
    a = dict(
        kind=np.zeros(n, np.int32),
        valid=np.zeros(n, bool),
        xy0=f32((n, 2)),
        heading0=f32(n),
        start_xy=f32((n, 2)),
        end_xy=f32((n, 2)),
        waypoints_xy=f32((n, routes.MAX_WAYPOINTS, 2)),
        n_waypoints=np.zeros(n, np.int32),
        speed_mps=f32(n),
        start_s=f32(n),
        back_and_forth=np.zeros(n, bool),
        ignore_robot=np.zeros(n, bool),
        turn_at_s=np.full(n, np.inf, np.float32),
        heading_turned=f32(n),
        queue_place=np.zeros(n, np.int32),
        queue_head=f32((n, 2)),
        queue_step=f32((n, 2)),
        queue_interval_s=np.ones(n, np.float32),
        exit_xy=f32((n, 2)),
        group=np.full(n, -1, np.int32),
        walking_group=np.full(n, -1, np.int32),
    )
    slot, group_index = 0, 0
    slot_of = []

    def route(start, end, slot, field: str = "to") -> float:
        """Fill ``slot``'s way round the walls (:func:`jaxsim.scenes.routes.waypoints`; none where
        the straight line crosses no wall) and return its first heading (rad), towards its first
        corner or its end; no way is a :class:`ScenarioError` naming the person's ``field``."""
        try:
            corners = routes.waypoints(start, end, spec.walls_m, spec.bounds_m)
        except routes.NoRoute as e:
            raise ScenarioError(spec.file, f"people[{len(slot_of) - 1}].{field}", str(e)) from None
        a["waypoints_xy"][slot, : len(corners)] = corners
        a["n_waypoints"][slot] = len(corners)
        first = corners[0] if len(corners) else end
        return math.atan2(first[1] - start[1], first[0] - start[0])

    for person in spec.people:
        slot_of.append(slot)
        b = person["behaviour"]
        if b == "standing":
            xy = draw.point(person["position"])
            a["xy0"][slot], a["start_xy"][slot], a["end_xy"][slot] = xy, xy, xy
            a["heading0"][slot] = math.radians(draw.number(person["heading_deg"]))
            a["valid"][slot] = True
            slot += 1
        elif b == "walk":
            start, end = draw.point(person["start"]), draw.point(person["end"])
            a["kind"][slot] = KIND["walk"]
            a["xy0"][slot], a["start_xy"][slot], a["end_xy"][slot] = start, start, end
            a["heading0"][slot] = route(start, end, slot)
            a["speed_mps"][slot] = draw.number(person["speed_mps"], (0.05, 3.0))
            a["start_s"][slot] = draw.number(person["start_s"], (0.0, np.inf))
            a["back_and_forth"][slot] = person["back_and_forth"]
            a["ignore_robot"][slot] = person["ignore_robot"]
            a["valid"][slot] = True
            slot += 1
        elif b == "group":
            size = draw.count(person["size"], 2)
            centre, radius = draw.point(person["centre"]), draw.number(person["radius_m"], (0.3, 5.0))
            rotation = math.radians(draw.number(person["rotation_deg"]))
            turn = (
                None if person["turn_inward_at_s"] is None else draw.number(person["turn_inward_at_s"], (0.0, np.inf))
            )
            slots = int(person["size"][1])
            for m in range(size):
                angle = rotation + 2 * math.pi * m / size
                xy = centre + radius * np.array([math.cos(angle), math.sin(angle)], np.float32)
                inward = angle + math.pi
                a["xy0"][slot + m], a["start_xy"][slot + m], a["end_xy"][slot + m] = xy, xy, xy
                a["heading0"][slot + m] = inward if person["facing"] == "in" else angle
                a["heading_turned"][slot + m] = inward
                a["turn_at_s"][slot + m] = np.inf if turn is None else turn
                a["group"][slot + m] = group_index
                a["valid"][slot + m] = True
            slot += slots
            group_index += 1
        elif b == "queue":
            length = draw.count(person["length"], 1)
            head = draw.point(person["head"])
            towards = math.radians(draw.number(person["towards_deg"]))
            spacing = draw.number(person["spacing_m"], (0.3, 3.0))
            back = -spacing * np.array([math.cos(towards), math.sin(towards)], np.float32)
            interval = draw.number(person["advance_every_s"], (1.0, np.inf))
            exit_xy = draw.point(person["exit"])
            for m in range(length):
                xy = head + m * back
                a["kind"][slot + m] = KIND["queue"]
                a["xy0"][slot + m], a["start_xy"][slot + m], a["end_xy"][slot + m] = xy, xy, exit_xy
                a["heading0"][slot + m] = towards
                a["speed_mps"][slot + m] = 1.0
                a["queue_place"][slot + m] = m
                a["queue_head"][slot + m], a["queue_step"][slot + m] = head, back
                a["queue_interval_s"][slot + m] = interval
                a["exit_xy"][slot + m] = exit_xy
                route(head, exit_xy, slot + m, "exit")  # served, from the head round the walls
                a["valid"][slot + m] = True
            slot += int(person["length"][1])
        else:  # stream
            start0 = draw.number(person["start_s"], (0.0, np.inf))
            interval = draw.number(person["interval_s"], (0.1, np.inf))
            for m in range(person["count"]):
                start, end = draw.point(person["start"]), draw.point(person["end"])
                a["kind"][slot + m] = KIND["stream"]
                a["xy0"][slot + m], a["start_xy"][slot + m], a["end_xy"][slot + m] = start, start, end
                a["heading0"][slot + m] = route(start, end, slot + m)
                a["speed_mps"][slot + m] = draw.number(person["speed_mps"], (0.05, 3.0))
                a["start_s"][slot + m] = start0 + m * interval
                a["ignore_robot"][slot + m] = person["ignore_robot"]
                a["valid"][slot + m] = True
            slot += person["count"]
    a["walking_group"] = walking_groups(spec.people, slot_of, n)
    robot = spec.robot
    if spec.recording is None:
        track_xy, track_present = recording_lib.empty_tracks(n)
        start_s, robot_xy = 0.0, draw.point(robot["start"])
    else:
        track_xy, track_present, start_s, robot_xy = _recorded_window(spec, rng, draw, n, held_out)
        a["kind"][:] = KIND["recorded"]
        a["valid"][:] = track_present.any(axis=1)
        a["xy0"][:] = track_xy[:, 0]
        step = track_xy[:, 1] - track_xy[:, 0]
        a["heading0"][:] = np.arctan2(step[:, 1], step[:, 0])
    return Variant(
        **a,
        track_xy=track_xy,
        track_present=track_present,
        window_start_s=np.float32(start_s),
        reactive=np.bool_(spec.recording is not None and spec.recording["playback"] == "reactive"),
        robot_xy=robot_xy,
        robot_yaw=np.float32(math.radians(draw.number(robot["yaw_deg"]))),
        goal_xy=draw.point(robot["goal"]),
        seed_u32=np.uint32(rng.integers(0, 2**32, dtype=np.uint64)),
        noise_turns=np.float32(0.0),
    )


def turn_variant(variant: Variant, bounds_m) -> Variant:
    """``variant`` (one, or a batch) turned a quarter turn counter-clockwise about the centre of
    ``bounds_m`` (the scene's :func:`~jaxsim.scenes.spec.turn_bounds_m`;
    :func:`~jaxsim.scenes.spec.turn_points`): every position, the queue's step between places, the
    recorded tracks, every heading (kept in [-pi, pi)) and the people's random pushes
    (``noise_turns``)."""
    quarter = math.radians(TURNED_DEG)

    def heading(a):
        return ((a + quarter + np.pi) % (2 * np.pi) - np.pi).astype(a.dtype)

    def step(v):  # a displacement: turned without the centre
        return np.stack([-v[..., 1], v[..., 0]], axis=-1).astype(v.dtype)

    points = ("xy0", "start_xy", "end_xy", "waypoints_xy", "queue_head", "exit_xy", "track_xy", "robot_xy", "goal_xy")
    return variant.replace(
        **{name: turn_points(getattr(variant, name), bounds_m) for name in points},
        queue_step=step(variant.queue_step),
        heading0=heading(variant.heading0),
        heading_turned=heading(variant.heading_turned),
        robot_yaw=heading(np.asarray(variant.robot_yaw)),
        noise_turns=(variant.noise_turns + TURNED_DEG / 360.0).astype(np.float32),
    )


START_DRAWS = 200  # windows and starts drawn for a recorded variant before its scene is refused


def _recorded_window(spec: SceneSpec, rng: np.random.Generator, draw: _Drawer, n: int, held_out: bool):
    """A recorded scene's window and robot start: ``(track_xy, track_present, start_s, robot_xy)``.

    The window is drawn from the file's ``window_within_s`` (held out: outside it), the start from
    ``robot.start``; both are drawn again until nobody recorded is within
    :data:`RECORDED_START_CLEAR_M` of the start at time 0 (a :class:`ScenarioError` naming
    ``robot.start`` after :data:`START_DRAWS` tries)."""
    rec = spec.recording
    data = recording_lib.load(rec)
    intervals = recording_lib.window_starts_s(rec["within_s"], spec.timeout_s, data.duration_s, held_out)
    n_samples = recording_lib.samples_per_episode(spec.timeout_s)
    for _ in range(START_DRAWS):
        first = recording_lib.draw_window_start(rng, intervals)
        xy, present = recording_lib.window(data, first, n_samples, n, rec["mirror_y_m"])
        robot_xy = draw.point(spec.robot["start"])
        gap = np.linalg.norm(xy[present[:, 0], 0] - robot_xy, axis=-1)
        if np.all(gap >= RECORDED_START_CLEAR_M):
            return xy, present, first * recording_lib.RECORD_DT_S, robot_xy
    raise ScenarioError(
        spec.file,
        "robot.start",
        f"no start clear of the recorded people ({RECORDED_START_CLEAR_M:.3f} m) in {START_DRAWS} draws of a "
        f"{'held-out ' if held_out else ''}window and a start: the start lies where they walk; move it",
    )


def recorded_start_problem(spec: SceneSpec) -> ScenarioError | None:
    """The error a recorded scene's variants would meet (None where there is none): a robot start
    never clear of the recorded people in :data:`START_DRAWS` draws of an evaluated window, or
    of a held-out one (a stream of its own, not a variant's). Checked when the scene is read, so
    that a start inside the crowd's path is refused before any work, not in a variant's draw."""
    for held_out in (False, True):
        rng = np.random.default_rng((0, 3, int(held_out)))  # 3: no variant's stream
        try:
            _recorded_window(spec, rng, _Drawer(rng, held_out), spec.n_people_slots, held_out)
        except ScenarioError as e:
            return e
    return None


def sample_variants(
    spec: SceneSpec,
    seed: int,
    n: int,
    first: int = 0,
    held_out: bool = False,
    n_slots: int = 0,
    training: bool = False,
) -> Variant:
    """Variants ``first .. first + n - 1``, stacked on a leading axis (``n_slots``, ``training``:
    as :func:`sample_variant`)."""
    variants = [sample_variant(spec, seed, k, held_out, n_slots, training) for k in range(first, first + n)]
    return Variant(**{f.name: np.stack([getattr(v, f.name) for v in variants]) for f in dataclasses.fields(Variant)})
