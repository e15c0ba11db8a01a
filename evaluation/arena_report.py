"""The arena's tables: per-episode metrics and trajectories as pandas frames, the per-scene summary.

``run_scene`` runs every method on a scene's variants (common random numbers: variant k is the
same for every method) and returns the per-episode metrics frame and the trajectories it keeps;
:func:`summary` reduces episodes to one row per scene and method, success rates with Wilson 95 %
intervals (``scipy.stats.binomtest``), the rest as means.
"""

from __future__ import annotations

import functools
from collections.abc import Callable

import jax
import jax.numpy as jnp
import numpy as np
import pandas as pd
from scipy import stats

from socialnav.common.intervals import wilson
from socialnav.evaluation import arena, nav_metrics
from socialnav.evaluation.arena_params import ArenaParams
from socialnav.evaluation.papers import RATES
from socialnav.jaxsim.scenes.actor import Actor, check_actor
from socialnav.jaxsim.scenes.spec import SceneSpec, mirror
from socialnav.jaxsim.scenes.variant import Variant, sample_variants
from socialnav.planners.baselines import BASELINES
from socialnav.planners.stack import METHODS

SUMMARY_MEANS = (
    "collisions",
    "intrusions",
    "d_min_m",
    "d_h_m",
    "d_1_m",
    "d_2_m",
    "time_s",
    "path_length_m",
    "chc_rad",
    "stalled_s",
    "spl",
    "zone_intimate",
    "zone_personal",
    "zone_social",
    "zone_public",
    "zone_body_intimate",
    "zone_body_personal",
    "zone_body_social",
    "zone_body_public",
    "group_share",
    "wall_contacts",
    "collisions_robot",
    "collisions_person",
    "intrusions_robot",
    "intrusions_person",
    "near_misses",
    "clearance_min_m",
    "group_intrusions",
    "speed_mean_mps",
    "turn_rate_mean_rps",
    "accel_mean_mps2",
    "jerk_mean_mps3",
    "path_irregularity_rad_per_m",
    "path_length_ratio",
    "no_progress_max_s",
    "people_speed_drop_mps",
    "people_deviation_m",
    "people_deviation_max_m",
)
# Shares of episodes reported in % beside the success rates (no interval).
SUMMARY_SHARES = ("deadlock", "timeout")


def _velocities(people_xy, present, dt_s):
    """(T, P, 2) people's velocities by finite differences (0 where a person is absent)."""
    v = jnp.diff(people_xy, axis=0, prepend=people_xy[:1]) / dt_s
    return jnp.where(present[..., None], v, 0.0)


def metrics_function(setup: arena.SceneSetup, config: arena.ArenaConfig, robot_radius_m: float):
    """``(trajectories, variants, trajectories without the robot) -> dict of metric arrays``, jitted
    and vmapped over episodes (the third from :func:`evaluation.arena.counterfactual_function`).

    The scene's rule enters as arguments (:func:`evaluation.nav_metrics.split_rule`), so a scene
    and its held-out mirror, or two scenes with rules of the same kinds, share one compiled program
    (compiling it took 1.6 s a scene row)."""
    structure, numbers = nav_metrics.split_rule(setup.spec.rule)
    program = _metrics_program(structure, setup.n_periods, config, float(robot_radius_m))
    return lambda tr, variants, without: program(tr, variants, without, numbers)


@functools.lru_cache(maxsize=64)
def _metrics_program(rule_structure, n_periods: int, config: arena.ArenaConfig, robot_radius_m: float):
    """The jitted metrics of :func:`metrics_function` for one rule structure (cached)."""
    timeout = n_periods * config.replan_every_steps * config.dt_s

    def one(tr: arena.Trajectory, v: Variant, without: arena.Trajectory, numbers):
        rule = nav_metrics.join_rule(rule_structure, numbers)
        velocity = _velocities(tr.people_xy, tr.people_present, config.dt_s)
        ok = nav_metrics.rule_satisfied(
            rule, tr.robot_xy, tr.reached, tr.people_xy, v.start_xy, v.end_xy, tr.people_present, v.group
        )
        metrics = nav_metrics.episode_metrics(
            tr.robot_xy,
            tr.robot_yaw,
            tr.robot_speed,
            tr.people_xy,
            velocity,
            tr.people_present,
            tr.reached,
            v.goal_xy,
            v.robot_xy,
            v.group,
            config.dt_s,
            timeout,
            robot_radius_m,
            config.person_radius_m,
            ok,
            config.goal_tolerance_m,
        )

        effect = nav_metrics.people_effect(
            tr.people_xy, tr.people_present, without.people_xy, without.people_present, config.dt_s
        )
        return {**metrics, **effect}

    return jax.jit(jax.vmap(one, in_axes=(0, 0, 0, None)))


