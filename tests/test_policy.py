"""The learned policy (planners/learning/policy.py) and its PPO training (planners/learning/policy_training.py,
planners/learning/policy_run.py): features on hand-made observations, GAE on a known answer, training that
improves the return, a resumed run equal to an uninterrupted one, the collector's batch restarting
the episodes that end (and their social channel), the arena's --policy-run."""

from __future__ import annotations

import dataclasses
import json
import math

import jax
import jax.numpy as jnp
import numpy as np
import pandas as pd
import pytest

from socialnav.cli import main
from socialnav.common.machine import compiler_host, hosts_of
from socialnav.common.memory import available_bytes
from socialnav.data import RECORDED_SCENES_DIR, SCENES_DIR
from socialnav.jaxsim.scenes import env as env_lib
from socialnav.jaxsim.scenes.robot import RobotParams
from socialnav.jaxsim.scenes.spec import load_scene
from socialnav.jaxsim.scenes.variant import sample_variant
from socialnav.models import policy_net
from socialnav.models.social_costs import GRADED_TOP
from socialnav.planners.layers import costmap
from socialnav.planners.learning import policy as policy_lib
from socialnav.planners.learning import policy_run, policy_social, policy_training

EASY = "snape_static_person"  # untrained, the robot drives into the person and stays


def _observation(people_xy, people_velocity, visible, yaw=0.0, goal=(5.0, 0.0)):
    p = len(people_xy)
    return env_lib.Observation(
        robot_xy_m=jnp.zeros(2),
        robot_yaw_rad=jnp.float32(yaw),
        robot_speed_mps=jnp.float32(0.25),
        robot_turn_rate_rps=jnp.float32(-0.5),
        goal_xy_m=jnp.asarray(goal, jnp.float32),
        people_xy_m=jnp.asarray(people_xy, jnp.float32).reshape(p, 2),
        people_heading_rad=jnp.zeros(p),
        people_velocity_mps=jnp.asarray(people_velocity, jnp.float32).reshape(p, 2),
        people_visible=jnp.asarray(visible),
        occupancy=jnp.zeros((16, 16)),
        time_s=jnp.float32(0.0),
    )


@pytest.mark.slow
def test_features_read_the_goal_own_motion_and_nearest_people_in_the_robots_frame():
    config = policy_lib.PolicyConfig(n_people=2)
    grid = costmap.GridSpec(40, 40, 0.25, -5.0, -5.0)
    field = jnp.zeros((40, 40))
    robot = RobotParams()
    # Facing +y (yaw pi/2): the goal 5 m along +y is straight ahead; the person at (-2, 0) is
    # on the robot's left at 2 m, walking along +x (to the robot's right); the person at (0, 1)
    # is unseen, the one at (3, 3) seen but farther.
    obs = _observation(
        [(-2.0, 0.0), (0.0, 1.0), (3.0, 3.0)],
        [(1.0, 0.0), (0.0, 0.0), (0.0, 0.0)],
        [True, False, True],
        yaw=math.pi / 2,
        goal=(0.0, 5.0),
    )
    x = np.asarray(policy_lib.features(config, obs, field, grid, robot))
    assert x.shape == (config.n_features(16),)
    np.testing.assert_allclose(x[:3], [0.5, 1.0, 0.0], atol=1e-6)  # 5 m ahead
    np.testing.assert_allclose(x[3:5], [0.25 / 0.5, -0.5 / 1.0], atol=1e-6)
    people = x[-12:].reshape(2, 6)
    gap = 2.0 - robot.radius_m
    np.testing.assert_allclose(people[0], [0.0, 2.0 / 4, 0.0, -1.0 / 1.5, gap / 4, 1.0], atol=1e-6)
    far = math.hypot(3, 3)
    np.testing.assert_allclose(people[1][:2], [3 / 4, -3 / 4], atol=1e-6)  # ahead and to the right
    np.testing.assert_allclose(people[1][4:], [(far - robot.radius_m) / 4, 1.0], atol=1e-6)
    # Nobody seen: the people's slots are all zero.
    none = policy_lib.features(config, obs.replace(people_visible=jnp.zeros(3, bool)), field, grid, robot)
    assert np.all(np.asarray(none)[-12:] == 0.0)


