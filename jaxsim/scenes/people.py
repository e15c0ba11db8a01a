"""People of a scene: where each behaviour wants them, and one step of the crowd model.

Walkers, stream members and served queue members move by the run's human model through the one
crowd function the warehouse uses too (:func:`jaxsim.humans.step_humans`; by default the
warehouse's social force, :func:`jaxsim.crowd.step_crowd`), with the robot as an agent they
avoid unless ``ignore_robot``. A walker or stream member whose straight line crosses a wall heads
for the corners of its way round the walls in turn (:attr:`Variant.waypoints_xy`,
:mod:`jaxsim.scenes.routes`), each passed when reached or when the point after it comes in sight
(:func:`next_in_sight`). People waiting in a queue step straight up to their place in line, one
place after another (:func:`queue_place`).
Standing people (and group members) stay where they stand, as the seeds' subjects did; a group
member turns to face the group's centre at its ``turn_at_s``.

A recorded crowd (a scene with a ``recording``, :mod:`jaxsim.scenes.recording`) is played back
one of two ways (the variant's ``reactive``): ``replayed``, every person is where the recording has them at
every step, robot or not (:func:`recorded_at`); ``reactive``, every person walks by the human
model towards where they are recorded :data:`~jaxsim.scenes.recording.LOOKAHEAD_SAMPLES` samples
(1 s) ahead, at the speed that gets them there in that time (at most
:data:`REACTIVE_MAX_SPEED_MPS`), so they avoid the robot and each other as the model does and
return to their path after; a person appears where and when the recording has them appear.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct

from socialnav.jaxsim import humans, rng
from socialnav.jaxsim.params import PERSON_RADIUS_M
from socialnav.jaxsim.scenes.recording import LOOKAHEAD_SAMPLES, RECORD_DT_S
from socialnav.jaxsim.scenes.spec import KIND
from socialnav.jaxsim.scenes.variant import Variant
from socialnav.jaxsim.scenes.world import SceneWorld, segment_blocked
from socialnav.jaxsim.walkers import Aims, RobotDisc, Walkers

ARRIVED_M = 0.3  # a walker within this distance of its target has arrived
STOP_RAMP_M = 0.5  # a queue member slows down over the last half metre to its place
AT_PLACE_M = 0.05  # a queue member this close to its place stands there
QUEUE_STEP_UP_DELAY_S = 0.5  # each place in line steps up this long after the one ahead of it
MOVING_MPS = 0.1  # slower than this a person keeps their heading (a standing body does not turn to its drift)
HUMAN_MODELS = humans.HUMAN_MODELS
# A reactive person pushed off their recorded path hurries back at most this fast (a brisk walk;
# Weidmann's free speed is 1.34 m/s).
REACTIVE_MAX_SPEED_MPS = 2.0


@struct.dataclass
class PeopleState:
    """(P,) people: xy (P, 2), velocity (P, 2), heading (P,), present (P,) bool (in the scene),
    leg (P,) int32 (a back-and-forth walker: 0 towards its end, 1 back), waypoint (P,) int32 (the
    corners of its way round the walls passed on this leg, :attr:`Variant.waypoints_xy`), done
    (P,) bool (a walker that has arrived for good, a stream member or queue member that has left)."""

    xy: jnp.ndarray
    velocity: jnp.ndarray
    heading: jnp.ndarray
    present: jnp.ndarray
    leg: jnp.ndarray
    waypoint: jnp.ndarray
    done: jnp.ndarray


def init_people(v: Variant) -> PeopleState:
    present = v.valid & ((v.kind != KIND["stream"]) | (v.start_s <= 0.0))
    present = present & ((v.kind != KIND["recorded"]) | v.track_present[:, 0])
    n = v.valid.shape[-1]
    recorded_velocity = recorded_at(v, jnp.float32(0.0))[1]  # a recorded crowd is already walking
    return PeopleState(
        xy=jnp.asarray(v.xy0),
        velocity=jnp.where((v.kind == KIND["recorded"])[:, None], recorded_velocity, jnp.zeros((n, 2), jnp.float32)),
        heading=jnp.asarray(v.heading0),
        present=present,
        leg=jnp.zeros(n, jnp.int32),
        waypoint=jnp.zeros(n, jnp.int32),
        done=jnp.zeros(n, bool),
    )


def queue_place(v: Variant, time_s):
    """(P,) int32 each queue member's place in line at ``time_s`` (0: the head, < 0: served).

    The head is served every ``queue_interval_s``; the line then steps up from the front, each
    place :data:`QUEUE_STEP_UP_DELAY_S` after the one ahead of it, as people in a line do. The
    ``k``-th service (at ``k interval``) moves the member first at place ``q`` on from place
    ``q - k + 1`` at ``k interval + (q - k + 1) delay`` (the head leaves at ``k interval``), so by
    ``t`` it has moved ``floor((t - (q + 1) delay) / (interval - delay))`` times (intervals are
    at least 1 s, the delay 0.5 s)."""
    delay = QUEUE_STEP_UP_DELAY_S
    steps = jnp.floor((time_s - (v.queue_place + 1) * delay) / (v.queue_interval_s - delay)).astype(jnp.int32)
    return v.queue_place - jnp.maximum(steps, 0)


def targets(v: Variant, s: PeopleState, time_s, routed: bool = False):
    """Where each person is going now: (target (P, 2), desired speed (P,), mobile (P,) bool).
    ``routed`` (static): walkers and served queue members head for the corners of their way round
    the walls first (:attr:`jaxsim.scenes.env.Env.routed`; without, straight for their leg's end
    or the exit)."""
    walk = v.kind == KIND["walk"]
    queue = v.kind == KIND["queue"]
    stream = v.kind == KIND["stream"]
    started = time_s >= v.start_s
    # Walkers and stream members: towards the end of their leg (or back, on a return leg), by the
    # corners of their way round the walls first.
    leg_target = leg_end(v, s.leg)
    if routed:
        to_corner = (s.waypoint < v.n_waypoints)[:, None]
        leg_target = jnp.where(to_corner, corner(v, s.leg, s.waypoint), leg_target)
    # Queue members: their place, moved up once per interval; past the head, the exit (their leg's
    # end), by the corners of its way round the walls first.
    place = queue_place(v, time_s)
    exit_target = leg_target if routed else v.exit_xy
    queue_target = jnp.where(
        (place >= 0)[:, None], v.queue_head + jnp.maximum(place, 0)[:, None] * v.queue_step, exit_target
    )
    target = jnp.where(queue[:, None], queue_target, jnp.where((walk | stream)[:, None], leg_target, s.xy))
    distance = jnp.linalg.norm(target - s.xy, axis=-1)
    queue_speed = v.speed_mps * jnp.clip(distance / STOP_RAMP_M, 0.0, 1.0)
    speed = jnp.where(queue, jnp.where(place >= 0, queue_speed, v.speed_mps), v.speed_mps)
    mobile = s.present & ~s.done & (((walk | stream) & started) | (queue & (distance > AT_PLACE_M)))
    return target, speed, mobile


def leg_end(v: Variant, leg):
    """(P, 2) where each walker's leg ``leg`` (P,) ends: its end, or its start on a return leg."""
    return jnp.where((leg == 1)[:, None], v.start_xy, v.end_xy)


