"""Whether a scene can be finished and judged at all: a way from the start to the goal wide
enough for the robot, time enough to go it, and rule boxes the robot can enter.

A scene whose walls close the way to the goal, or leave a gap narrower than the robot, runs to the
end and scores every method 0 % goal success: a table of an impossible task that reads like one of
bad methods; a walker whose end no person can reach round the walls would stand against a wall all
episode (:func:`people_problem`). :func:`refuse_unfinishable` finds such a scene before any episode runs,
from the walls alone (people move, so they can block a way only for a while; they are not counted):
a goal within the goal tolerance of a start (:func:`arrival_problem`), a goal past the walls
(:func:`goal_problem`), a timeout shorter than the straight line from start to goal takes at the
robot's top speed (:func:`time_problem`: a bound no way round a wall or a person can beat), and a
rule's box (``visit``, ``keep_right``) the robot cannot enter (:func:`rule_problem`): a ``visit``
no method can keep, or a ``keep_right`` every method keeps by never being inside it.

How: the robot's centre can be where the exact distance to every wall box and to the scene's bounds
(the planners' edge of the world) is at least its radius. Those cells of a grid of
:data:`~jaxsim.scenes.routes.RESOLUTION_M` form connected regions (8 neighbours,
:func:`scipy.ndimage.label`; :func:`~jaxsim.scenes.routes.free_regions`); the goal is reachable
when a cell within the goal tolerance of it lies in a region the robot's start reaches, for the
middle and every corner of the start's and the goal's ranges; a rule's box can be entered when a
cell inside it does. The grid errs towards "reachable": a cell counts as free when its clearance is
up to one cell short of the radius, so a way the robot fits through is never refused (whatever the
grid's offset or the way's angle), one narrower than the robot by up to two cells (10 cm) may pass,
and one narrower by more is refused: the check refuses what is clearly impossible, not what is
tight.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Iterator

import numpy as np

from socialnav.jaxsim.scenario.errors import ScenarioError
from socialnav.jaxsim.scenes import routes
from socialnav.jaxsim.scenes.robot import RobotParams
from socialnav.jaxsim.scenes.routes import free_regions
from socialnav.jaxsim.scenes.spec import SceneSpec, range_gap_m

Range = tuple[tuple[float, float], tuple[float, float]]  # a scene's point: ((x0, x1), (y0, y1)) in metres
Problem = tuple[str, str]  # (the scene file's field, why)


def _corners_and_middle(point: Range) -> list[tuple[float, float]]:
    """A point's range as its middle and its four corners."""
    (x0, x1), (y0, y1) = point
    return [((x0 + x1) / 2, (y0 + y1) / 2), *itertools.product((x0, x1), (y0, y1))]


def _regions_near(regions, xy, within_m: float) -> set[int]:
    """The regions with a cell whose centre is within ``within_m`` of ``xy``."""
    labels, xs, ys = regions
    near = (xs[None, :] - xy[0]) ** 2 + (ys[:, None] - xy[1]) ** 2 <= within_m**2
    return set(np.unique(labels[near]).tolist()) - {0}


def goal_problem(regions, start: Range, goal: Range, robot_radius_m: float, goal_tolerance_m: float) -> Problem | None:
    """``robot.goal`` when the robot cannot come within ``goal_tolerance_m`` of ``goal`` from
    ``start`` in :func:`free_regions`' ``regions`` (``robot.start`` where its body has no room at
    the start at all); None when it can, for the middle and every corner of both ranges."""
    width = f"a robot of radius {robot_radius_m:g} m (a way {2 * robot_radius_m:g} m wide)"
    starts = []
    for x, y in _corners_and_middle(start):
        near = _regions_near(regions, (x, y), robot_radius_m)
        if not near:
            return "robot.start", f"({x:g}, {y:g}) leaves no room for {width} between the walls"
        starts.append(((x, y), near))
    for gx, gy in _corners_and_middle(goal):
        goal_regions = _regions_near(regions, (gx, gy), goal_tolerance_m)
        for (sx, sy), near in starts:
            if not near & goal_regions:
                return (
                    "robot.goal",
                    f"({gx:g}, {gy:g}) cannot be reached from robot.start ({sx:g}, {sy:g}) by {width}: "
                    "the walls close the way or leave it narrower",
                )
    return None


def arrival_problem(start: Range, goal: Range, goal_tolerance_m: float) -> Problem | None:
    """``robot.goal`` when some start and goal the ranges draw lie within ``goal_tolerance_m`` of
    each other: that episode ends before the robot moves (the scene file keeps them
    :data:`~jaxsim.scenes.spec.MIN_START_GOAL_M` apart, which a larger tolerance undoes)."""
    gap_m = range_gap_m(start, goal)
    if gap_m > goal_tolerance_m:
        return None
    return (
        "robot.goal",
        f"can be {gap_m:.2f} m from robot.start, within the goal tolerance of {goal_tolerance_m:g} m "
        "(EnvConfig.goal_tolerance_m): an episode would end before the robot moves",
    )


