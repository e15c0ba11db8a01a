"""One scene of the arena: every method on the same seeded variants, measured.

:func:`run_scene` draws a scene's variants (common random numbers: variant k is the same for every
method), runs each method's episodes (:mod:`evaluation.arena.episodes`: the stacks, the reactive baselines,
a user's actor) and the people without the robot, measures every episode
(:func:`metrics_function`, :mod:`evaluation.arena.nav_metrics`) and returns the episodes frame and the
trajectories it keeps (:mod:`evaluation.arena.report`'s frames).
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Callable, Mapping

import jax
import jax.numpy as jnp
import numpy as np
import pandas as pd

from socialnav.evaluation.arena import episodes as arena
from socialnav.evaluation.arena import nav_metrics
from socialnav.evaluation.arena.params import ArenaParams
from socialnav.evaluation.arena.report import episode_frame, trajectory_frame
from socialnav.jaxsim.scenario.errors import ScenarioError
from socialnav.jaxsim.scenes.actor import Actor, check_actor
from socialnav.jaxsim.scenes.spec import SceneSpec, mirror
from socialnav.jaxsim.scenes.variant import Variant, sample_variants
from socialnav.planners.reactive.baselines import BASELINES
from socialnav.planners.stack import METHODS


def _velocities(people_xy, present, dt_s):
    """(T, P, 2) people's velocities by finite differences (0 where a person is absent)."""
    v = jnp.diff(people_xy, axis=0, prepend=people_xy[:1]) / dt_s
    return jnp.where(present[..., None], v, 0.0)


def metrics_function(rule: dict, n_periods: int, config: arena.ArenaConfig, robot_radius_m: float):
    """``(trajectories, variants, trajectories without the robot) -> dict of metric arrays``, jitted
    and vmapped over episodes (the third from :func:`evaluation.arena.episodes.counterfactual_function`),
    for a scene's social ``rule`` (:attr:`jaxsim.scenes.spec.SceneSpec.rule`) and episodes of
    ``n_periods`` replanning periods (:attr:`evaluation.arena.episodes.SceneSetup.n_periods`).

    The rule enters as arguments (:func:`evaluation.arena.nav_metrics.split_rule`), so a scene
    and its held-out mirror, or two scenes with rules of the same kinds, share one compiled program
    (compiling it took 1.6 s a scene row)."""
    structure, numbers = nav_metrics.split_rule(rule)
    program = _metrics_program(structure, n_periods, config, float(robot_radius_m))
    return lambda tr, variants, without: program(tr, variants, without, numbers)


@functools.lru_cache(maxsize=64)
def _metrics_program(rule_structure, n_periods: int, config: arena.ArenaConfig, robot_radius_m: float):
    """The jitted metrics of :func:`metrics_function` for one rule structure (cached)."""
    timeout = n_periods * config.replan_every_steps * config.env.dt_s

    def one(tr: arena.Trajectory, v: Variant, without: arena.Trajectory, numbers):
        rule = nav_metrics.join_rule(rule_structure, numbers)
        velocity = _velocities(tr.people_xy_m, tr.people_present, config.env.dt_s)
        ok = nav_metrics.rule_satisfied(
            rule, tr.robot_xy_m, tr.reached, tr.people_xy_m, v.start_xy, v.end_xy, tr.people_present, v.group
        )
        metrics = nav_metrics.episode_metrics(
            tr.robot_xy_m,
            tr.robot_yaw_rad,
            tr.robot_speed_mps,
            tr.people_xy_m,
            velocity,
            tr.people_present,
            tr.reached,
            v.goal_xy,
            v.robot_xy,
            v.group,
            config.env.dt_s,
            timeout,
            robot_radius_m,
            config.env.person_radius_m,
            ok,
            config.env.goal_tolerance_m,
        )

        effect = nav_metrics.people_effect(
            tr.people_xy_m, tr.people_present, without.people_xy_m, without.people_present, config.env.dt_s
        )
        return {**metrics, **effect}

    return jax.jit(jax.vmap(one, in_axes=(0, 0, 0, None)))


HELD_OUT = "@held_out"
TURNED = "@turned"


def row_name(scene: str, held_out: bool = False, turned: bool = False) -> str:
    """A scene row's name: ``<scene>``, ``<scene>@held_out`` (mirrored, its ranges exceeded) or
    ``<scene>@turned`` (a quarter turn, :func:`jaxsim.scenes.spec.turn`)."""
    return scene + (HELD_OUT if held_out else "") + (TURNED if turned else "")