def corner(v: Variant, leg, passed):
    """(P, 2) the corner each walker on leg ``leg`` (P,) heads for after passing ``passed`` (P,) of
    them: the variant's waypoints in order, backwards on a return leg (clipped to the array where
    none is left; :func:`targets` then takes the leg's end)."""
    index = jnp.where(leg == 1, v.n_waypoints - 1 - passed, passed)
    index = jnp.clip(index, 0, v.waypoints_xy.shape[-2] - 1)
    return jnp.take_along_axis(v.waypoints_xy, index[:, None, None], axis=-2)[:, 0]


def next_in_sight(v: Variant, s: PeopleState, xy, walls_m):
    """(P,) bool: from ``xy`` (P, 2), the point after the corner each walker heads for (the next
    corner, or the leg's end) is in sight past the walls grown by a person's body
    (:data:`jaxsim.params.PERSON_RADIUS_M`), so the body clears the wall's corner going straight
    there: the corner is passed (:func:`step_people`, as it is when reached)."""
    after = jnp.where((s.waypoint + 1 < v.n_waypoints)[:, None], corner(v, s.leg, s.waypoint + 1), leg_end(v, s.leg))
    grown = walls_m + jnp.array([-PERSON_RADIUS_M, PERSON_RADIUS_M, -PERSON_RADIUS_M, PERSON_RADIUS_M])
    return ~segment_blocked(xy, after, grown)


def _sample(time_s):
    """The recording's sample index at ``time_s`` (a float step times ``dt_s`` lands a hair below
    a whole sample: rounded up from 1e-4 below)."""
    return jnp.floor(time_s / RECORD_DT_S + 1e-4).astype(jnp.int32)


