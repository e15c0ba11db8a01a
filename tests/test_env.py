"""The environment (reset/step), actors and the rollout: determinism, batching, specs, reward,
the wrappers, and a user's own actor from Python and from the command line."""

from __future__ import annotations

import json

import jax
import jax.numpy as jnp
import numpy as np
import pandas as pd
import pytest

from socialnav import cli
from socialnav.data import DATA_DIR
from socialnav.evaluation.arena import episodes as arena
from socialnav.jaxsim.scenes import env as env_lib
from socialnav.jaxsim.scenes import robot as robot_lib
from socialnav.jaxsim.scenes import specs
from socialnav.jaxsim.scenes.actor import Actor, rollout
from socialnav.jaxsim.scenes.spec import load_scene
from socialnav.jaxsim.scenes.variant import sample_variant, sample_variants
from socialnav.planners import actors


@pytest.fixture(scope="module")
def setup():
    return arena.setup_scene(load_scene(DATA_DIR / "scenes" / "casn_head_on.json"))


def _variants(setup, n, seed=0):
    return jax.tree_util.tree_map(jnp.asarray, sample_variants(setup.spec, seed, n, 0, False, setup.n_slots))


def _leaves(tree):
    """The arrays of a pytree, typed keys as their raw data (comparable)."""
    keys = lambda a: jax.random.key_data(a) if jax.dtypes.issubdtype(a.dtype, jax.dtypes.prng_key) else a
    return [np.asarray(keys(a)) for a in jax.tree_util.tree_leaves(tree)]


def _one(variants, k):
    return jax.tree_util.tree_map(lambda a: a[k], variants)


@pytest.mark.slow
def test_reset_and_step_are_deterministic_and_follow_the_specs(setup):
    env = setup.env
    variant = _one(_variants(setup, 1), 0)
    key = jax.random.key(1)
    reset, step = jax.jit(env.reset), jax.jit(env.step)
    s1, t1 = reset(key, variant)
    s2, t2 = reset(key, variant)
    action = jnp.array([0.4, 0.3])
    for _ in range(5):
        s1, t1 = step(s1, action)
        s2, t2 = step(s2, action)
    for a, b in zip(_leaves((s1, t1)), _leaves((s2, t2)), strict=True):
        np.testing.assert_array_equal(a, b)
    n = variant.valid.shape[0]
    spec = env.observation_spec(n)
    for field, value in zip(jax.tree.leaves(spec), jax.tree.leaves(t1.observation), strict=True):
        assert value.shape == field.shape and value.dtype == field.dtype, field.name
    assert specs.problems(spec, t1.observation) == []
    assert jax.tree.structure(jax.tree.map(lambda s: s.zeros(), spec)) == jax.tree.structure(t1.observation)
    wrong = t1.observation.replace(people_xy_m=jnp.zeros((n + 1, 2)), people_visible=jnp.zeros(n))
    assert specs.problems(spec, wrong) == [
        f"people_xy_m: shape ({n + 1}, 2), expected ({n}, 2)",
        "people_visible: dtype float32, expected bool",
    ]
    action = env.action_spec()
    assert action.shape == (2,) and action.maximum[0] == pytest.approx(float(env.robot.max_speed_mps))
    assert action.problem(jnp.zeros(3)) == "action: shape (3,), expected (2,)" and action.problem(jnp.zeros(2)) is None
    assert float(t1.observation.time_s) == pytest.approx(0.5)


@pytest.mark.slow
def test_the_base_clips_an_action_beyond_its_limits(setup):
    env = setup.env
    state, _ = jax.jit(env.reset)(jax.random.key(0), _one(_variants(setup, 1), 0))
    step = jax.jit(env.step)
    for _ in range(40):
        state, ts = step(state, jnp.array([50.0, -50.0]))
        assert float(ts.observation.robot_speed_mps) <= float(env.robot.max_speed_mps) + 1e-6
        assert abs(float(ts.observation.robot_turn_rate_rps)) <= float(env.robot.max_turn_rate_rps) + 1e-6


@pytest.mark.slow
def test_a_variant_alone_equals_the_same_variant_in_a_batch(setup):
    """Through the arena's batch program (padded to a multiple of ``arena.LANES``: XLA
    vectorises other batch sizes differently)."""
    actor = actors.go_to_goal()
    variants = _variants(setup, 9)
    together = arena.actor_function(setup, actor, setup.env.robot)(variants)
    four = arena.actor_function(setup, actor, setup.env.robot)(jax.tree_util.tree_map(lambda a: a[:4], variants))
    for a, b in zip(_leaves(four), _leaves(together), strict=True):
        np.testing.assert_array_equal(a, b[:4])
    for k in (0, 8):
        alone = arena.actor_function(setup, actor, setup.env.robot)(
            jax.tree_util.tree_map(lambda a, k=k: a[k : k + 1], variants)
        )
        for a, b in zip(_leaves(alone), _leaves(together), strict=True):
            np.testing.assert_array_equal(a[0], b[k])