@pytest.mark.slow
def test_the_optional_social_layer_channel_shows_a_person_ahead():
    grid = costmap.GridSpec(40, 40, 0.25, -5.0, -5.0)
    obs = _observation([(1.0, 0.0)], [(0.0, 0.0)], [True])
    plain = policy_lib.PolicyConfig(n_people=2)
    social = policy_lib.PolicyConfig(n_people=2, social_layer="snl_large")
    assert social.n_features(16) == plain.n_features(16) + 81
    x = np.asarray(policy_lib.features(social, obs, jnp.zeros((40, 40)), grid, RobotParams()))
    channel = x[5 + 81 : 5 + 162].reshape(9, 9)  # rows: forward offsets -2..2 m; columns: left
    assert x.shape == (social.n_features(16),) and 0.0 <= channel.min() and channel.max() <= 1.0
    assert channel[6, 4] == channel.max() > 0.2 and channel[0, 4] == 0.0  # peak 1 m ahead, none 2 m behind
    unseen = policy_lib.features(
        social, obs.replace(people_visible=jnp.array([False])), jnp.zeros((40, 40)), grid, RobotParams()
    )
    assert np.all(np.asarray(unseen)[5 + 81 : 5 + 162] == 0.0)
    with pytest.raises(ValueError, match="social_layer"):
        policy_lib.PolicyConfig(social_layer="snl_huge")
    with pytest.raises(ValueError, match="gscl_run"):
        policy_lib.PolicyConfig(social_layer="gscl")
    with pytest.raises(ValueError, match="carries state"):
        policy_lib.features(policy_lib.PolicyConfig(social_layer="casn"), obs, jnp.zeros((40, 40)), grid, RobotParams())


def test_the_casn_channel_shows_a_walker_at_its_collision_point_and_freezes_it():
    # A person 3 m ahead walking at the robot at 1 m/s: CASN puts their discs at the collision
    # point h - p (h - r), p = 1 / (1 + 0.5) (CASN's robot speed): 1 m ahead, inside 2 m: frozen.
    obs = _observation([(3.0, 0.0)], [(-1.0, 0.0)], [True])
    config = policy_lib.PolicyConfig(n_people=2, social_layer="casn")
    state = policy_social.initial_state(1)
    # Jitted as the policy runs it (op by op, this test compiled ~90 programs).
    casn_window = jax.jit(lambda o, s: policy_social.window("casn", o, policy_lib.window_points(config, o), s))
    window, state = casn_window(obs, state)
    channel = np.asarray(window).reshape(9, 9)
    assert channel[6, 4] == pytest.approx(252 / 254)  # 1 m ahead: intimate + personal discs
    assert channel[0, 4] == 0.0 and channel[8, 0] == 0.0  # 2 m behind; 2 m ahead, 2 m left (> 1.2 m)
    assert bool(state.casn.frozen[0]) and np.allclose(np.asarray(state.casn.frozen_xy_m[0]), (1.0, 0.0), atol=1e-5)
    # The person keeps walking (now 2 m ahead, their collision point 0.67 m): the frozen point stays.
    later = obs.replace(people_xy_m=jnp.array([[2.0, 0.0]]))
    again, state = casn_window(later, state)
    np.testing.assert_array_equal(np.asarray(again), np.asarray(window))
    x, _ = jax.jit(
        lambda o: policy_lib.observe(
            config, o, jnp.zeros((40, 40)), costmap.GridSpec(40, 40, 0.25, -5, -5), RobotParams(),
            policy_social.initial_state(1),
        )
    )(obs)  # fmt: skip
    np.testing.assert_array_equal(np.asarray(x)[5 + 81 : 5 + 162], np.asarray(window))


