"""Social-navigation metrics of one episode, from its trajectory arrays (pure JAX: vmap over episodes).

Every definition pinned here, with its source and the choice where the suites disagree
(``../shared/notes/social-navigation.md`` Sec. 2). Distances are **centre to centre** (as seeds
001 and 004 and SocNavBench report them; HuNavSim subtracts the radii) unless the name says
otherwise. Sampled at the episode's step (0.1 s); only steps before the goal is reached count
for the proxemic and person-distance metrics (after that the robot has arrived).

* ``goal_success``: the centre within the goal tolerance before the timeout (HuNavSim's reading;
  a collision does not void it, unlike Francis et al.'s S; ``collisions`` is reported apart).
* ``social_success``: goal success and the scene's rule (:mod:`jaxsim.scenes.spec`).
* ``goal_no_collision``, ``social_no_collision``: the same with no collision before arrival, as
  if a collision ended the run: seed 002's reading (Sec. 5.3.1: the baselines "frequently result
  in collisions that prevent goal completion") and Francis et al.'s S.
* ``collisions``: encounters of a present person closer than robot radius + person radius,
  counted once per encounter (:func:`evaluation.metrics.collision_encounters`), split into
  ``collisions_robot`` (the robot moving towards the person faster than the person towards it,
  at the encounter's start) and ``collisions_person``.
* ``time_s`` (tau, seed 004): to the goal (the timeout when not reached); ``path_length_m`` (d_t):
  distance driven to then; ``chc_rad``: cumulative heading change, sum of wrapped yaw changes at
  10 Hz (rate-dependent: HuNavSim samples at 1 Hz); ``stalled_s``: time below 0.05 m/s before the
  goal; ``spl``: success x straight-line distance / max(driven, straight line) (social-jym's form).
* ``d_h_m``: mean over time of the distance to the nearest present person (seed 004 Eq. 16);
  ``d_min_m``: the smallest over time and people; ``d_person_m`` (P,): per person (d_1, d_2).
* ``zone_share``: share of time with the nearest person in each Hall zone, intimate < 0.45 m,
  personal < 1.2, social < 3.6, public beyond or nobody present (seeds 002, 004; seed 000 uses 0.5
  for intimate); the four shares sum to 1. ``zone_share_body``: the same zones body to body (the
  nearest centre's distance less both radii: HuNavSim's reading). Centre to centre, the intimate
  zone (0.45 m) lies inside contact (robot radius + person radius, 0.525 m for the arena's TIAGo
  and people): time in it means overlapping bodies. Seed 002 uses Hall's zones without saying
  which distance; its Table 2 is compared both ways (:func:`evaluation.arena.papers.stats_comparison`).
* ``intrusions``: personal-space entries: entries of the robot into a person's 1.2 m (one per
  entry, per person); ``intruded``: whether the robot entered anyone's 1.2 m at all, which is
  what seed 001 counts ("the number of times the robot intrudes the personal spaces" never
  exceeds its number of trials: SNL's 33 in 33 head-on trials, "every trial" in the group).
* ``ttc_min_s``: smallest time to collision at constant velocities over the episode (inf if none).
* ``group_share``: share of time inside a group's circle (its members' mean distance to their
  centroid); ``group_intrusions``: entries into such a circle (an F-formation's o- and p-space,
  approximated by the circle through its members; SEAN 2.0 and Francis et al. count group-space
  intrusions, SocNavBench does not).

Motion quality (before arrival; Francis et al. 2025, SocNavBench, robot_sf):

* ``speed_mean_mps``, ``turn_rate_mean_rps`` (mean |yaw rate|), ``accel_mean_mps2`` (mean |dv/dt|),
  ``jerk_mean_mps3`` (mean |d2v/dt2|), by finite differences of the 10 Hz record (SocNavBench
  differentiates its own 10 Hz trajectory the same way; its jerk is of the planar velocity, ours
  of the speed along the heading: the base cannot move sideways).
* ``path_irregularity_rad_per_m``: turning beyond the one turn needed to face the goal from the
  start, per metre driven (Guzzi et al. 2013, Francis et al.'s definition; HuNavSim reports the
  raw cumulative heading change).
* ``path_length_ratio``: driven over the straight line from the start to the goal's tolerance
  circle (>= 1 to float rounding; the inverse of social-jym's path efficiency and of SPL's ratio).
* ``deadlock``: not arrived, and less than ``DEADLOCK_PROGRESS_M`` of progress towards the goal in
  the last ``DEADLOCK_S`` of the episode (stuck, as robot_sf's and Francis et al.'s "deadlock"
  apart from a slow timeout); ``timeout``: not arrived and not deadlocked;
  ``no_progress_max_s``: the longest stretch without progress before arrival.

Safety apart from centres:

* ``clearance_min_m``: the smallest body-to-body gap (``d_min_m`` minus both radii; HuNavSim's
  reading); ``near_misses``: encounters closer than ``NEAR_MISS_M`` body to body that stay
  without contact (counted once each, like collisions).
* ``intrusions_robot`` / ``intrusions_person``: personal-space entries split as collisions are,
  by who closed in faster at the entry (the robot moving into a person vs a person walking up to
  a robot that stands or moves slower).
* ``wall_contacts`` (the base's count of moves that would have entered a wall) is reported by
  the arena beside these.

The robot's effect on the people (counterfactual, :func:`people_effect`): each variant is run a
second time with the robot standing far away (:func:`evaluation.arena.episodes.without_robot`: its force
exactly 0), everything else equal: the same draws, the same random force stream (common random
numbers), so the second run is the crowd as it would have moved without the robot.
``people_speed_drop_mps``: the people's mean speed without the robot minus with it (mean over the
people who move; negative where detours make them walk faster); ``people_deviation_m``: the mean
over people and time of the distance between their two positions; ``people_deviation_max_m``: its
largest value. Exactly 0 where the people ignore the robot; nearly 0 where it never comes near
anyone (the social force's exponential tail).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from socialnav.evaluation.metrics import collision_encounters
from socialnav.jaxsim.scenes import rule_monitor
from socialnav.planners.layers.scene import wrap_angle

VERSION = "nav-metrics 5"  # 5: zone_share_body; 4: goal_no_collision, social_no_collision; 3: intruded
ZONES_M = {"intimate": 0.45, "personal": 1.2, "social": 3.6}
ZONE_NAMES = ("intimate", "personal", "social", "public")
STALLED_MPS = 0.05
DEADLOCK_S = 5.0  # no progress for this long at the end: deadlock
DEADLOCK_PROGRESS_M = 0.1
NEAR_MISS_M = 0.2  # body-to-body gap of a near miss


def episode_metrics(
    robot_xy,
    robot_yaw,
    robot_speed,
    people_xy,
    people_velocity,
    present,
    reached,
    goal_xy,
    start_xy,
    group,
    dt_s: float,
    timeout_s: float,
    robot_radius_m: float,
    person_radius_m: float,
    rule_ok,
    goal_tolerance_m: float = 0.0,
):
    """Metrics of one episode.

    Args:
      robot_xy (T, 2), robot_yaw (T,), robot_speed (T,); people_xy (T, P, 2), people_velocity
      (T, P, 2), present (T, P) bool; reached (T,) bool (goal reached by then); goal_xy, start_xy
      (2,); group (P,) int32 group of each person (-1 none); rule_ok () bool, the scene's rule;
      goal_tolerance_m: the arrival radius (the path-length ratio's straight line ends on it).

    Returns: a dict of arrays (scalars, ``d_person_m`` (P,), ``zone_share`` and ``zone_share_body`` (4,)).
    """
    active = ~jnp.concatenate([jnp.zeros(1, bool), reached[:-1]])  # steps before arrival
    success = reached[-1]
    arrival = jnp.argmax(reached)
    time_s = jnp.where(success, (arrival + 1) * dt_s, timeout_s)
    steps = jnp.linalg.norm(jnp.diff(robot_xy, axis=0), axis=-1)
    path_length = jnp.sum(jnp.where(active[1:], steps, 0.0))
    chc = jnp.sum(jnp.where(active[1:], jnp.abs(wrap_angle(jnp.diff(robot_yaw))), 0.0))
    stalled = jnp.sum(active & (robot_speed < STALLED_MPS)) * dt_s
    straight = jnp.linalg.norm(goal_xy - start_xy)
    spl = jnp.where(success, straight / jnp.maximum(path_length, straight), 0.0)

    offset = people_xy - robot_xy[:, None, :]
    dist = jnp.linalg.norm(offset, axis=-1)  # (T, P)
    seen = present & active[:, None]
    dist_masked = jnp.where(seen, dist, jnp.inf)
    nearest = jnp.min(dist_masked, axis=1)  # (T,)
    has_near = jnp.isfinite(nearest)
    d_h = jnp.sum(jnp.where(has_near, nearest, 0.0)) / jnp.maximum(jnp.sum(has_near), 1)
    d_person = jnp.min(dist_masked, axis=0)
    d_min = jnp.min(d_person)
    edges = jnp.array([ZONES_M["intimate"], ZONES_M["personal"], ZONES_M["social"]])

    def shares(distance):  # (4,) share of the steps before arrival in each zone; nobody near: public
        zone = jnp.where(has_near, jnp.sum(distance[:, None] >= edges[None], axis=1), 3)
        return jnp.array([jnp.sum(active & (zone == z)) for z in range(4)]) / jnp.maximum(jnp.sum(active), 1)

    zone_share = shares(nearest)
    zone_share_body = shares(nearest - robot_radius_m - person_radius_m)

    # Personal-space intrusions: entries into a person's 1.2 m.
    inside = seen & (dist < ZONES_M["personal"])
    entered = inside & ~jnp.concatenate([jnp.zeros((1,) + inside.shape[1:], bool), inside[:-1]])
    intrusions = jnp.sum(entered)

    # Collisions once per encounter, attributed at the encounter's start.
    radius = robot_radius_m + person_radius_m
    robot_v = robot_speed[:, None] * jnp.stack([jnp.cos(robot_yaw), jnp.sin(robot_yaw)], -1)  # (T, 2)
    unit = offset / jnp.maximum(dist, 1e-9)[..., None]
    robot_closing = jnp.sum(robot_v[:, None, :] * unit, axis=-1)
    person_closing = -jnp.sum(people_velocity * unit, axis=-1)

    def collide(contact, xs):
        d, p, rc, pc = xs
        now, _ = collision_encounters(contact, d, p, radius, 0.1)
        start = now & ~contact
        return now, (jnp.sum(start & (rc >= pc)), jnp.sum(start & (rc < pc)))

    _, (by_robot, by_person) = jax.lax.scan(
        collide, jnp.zeros(dist.shape[1], bool), (dist, seen, robot_closing, person_closing)
    )
    collisions = jnp.sum(by_robot) + jnp.sum(by_person)

    # Time to collision at constant velocities (the bodies touching), over steps and people.
    rel_v = people_velocity - robot_v[:, None, :]
    a = jnp.sum(rel_v * rel_v, axis=-1)
    b = 2 * jnp.sum(offset * rel_v, axis=-1)
    c = dist * dist - radius * radius
    disc = b * b - 4 * a * c
    t_hit = (-b - jnp.sqrt(jnp.maximum(disc, 0.0))) / jnp.maximum(2 * a, 1e-9)
    ttc = jnp.where(seen & (disc > 0) & (t_hit > 0) & (a > 1e-9), t_hit, jnp.inf)
    ttc = jnp.where(seen & (c <= 0), 0.0, ttc)

    # Inside a group's circle.
    n = group.shape[0]
    member = (group[None, :] == jnp.arange(n)[:, None]) & (group[None, :] >= 0)  # (G, P)
    count = jnp.sum(member, axis=1)
    centre = jnp.einsum("gp,tpd->tgd", member.astype(robot_xy.dtype), people_xy) / jnp.maximum(count, 1)[None, :, None]
    spread = jnp.linalg.norm(people_xy[:, None, :, :] - centre[:, :, None, :], axis=-1)  # (T, G, P)
    radius_g = jnp.sum(jnp.where(member[None], spread, 0.0), axis=-1) / jnp.maximum(count, 1)[None]
    in_group = jnp.any((count >= 2)[None] & (jnp.linalg.norm(robot_xy[:, None] - centre, axis=-1) < radius_g), axis=1)
    group_share = jnp.sum(active & in_group) / jnp.maximum(jnp.sum(active), 1)

    # Motion quality, before arrival.
    moving_steps = jnp.maximum(jnp.sum(active), 1)
    yaw_rate = wrap_angle(jnp.diff(robot_yaw, prepend=robot_yaw[:1])) / dt_s
    accel = jnp.diff(robot_speed, prepend=robot_speed[:1]) / dt_s
    jerk = jnp.diff(accel, prepend=accel[:1]) / dt_s
    mean_active = lambda x: jnp.sum(jnp.where(active, x, 0.0)) / moving_steps
    facing = jnp.arctan2(goal_xy[1] - start_xy[1], goal_xy[0] - start_xy[0])
    needed = jnp.abs(wrap_angle(facing - robot_yaw[0]))
    irregularity = jnp.maximum(chc - needed, 0.0) / jnp.maximum(path_length, 1e-6)
    length_ratio = path_length / jnp.maximum(straight - goal_tolerance_m, 1e-6)

    # Progress towards the goal: deadlock (none over the last DEADLOCK_S) apart from a timeout.
    to_goal = jnp.linalg.norm(robot_xy - goal_xy, axis=-1)
    window = max(int(round(DEADLOCK_S / dt_s)), 1)
    best_before = jax.lax.cummin(to_goal)
    if to_goal.shape[0] > window:
        deadlock = ~success & (best_before[-window - 1] - to_goal[-window:].min() < DEADLOCK_PROGRESS_M)
    else:
        deadlock = jnp.array(False)
    progressed = jnp.concatenate([jnp.ones(1, bool), best_before[1:] < best_before[:-1] - 1e-3])

    def still(run, step):
        p, a = step
        run = jnp.where(p | ~a, 0, run + 1)
        return run, run

    _, runs = jax.lax.scan(still, jnp.int32(0), (progressed, active))
    no_progress_max = jnp.max(runs) * dt_s

    # Body-edge clearance and near misses; personal-space entries by who closed in.
    gap = dist_masked - radius
    clearance_min = jnp.min(gap)

    def near(carry, xs):
        inside, touched = carry
        g, p = xs
        now = p & (g < NEAR_MISS_M)
        ended = inside & ~now
        missed = jnp.sum(ended & ~touched)
        touched = jnp.where(now, (touched & inside) | (g < 0.0), False)
        return (now, touched), missed

    none = jnp.zeros(dist.shape[1], bool)
    (inside, touched), missed = jax.lax.scan(near, (none, none), (jnp.where(seen, gap, jnp.inf), seen))
    near_misses = jnp.sum(missed) + jnp.sum(inside & ~touched)  # an encounter still open at the end
    entered_by_robot = entered & (robot_closing >= person_closing)

    # Group-space entries.
    entered_group = in_group & ~jnp.concatenate([jnp.zeros(1, bool), in_group[:-1]]) & active

    return {
        "goal_success": success,
        "deadlock": deadlock,
        "timeout": ~success & ~deadlock,
        "no_progress_max_s": no_progress_max,
        "speed_mean_mps": mean_active(robot_speed),
        "turn_rate_mean_rps": mean_active(jnp.abs(yaw_rate)),
        "accel_mean_mps2": mean_active(jnp.abs(accel)),
        "jerk_mean_mps3": mean_active(jnp.abs(jerk)),
        "path_irregularity_rad_per_m": irregularity,
        "path_length_ratio": length_ratio,
        "clearance_min_m": clearance_min,
        "near_misses": near_misses,
        "intrusions_robot": jnp.sum(entered_by_robot),
        "intrusions_person": jnp.sum(entered & ~entered_by_robot),
        "group_intrusions": jnp.sum(entered_group),
        "social_success": success & rule_ok,
        "goal_no_collision": success & (collisions == 0),
        "social_no_collision": success & rule_ok & (collisions == 0),
        "collisions": collisions,
        "collisions_robot": jnp.sum(by_robot),
        "collisions_person": jnp.sum(by_person),
        "time_s": time_s,
        "path_length_m": path_length,
        "chc_rad": chc,
        "stalled_s": stalled,
        "spl": spl,
        "d_h_m": d_h,
        "d_min_m": d_min,
        "d_person_m": d_person,
        "zone_share": zone_share,
        "zone_share_body": zone_share_body,
        "intrusions": intrusions,
        "intruded": intrusions > 0,
        "ttc_min_s": jnp.min(ttc),
        "group_share": group_share,
    }


def people_effect(people_xy, present, people_xy_without, present_without, dt_s: float, moving_mps: float = 0.05):
    """The robot's effect on the people of one episode, against the same variant without the
    robot (the module's docstring says how that run is made).

    Args:
      people_xy (T, P, 2), present (T, P): with the robot; people_xy_without, present_without:
        the counterfactual run. Steps where a person is absent from either count for neither.
      moving_mps: a person whose mean speed without the robot is below this is standing (their
        speed drop is not averaged in).

    Returns: ``people_speed_drop_mps``, ``people_deviation_m``, ``people_deviation_max_m`` (()
    each; 0 with nobody present).
    """
    both = present & present_without  # (T, P)
    step = both[1:] & both[:-1]
    speed = jnp.linalg.norm(jnp.diff(people_xy, axis=0), axis=-1) / dt_s
    speed_without = jnp.linalg.norm(jnp.diff(people_xy_without, axis=0), axis=-1) / dt_s
    count = jnp.maximum(jnp.sum(step, axis=0), 1)
    mean_with = jnp.sum(jnp.where(step, speed, 0.0), axis=0) / count  # (P,)
    mean_without = jnp.sum(jnp.where(step, speed_without, 0.0), axis=0) / count
    mover = (jnp.sum(step, axis=0) > 0) & (mean_without >= moving_mps)
    drop = jnp.sum(jnp.where(mover, mean_without - mean_with, 0.0)) / jnp.maximum(jnp.sum(mover), 1)
    apart = jnp.where(both, jnp.linalg.norm(people_xy - people_xy_without, axis=-1), 0.0)
    deviation = jnp.sum(apart) / jnp.maximum(jnp.sum(both), 1)
    return {
        "people_speed_drop_mps": drop,
        "people_deviation_m": deviation,
        "people_deviation_max_m": jnp.max(apart),
    }


# ------------------------------------------------------------------ the scenes' rules


# A rule's fields that are numbers (traced in a compiled check) and those that shape the program.
RULE_NUMBERS = ("distance_m", "centre", "radius_m", "box", "min_share", "head", "half_width_m", "length_m", "ahead_m")
RULE_STRUCTURE = ("type", "group", "person")


def right_of(direction_deg) -> np.ndarray:
    """(2,) float32 unit vector on the right of travel along ``direction_deg`` (host side: the
    same bits whether the rule's numbers are constants or arguments of a compiled check)."""
    angle = np.radians(direction_deg)
    return np.array([np.sin(angle), -np.cos(angle)], np.float32)


def split_rule(rule: dict):
    """A scene's rule as ``(structure, numbers)``: the hashable structure (the kinds, the person
    and group indices: what changes the program) and a pytree of float32 arrays (boxes, centres,
    distances, shares, a keep-right's right-hand vector: what changes only the values), so that one
    compiled check serves every scene whose rule has the same structure (a scene and its mirror).
    :func:`join_rule` puts them back together; :func:`rule_satisfied` takes either form."""
    if rule["type"] == "all":
        parts = [split_rule(sub) for sub in rule["rules"]]
        return ("all", tuple(structure for structure, _ in parts)), [numbers for _, numbers in parts]
    structure = tuple(sorted((k, v) for k, v in rule.items() if k in RULE_STRUCTURE))
    numbers = {k: np.asarray(v, np.float32) for k, v in rule.items() if k in RULE_NUMBERS}
    if "direction_deg" in rule:
        numbers["right"] = right_of(rule["direction_deg"])
    return structure, numbers


def join_rule(structure, numbers) -> dict:
    """The rule dict of :func:`split_rule`'s parts (its numbers may be traced arrays)."""
    if structure[0] == "all":
        return {"type": "all", "rules": [join_rule(s, n) for s, n in zip(structure[1], numbers, strict=True)]}
    return {**dict(structure), **numbers}


def rule_satisfied(rule: dict, robot_xy, reached, people_xy, people_start_xy, people_end_xy, present, group):
    """() bool: the trajectory obeys a scene's rule (:mod:`jaxsim.scenes.spec`), over the steps
    before the goal is reached. ``people_start_xy``, ``people_end_xy``: (P, 2) walkers' legs."""
    active = ~jnp.concatenate([jnp.zeros(1, bool), reached[:-1]])
    kind = rule["type"]
    if kind == "all":
        oks = [
            rule_satisfied(r, robot_xy, reached, people_xy, people_start_xy, people_end_xy, present, group)
            for r in rule["rules"]
        ]
        return jnp.all(jnp.stack(oks))
    if kind == "min_distance":
        d = jnp.linalg.norm(people_xy - robot_xy[:, None], axis=-1)
        return jnp.all(jnp.where(present & active[:, None], d >= rule["distance_m"], True))
    if kind == "avoid_circle":
        d = jnp.linalg.norm(robot_xy - jnp.asarray(rule["centre"], robot_xy.dtype), axis=-1)
        return jnp.all(jnp.where(active, d >= rule["radius_m"], True))
    if kind == "avoid_group":
        member = group == rule["group"]
        count = jnp.maximum(jnp.sum(member), 1)
        centre = jnp.sum(jnp.where(member[None, :, None], people_xy, 0.0), axis=1) / count  # (T, 2)
        spread = jnp.linalg.norm(people_xy - centre[:, None], axis=-1)
        radius = jnp.sum(jnp.where(member[None], spread, 0.0), axis=1) / count
        return jnp.all(jnp.where(active, jnp.linalg.norm(robot_xy - centre, axis=-1) >= radius, True))
    if kind in ("keep_right", "visit"):
        box = jnp.asarray(rule["box"], robot_xy.dtype)
        inside = (
            (robot_xy[:, 0] >= box[0])
            & (robot_xy[:, 0] <= box[1])
            & (robot_xy[:, 1] >= box[2])
            & (robot_xy[:, 1] <= box[3])
        ) & active
        if kind == "visit":
            return jnp.any(inside)
        right = jnp.asarray(rule["right"] if "right" in rule else right_of(rule["direction_deg"]), robot_xy.dtype)
        centre = jnp.array([(box[0] + box[1]) / 2, (box[2] + box[3]) / 2])
        on_right = jnp.sum((robot_xy - centre) * right, axis=-1) > 0
        share = jnp.sum(inside & on_right) / jnp.maximum(jnp.sum(inside), 1)
        return (jnp.sum(inside) == 0) | (share >= rule["min_share"])
    if kind == "pass_behind":
        # The robot crosses the walker's line of motion behind them: when the robot is on the
        # line (its signed side changes), the walker has already passed the robot's position.
        i = rule["person"]
        start, end = people_start_xy[i], people_end_xy[i]
        direction = (end - start) / jnp.maximum(jnp.linalg.norm(end - start), 1e-9)
        normal = jnp.array([-direction[1], direction[0]])
        side = jnp.sum((robot_xy - start) * normal, axis=-1)
        crosses = (jnp.sign(side[1:]) != jnp.sign(side[:-1])) & active[1:]
        # Along the walker's direction, the walker is ahead of the crossing point.
        ahead = jnp.sum((people_xy[1:, i] - robot_xy[1:]) * direction, axis=-1) > 0
        return jnp.all(jnp.where(crosses, ahead, True))
    if kind == "queue":
        return ~jnp.any(active & rule_monitor.queue_cut_in(rule, robot_xy, people_xy, present))
    raise ValueError(f"unknown rule {kind!r}")