def _open_room(tmp_path):
    scene = {
        "name": "open_room",
        "bounds_m": [-4, 4, -3, 3],
        "walls": [[-4, 4, -3, -2.9], [-4, 4, 2.9, 3], [-4, -3.9, -3, 3], [3.9, 4, -3, 3]],
        "robot": {"start": [-3, 0.5], "yaw_deg": 0, "goal": [3, 0]},
        "timeout_s": 30,
        "people": [],
        "rule": {"type": "min_distance", "distance_m": 0.45},
    }
    path = tmp_path / "open_room.json"
    path.write_text(json.dumps(scene))
    return load_scene(path)


@pytest.mark.slow
def test_reward_pays_the_goal_once_and_charges_a_contact(tmp_path):
    """A scene without people: driving to the goal earns the progress made plus the goal reward,
    once. Then a person placed on the robot: the collision penalty."""
    spec = _open_room(tmp_path)
    setup_ = arena.setup_scene(spec)
    env = setup_.env
    variant = jax.tree_util.tree_map(jnp.asarray, sample_variant(spec, 0, 0, n_slots=setup_.n_slots))
    (state, _), records = jax.jit(lambda v: rollout(env, actors.go_to_goal(), env.robot, v, jax.random.key(0)))(variant)
    reward = np.asarray(records.reward)
    reached = np.asarray(records.reached)
    assert reached[-1] and not reached[0]
    start = np.asarray(variant.robot_xy)
    goal = np.asarray(variant.goal_xy)
    end_before = np.asarray(records.robot_xy_m)[np.argmax(reached)]
    progress = np.linalg.norm(start - goal) - np.linalg.norm(end_before - goal)
    expected = env.reward.goal_reward + env.reward.progress_weight * progress
    assert reward.sum() == pytest.approx(expected, rel=1e-4)
    assert np.all(reward[np.argmax(reached) + 1 :] == 0.0)
    # A person on top of the robot.
    s, _ = jax.jit(env.reset)(jax.random.key(0), variant)
    people = s.people.replace(xy=s.people.xy.at[0].set(s.robot.xy), present=s.people.present.at[0].set(True))
    s = s.replace(people=people, variant=s.variant.replace(valid=s.variant.valid.at[0].set(True)))
    _, ts = jax.jit(env.step)(s, jnp.zeros(2))
    assert bool(ts.info.person_contact)
    assert float(ts.reward) <= env.reward.collision_penalty + 1e-6


@pytest.mark.slow
def test_a_parameter_sweep_reuses_the_compiled_program(setup):
    variants = _variants(setup, 2)
    actor = actors.go_to_goal()
    fast_tr = arena.actor_function(setup, actor, setup.env.robot)(variants)
    compiled = arena._episode_program(actor)._cache_size()  # other modules' shapes may be there too
    slow_tr = arena.actor_function(setup, actor, setup.env.robot.replace(max_speed_mps=0.25))(variants)
    assert float(jnp.max(slow_tr.robot_speed_mps)) <= 0.25 + 1e-6 < float(jnp.max(fast_tr.robot_speed_mps))
    assert arena._episode_program(actor)._cache_size() == compiled  # the speed limit is traced


MY_ACTOR = '''
import jax.numpy as jnp
from socialnav.jaxsim.scenes.actor import Actor


def creep(env):
    """Straight at the goal at a third of the speed limit, no planner."""

    def act(robot, state, obs, key):
        to_goal = obs.goal_xy_m - obs.robot_xy_m
        error = jnp.arctan2(to_goal[1], to_goal[0]) - obs.robot_yaw_rad
        error = jnp.arctan2(jnp.sin(error), jnp.cos(error))
        return jnp.stack([robot.max_speed_mps / 3, 2.0 * error]), state

    return Actor(init=lambda key, obs: (), act=act)


def broken(env):
    return 42
'''