def recorded_at(v: Variant, time_s):
    """A recorded crowd at ``time_s``: ``(xy (P, 2), velocity (P, 2), present (P,) bool)``,
    positions interpolated linearly between samples, the velocity the sample's forward difference
    (the backward one at a person's last sample; 0 for a person seen once)."""
    f = v.track_xy.shape[-2]
    k = jnp.clip(_sample(time_s), 0, f - 1)
    ahead, behind = jnp.minimum(k + 1, f - 1), jnp.maximum(k - 1, 0)
    here_xy, ahead_xy, behind_xy = v.track_xy[:, k], v.track_xy[:, ahead], v.track_xy[:, behind]
    fraction = jnp.clip(time_s / RECORD_DT_S - k, 0.0, 1.0)
    fraction = jnp.where(fraction < 1e-3, 0.0, fraction)  # on a sample (the step's rounding): exactly it
    present = v.track_present[:, k] & v.valid
    forward = present & v.track_present[:, ahead] & (ahead > k)
    backward = present & v.track_present[:, behind] & (behind < k)
    velocity = jnp.where(
        forward[:, None],
        (ahead_xy - here_xy) / RECORD_DT_S,
        jnp.where(backward[:, None], (here_xy - behind_xy) / RECORD_DT_S, 0.0),
    )
    xy = here_xy + jnp.where(forward, fraction, 0.0)[:, None] * (ahead_xy - here_xy)
    return xy, velocity, present


def recorded_ahead(v: Variant, time_s, samples: int = LOOKAHEAD_SAMPLES):
    """(P, 2) where each recorded person is ``samples`` samples after ``time_s``, or at their last
    sample if it comes sooner (the slot's next person is at least that many empty samples later:
    :data:`~jaxsim.scenes.recording.SLOT_GAP_SAMPLES`)."""
    f = v.track_xy.shape[-2]
    k = jnp.clip(_sample(time_s), 0, f - 1)
    index = jnp.minimum(k + jnp.arange(samples + 1), f - 1)  # (S + 1,)
    present = v.track_present[:, index]  # (P, S + 1)
    last = jnp.max(jnp.where(present, jnp.arange(samples + 1), 0), axis=1)
    return v.track_xy[jnp.arange(v.track_xy.shape[0]), index[last]]


def _moved(s: PeopleState, xy, velocity, present) -> PeopleState:
    """``s`` at new positions and velocities: a moving person faces where they go, a standing one
    keeps their heading."""
    moving = jnp.linalg.norm(velocity, axis=-1) > MOVING_MPS
    heading = jnp.where(moving, jnp.arctan2(velocity[:, 1], velocity[:, 0]), s.heading)
    return s.replace(xy=xy, velocity=velocity, heading=heading, present=present)


def step_people(
    model: str,
    constants: humans.HumanParams,
    world: SceneWorld,
    v: Variant,
    s: PeopleState,
    robot: RobotDisc,
    step,
    group_id=None,
    recorded: bool = False,
    routed: bool = False,
) -> PeopleState:
    """One step of ``constants.crowd.dt_s``: behaviours, then the human model on the mobile people.

    Args:
      model: static, :data:`jaxsim.humans.HUMAN_MODELS`: ``social_force``
        (:func:`jaxsim.crowd.step_crowd`, the warehouse's), ``orca`` (:func:`jaxsim.orca.step_orca`),
        a velocity model with bodies (:mod:`jaxsim.speed_model`) or the power law
        (:mod:`jaxsim.power_law`), and their ``_calibrated`` fits.
      constants: the human models' constants (:func:`jaxsim.humans.human_params`).
      robot: the robot's previous position and velocity, a disc the people avoid (its radius not
        used by the social force).
      step: () int32 step counter (time and the random force's stream).
      group_id: (P,) int32 the walking groups (``Variant.walking_group``; None: nobody walks
        with anyone, and the group terms are not computed).
      recorded: static, the people are a recorded crowd (every one of them), played back as
        ``v.reactive`` says: both ways are computed and one kept, so a recording's replayed and
        reactive scenes share one compiled program.
      routed: static, walkers, stream members and served queue members walk the corners of their
        way round the walls (:attr:`Variant.waypoints_xy`; :func:`jaxsim.scenes.routes.may_route`);
        False: straight for their leg's end or exit, without the corners' bookkeeping (their
        variants have no corners).
    """
    humans.check_model(model)
    dt = constants.crowd.dt_s
    time_s = step.astype(jnp.float32) * dt
    if recorded:
        after = recorded_at(v, time_s + dt)  # where the recording has everyone at the step's end
        replayed = _moved(s, *after)
        reactive = _reactive(model, constants, world, v, s, robot, step, group_id, after)
        return jax.tree_util.tree_map(lambda a, b: jnp.where(v.reactive, a, b), reactive, replayed)
    target, speed, mobile = targets(v, s, time_s, routed)
    u = _uniforms(v, step, s.xy.shape[0], model)
    walkers = Walkers.of(s.xy, s.velocity, s.present, mobile, v.ignore_robot)
    # pedsim's cap is the desired speed (a queue member's slows down to its place)
    aims = Aims(target[:, 0] - walkers.x_m, target[:, 1] - walkers.y_m, speed, speed)
    walkers = humans.step_humans(model, constants, world.wall_field, walkers, aims, robot, (u[0], u[1]), group_id)
    xy, new_v = walkers.xy_m, walkers.velocity_mps
    # People waiting in line step straight up to their place (the human model's repulsion between
    # people a body apart would spread the line sideways by up to half a metre, and a robot
    # coming up behind would push them out of line); once served they walk to the exit by the
    # human model like anyone else.
    place = queue_place(v, time_s)
    in_line = (v.kind == KIND["queue"]) & (place >= 0) & mobile
    to_place = target - s.xy
    gap = jnp.linalg.norm(to_place, axis=-1, keepdims=True)
    line_v = to_place / jnp.maximum(gap, 1e-9) * jnp.minimum(speed[:, None], gap / dt)
    xy = jnp.where(in_line[:, None], s.xy + line_v * dt, xy)
    new_v = jnp.where(in_line[:, None], line_v, new_v)

    moving = jnp.linalg.norm(new_v, axis=-1) > MOVING_MPS
    turned = jnp.where(time_s >= v.turn_at_s, v.heading_turned, v.heading0)
    heading = jnp.where(moving, jnp.arctan2(new_v[:, 1], new_v[:, 0]), jnp.where(v.kind == 0, turned, s.heading))

    walk = v.kind == KIND["walk"]
    stream = v.kind == KIND["stream"]
    queue = v.kind == KIND["queue"]
    arrived = jnp.linalg.norm(target - xy, axis=-1) < ARRIVED_M  # at the target: a corner or the leg's end
    passed = jnp.zeros_like(arrived)
    if routed:  # a corner passed, the next one (or the leg's end) is the target from the next step
        to_corner = s.waypoint < v.n_waypoints
        on_way = walk | stream | (queue & (place < 0))  # a queue member once served
        passed = mobile & on_way & to_corner & (arrived | next_in_sight(v, s, xy, world.walls_m))
        arrived = arrived & ~to_corner  # only the leg's end is an arrival
    flip = mobile & walk & arrived & v.back_and_forth
    leg = jnp.where(flip, 1 - s.leg, s.leg)
    waypoint = jnp.where(flip, 0, jnp.where(passed, s.waypoint + 1, s.waypoint))
    done = s.done | (mobile & arrived & ((walk & ~v.back_and_forth) | stream | (queue & (place < 0))))
    leaves = done & (stream | queue)
    enters = v.valid & stream & (time_s + dt >= v.start_s) & ~done
    present = jnp.where(stream, enters, s.present & ~leaves)
    return PeopleState(xy=xy, velocity=new_v, heading=heading, present=present, leg=leg, waypoint=waypoint, done=done)


