"""What the robot perceives of the people: who is in range and in line of sight (walls occlude),
and velocities estimated from a window of past observed positions (seed 004 Sec. 3.1, Eq. 2),
not read from the simulator."""

from __future__ import annotations

import jax.numpy as jnp
from flax import struct

from socialnav.jaxsim.scenes.world import SceneWorld, segment_blocked

RANGE_M = 8.0  # GSCL's window reaches 8 m from the robot; the seeds' RGB-D sensors about as far
WINDOW = 5  # positions kept per person: 0.4 s at 10 Hz


@struct.dataclass
class Tracks:
    """(WINDOW, P) history, newest last: xy (W, P, 2), seen (W, P) bool."""

    xy: jnp.ndarray
    seen: jnp.ndarray


def init_tracks(n_people: int, window: int = WINDOW) -> Tracks:
    return Tracks(xy=jnp.zeros((window, n_people, 2), jnp.float32), seen=jnp.zeros((window, n_people), bool))


def visible(world: SceneWorld, robot_xy, people_xy, present, range_m: float = RANGE_M):
    """(P,) bool: present, within ``range_m`` and no wall between the robot and the person."""
    near = jnp.linalg.norm(people_xy - robot_xy, axis=-1) <= range_m
    blocked = segment_blocked(jnp.broadcast_to(robot_xy, people_xy.shape), people_xy, world.walls_m)
    return present & near & ~blocked


def velocity(tracks: Tracks, dt_s: float):
    """(P, 2) velocity estimate of a track window: the displacement over the window divided by its
    duration where the person was seen at both ends (Eq. 2 over the window), else 0."""
    span_s = (tracks.xy.shape[0] - 1) * dt_s
    both = tracks.seen[0] & tracks.seen[-1]
    return jnp.where(both[:, None], (tracks.xy[-1] - tracks.xy[0]) / span_s, 0.0)


def observe(tracks: Tracks, people_xy, seen, dt_s: float):
    """Push this step's observation; returns (tracks, velocity estimate (P, 2)).

    The velocity is the displacement over the window divided by its duration, where the person
    was seen at both ends (Eq. 2 over the window), else 0 (a person just seen is taken as still).
    """
    xy = jnp.concatenate([tracks.xy[1:], people_xy[None]], axis=0)
    seen_w = jnp.concatenate([tracks.seen[1:], seen[None]], axis=0)
    tracks = Tracks(xy=xy, seen=seen_w)
    return tracks, velocity(tracks, dt_s)