@pytest.mark.slow
def test_a_users_actor_runs_from_the_command_line_beside_the_built_in_ones(tmp_path):
    module = tmp_path / "my_actor.py"
    module.write_text(MY_ACTOR)
    argv = ["arena", "--scenes", "casn_static_person", "--methods", "navfn", "--variants", "3", "--no-progress"]
    out = tmp_path / "run"
    assert cli.main([*argv, "--actor", f"{module}:creep", "--out", str(out)]) == 0
    summary = pd.read_csv(out / "summary.csv")
    assert list(summary["method"]) == ["navfn", "creep"]
    episodes = pd.read_parquet(out / "episodes" / "casn_static_person.parquet")
    creep = episodes[episodes.method == "creep"]
    assert len(creep) == 3 and creep["time_s"].min() > episodes[episodes.method == "navfn"]["time_s"].max()


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("nowhere_module_xyz:make", "cannot import nowhere_module_xyz"),
        ("{module}:missing", "has no function missing"),
        ("{module}:broken", "must return an Actor"),
        ("{module}", "expected module:function"),
        ("{module}:navfn_x", "has no function navfn_x"),
    ],
)
def test_a_bad_actor_is_refused_in_one_line(tmp_path, capsys, spec, message):
    module = tmp_path / "my_actor.py"
    module.write_text(MY_ACTOR)
    argv = ["arena", "--scenes", "casn_static_person", "--variants", "1", "--no-progress", "--out", str(tmp_path / "o")]
    assert cli.main([*argv, "--actor", spec.format(module=module)]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
    assert not (tmp_path / "o" / "run.json").exists()


def test_an_actor_named_like_a_built_in_method_is_refused(tmp_path, capsys):
    module = tmp_path / "my_actor.py"
    module.write_text(MY_ACTOR + "\nnavfn = creep\n")
    argv = ["arena", "--scenes", "casn_static_person", "--variants", "1", "--out", str(tmp_path / "o")]
    assert cli.main([*argv, "--actor", f"{module}:navfn"]) == 2
    assert "is taken" in capsys.readouterr().err


def test_an_actor_is_an_immutable_pair_of_functions():
    actor = Actor(init=lambda key, obs: (), act=lambda p, s, o, k: (jnp.zeros(2), s))
    with pytest.raises(AttributeError):
        actor.name = "other"  # frozen: a cache key
    assert env_lib.episode_steps(30.0, 0.1, 10) == 300 and env_lib.episode_steps(30.05, 0.1, 10) == 310


# ---------------------------------------------------------------- Gymnasium


def test_the_gymnasium_env_passes_the_env_checker():
    gym_env = pytest.importorskip("socialnav.jaxsim.scenes.gym_env")
    from gymnasium.utils.env_checker import check_env

    env = gym_env.SocialNavEnv(load_scene(DATA_DIR / "scenes" / "casn_head_on.json"), pool=8)
    check_env(env, skip_render_check=True)
    obs, _ = env.reset(seed=3)
    assert env.observation_space.contains(obs)


@pytest.mark.slow
def test_the_vector_env_steps_a_batch_and_resets_an_ended_episode_on_the_next_step():
    gym_env = pytest.importorskip("socialnav.jaxsim.scenes.gym_env")
    spec = load_scene(DATA_DIR / "scenes" / "casn_head_on.json")
    venv = gym_env.SocialNavVectorEnv(spec, num_envs=3, pool=8, config=env_lib.EnvConfig(max_steps=5))
    obs, _ = venv.reset(seed=1)
    again, _ = gym_env.SocialNavVectorEnv(spec, num_envs=3, pool=8, config=env_lib.EnvConfig(max_steps=5)).reset(seed=1)
    for k in obs:
        np.testing.assert_array_equal(obs[k], again[k])
    assert venv.observation_space.contains(obs) and obs["people_xy_m"].shape[0] == 3
    action = np.tile(venv.single_action_space.high, (3, 1))
    for step in range(1, 6):
        obs, reward, terminated, truncated, _ = venv.step(action)
        assert reward.shape == (3,) and reward.dtype == np.float32
        np.testing.assert_allclose(obs["time_s"], 0.1 * step, rtol=1e-5)
    assert truncated.all() and not terminated.any()
    obs, reward, terminated, truncated, _ = venv.step(action)  # the new episodes' first observations
    assert np.all(obs["time_s"] == 0.0) and np.all(reward == 0.0) and not (terminated | truncated).any()
    assert venv.observation_space.contains(obs)


@pytest.mark.slow
def test_a_layer_parameter_sweep_reuses_the_stacks_program(setup):
    """The SNL covariance is a traced leaf: a wider one changes the episodes, not the program."""
    from socialnav.planners import stack
    from socialnav.planners.layers import snl_layer as snl

    variants = _variants(setup, 2)
    method = stack.METHODS["snl_small"]
    small = arena.episode_function(setup, method)(variants)
    actor = arena.method_actor(method, setup.grid, float(setup.env.robot.radius_m), arena.ArenaConfig())
    compiled = arena._episode_program(actor)._cache_size()  # other modules' shapes may be there too
    wide = stack.layer_params(method).replace(snl=snl.SNLParams(covariance=2.0))
    large = arena.episode_function(setup, method, layers=wide)(variants)
    assert arena._episode_program(actor)._cache_size() == compiled
    assert not np.array_equal(np.asarray(small.robot_xy_m), np.asarray(large.robot_xy_m))


# ---------------------------------------------------------------- a scene file to the planner's Scene


@pytest.mark.slow
def test_planner_scene_is_the_variant_at_its_start_and_moves_with_time(setup):
    variant = _one(_variants(setup, 2, seed=3), 1)
    truth = arena.planner_scene(setup, variant)
    present = np.asarray(truth.people_valid)
    assert present.any()
    np.testing.assert_allclose(np.asarray(truth.people_xy_m)[present], np.asarray(variant.xy0)[present], atol=1e-6)
    np.testing.assert_array_equal(np.asarray(truth.robot_xy_m), np.asarray(variant.robot_xy))
    np.testing.assert_array_equal(np.asarray(truth.goal_xy_m), np.asarray(variant.goal_xy))
    later = arena.planner_scene(setup, variant, time_s=2.0)
    moved = np.linalg.norm(np.asarray(later.people_xy_m) - np.asarray(truth.people_xy_m), axis=-1)[present]
    assert moved.max() > 0.5  # walkers at about 1 m/s for 2 s
    np.testing.assert_array_equal(np.asarray(later.robot_xy_m), np.asarray(truth.robot_xy_m))  # it stood
    # What the sensors report is a subset of the truth, at the true places, velocities unknown at t = 0.
    seen = arena.planner_scene(setup, variant, perceived=True)
    visible = np.asarray(seen.people_valid)
    assert not (visible & ~present).any()
    np.testing.assert_allclose(np.asarray(seen.people_xy_m)[visible], np.asarray(truth.people_xy_m)[visible])


@pytest.mark.slow
def test_scene_from_file_draws_the_arenas_variant_and_names_a_bad_file(setup, tmp_path):
    from socialnav.evaluation import scene_from_file

    scene, file_setup = scene_from_file(DATA_DIR / "scenes" / "casn_head_on.json", variant=1, seed=3)
    expected = arena.planner_scene(setup, _one(_variants(setup, 2, seed=3), 1))
    for a, b in zip(_leaves(scene), _leaves(expected)):
        np.testing.assert_array_equal(a, b)
    assert file_setup.grid == setup.grid
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"name": "bad"}))
    with pytest.raises(ValueError, match="bad.json"):
        scene_from_file(bad)
    with pytest.raises(ValueError, match="variant must be an integer >= 0"):
        scene_from_file(DATA_DIR / "scenes" / "casn_head_on.json", variant=-1)
    # The held-out row is the mirrored scene: the goal's y flips about the bounds' middle.
    mirrored, _ = scene_from_file(DATA_DIR / "scenes" / "gscl_l_hallway.json", held_out=True)
    plain, hall = scene_from_file(DATA_DIR / "scenes" / "gscl_l_hallway.json")
    middle = hall.spec.bounds_m[2] + hall.spec.bounds_m[3]
    assert float(mirrored.goal_xy_m[1]) == pytest.approx(middle - float(plain.goal_xy_m[1]), abs=1.0)