def _reactive(
    model: str, constants: humans.HumanParams, world: SceneWorld, v: Variant, s: PeopleState, robot: RobotDisc, step,
    group_id, after,
) -> PeopleState:  # fmt: skip
    """One step of a reactive recorded crowd (see the module's docstring; the arguments of
    :func:`step_people`); ``after``: the recording at the step's end (:func:`recorded_at`)."""
    time_s = step.astype(jnp.float32) * constants.crowd.dt_s
    lookahead_s = LOOKAHEAD_SAMPLES * RECORD_DT_S
    aim = recorded_ahead(v, time_s) - s.xy
    speed = jnp.minimum(jnp.linalg.norm(aim, axis=-1) / lookahead_s, REACTIVE_MAX_SPEED_MPS)
    u = _uniforms(v, step, s.xy.shape[0], model)
    walkers = Walkers.of(s.xy, s.velocity, s.present, s.present, v.ignore_robot)
    aims = Aims(aim[:, 0], aim[:, 1], speed, speed)
    walkers = humans.step_humans(model, constants, world.wall_field, walkers, aims, robot, (u[0], u[1]), group_id)
    entry_xy, entry_velocity, present = after
    entering = present & ~s.present  # appears where the recording has them appear
    xy = jnp.where(entering[:, None], entry_xy, walkers.xy_m)
    velocity = jnp.where(entering[:, None], entry_velocity, walkers.velocity_mps)
    return _moved(s, xy, velocity, present)


def _uniforms(v: Variant, step, n: int, model: str):
    """(2, n) the step's uniforms of the human model (:func:`jaxsim.humans.step_humans`'s ``uniforms``).
    The social force's second draw is its random push's angle in turns, and gets the variant's
    ``noise_turns`` (a turned scene's pushes turned with it; ``+ 0`` changes no bit); the other
    models' draws are not directions and stay as drawn."""
    u = rng.hash_uniform16(v.seed_u32, step, (2, n))
    if model != "social_force":
        return u
    return jnp.stack([u[0], u[1] + v.noise_turns])


def stack_people(states: list[PeopleState]) -> PeopleState:
    return jax.tree_util.tree_map(lambda *a: jnp.stack(a), *states)