@pytest.mark.slow
def test_the_gscl_channel_reads_the_networks_window_where_it_was_computed():
    # A stand-in network that puts 0.5 on two cells of its 40 x 40 window of 0.4 m: rows 19-20,
    # column 22 hold x in [0.8, 1.2), y in [-0.4, 0.4) from the window's centre, where only the
    # policy's point 1 m ahead (0.5 m spacing) falls.
    def predict(maps):
        assert maps.shape[1:] == (40, 40) and maps.dtype == jnp.uint8
        return jnp.zeros(maps.shape, jnp.float32).at[:, 19:21, 22].set(0.5)

    config = policy_lib.PolicyConfig(n_people=2, social_layer="gscl", gscl_run="/runs/gscl")
    obs = _observation([(1.0, 0.0)], [(0.0, 0.0)], [True])
    spec = costmap.GridSpec(40, 40, 0.25, -5.0, -5.0)
    state = policy_social.initial_state(1)
    before, _ = policy_social.window("gscl", obs, policy_lib.window_points(config, obs), state)
    assert np.all(np.asarray(before) == 0.0)  # nothing computed yet
    state = policy_social.gscl_refresh(predict, jnp.zeros((40, 40)), spec, obs, state)
    window, _ = policy_social.window("gscl", obs, policy_lib.window_points(config, obs), state)
    channel = np.asarray(window).reshape(9, 9)
    # The layer reads a network's graded range [0, GRADED_TOP] as Nav2's [0, 252] (gscl_layer.read_cost).
    want = 0.5 / GRADED_TOP * 252 / 254
    assert channel[6, 4] == pytest.approx(want) and np.count_nonzero(channel) == 1  # (1.0, 0.0)
    # The robot moves 0.5 m forward: the same world cell is now 0.5 m ahead of it.
    moved = obs.replace(robot_xy_m=jnp.array([0.5, 0.0]))
    channel = np.asarray(policy_social.window("gscl", moved, policy_lib.window_points(config, moved), state)[0])
    assert channel.reshape(9, 9)[5, 4] == pytest.approx(want)


def test_guidance_field_is_zero_at_the_goal_and_no_shorter_than_the_straight_line():
    spec = load_scene(SCENES_DIR / f"{EASY}.json")
    env = env_lib.make_env(spec)
    grid = policy_lib.scene_grid(env)
    t = policy_lib.traversal(env)
    goal = jnp.asarray(sample_variant(spec, 0, 0).goal_xy)
    field = policy_lib.guidance_field(t, goal, grid)
    assert float(policy_lib.field_at(field, goal, grid)) == 0.0
    start = jnp.asarray(sample_variant(spec, 0, 0).robot_xy)
    along = float(policy_lib.field_at(field, start, grid))
    assert along >= float(jnp.linalg.norm(start - goal)) - 2 * grid.resolution_m
    assert math.isinf(float(policy_lib.field_at(field, jnp.array([1e3, 1e3]), grid)))  # off the map


def test_command_maps_the_normalised_action_onto_the_bases_limits():
    robot = RobotParams(max_speed_mps=0.8, max_turn_rate_rps=1.2)
    u = jnp.array([[-1.0, 0.0], [1.0, 1.0], [0.0, -0.5], [3.0, -7.0]])
    np.testing.assert_allclose(policy_lib.command(u, robot), [[0, 0], [0.8, 1.2], [0.4, -0.6], [0.8, -1.2]], atol=1e-6)