def time_problem(
    start: Range, goal: Range, timeout_s: float, max_speed_mps: float, goal_tolerance_m: float
) -> Problem | None:
    """``timeout_s`` when, for some start and goal the ranges draw (their corners and middles),
    the straight line to within ``goal_tolerance_m`` of the goal takes longer at ``max_speed_mps``
    than ``timeout_s``; None when every draw has time enough."""
    (sx, sy), (gx, gy) = max(
        itertools.product(_corners_and_middle(start), _corners_and_middle(goal)),
        key=lambda pair: np.hypot(pair[1][0] - pair[0][0], pair[1][1] - pair[0][1]),
    )
    distance_m = max(float(np.hypot(gx - sx, gy - sy)) - goal_tolerance_m, 0.0)
    needed_s = distance_m / max_speed_mps
    if needed_s <= timeout_s:
        return None
    return (
        "timeout_s",
        f"{timeout_s:g} s is shorter than the {needed_s:.1f} s the robot needs at its top speed "
        f"({max_speed_mps:g} m/s) for the {distance_m:.2f} m from robot.start ({sx:g}, {sy:g}) to within "
        f"{goal_tolerance_m:g} m of robot.goal ({gx:g}, {gy:g}) in a straight line",
    )


def _boxes_of(rule: dict, where: str) -> Iterator[tuple[str, np.ndarray]]:
    """``(where, box)`` of every box rule in ``rule`` (the rules of an ``all`` included)."""
    if rule["type"] in ("visit", "keep_right"):
        yield f"{where}.box", rule["box"]
    for i, sub in enumerate(rule.get("rules", ())):
        yield from _boxes_of(sub, f"{where}.rules[{i}]")


def rule_problem(regions, start: Range, rules: Iterable[tuple[str, dict]], robot_radius_m: float) -> Problem | None:
    """The first box of ``rules`` (``(field, rule)`` pairs) with no cell of ``regions`` the robot
    can reach from ``start``; None when every box has one."""
    reached = set().union(*(_regions_near(regions, xy, robot_radius_m) for xy in _corners_and_middle(start)))
    labels, xs, ys = regions
    for where, box in (pair for name, rule in rules for pair in _boxes_of(rule, name)):
        x0, x1, y0, y1 = (float(v) for v in box)
        inside = labels[np.ix_((ys >= y0) & (ys <= y1), (xs >= x0) & (xs <= x1))]
        if not reached & set(np.unique(inside).tolist()):
            return (
                where,
                f"{[x0, x1, y0, y1]} holds no place a robot of radius {robot_radius_m:g} m can reach from "
                "robot.start: the rule would be kept or broken by every method alike",
            )
    return None


def people_problem(people, bounds_m, walls_m: np.ndarray) -> Problem | None:
    """``people[i].to`` (a queue's ``people[i].exit``) of the first walker, stream or queue of a
    scene's ``people`` (:attr:`~jaxsim.scenes.spec.SceneSpec.people`) that, for some start and end
    its ranges draw (their middles and corners; a queue's head and exit), has no way round the
    walls (K, 4) within ``bounds_m`` a person's body fits through, or one of more corners than a
    variant holds (:func:`jaxsim.scenes.routes.waypoints`); None when every one has its way. Such
    a person would stand against a wall all episode."""
    for i, person in enumerate(people):
        if person["behaviour"] not in routes.WAYS:
            continue
        start_field, end_field, named = routes.WAYS[person["behaviour"]]
        ends = itertools.product(_corners_and_middle(person[start_field]), _corners_and_middle(person[end_field]))
        for start, end in ends:
            try:
                routes.waypoints(start, end, walls_m, bounds_m)
            except routes.NoRoute as e:
                return f"people[{i}].{named}", str(e)
    return None


def refuse_unfinishable(
    spec: SceneSpec, robot: RobotParams, goal_tolerance_m: float, check_timeout: bool = True
) -> None:
    """Raise :class:`~jaxsim.scenario.errors.ScenarioError`, naming the scene file and its field,
    for the first reason no method can finish the scene, or be told apart by its rule, with
    ``robot`` (a walker with no way to its end, :func:`people_problem`; a start within the goal
    tolerance, the goal, the timeout, then the rule and held-out rule's boxes, both written in the
    file's frame); nothing when there is none. ``check_timeout=False`` leaves the scene's
    ``timeout_s`` out, where something else sets an episode's length."""
    radius_m, speed_mps = float(robot.radius_m), float(robot.max_speed_mps)
    regions = free_regions(spec.bounds_m, spec.walls_m, radius_m)
    start, goal = spec.robot["start"], spec.robot["goal"]
    rules = [("rule", spec.rule)] + ([("held_out_rule", spec.held_out_rule)] if spec.held_out_rule else [])
    problem = (
        people_problem(spec.people, spec.bounds_m, spec.walls_m)
        or arrival_problem(start, goal, goal_tolerance_m)
        or goal_problem(regions, start, goal, radius_m, goal_tolerance_m)
        or (time_problem(start, goal, spec.timeout_s, speed_mps, goal_tolerance_m) if check_timeout else None)
        or rule_problem(regions, start, rules, radius_m)
    )
    if problem is not None:
        raise ScenarioError(spec.file, *problem)


def scene_problem(
    spec: SceneSpec,
    robot_radius_m: float,
    max_speed_mps: float,
    goal_tolerance_m: float,
    check_timeout: bool = True,
) -> Problem | None:
    """:func:`refuse_unfinishable`'s reason as a value, for a robot of ``robot_radius_m`` and
    ``max_speed_mps``: ``(field, why)``, or None when there is none."""
    robot = RobotParams(max_speed_mps=max_speed_mps, radius_m=robot_radius_m)
    try:
        refuse_unfinishable(spec, robot, goal_tolerance_m, check_timeout)
    except ScenarioError as e:
        return e.field, e.reason
    return None
