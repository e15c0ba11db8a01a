"""A scene's social rule checked step by step: a constant-size state instead of a trajectory.

:func:`evaluation.arena.nav_metrics.rule_satisfied` checks a scene's rule (:mod:`jaxsim.scenes.spec`)
on a whole recorded trajectory, vectorised over its steps: what the arena does after a rollout.
A training loop keeps no trajectory (thousands of episodes, each ending at its own step), so it
needs the same verdict from a running state updated once per step: :func:`monitor`. The two are
the same definitions written twice, once vectorised and once streaming; ``tests/test_policy.py``
holds them equal on random trajectories for every rule kind and every built-in scene's rule.

Per step the monitor takes the robot's centre, whether the goal was reached at this step, and
the people's centres and presence; per episode the walkers' legs and the groups. As in the batch
form, only steps up to and including the first one at the goal count.
"""

from __future__ import annotations

from collections.abc import Callable

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct


@struct.dataclass
class Step:
    """One step: robot_xy_m (2,), reached () bool (at the goal at this step), people_xy_m (P, 2),
    people_present (P,) bool (the names of :class:`jaxsim.scenes.env.StepInfo`)."""

    robot_xy_m: jax.Array
    reached: jax.Array
    people_xy_m: jax.Array
    people_present: jax.Array


@struct.dataclass
class Episode:
    """An episode's constants: the walkers' legs ``start_xy``, ``end_xy`` (P, 2) and ``group``
    (P,) int32 (-1: none), as in :class:`jaxsim.scenes.variant.Variant`."""

    start_xy: jax.Array
    end_xy: jax.Array
    group: jax.Array


@struct.dataclass
class MonitorState:
    """``done``: the goal was reached at an earlier step (later steps do not count); ``leaves``:
    one tuple of arrays per leaf rule (``all`` is flattened)."""

    done: jax.Array
    leaves: tuple


def queue_cut_in(rule: dict, robot_xy, people_xy, present):
    """bool (...): the robot cuts into the queue of a ``queue`` rule (:mod:`jaxsim.scenes.spec`):
    its centre is in the line's lane and ahead, along the lane, of a present person still in it.
    ``robot_xy`` (..., 2), ``people_xy`` (..., P, 2), ``present`` (..., P): one step or a
    trajectory's steps. The lane's frame comes from the rule's ``head`` and ``right`` (the right of
    the way the queue faces, :func:`evaluation.arena.nav_metrics.right_of`) or ``direction_deg``."""
    if "right" in rule:
        right = jnp.asarray(rule["right"], jnp.float32)
    else:
        angle = np.radians(rule["direction_deg"])
        right = jnp.array([np.sin(angle), -np.cos(angle)], jnp.float32)
    forward = jnp.stack([-right[1], right[0]])
    head = jnp.asarray(rule["head"], jnp.float32)

    def lane(xy):
        d = xy - head
        along, side = jnp.sum(d * forward, axis=-1), jnp.sum(d * right, axis=-1)
        inside = (along >= -rule["length_m"]) & (along <= rule["ahead_m"]) & (jnp.abs(side) <= rule["half_width_m"])
        return along, inside

    robot_along, robot_in = lane(robot_xy)
    people_along, people_in = lane(people_xy)
    ahead_of_someone = jnp.any(present & people_in & (robot_along[..., None] > people_along), axis=-1)
    return robot_in & ahead_of_someone


def _leaves(rule: dict) -> list[dict]:
    if rule["type"] == "all":
        return [leaf for sub in rule["rules"] for leaf in _leaves(sub)]
    return [rule]