# ---------------------------------------------------------------- actions at the boundary


@pytest.mark.parametrize("bad", [jnp.array([jnp.nan, 0.3]), jnp.array([0.5, jnp.inf]), jnp.array([-jnp.inf, 0.0])])
def test_a_non_finite_action_stops_the_robot_and_is_marked(bad):
    """On a scene whose people walk around the robot: a NaN or infinite action is never applied
    (the base stops), the step says so, and nothing turns NaN: not the robot, the people who
    avoid it, nor the reward."""
    setup = arena.setup_scene(load_scene(DATA_DIR / "scenes" / "snape_walking.json"))
    env = setup.env
    state, ts = jax.jit(env.reset)(jax.random.key(0), _one(_variants(setup, 1), 0))
    step = jax.jit(env.step)
    for _ in range(5):
        state, ts = step(state, jnp.array([0.5, 0.0]))
    assert not bool(ts.info.invalid_action)
    moving_xy = np.asarray(state.robot.xy)
    for _ in range(20):
        state, ts = step(state, bad)
        assert bool(ts.info.invalid_action)
    assert float(ts.observation.robot_speed_mps) == pytest.approx(0.0, abs=1e-6)
    assert np.linalg.norm(np.asarray(state.robot.xy) - moving_xy) < 0.5  # braked, not driven
    for leaf in jax.tree_util.tree_leaves((ts.observation, ts.reward, state.people.xy, state.robot)):
        if jnp.issubdtype(leaf.dtype, jnp.floating):
            assert np.all(np.isfinite(np.asarray(leaf))), leaf
    state, ts = step(state, jnp.array([0.5, 0.0]))
    assert not bool(ts.info.invalid_action) and float(ts.observation.robot_speed_mps) > 0.0