def run_scene(
    spec: SceneSpec,
    methods: list[str],
    n_variants: int,
    seed: int = 0,
    first: int = 0,
    keep_trajectories: int = 0,
    gscl_model=None,
    config: arena.ArenaConfig = arena.ArenaConfig(),
    on_method: Callable[[str], None] | None = None,
    held_out: bool = False,
    user_actors: dict[str, Callable] | None = None,
    params: ArenaParams | None = None,
    n_devices: int | None = None,
    human_values: Mapping[str, float] | None = None,
):
    """Every method on variants ``first .. first + n_variants - 1`` of one scene:
    ``(episodes frame, trajectories frame or None)``. ``held_out``: the scene mirrored
    (:func:`jaxsim.scenes.spec.mirror`) with every range drawn just outside itself, its rows named
    ``<scene>@held_out``; a turned ``spec`` (:func:`jaxsim.scenes.spec.turn`) gives rows
    ``<scene>@turned``. ``user_actors``: method name -> a factory ``env -> Actor`` or ``env ->
    (Actor, params)`` (:func:`user_actor`), for the names of ``methods`` that are not built in.
    ``params``: the robot's limits and the layers' parameters (:mod:`evaluation.arena.params`;
    default: the seeds' values). ``gscl_model``: the network of method ``gscl``
    (:func:`planners.layers.gscl`: a :class:`~socialnav.models.inference.SocialCostModel`, its
    weights traced, so another checkpoint of the same network reuses the compiled program; or a
    function of the maps). ``n_devices``: host devices the methods run
    on at the same time (:func:`evaluation.arena.episodes.run_spread`; default: every local one).
    ``human_values``: the people's constants as a calibration fitted them (``"<part>.<field>"`` ->
    number, :func:`jaxsim.humans.with_values`; default: ``config.env.human_model``'s own)."""
    name = row_name(spec.name, held_out, spec.turned_from is not None)
    if held_out:
        spec = mirror(spec)
    params = ArenaParams() if params is None else params
    robot = params.robot
    # its env has the run's people and robot
    setup = arena.setup_scene(spec, config, robot, arena.crowd_params(), human_values=human_values)
    arena.release_programs_if_crowded(caches=(_metrics_program,), key=setup.program_key)
    measure = metrics_function(spec.rule, setup.n_periods, config, float(robot.radius_m))
    episodes, trajectories = [], []
    user_actors = user_actors or {}
    runs = [arena.counterfactual_function(setup)]  # the people without the robot
    for method in methods:
        if method in user_actors:
            actor, actor_params = user_actor(user_actors[method], setup.env, setup.n_slots)
            runs.append(arena.actor_function(setup, actor, actor_params))
        elif method in BASELINES:
            runs.append(arena.baseline_function(setup, method, config=config))
        else:
            runs.append(
                arena.episode_function(
                    setup, METHODS[method], config=config, gscl_model=gscl_model, layers=params.layers_for(method)
                )
            )
    variants = jax.tree_util.tree_map(
        jnp.asarray, sample_variants(spec, seed, n_variants, first, held_out, setup.n_slots)
    )
    results = arena.run_spread(runs, variants, n_devices)
    without = next(results)
    for method, tr in itertools.chain([("without the robot", without)], zip(methods, results)):  # as they come
        lost = lost_people(tr.people_xy_m, tr.people_present, first, config.env.dt_s)
        if lost is not None:  # the scene named, as a variant that cannot be drawn is
            raise ScenarioError(spec.file, "people", f"{lost} ({method}): the people's model "
                                f"({config.env.human_model}) failed; check its constants (--human-fit)")  # fmt: skip
        if tr is without:
            continue
        metrics = measure(tr, variants, without)
        episodes.append(episode_frame(name, method, first, metrics, tr.wall_contacts, tr.invalid_actions))
        kept = trajectory_frame(name, method, first, tr, keep_trajectories, config.env.dt_s)
        if kept is not None:
            trajectories.append(kept)
        if on_method is not None:
            on_method(method)
    return pd.concat(episodes, ignore_index=True), (
        pd.concat(trajectories, ignore_index=True) if trajectories else None
    )


def lost_people(people_xy_m, people_present, first: int, dt_s: float) -> str | None:
    """Where a present person's position in a batch of episodes (``people_xy_m`` (B, T, P, 2),
    ``people_present`` (B, T, P)) is not finite, in words (the first such person, variant
    ``first + b`` and time), or None. The metrics would pass over them (NaN compares false) and the
    table count a crowd that is not there; a human model's constants can do it (a body wider than
    the scene's corridors)."""
    xy, present = np.asarray(people_xy_m), np.asarray(people_present)
    lost = present & ~np.isfinite(xy).all(axis=-1)
    if not lost.any():
        return None
    variant, step, person = (int(i[0]) for i in np.nonzero(lost))
    return f"person {person}'s position is not finite at t = {(step + 1) * dt_s:.1f} s of variant {first + variant}"


def user_actor(factory: Callable, env, n_people: int | None = None) -> tuple[Actor, object]:
    """``(actor, params)`` from a user's factory called with the scene's env: it returns an
    :class:`~jaxsim.scenes.actor.Actor` (its params are then the env's robot limits,
    :class:`~jaxsim.scenes.robot.RobotParams`) or ``(actor, params)``. With ``n_people`` (the
    scene's padded people slots) the actor is traced once on such an observation and an action
    that is not of shape (2,) is refused (:func:`jaxsim.scenes.actor.check_actor`), before any
    episode runs."""
    made = factory(env)
    name = getattr(factory, "__name__", repr(factory))
    if isinstance(made, Actor):
        made = made, env.robot
    if not (isinstance(made, tuple) and len(made) == 2 and isinstance(made[0], Actor)):
        raise TypeError(f"{name}(env) must return an Actor or (Actor, params), got {type(made).__name__}")
    if n_people is not None:
        check_actor(env, made[0], made[1], n_people)
    return made