def test_gae_on_a_hand_computed_case():
    # One episode of 3 steps ending at step 1, then a new one; gamma 0.5, lambda 1 (Monte Carlo):
    # step 0: r0 + g r1 - v0 (the episode ends at 1); step 1: r1 - v1; step 2: r2 + g V_last - v2.
    values = jnp.array([[1.0], [2.0], [3.0]])
    rewards = jnp.array([[1.0], [4.0], [2.0]])
    dones = jnp.array([[False], [True], [False]])
    adv = policy_training.gae(values, rewards, dones, jnp.array([10.0]), 0.5, 1.0)
    np.testing.assert_allclose(adv[:, 0], [1 + 0.5 * 4 - 1, 4 - 2, 2 + 0.5 * 10 - 3], atol=1e-6)
    # lambda 0: one-step TD errors.
    adv0 = policy_training.gae(values, rewards, dones, jnp.array([10.0]), 0.5, 0.0)
    np.testing.assert_allclose(adv0[:, 0], [1 + 0.5 * 2 - 1, 4 - 2, 2 + 0.5 * 10 - 3], atol=1e-6)


def test_training_variants_are_a_stream_of_their_own():
    spec = load_scene(SCENES_DIR / f"{EASY}.json")
    for k in range(5):
        train = sample_variant(spec, 0, k, training=True)
        for other in (sample_variant(spec, 0, k), sample_variant(spec, 0, k, held_out=True)):
            assert not np.array_equal(train.robot_xy, other.robot_xy) or not np.array_equal(
                train.goal_xy, other.goal_xy
            )
    with pytest.raises(ValueError, match="not both"):
        sample_variant(spec, 0, 0, held_out=True, training=True)


def test_training_episodes_end_where_the_arenas_do():
    """The trainer's episodes have the arena's step and time limit (whole replanning periods)."""
    from socialnav.evaluation.arena.episodes import ArenaConfig

    config = ArenaConfig()
    assert policy_training.ARENA_PERIOD_STEPS == config.replan_every_steps
    for name in ("casn_head_on", "gscl_crowded_entrance", "snape_walking"):
        spec = load_scene(SCENES_DIR / f"{name}.json")
        trainer_env = policy_training.scene_env(spec).config
        assert trainer_env.dt_s == config.env.dt_s
        periods = math.ceil(spec.timeout_s / (config.env.dt_s * config.replan_every_steps))
        assert trainer_env.max_steps == periods * config.replan_every_steps


@pytest.mark.slow
def test_the_trainers_batch_restarts_the_episodes_that_end_and_their_social_channel():
    """The collector's world (``batch_step``) and actor (``sampling_actor``), as the control loop
    runs them: an episode at its time limit ends, is counted and restarts at time 0 on a pool
    variant while the others go on; the actor gives a restarted episode a fresh social channel
    whatever it carried, and keeps the others'."""
    spec = load_scene(SCENES_DIR / f"{EASY}.json")
    config = dataclasses.replace(
        _tiny(1), envs_per_scene=4, pool_per_scene=8, policy=policy_lib.PolicyConfig(hidden=(8,), social_layer="casn")
    )
    scene = policy_training.make_scene(spec, config)
    runner = policy_training.init_runner(scene, config, jax.random.key(0), spec.rule)
    last = scene.env.config.max_steps - 1
    world = policy_training.BatchWorld(runner.env_state.replace(step=jnp.array([last, 0, 0, 0])), jnp.int32(0))
    grid = policy_lib.scene_grid(scene.env)
    env = policy_training.training_env(scene, config, grid, spec.rule)
    stand = jnp.zeros((4, 2))
    action = policy_training.Sampled(stand, jnp.zeros((4, 1)), stand, jnp.zeros(4), jnp.zeros(4))
    step = jax.jit(policy_training.batch_step(env, scene.pool, jax.random.split(jax.random.key(1), 3)))
    world, out = step(world, action)
    assert np.asarray(out.done).tolist() == [True, False, False, False] and int(world.steps) == 1
    assert int(out.ended[0]) == 1 and int(out.ended[2]) == 0  # one episode ended, by its time limit
    np.testing.assert_allclose(np.asarray(out.observation.observation.time_s), [0.0, 0.1, 0.1, 0.1], atol=1e-6)
    assert np.asarray(world.env_state.step).tolist() == [0, 1, 1, 1]
    assert 0 <= int(out.observation.pool_index[0]) < config.pool_per_scene

    graphdef, weights = policy_net.init_weights(config.policy.n_features(16), (8,), 0, -0.5)
    actor = policy_training.sampling_actor(config, graphdef, grid)
    params = policy_training.SamplerParams(weights, scene.fields, scene.env.robot, jnp.zeros((grid.height, grid.width)))
    fresh = actor.init(None, out.observation)
    casn = fresh.social.casn
    carried = fresh.replace(
        social=fresh.social.replace(casn=casn.replace(frozen=~casn.frozen, frozen_xy_m=casn.frozen_xy_m + 3.0))
    )
    # only the restarted episode gets a fresh channel
    started = policy_training._started(carried.social, out.observation.observation)
    assert not bool(started.casn.frozen[0].any()) and bool(started.casn.frozen[1:].all())
    act = jax.jit(lambda state: actor.act(params, state, out.observation, jax.random.key(2)))
    (a_fresh, s_fresh), (a_carried, s_carried) = act(fresh), act(carried)
    np.testing.assert_array_equal(np.asarray(a_fresh.features[0]), np.asarray(a_carried.features[0]))
    for leaf_fresh, leaf_carried in zip(
        jax.tree.leaves(s_fresh.social), jax.tree.leaves(s_carried.social), strict=True
    ):
        np.testing.assert_array_equal(np.asarray(leaf_fresh[0]), np.asarray(leaf_carried[0]))
    assert int(s_carried.steps) == 1 and a_fresh.command.shape == (4, 2)