@pytest.mark.slow
@pytest.mark.parametrize("bad", [jnp.array([0.5]), jnp.array([0.5, 0.1, 9.0]), jnp.float32(0.5), jnp.zeros((1, 2))])
def test_an_action_of_another_shape_is_refused_when_traced(setup, bad):
    env = setup.env
    state, _ = env.reset(jax.random.key(0), _one(_variants(setup, 1), 0))
    with pytest.raises(ValueError, match=r"shape \(2,\)"):
        jax.jit(env.step)(state, bad)
    with pytest.raises(ValueError, match=r"shape \(2,\)"):
        env.step(state, bad)
    variants = _variants(setup, 2)
    states, _ = jax.vmap(env.reset)(jax.random.split(jax.random.key(0), 2), variants)
    with pytest.raises(ValueError, match=r"shape \(2,\)"):  # a batch of scalars: one lane's shape is ()
        jax.vmap(env.step)(states, jnp.zeros(2))


def _actor_returning(action):
    return Actor(init=lambda key, obs: (), act=lambda p, s, o, k: (action, s), name="odd")


@pytest.mark.parametrize("action", [jnp.zeros(1), jnp.zeros(3), jnp.float32(0.0), jnp.zeros((2, 2))])
def test_check_actor_refuses_an_action_of_another_shape(setup, action):
    from socialnav.jaxsim.scenes.actor import check_actor

    with pytest.raises(ValueError, match=r"actor 'odd'.*shape \(2,\)"):
        check_actor(setup.env, _actor_returning(action), (), setup.n_slots)
    check_actor(setup.env, _actor_returning(jnp.zeros(2)), (), setup.n_slots)  # the right one passes
    check_actor(setup.env, _actor_returning((0.1, 0.0)), (), setup.n_slots)  # a pair reads as (2,)


@pytest.mark.slow
def test_the_gymnasium_adapters_stop_on_a_nan_action_and_refuse_a_wrong_shape():
    gym_env = pytest.importorskip("socialnav.jaxsim.scenes.gym_env")
    spec = load_scene(DATA_DIR / "scenes" / "snape_walking.json")
    env = gym_env.SocialNavEnv(spec, pool=4)
    env.reset(seed=0)
    for _ in range(5):
        obs, reward, *_, info = env.step(np.array([np.nan, np.nan], np.float32))
        assert info["invalid_action"] and np.isfinite(reward)
        assert env.observation_space.contains(obs)
    obs, *_, info = env.step(env.action_space.high)
    assert not info["invalid_action"] and env.observation_space.contains(obs)
    assert isinstance(info["person_contact"], bool) and isinstance(info["rule_kept"], bool)
    for bad in (np.zeros(1), np.zeros(3), 0.5, np.zeros((1, 2)), "fast"):
        with pytest.raises(ValueError, match=r"SocialNavEnv.step: actions must"):
            env.step(bad)
    venv = gym_env.SocialNavVectorEnv(spec, num_envs=2, pool=4)
    venv.reset(seed=0)
    obs, *_, info = venv.step(np.array([[np.inf, 0.0], [0.3, 0.0]], np.float32))
    assert list(info["invalid_action"]) == [True, False] and venv.observation_space.contains(obs)
    # The step's contact and the scene's rule so far (jaxsim.scenes.wrappers.RuleMonitor), per episode.
    assert set(info) == {"invalid_action", "person_contact", "rule_kept"}
    assert all(v.shape == (2,) and v.dtype == bool for v in info.values())
    with pytest.raises(ValueError, match=r"shape \(2, 2\).*got shape \(2,\)"):
        venv.step(np.zeros(2))


NAN_ACTORS = """
import jax.numpy as jnp
from socialnav.jaxsim.scenes import Actor


def nan_after_a_second(env):
    def act(robot, state, obs, key):
        return jnp.where(obs.time_s > 1.0, jnp.nan, 1.0) * jnp.array([robot.max_speed_mps, 0.0]), state

    return Actor(init=lambda key, obs: (), act=act, name="nan_after_a_second")


def one_number(env):
    return Actor(init=lambda key, obs: (), act=lambda p, s, o, k: (jnp.array([0.5]), s), name="one_number")


def a_scalar(env):
    return Actor(init=lambda key, obs: (), act=lambda p, s, o, k: (jnp.float32(0.5), s), name="a_scalar")
"""