def episode_frame(
    scene: str, method: str, first: int, metrics: dict, wall_contacts, invalid_actions=None
) -> pd.DataFrame:
    """One row per episode: scalar metrics, zone shares, the first people's minimum distances,
    the wall contacts and ``invalid_action_steps`` (the steps whose action had a NaN or infinite
    entry, the base stopped instead; 0 for a sound actor)."""
    m = {k: np.asarray(v) for k, v in metrics.items()}
    n = len(m["goal_success"])
    rows = {"scene": [scene] * n, "method": [method] * n, "variant": np.arange(first, first + n)}
    for key, value in m.items():
        if key in ("zone_share", "zone_share_body"):
            for z, name in enumerate(nav_metrics.ZONE_NAMES):
                rows[f"zone_{'body_' if key.endswith('body') else ''}{name}"] = value[:, z]
        elif key == "d_person_m":
            for p in range(min(value.shape[1], 2)):
                rows[f"d_{p + 1}_m"] = np.where(np.isfinite(value[:, p]), value[:, p], np.nan)  # NaN: nobody there
        else:
            rows[key] = value
    rows["wall_contacts"] = np.asarray(wall_contacts)
    rows["invalid_action_steps"] = np.zeros(n, np.int32) if invalid_actions is None else np.asarray(invalid_actions)
    frame = pd.DataFrame(rows)
    frame["metrics_version"] = nav_metrics.VERSION
    return frame


_KEPT = ("robot_xy", "robot_yaw", "robot_speed", "reached", "speed_gain", "people_xy", "people_present")


def trajectory_frame(scene: str, method: str, first: int, tr: arena.Trajectory, keep: int, dt_s: float):
    """Long frame of the first ``keep`` episodes: one row per (variant, step), the robot's pose and
    speed, and ``p<k>_x, p<k>_y, p<k>_present`` per person slot."""
    keep = min(keep, tr.robot_xy.shape[0])
    if keep == 0:
        return None
    # To the host first, then the first ``keep``: slicing the device arrays compiled a small
    # program per array and scene shape (0.1-0.15 s a method, half a minute over the full table).
    host = {k: np.asarray(getattr(tr, k))[:keep] for k in _KEPT}
    t = host["robot_xy"].shape[1]
    xy = host["robot_xy"].reshape(-1, 2)
    cols = {
        "scene": scene,
        "method": method,
        "variant": np.repeat(np.arange(first, first + keep), t),
        "t_s": np.tile((np.arange(t) + 1) * dt_s, keep),
        "robot_x": xy[:, 0],
        "robot_y": xy[:, 1],
        **{k: host[k].reshape(-1) for k in ("robot_yaw", "robot_speed", "reached", "speed_gain")},
    }
    pxy, present = host["people_xy"], host["people_present"]
    for p in range(pxy.shape[2]):
        cols[f"p{p}_x"] = pxy[:, :, p, 0].reshape(-1)
        cols[f"p{p}_y"] = pxy[:, :, p, 1].reshape(-1)
        cols[f"p{p}_present"] = present[:, :, p].reshape(-1)
    return pd.DataFrame(cols)