def test_config_round_trips_and_refuses_bad_values():
    config = policy_training.PPOConfig(scenes=("a", "b"), updates=7, policy=policy_lib.PolicyConfig(hidden=(16,)))
    assert policy_training.PPOConfig.from_json(json.loads(json.dumps(config.to_json()))) == config
    with pytest.raises(ValueError, match="envs_per_scene"):
        policy_training.PPOConfig(envs_per_scene=0)
    with pytest.raises(ValueError, match="unknown setting"):
        policy_training.PPOConfig.from_json({**config.to_json(), "learning_rat": 1.0})
    with pytest.raises(ValueError, match="human_model must be one of social_force"):
        policy_training.PPOConfig(human_model="zombies")
    # a run written before the setting existed trained among the social force
    old = {k: v for k, v in config.to_json().items() if k != "human_model"}
    assert policy_training.PPOConfig.from_json(old).human_model == "social_force"


def _tiny(updates: int, seed: int = 0) -> policy_training.PPOConfig:
    return policy_training.PPOConfig(
        scenes=(EASY,),
        envs_per_scene=32,
        rollout_steps=64,
        updates=updates,
        minibatches=4,
        pool_per_scene=32,
        seed=seed,
        checkpoint_every=100,
        policy=policy_lib.PolicyConfig(hidden=(64, 64)),
    )


@pytest.mark.slow
def test_a_tiny_training_run_improves_the_return():
    spec = load_scene(SCENES_DIR / f"{EASY}.json")
    trainer = policy_training.Trainer([spec], _tiny(15))
    state = trainer.initial_state()
    before = policy_training.evaluate_return(trainer, state.weights, 16)
    for _ in range(15):
        state, metrics = trainer.step(state)
    after = policy_training.evaluate_return(trainer, state.weights, 16)
    assert np.isfinite(metrics["policy_loss"]) and metrics["env_steps"] == 15 * 32 * 64
    assert 0.0 <= metrics["social_rate"] <= metrics["goal_rate"]  # social success: the goal and the rule
    assert after > before + 1.0, (before, after)  # measured: -20.0 -> 0.4