def _leaf(rule: dict):
    """``(init (), update(state, step, episode, active), verdict(state))`` of one leaf rule."""
    kind = rule["type"]
    if kind in ("min_distance", "avoid_circle", "avoid_group"):

        def init():
            return (jnp.array(True),)

        def update(s, step: Step, ep: Episode, active):
            if kind == "min_distance":
                d = jnp.linalg.norm(step.people_xy_m - step.robot_xy_m, axis=-1)
                ok = jnp.all(jnp.where(step.people_present & active, d >= rule["distance_m"], True))
            elif kind == "avoid_circle":
                d = jnp.linalg.norm(step.robot_xy_m - jnp.asarray(rule["centre"], jnp.float32))
                ok = ~active | (d >= rule["radius_m"])
            else:
                member = ep.group == rule["group"]
                count = jnp.maximum(jnp.sum(member), 1)
                centre = jnp.sum(jnp.where(member[:, None], step.people_xy_m, 0.0), axis=0) / count
                spread = jnp.linalg.norm(step.people_xy_m - centre, axis=-1)
                radius = jnp.sum(jnp.where(member, spread, 0.0)) / count
                ok = ~active | (jnp.linalg.norm(step.robot_xy_m - centre) >= radius)
            return (s[0] & ok,)

        return init, update, lambda s: s[0]

    if kind in ("keep_right", "visit"):
        box = np.asarray(rule["box"], np.float32)
        angle = np.radians(rule.get("direction_deg", 0.0))
        right = jnp.array([np.sin(angle), -np.cos(angle)], jnp.float32)
        centre = jnp.array([(box[0] + box[1]) / 2, (box[2] + box[3]) / 2], jnp.float32)

        def init():
            return (jnp.int32(0), jnp.int32(0))  # steps inside the box, of them on its right half

        def update(s, step: Step, ep: Episode, active):
            xy = step.robot_xy_m
            inside = (xy[0] >= box[0]) & (xy[0] <= box[1]) & (xy[1] >= box[2]) & (xy[1] <= box[3]) & active
            on_right = jnp.sum((xy - centre) * right) > 0
            return (s[0] + inside, s[1] + (inside & on_right))

        if kind == "visit":
            return init, update, lambda s: s[0] > 0
        share = rule["min_share"]
        return init, update, lambda s: (s[0] == 0) | (s[1] / jnp.maximum(s[0], 1) >= share)

    if kind == "pass_behind":
        i = rule["person"]

        def init():  # still fine, the robot's side of the line at the last step, a last step seen
            return (jnp.array(True), jnp.float32(0.0), jnp.array(False))

        def update(s, step: Step, ep: Episode, active):
            start, end = ep.start_xy[i], ep.end_xy[i]
            direction = (end - start) / jnp.maximum(jnp.linalg.norm(end - start), 1e-9)
            normal = jnp.array([-direction[1], direction[0]])
            side = jnp.sum((step.robot_xy_m - start) * normal)
            crosses = s[2] & (jnp.sign(side) != jnp.sign(s[1])) & active
            ahead = jnp.sum((step.people_xy_m[i] - step.robot_xy_m) * direction) > 0
            return (s[0] & (~crosses | ahead), side, jnp.array(True))

        return init, update, lambda s: s[0]

    if kind == "queue":

        def init():
            return (jnp.array(True),)

        def update(s, step: Step, ep: Episode, active):
            return (s[0] & ~(active & queue_cut_in(rule, step.robot_xy_m, step.people_xy_m, step.people_present)),)

        return init, update, lambda s: s[0]

    raise ValueError(f"unknown rule {kind!r}")


def monitor(rule: dict) -> tuple[Callable, Callable, Callable]:
    """``(init() -> state, update(state, step, episode) -> state, verdict(state) -> () bool)`` of
    a scene's ``rule`` (a static dict; vmap the three over episodes). ``verdict`` after an
    episode's last step equals :func:`evaluation.arena.nav_metrics.rule_satisfied` on its trajectory."""
    leaves = [_leaf(r) for r in _leaves(rule)]

    def init() -> MonitorState:
        return MonitorState(done=jnp.array(False), leaves=tuple(leaf[0]() for leaf in leaves))

    def update(state: MonitorState, step: Step, episode: Episode) -> MonitorState:
        active = ~state.done
        new = tuple(leaf[1](s, step, episode, active) for leaf, s in zip(leaves, state.leaves, strict=True))
        return MonitorState(done=state.done | step.reached, leaves=new)

    def verdict(state: MonitorState):
        return jnp.all(jnp.stack([leaf[2](s) for leaf, s in zip(leaves, state.leaves, strict=True)]))

    return init, update, verdict