HELD_OUT = "@held_out"


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
):
    """Every method on variants ``first .. first + n_variants - 1`` of one scene:
    ``(episodes frame, trajectories frame or None)``. ``held_out``: the scene mirrored
    (:func:`jaxsim.scenes.spec.mirror`) with every range drawn just outside itself, its rows named
    ``<scene>@held_out``. ``user_actors``: method name -> a factory ``env -> Actor`` or ``env ->
    (Actor, params)`` (:func:`user_actor`), for the names of ``methods`` that are not built in.
    ``params``: the robot's limits and the layers' parameters (:mod:`evaluation.arena_params`;
    default: the seeds' values). ``gscl_model``: the network of method ``gscl``
    (:func:`planners.layers.gscl`: a :class:`~socialnav.models.inference.SocialCostModel`, its
    weights traced, so another checkpoint of the same network reuses the compiled program; or a
    function of the maps). ``n_devices``: host devices the methods run
    on at the same time (:func:`evaluation.arena.run_spread`; default: every local one)."""
    name = spec.name + (HELD_OUT if held_out else "")
    if held_out:
        spec = mirror(spec)
    setup = arena.setup_scene(spec, config)
    arena.release_programs_if_crowded(caches=(_metrics_program,), key=arena.program_key(setup))
    crowd = arena.crowd_params()
    variants = jax.tree_util.tree_map(
        jnp.asarray, sample_variants(spec, seed, n_variants, first, held_out, setup.n_slots)
    )
    params = ArenaParams() if params is None else params
    robot = params.robot
    measure = metrics_function(setup, config, float(robot.radius_m))
    episodes, trajectories = [], []
    user_actors = user_actors or {}
    runs = [arena.counterfactual_function(setup, crowd)]  # the people without the robot
    for method in methods:
        if method in user_actors:
            env = setup.env.replace(crowd=crowd, robot=robot)
            actor, actor_params = user_actor(user_actors[method], env, setup.n_slots)
            runs.append(arena.actor_function(setup, actor, actor_params, env))
        elif method in BASELINES:
            runs.append(arena.baseline_function(setup, method, crowd, robot, config))
        else:
            runs.append(
                arena.episode_function(
                    setup,
                    METHODS[method],
                    crowd,
                    robot,
                    config,
                    gscl_model,
                    layers=params.layers_for(method),
                )
            )
    results = arena.run_spread(runs, variants, n_devices)
    without = next(results)
    for method, tr in zip(methods, results):
        metrics = measure(tr, variants, without)
        episodes.append(episode_frame(name, method, first, metrics, tr.wall_contacts, tr.invalid_actions))
        kept = trajectory_frame(name, method, first, tr, keep_trajectories, config.dt_s)
        if kept is not None:
            trajectories.append(kept)
        if on_method is not None:
            on_method(method)
    return pd.concat(episodes, ignore_index=True), (
        pd.concat(trajectories, ignore_index=True) if trajectories else None
    )


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


# The means that get a 95 % interval in the summary (``<key>_lo``, ``<key>_hi``).
INTERVAL_MEANS = (
    "collisions", "intrusions", "d_min_m", "d_h_m", "d_1_m", "d_2_m", "time_s", "path_length_m", "chc_rad", "spl",
    "zone_intimate", "zone_personal", "zone_social",
)  # fmt: skip


def mean_interval(values) -> tuple[float, float]:
    """95 % Student-t interval of a mean (``scipy.stats.t``; NaN and inf dropped); the mean itself
    twice when every value is equal, NaN with fewer than two values."""
    x = np.asarray(values, float)
    x = x[np.isfinite(x)]
    if len(x) < 2:
        return float("nan"), float("nan")
    m, se = float(x.mean()), float(stats.sem(x))
    if se == 0:
        return m, m
    lo, hi = stats.t.interval(0.95, len(x) - 1, loc=m, scale=se)
    return float(lo), float(hi)


def summary(episodes: pd.DataFrame) -> pd.DataFrame:
    """One row per (scene, method): n, goal and social success and the share of episodes with a
    personal-space intrusion (%, :data:`RATES`) with Wilson 95 % intervals
    (``_ci`` as text, ``_lo``/``_hi`` in %), means, t intervals of :data:`INTERVAL_MEANS`, and
    ``invalid_action_pct``, the share of episodes in which the actor gave a NaN or infinite
    action at least once (its rows measure a robot stopped on those steps, not the method)."""
    rows = []
    for (scene, method), g in episodes.groupby(["scene", "method"], sort=False):
        n = len(g)
        row = {"scene": scene, "method": method, "n": n}
        for key in RATES:
            if key not in g:  # a run from before a rate existed
                continue
            k = int(g[key].sum())
            lo, hi = wilson(k, n)
            row[key + "_pct"] = 100.0 * k / n
            row[key + "_ci"] = f"{100 * lo:.0f}-{100 * hi:.0f}"
            row[key + "_lo"], row[key + "_hi"] = 100.0 * lo, 100.0 * hi
        for key in SUMMARY_SHARES:
            if key in g:
                row[key + "_pct"] = 100.0 * float(g[key].mean())
        if "invalid_action_steps" in g:
            row["invalid_action_pct"] = 100.0 * float((g["invalid_action_steps"] > 0).mean())
        for key in SUMMARY_MEANS:
            if key in g:
                values = g[key].replace([np.inf, -np.inf], np.nan)
                row[key] = float(values.mean())
                if key in INTERVAL_MEANS:
                    row[key + "_lo"], row[key + "_hi"] = mean_interval(values)
        rows.append(row)
    return pd.DataFrame(rows)