@pytest.mark.slow
def test_a_run_resumed_after_a_stop_equals_one_never_stopped(tmp_path):
    spec = load_scene(SCENES_DIR / f"{EASY}.json")
    config = _tiny(4)
    whole = policy_run.train([spec], config, tmp_path / "whole", progress=False)
    cut = tmp_path / "cut"
    first = policy_run.train([spec], config, cut, progress=False, stop_after_updates=2)
    assert len(first) == 2 and (cut / "checkpoints" / "2").is_dir()
    rest = policy_run.train([spec], config, cut, progress=False, log=lambda _: None)
    assert [h["update"] for h in rest] == [1, 2, 3, 4]
    for a, b in zip(whole, rest, strict=True):  # NaN (no episode ended yet) compares equal as JSON
        assert json.dumps({k: v for k, v in a.items() if k != "wall_s"}) == json.dumps(
            {k: v for k, v in b.items() if k != "wall_s"}
        )
    _, _, w_whole, step_whole = policy_run.load_weights(tmp_path / "whole")
    _, _, w_cut, step_cut = policy_run.load_weights(cut)
    assert step_whole == step_cut == 4
    for a, b in zip(jax.tree.leaves(w_whole), jax.tree.leaves(w_cut), strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    lines = (cut / "metrics.jsonl").read_text().splitlines()
    assert len(lines) == 4 and (cut / "curve.png").stat().st_size > 0
    assert hosts_of([json.loads(line) for line in lines]) == [compiler_host()]  # where each update ran
    # Trained on for longer: the same run with more updates continues it.
    longer = policy_run.train([spec], _tiny(5), cut, progress=False, log=lambda _: None)
    assert [h["update"] for h in longer] == [1, 2, 3, 4, 5] and policy_run.read_config(cut)[0].updates == 5
    # Another configuration in the same folder is refused, naming the file.
    with pytest.raises(policy_run.PolicyRunError, match="config.json"):
        policy_run.train([spec], _tiny(4, seed=1), cut, progress=False)


@pytest.mark.slow
def test_policy_train_and_arena_policy_run_from_the_command_line(tmp_path, capsys):
    run = tmp_path / "ppo"
    argv = ["policy", "train", "--out", str(run), "--scenes", EASY, "--updates", "2", "--envs-per-scene", "8"]
    assert main([*argv, "--rollout-steps", "16", "--no-progress"]) == 0
    assert "update 2:" in capsys.readouterr().out
    out = tmp_path / "arena"
    code = main(
        ["arena", "--out", str(out), "--scenes", EASY, "--methods", "navfn", "--variants", "3"]
        + ["--policy-run", str(run), "--no-progress"]
    )
    assert code == 0
    summary = pd.read_csv(out / "summary.csv")
    assert set(summary.method) == {"navfn", "ppo"}
    assert json.loads((out / "run.json").read_text())["policy_model"]


@pytest.mark.slow
def test_a_resume_keeps_the_recorded_settings_and_says_when_one_changes(tmp_path, capsys):
    """Started with --updates 3 and resumed with the same options but no --updates: still a
    3-update run (it became a 300-update one, its config.json rewritten); a new --updates is
    taken and said; another change is refused naming the field."""
    run = tmp_path / "ppo"
    argv = ["policy", "train", "--out", str(run), "--scenes", EASY, "--envs-per-scene", "4", "--rollout-steps", "8"]
    assert main([*argv, "--updates", "3", "--no-progress"]) == 0
    capsys.readouterr()
    assert main([*argv, "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "3 updates" in out and "given" not in out and policy_run.read_config(run)[0].updates == 3
    assert main([*argv, "--updates", "4", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "updates 4 given, the run recorded 3" in out and policy_run.read_config(run)[0].updates == 4
    assert len((run / "metrics.jsonl").read_text().splitlines()) == 4
    assert main([*argv[:-2], "--rollout-steps", "16", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "other settings (rollout_steps)" in err and len(err.strip().splitlines()) == 1


@pytest.mark.slow
def test_a_policy_trains_among_a_recorded_crowd_moved_by_the_human_model_asked(tmp_path, capsys):
    """``--scenes`` takes a recorded scene by a pattern of its name, ``--human-model`` is recorded in the run and
    moves the reactive people of the env the policy trains in."""
    run = tmp_path / "ppo"
    argv = ["policy", "train", "--out", str(run), "--scenes", "hotel_reac*", "--updates", "1"]
    argv += ["--envs-per-scene", "4", "--rollout-steps", "8", "--human-model", "collision_free_speed_calibrated"]
    assert main([*argv, "--no-progress"]) == 0
    assert "people moved by collision_free_speed_calibrated" in capsys.readouterr().out
    config = policy_run.read_config(run)[0]
    assert config.scenes == ("hotel_reactive",) and config.human_model == "collision_free_speed_calibrated"
    spec = load_scene(RECORDED_SCENES_DIR / "hotel_reactive.json")
    assert policy_training.make_scene(spec, config).env.config.human_model == "collision_free_speed_calibrated"
    assert main([*argv[:-2], "--human-model", "orca", "--no-progress"]) == 2  # a resumed run keeps its people
    assert "other settings (human_model)" in capsys.readouterr().err


def _truncate_step(folder):
    for f in folder.rglob("*"):
        if f.is_file() and f.stat().st_size > 100:
            f.write_bytes(f.read_bytes()[: f.stat().st_size // 3])


@pytest.mark.slow
def test_a_damaged_policy_checkpoint_falls_back_to_the_intact_one(tmp_path):
    """The newest checkpoint damaged: training resumes from the older one with a warning (it
    blamed "an earlier version" and advised starting over), saves the lost updates again, and
    resumes again; the benchmark reads the intact weights. Every checkpoint damaged: one line
    naming each step and the fix."""
    spec = load_scene(SCENES_DIR / f"{EASY}.json")
    config = dataclasses.replace(_tiny(4), envs_per_scene=4, rollout_steps=8, checkpoint_every=2)
    run = tmp_path / "run"
    policy_run.train([spec], config, run, progress=False)
    _truncate_step(run / "checkpoints" / "4")
    said = []
    assert policy_run.load_weights(run, log=said.append)[3] == 2 and "using step 2" in said[-1]
    history = policy_run.train([spec], config, run, progress=False, log=said.append)
    assert [h["update"] for h in history] == [1, 2, 3, 4]
    assert any("skipped unreadable checkpoint" in w and "step 4" in w for w in said)
    assert any("removed the unreadable checkpoint of step 4" in w for w in said)
    assert policy_run.load_weights(run)[3] == 4
    assert policy_run.train([spec], config, run, progress=False, log=said.append)[-1]["update"] == 4
    for step in ("2", "4"):
        _truncate_step(run / "checkpoints" / step)
    with pytest.raises(policy_run.PolicyRunError, match="no checkpoint restores") as err:
        policy_run.train([spec], config, run, progress=False, log=said.append)
    assert "step 4" in str(err.value) and "step 2" in str(err.value) and "remove the damaged" in str(err.value)


def test_bad_input_to_policy_train_and_arena_policy_run_is_one_line(tmp_path, capsys):
    code = main(["policy", "train", "--out", str(tmp_path / "r"), "--scenes", "no_such_scene", "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2 and "unknown no_such_scene" in err and len(err.strip().splitlines()) == 1
    (tmp_path / "notarun").mkdir()
    code = main(["arena", "--out", str(tmp_path / "a"), "--scenes", EASY, "--policy-run", str(tmp_path / "notarun")])
    err = capsys.readouterr().err
    assert code == 2 and "config.json" in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize(
    ("size", "says"),
    [
        pytest.param(
            ["--envs-per-scene", "1000000"],
            "GB at once",  # 5.8 TB: was an out-of-memory kill
            marks=pytest.mark.skipif(available_bytes() is None, reason="no /proc/meminfo here: no memory check"),
        ),
        (["--rollout-steps", "10000000"], "past the 2^31"),  # 9e9 transitions: was an OverflowError traceback
    ],
)
def test_an_update_too_large_for_the_machine_is_refused_before_anything_is_written(tmp_path, capsys, size, says):
    out = tmp_path / "r"
    assert main(["policy", "train", "--out", str(out), *size, "--updates", "1", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert says in err and size[0] in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_the_python_entry_refuses_the_same_sizes_before_it_makes_the_folder(tmp_path):
    from socialnav.data import SCENES_DIR
    from socialnav.jaxsim.scenes.spec import load_scene
    from socialnav.planners.learning import policy_run
    from socialnav.planners.learning.policy_training import PPOConfig, size_problem

    config = PPOConfig(rollout_steps=10_000_000)
    with pytest.raises(policy_run.PolicyRunError, match=r"rollout_steps 10000000 .* past the 2\^31"):
        policy_run.train([load_scene(SCENES_DIR / f"{EASY}.json")] * 4, config, tmp_path / "r")
    assert not (tmp_path / "r").exists()
    assert "GB at once" in size_problem(14, PPOConfig(), available_bytes=10**9)  # 2.9 GB against 1 GB free
    assert size_problem(14, PPOConfig(), available_bytes=None) is None  # nothing known: no memory check


def test_the_memory_estimate_grows_with_every_transition_of_an_update():
    from socialnav.planners.learning.policy_training import PPOConfig, memory_bytes, transitions_per_update

    small, wide = PPOConfig(), PPOConfig(envs_per_scene=256)
    assert transitions_per_update(14, small) == 14 * 64 * 64
    assert memory_bytes(14, wide) - memory_bytes(14, small) == pytest.approx(
        (transitions_per_update(14, wide) - transitions_per_update(14, small)) * 6.5e3
    )


@pytest.mark.slow
def test_a_policy_with_the_gscl_channel_trains_and_runs_in_the_arena(tmp_path, capsys):
    from socialnav.models import train as gscl_train
    from socialnav.models.config import TrainConfig

    gscl = tmp_path / "gscl"
    tiny = TrainConfig(
        features=(4, 4, 8, 8), epochs=1, batch_size=16, train_fraction=0.01, test_fraction=0.004, warmup_steps=1
    )
    gscl_train.train(tiny, gscl, progress=False, max_steps=2, log=lambda *_: None)
    run = tmp_path / "ppo"
    argv = ["policy", "train", "--out", str(run), "--scenes", EASY, "--updates", "1", "--envs-per-scene", "4"]
    argv += ["--rollout-steps", "12", "--social-layer", "gscl", "--gscl-run", str(gscl), "--no-progress"]
    assert main(argv) == 0
    config, _ = policy_run.read_config(run)
    assert config.policy.social_layer == "gscl" and config.policy.gscl_run == str(gscl.resolve())
    out = tmp_path / "arena"
    code = main(
        ["arena", "--out", str(out), "--scenes", EASY, "--methods", "navfn", "--variants", "2"]
        + ["--policy-run", str(run), "--no-progress"]
    )
    assert code == 0
    assert set(pd.read_csv(out / "summary.csv").method) == {"navfn", "ppo"}
    # The benchmark's digest covers the GSCL network the policy reads, not only its own weights.
    digest = json.loads((out / "run.json").read_text())["policy_model"]
    assert digest == policy_run.run_digest(run) != policy_run.weights_digest(policy_run.load_weights(run)[2])
    capsys.readouterr()
    # --gscl-run goes with --social-layer gscl; a folder that is no model is named.
    not_a_run = ["--social-layer", "gscl", "--gscl-run", str(tmp_path)]
    for extra in (["--gscl-run", str(gscl)], not_a_run):
        code = main(["policy", "train", "--out", str(tmp_path / "bad"), "--scenes", EASY, "--no-progress", *extra])
        err = capsys.readouterr().err
        assert code == 2 and "--gscl-run" in err and len(err.strip().splitlines()) == 1