@pytest.mark.slow
def test_the_arena_marks_an_actor_whose_actions_go_non_finite(tmp_path, capsys):
    module = tmp_path / "nan_actors.py"
    module.write_text(NAN_ACTORS)
    out = tmp_path / "run"
    argv = ["arena", "--scenes", "snape_walking", "--methods", "navfn", "--variants", "2", "--no-progress"]
    assert cli.main([*argv, "--actor", f"{module}:nan_after_a_second", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "nan_after_a_second gave a NaN or infinite action in 100 %" in err and "Traceback" not in err
    summary = pd.read_csv(out / "summary.csv").set_index("method")
    assert summary.loc["nan_after_a_second", "invalid_action_pct"] == 100.0
    assert summary.loc["navfn", "invalid_action_pct"] == 0.0
    episodes = pd.read_parquet(out / "episodes" / "snape_walking.parquet")
    broken = episodes[episodes.method == "nan_after_a_second"]
    assert (broken["invalid_action_steps"] > 0).all() and np.isfinite(broken["d_min_m"]).all()
    trajectories = pd.read_parquet(out / "trajectories" / "snape_walking.parquet")
    assert np.isfinite(trajectories.filter(regex="^(robot|p\\d+)_[xy]$").to_numpy()).all()
    assert (out / "pictures" / "methods.png").is_file()


@pytest.mark.parametrize("function", ["one_number", "a_scalar"])
def test_the_arena_refuses_an_actor_whose_action_has_another_shape(tmp_path, capsys, function):
    module = tmp_path / "nan_actors.py"
    module.write_text(NAN_ACTORS)
    argv = ["arena", "--scenes", "snape_walking", "--methods", "navfn", "--variants", "2", "--no-progress"]
    assert cli.main([*argv, "--actor", f"{module}:{function}", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f"actor '{function}'" in err and "shape (2,)" in err, err
    assert not (tmp_path / "o" / "run.json").exists()


def test_a_velocity_models_people_feel_the_robot_widened_to_the_envs_bodies(setup):
    """A velocity model's people keep their own fitted body (0.18 m for the steering model),
    narrower than the env's person (0.25 m) whose contacts the metrics count: they feel the robot
    widened by the difference, so the contact distance is the env's; the social force's people
    feel the robot as it is."""
    from socialnav.jaxsim.scenes.env import EnvConfig, felt_robot_radius_m, make_env
    from socialnav.jaxsim.speed_model import CALIBRATED

    steering = make_env(setup.spec, EnvConfig(human_model="steering_speed_calibrated"))
    body = CALIBRATED["steering_speed_calibrated"].radius_m
    felt = float(felt_robot_radius_m(steering.config, steering.robot, steering.velocity))
    assert felt == pytest.approx(steering.robot.radius_m + steering.config.person_radius_m - body)
    assert felt + body == pytest.approx(steering.robot.radius_m + steering.config.person_radius_m)
    plain = make_env(setup.spec, EnvConfig())
    assert float(felt_robot_radius_m(plain.config, plain.robot, plain.velocity)) == pytest.approx(plain.robot.radius_m)


def _counting_actor(every_steps: int) -> Actor:
    """An actor whose plan counts its calls and whose action carries the count (v = plans so far)."""
    from socialnav.jaxsim.actor import replanning

    def plan(params, plans, obs, key):
        return plans + 1

    def act(params, plans, obs, key):
        return jnp.stack([plans.astype(jnp.float32), jnp.float32(0.0)]), plans

    inner = Actor(init=lambda key, obs: jnp.int32(0), act=act, name="counting")
    return replanning(inner, plan, every_steps)


@pytest.mark.parametrize(
    "every, due",  # one in the fast tier; each other period compiles two programs of its own
    [
        (10, [0, 10, 20]),
        pytest.param(7, [0, 7, 14, 21], marks=pytest.mark.slow),
        pytest.param(0, [0], marks=pytest.mark.slow),
    ],
)
def test_replanning_plans_before_every_nth_action_and_only_then_in_a_batch(setup, every, due):
    """``replanning(actor, plan, every)``: the plan runs before actions 0, every, 2 every, ...
    (``every = 0``: before the first only), the same in a vmapped batch as alone, and a batch's
    program asks whether a plan is due with one scalar ``cond`` (a select would plan every step)."""
    from socialnav.jaxsim.actor import Replanned, inner_state

    actor = _counting_actor(every)
    variants = _variants(setup, 3)
    run = lambda v: rollout(setup.env, actor, setup.env.robot, v, jax.random.key(1), n_steps=25)
    (_, final), records = jax.jit(jax.vmap(run))(variants)
    plans_by_step = np.asarray(records.action)[:, :, 0]
    expected = np.cumsum(np.isin(np.arange(25), due))
    assert (plans_by_step == expected).all()
    assert isinstance(final, Replanned) and (np.asarray(inner_state(final)) == len(due)).all()
    (_, alone), _ = jax.jit(run)(_one(variants, 1))
    assert int(inner_state(alone)) == len(due)
    # Every cond of the single episode's program is still a cond in the batch's (a batched
    # predicate would have made the plan's a select).
    batched, single = jax.make_jaxpr(jax.vmap(run))(variants), jax.make_jaxpr(run)(_one(variants, 1))
    assert str(batched).count("cond[") == str(single).count("cond[") >= 1
    with pytest.raises(ValueError, match="every_steps must be >= 0"):
        _counting_actor(-1)


@pytest.mark.slow
def test_reset_where_restarts_only_the_episodes_asked_and_runs_no_reset_when_none_is(setup):
    """jaxsim.scenes.wrappers: a batch of four, two restarted from pool draws, equal bit for bit to
    env.reset of those draws; the other two as stepped; with an empty mask nothing is reset."""
    from socialnav.jaxsim.scenes import wrappers

    env = setup.env
    pool = wrappers.VariantPool(_variants(setup, 6, seed=3))
    assert pool.size == 6
    index = pool.draw(jax.random.key(0), 4)
    assert index.shape == (4,) and bool(jnp.all((index >= 0) & (index < 6)))
    keys = jax.random.split(jax.random.key(1), 4)
    state, ts = jax.jit(jax.vmap(env.reset))(keys, pool.take(index))
    state, ts = jax.jit(jax.vmap(env.step))(state, jnp.full((4, 2), 0.3))
    mask = jnp.array([True, False, True, False])
    fresh_keys = jax.random.split(jax.random.key(2), 4)
    fresh_index = jnp.array([5, 4, 3, 2])
    restart = jax.jit(lambda m: wrappers.reset_where(env, m, fresh_keys, pool.take(fresh_index), state, ts))
    new_state, new_ts = restart(mask)
    for b in range(4):
        if mask[b]:
            want = jax.jit(env.reset)(fresh_keys[b], _one(pool.variants, int(fresh_index[b])))
        else:
            want = (_one(state, b), _one(ts, b))
        for got, expected in zip(_leaves(_one((new_state, new_ts), b)), _leaves(want), strict=True):
            np.testing.assert_array_equal(got, expected)
    assert int(new_state.step[0]) == 0 and int(new_state.step[1]) == 1
    for got, expected in zip(_leaves(restart(jnp.zeros(4, bool))), _leaves((state, ts)), strict=True):
        np.testing.assert_array_equal(got, expected)


def _to_goal_actor(speed_mps: float = 0.6) -> Actor:
    """Drives at ``speed_mps`` and turns towards the goal (a robot that meets whoever is on its line)."""

    def act(params, state, obs, key):
        to_goal = obs.goal_xy_m - obs.robot_xy_m
        error = jnp.arctan2(to_goal[1], to_goal[0]) - obs.robot_yaw_rad
        return jnp.stack([jnp.float32(speed_mps), 2.0 * jnp.arctan2(jnp.sin(error), jnp.cos(error))]), state

    return Actor(init=lambda key, obs: jnp.int32(0), act=act, name="to_goal")


def test_wrappers_keep_the_pool_index_the_shaped_reward_the_rule_and_the_episodes_statistics(setup):
    """jaxsim.scenes.wrappers stacked as the PPO trainer stacks them, against the bare env on the
    same draws: the same motion; the reward plus 0.1 per metre gained on a straight-line potential
    (clipped, none once the goal was reached); the return, length and contact as the steps add
    them; the rule's verdict equal to the arena's check of the whole trajectory; and a restart
    through reset_where sets every episode's extras back to their start."""
    from socialnav.evaluation.arena import nav_metrics
    from socialnav.jaxsim.scenes import wrappers

    env = setup.env
    rule = {"type": "visit", "box": [-4.5, 4.5, 0.05, 1.0]}  # kept by some of these draws, not all
    pool = wrappers.VariantPool(_variants(setup, 5, seed=4))
    distance_to_goal_m = lambda s, _: jnp.linalg.norm(s.robot.xy - s.variant.goal_xy)
    shaped = wrappers.PotentialShaping(wrappers.FromPool(env, pool), distance_to_goal_m, weight=0.1, clip_m=0.5)
    wrapped = wrappers.EpisodeStatistics(wrappers.RuleMonitor.of(shaped, rule))
    assert wrapped.config is env.config and wrapped.unwrapped is env and wrapped.robot is env.robot

    def record(seen, action, actor_state, ts):
        return ts.reward, ts.info.person_contact, ts.observation.robot_xy_m, ts.info.reached, ts.info.people_xy_m

    index, key, steps = jnp.array([4, 0, 2, 2]), jax.random.key(5), 200
    run = lambda e, v: rollout(e, _to_goal_actor(), e.robot, v, key, n_steps=steps, record=record)
    (final, _), (reward, contact, xy, reached, people_xy) = jax.jit(jax.vmap(lambda i: run(wrapped, i)))(index)
    (bare_final, _), (bare_reward, *_) = jax.jit(jax.vmap(lambda v: run(env, v)))(pool.take(index))

    np.testing.assert_array_equal(np.asarray(final.robot.xy), np.asarray(bare_final.robot.xy))
    np.testing.assert_array_equal(np.asarray(final.extras["pool_index"]), np.asarray(index))
    variants = pool.take(index)
    start = np.asarray(variants.robot_xy)[:, None]
    path = np.concatenate([start, np.asarray(xy)], axis=1)
    to_go = np.linalg.norm(path - np.asarray(variants.goal_xy)[:, None], axis=-1)
    was_reached = np.concatenate([np.zeros((4, 1), bool), np.asarray(reached)[:, :-1]], axis=1)
    gained = np.where(was_reached, 0.0, np.clip(to_go[:, :-1] - to_go[:, 1:], -0.5, 0.5))
    np.testing.assert_allclose(np.asarray(reward) - np.asarray(bare_reward), 0.1 * gained, atol=1e-5)
    assert np.asarray(reached).any() and not np.asarray(reached).all()  # the mask is exercised

    e = final.extras
    np.testing.assert_allclose(np.asarray(e["episode_return"]), np.asarray(reward).sum(axis=1), rtol=1e-5)
    assert (np.asarray(e["episode_steps"]) == steps).all()
    np.testing.assert_array_equal(np.asarray(e["episode_person_contact"]), np.asarray(contact).any(axis=1))
    check = lambda *a: nav_metrics.rule_satisfied(rule, *a)
    arena_verdict = jax.vmap(check)(
        xy, reached, people_xy, variants.start_xy, variants.end_xy, jnp.ones(people_xy.shape[:-1], bool), variants.group
    )
    np.testing.assert_array_equal(np.asarray(e["rule_kept"]), np.asarray(arena_verdict))
    assert 0 < int(np.asarray(arena_verdict).sum()) < 4

    keys = jax.random.split(jax.random.key(6), 4)
    mask = jnp.array([True, False, False, True])
    fresh, ts = jax.vmap(wrapped.reset)(keys, index)
    restarted, _ = jax.jit(lambda m: wrappers.reset_where(wrapped, m, keys, index, final, ts))(mask)
    assert list(np.asarray(restarted.extras["episode_steps"])) == [0, steps, steps, 0]
    for got, start, end in zip(*(_leaves(t.extras) for t in (restarted, fresh, final)), strict=True):
        np.testing.assert_array_equal(got[[0, 3]], start[[0, 3]])
        np.testing.assert_array_equal(got[[1, 2]], end[[1, 2]])


@pytest.mark.parametrize(
    "setting",
    [
        {"dt_s": 0.0},  # nothing would move
        {"dt_s": -0.1},
        {"dt_s": float("nan")},  # every position NaN
        {"goal_tolerance_m": -1.0},  # never reached
        {"person_radius_m": 0.0},
        {"person_radius_m": 3.0},  # every pair of people in contact
        {"person_radius_m": 0.05},
        {"window_resolution_m": 0.0},
        {"sensor_range_m": -1.0},
        {"sensor_range_m": float("nan")},
        {"max_steps": 0},
        {"max_steps": 2.5},
        {"window_cells": -2},
        {"human_model": "zombies"},
    ],
)
def test_an_env_setting_no_episode_can_run_with_is_refused_naming_the_field(setting):
    """Each ran before (a step of 0 moved nothing, a NaN one made every position NaN)."""
    ((name, _),) = setting.items()
    with pytest.raises(ValueError, match=rf"^EnvConfig\.{name} must be"):
        env_lib.EnvConfig(**setting)


@pytest.mark.parametrize(
    ("config", "robot", "moved"),
    [
        (env_lib.EnvConfig(), robot_lib.RobotParams(max_speed_mps=3.0), "0.3 m"),
        (env_lib.EnvConfig(dt_s=0.6), robot_lib.RobotParams(), "0.3 m"),  # the default 0.5 m/s robot
    ],
)
def test_an_env_whose_step_could_carry_the_robot_through_a_wall_is_refused(setup, config, robot, moved):
    """A step at top speed not shorter than the robot's radius (``jaxsim.scenes.robot``)."""
    with pytest.raises(ValueError, match=rf"max_speed_mps .*dt_s .* moves {moved}, not less than the robot's radius"):
        env_lib.make_env(setup.spec, config, robot)
    assert env_lib.make_env(setup.spec, env_lib.EnvConfig(dt_s=0.5), robot_lib.RobotParams()).config.dt_s == 0.5


def test_the_env_settings_at_their_edges_are_accepted():
    """No sensor limit, no occupancy window, a numpy step count (the arena computes some)."""
    config = env_lib.EnvConfig(sensor_range_m=float("inf"), window_cells=0, max_steps=np.int64(5))
    assert config.max_steps == 5 and env_lib.config_problem(config) is None
