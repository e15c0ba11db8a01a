"""Walking groups (Moussaïd et al. 2010, :mod:`jaxsim.groups`): the terms' known answers, a pair
that walks together under every human model where the same two people alone drift apart, groups
found in recorded windows, and a group strength recovered from trajectories walked with it."""

from __future__ import annotations

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from socialnav.data import WAREHOUSE_DIR
from socialnav.evaluation.humans import measures
from socialnav.evaluation.humans import trajectory_calibration as tc
from socialnav.evaluation.humans import validation as hv
from socialnav.jaxsim import groups, humans
from socialnav.jaxsim.grid import Grid
from socialnav.jaxsim.scenario.loader import load_scenario
from socialnav.jaxsim.walkers import Aims, RobotDisc, Walkers

P = groups.GroupParams()
FAR = RobotDisc(jnp.float32(1e4), jnp.float32(1e4), jnp.float32(0.0), jnp.float32(0.0), 0.0)


def _aim(xy, aim, speed, group_id, max_speed=2.0):
    xy, aim = np.asarray(xy, np.float32), np.asarray(aim, np.float32)
    n = len(xy)
    people = Walkers.of(jnp.asarray(xy), jnp.zeros((n, 2)), jnp.ones(n, bool), jnp.ones(n, bool))
    aims = Aims(jnp.asarray(aim[:, 0]), jnp.asarray(aim[:, 1]), jnp.asarray(speed, jnp.float32),
                jnp.full(n, max_speed, jnp.float32))  # fmt: skip
    out = groups.group_aim(P, people, aims, jnp.asarray(group_id, jnp.int32))
    return [np.asarray(a) for a in (out.dx_m, out.dy_m, out.speed_mps)]


def test_a_pair_side_by_side_within_reach_keeps_its_aims():
    dx, dy, speed = _aim([[0, 0], [0, 0.8]], [[10, 0], [10, 0]], [1.2, 1.4], [0, 0])
    np.testing.assert_allclose(dx, [10, 10], atol=1e-5)  # the mate is at 90 degrees: in view
    np.testing.assert_allclose(dy, [0, 0], atol=1e-5)  # 0.8 m apart: no attraction, no repulsion
    np.testing.assert_allclose(speed, [1.2, 1.4], atol=1e-6)


def test_the_one_ahead_slows_by_the_gaze_and_a_far_mate_is_pulled_in():
    # the mate 1.5 m straight behind: the head turns pi/2 beyond the 90 degree field, and the
    # pair is 0.75 m from its centre (> (2 - 1) / 2): attraction 3 m/s^2 towards it
    dx, dy, speed = _aim([[1.5, 0], [0, 0]], [[10, 0], [10, 0]], [1.2, 1.2], [3, 3])
    slow = 1 + P.relaxation_s * P.gaze_per_rad * math.pi / 2
    leader = (1.2 - P.relaxation_s * P.attraction_mps2) / slow
    assert speed[0] == pytest.approx(abs(leader), rel=1e-4)
    assert dx[0] < 0  # 1.2 - 1.5 < 0: the leader turns back towards the follower
    # the follower sees its mate ahead (no turn) and is pulled on: 1.2 + 1.5 m/s, capped at 2
    assert speed[1] == pytest.approx(2.0) and dx[1] > 0
    assert dy[1] == pytest.approx(0.0, abs=1e-5)


@pytest.mark.slow
def test_mates_closer_than_the_repulsion_distance_push_apart_and_no_one_alone_is_touched():
    dx, dy, speed = _aim([[0, 0], [0, 0.4], [0, 0.2]], [[10, 0], [10, 0], [10, 0]], [1.0, 1.0, 1.0], [5, 5, -1])
    w = P.relaxation_s * P.repulsion_mps2  # 0.5 m/s sideways, away from the mate
    np.testing.assert_allclose(speed[:2], np.hypot(1.0, w), rtol=1e-5)
    assert dy[0] < 0 < dy[1]
    assert (dx[2], dy[2], speed[2]) == (10.0, 0.0, 1.0)  # walks alone: exactly as given


def test_a_mate_who_is_not_present_leaves_the_other_alone():
    xy, aim = np.array([[0, 0], [5, 0]], np.float32), np.array([[10, 0], [10, 0]], np.float32)
    people = Walkers.of(jnp.asarray(xy), jnp.zeros((2, 2)), jnp.array([True, False]), jnp.ones(2, bool))
    aims = Aims(jnp.asarray(aim[:, 0]), jnp.asarray(aim[:, 1]), jnp.ones(2), jnp.ones(2) * 2)
    out = groups.group_aim(P, people, aims, jnp.zeros(2, jnp.int32))
    np.testing.assert_array_equal(np.asarray(out.speed_mps)[0], 1.0)
    np.testing.assert_array_equal(np.asarray(out.dx_m)[0], 10.0)


def _open_field():
    values = np.zeros((2, 2, 3), np.float32)
    values[..., 0] = 1e4
    values[..., 1] = 1.0
    return Grid.of_samples(jnp.asarray(values), -1e4, -1e4, 2e4)


@functools.partial(jax.jit, static_argnames=("model", "grouped", "n_steps"))
def _walk(model: str, grouped: bool, n_steps: int):
    """(T, 3, 2): a pair (desired 1.2 and 1.5 m/s, 0.7 m apart side by side) walking along +x,
    and a walker coming the other way between them."""
    params = humans.human_params(model, load_scenario(WAREHOUSE_DIR).params)
    xy = jnp.array([[0.0, 0.0], [0.0, 0.7], [12.0, 0.35]])
    direction = jnp.array([1.0, 1.0, -1.0])
    speed = jnp.array([1.2, 1.5, 1.3])
    group_id = jnp.array([0, 0, -1], jnp.int32) if grouped else None
    here = jnp.ones(3, bool)

    def step(carry, k):
        xy, v = carry
        u = jax.random.uniform(k, (2, 3), minval=1e-6, maxval=1.0)
        people = humans.step_humans(
            model, params, _open_field(), Walkers.of(xy, v, here, here), Aims(direction * 10.0, jnp.zeros(3), speed,
            speed), FAR, (u[0], u[1]), group_id,
        )  # fmt: skip
        return (people.xy_m, people.velocity_mps), people.xy_m

    _, path = jax.lax.scan(step, (xy, jnp.zeros_like(xy)), jax.random.split(jax.random.key(0), n_steps))
    return path


@pytest.mark.slow
@pytest.mark.parametrize("model", humans.HUMAN_MODELS)
def test_a_pair_walking_together_stays_within_1_m_where_alone_they_drift_apart(model):
    """Moussaïd's attraction starts where a pair is more than (2 - 1) / 2 m from its centre, so a
    pair holds about 1 m apart (the social force's own repulsion keeps it at that edge); the
    walker coming through between them parts them for a moment, by less than its body's width,
    and they close up again. (For the walker to pass, the two centres must be four body radii
    apart: more than 1 m for the bodies of 0.295 m that ``power_law_calibrated`` fitted.)"""
    from socialnav.evaluation.humans import calibration as hc

    together = np.asarray(_walk(model, True, 200))
    alone = np.asarray(_walk(model, False, 200))
    gap = np.linalg.norm(together[:, 0] - together[:, 1], axis=-1)[20:]  # after 2 s
    passing = 4 * hc.named_model(model).radius_m + 0.05
    assert np.percentile(gap, 95) <= max(1.05, passing), np.percentile(gap, 95)
    assert gap.max() <= 1.5 and gap[-1] <= 1.05, (gap.max(), gap[-1])
    assert np.linalg.norm(alone[-1, 0] - alone[-1, 1]) > 3.0  # 0.3 m/s apart for 20 s
    assert together[-1, :2, 0].min() > 12.0  # and the pair got past the walker


@pytest.mark.slow
def test_no_groups_and_everyone_alone_step_alike():
    params = humans.human_params("social_force", load_scenario(WAREHOUSE_DIR).params)
    people = Walkers(jnp.array([0.0, 0.5, 3.0]), jnp.array([0.0, 0.2, 0.1]), jnp.zeros(3), jnp.zeros(3),
                     jnp.ones(3, bool), jnp.ones(3, bool))  # fmt: skip
    aims = Aims(jnp.ones(3) * 10, jnp.zeros(3), jnp.ones(3), jnp.ones(3) * 1.5)
    args = (people, aims, FAR, (jnp.full(3, 0.5), jnp.full(3, 0.5)))
    plain = humans.step_humans("social_force", params, _open_field(), *args)
    alone = humans.step_humans("social_force", params, _open_field(), *args, group_id=jnp.full(3, -1, jnp.int32))
    for a, b in zip(jax.tree.leaves(plain), jax.tree.leaves(alone), strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


# ---------------------------------------------------------------- groups in recorded crowds


def test_walking_groups_are_people_moving_within_reach_all_window_long():
    t = np.arange(8)[:, None] * np.array([0.5, 0.0])  # 0.5 m a frame along x
    observed = np.stack([
        t + [0, 0], t + [0, 0.8],  # a pair abreast
        t + [0, 3.0],  # alone, 2.2 m from the pair
        np.zeros((8, 2)) + [5, 5], np.zeros((8, 2)) + [5, 5.5],  # standing together: not walking
        t + [0, -0.9],  # joins the pair's first member: a group of three
    ])[None]  # fmt: skip
    group = measures.walking_groups(observed)
    np.testing.assert_array_equal(group[0], [0, 0, -1, -1, -1, 0])
    observed[0, 1, 3] = np.nan  # absent for a frame: no longer scored as walking with anyone
    np.testing.assert_array_equal(measures.walking_groups(observed)[0], [0, -1, -1, -1, -1, 0])
    # Windows apart: a group never spans two windows, and its id is its lowest member's index in
    # its own window (here people 2 and 4 of the second window; 0 and 1 walk 3 m apart).
    second = np.stack([t + [0, 0], t + [0, 3.0], t + [0, 6.0], t + [0, 9.0], t + [0, 6.5], t + [0, 12.0]])
    both = measures.walking_groups(np.concatenate([observed, second[None]]))
    np.testing.assert_array_equal(both, [[0, -1, -1, -1, -1, 0], [-1, -1, 2, -1, 2, -1]])
    assert measures.walking_groups(np.zeros((0, 3, 8, 2))).shape == (0, 3)


def _synthetic_windows(truth: hv.HumanModel, n_windows: int = 32) -> hv.PredictionWindows:
    """Windows of two pairs each (desired 1.0 and 1.4 m/s abreast, heading at random), their
    futures walked by ``truth`` in groups."""
    rng = np.random.default_rng(0)
    heading = rng.uniform(0, 2 * np.pi, (n_windows, 2))
    e = np.stack([np.cos(heading), np.sin(heading)], -1)  # (W, 2 pairs, 2)
    side = np.stack([-e[..., 1], e[..., 0]], -1)
    centre = rng.uniform(-2, 2, (n_windows, 2, 2)) + np.array([[0.0, 0.0], [6.0, 0.0]])
    start = np.concatenate([centre, centre + 0.8 * side], axis=1).astype(np.float32)  # (W, 4, 2)
    speed = np.tile(np.array([1.0, 1.0, 1.4, 1.4], np.float32), (n_windows, 1))
    velocity = (np.concatenate([e, e], axis=1) * speed[..., None]).astype(np.float32)
    group = np.tile(np.array([0, 1, 0, 1], np.int32), (n_windows, 1))
    w = hv.PredictionWindows(start, velocity, speed, np.ones((n_windows, 4), bool), start, group,
                             np.zeros((n_windows, 4, 12, 2), np.float32), np.ones((n_windows, 4), bool),
                             np.zeros((n_windows, 4, 12, 2), np.float32), (0.4,) * n_windows)  # fmt: skip
    future = hv.window_predictor(truth.name, truth.dt_s, "velocity", True)(truth.params, w, jax.random.key(1))
    return w.replace(future=np.asarray(future))


@pytest.mark.slow
def test_calibration_on_trajectories_recovers_a_known_gaze_strength_by_gradient_and_by_search():
    model = hv.HumanModel("collision_free_speed")
    fields = ("group.gaze_per_rad",)
    truth = tc.with_values(model, fields, [1.5])
    windows = _synthetic_windows(truth)
    start = tc.with_values(model, fields, [4.0])
    assert float(tc.ade_loss(start, fields, jnp.log(jnp.array([4.0])), windows, jax.random.key(1))) > 0.01
    by_gradient, history = tc.fit_gradient(start, fields, windows, steps=40, learning_rate=0.1, log=lambda _: None)
    by_search, _ = tc.fit_nelder_mead(start, fields, windows, 40, log=lambda _: None)
    assert float(by_gradient.group.gaze_per_rad) == pytest.approx(1.5, rel=0.15)
    assert float(by_search.group.gaze_per_rad) == pytest.approx(1.5, rel=0.15)
    assert min(h[1] for h in history) < 0.2 * history[0][1]


@pytest.mark.slow
def test_the_eth_ucy_calibration_command_fits_on_training_windows_and_scores_the_held_out_scene(tmp_path, capsys):
    import json

    from socialnav import cli

    out = tmp_path / "fit"
    argv = ["humans", "calibrate", "--data", "eth_ucy", "--model", "collision_free_speed_calibrated", "--scenes",
            "hotel", "--sample", "8", "--steps", "2", "--evaluations", "3", "--out", str(out)]  # fmt: skip
    assert cli.main(argv) == 0
    fit = json.loads((out / "fit.json").read_text())
    (row,) = fit["scenes"]
    assert fit["model"] == "collision_free_speed_calibrated"  # the preset it started from, not only its kind
    assert row["scene"] == "hotel" and row["sample_windows"] == 8 and len(row["gradient_history"]) == 2
    assert row["sample_loss"]["nelder_mead"] <= row["sample_loss"]["start"] + 1e-4  # its first point is the start
    assert 0.2 < row["constant_velocity"][0] < 0.5 and all(np.isfinite(row["nelder_mead"]))  # hotel: 0.32 m
    assert (out / "curve.png").is_file() and "Nelder-Mead: test ADE/FDE" in capsys.readouterr().out
    # the scene's row was kept in progress.json as it ended; the finished fit replaced it
    from socialnav.common import runfolder

    assert fit["complete"] and not (out / "progress.json").exists()
    assert sorted(runfolder.read_manifest(out).files) == ["curve.png", "fit.json"]
    from socialnav.evaluation.humans import calibration as hc
    from socialnav.evaluation.humans import trajectory_calibration as tc

    saved = []
    model = hc.named_model("collision_free_speed_calibrated")
    again = tc.calibrate(model, ["hotel"], 2, 0.2, 3, 8, log=lambda *_: None, progress=saved.append)
    (record,) = saved
    assert not record["complete"] and record["scenes"] == again["scenes"] and record["start"] == again["start"]
    # the average's difference from constant velocity (here one scene's) is the fit's as the row scored it,
    # but for the values' rounding to four figures in fit.json (which the average is predicted again from)
    for method in ("gradient", "nelder_mead"):
        average = fit["average_vs_cv"][method]
        for k, e in enumerate(("ade_m", "fde_m")):
            difference, low, high = average[e]
            assert difference == pytest.approx(row[method][k] - row["constant_velocity"][k], abs=1e-3)
            assert low <= difference <= high
        assert average["scenes"] == ["hotel"]
        assert average["by_scene"]["hotel"]["ade_m"][0] == pytest.approx(average["ade_m"][0], abs=1e-4)  # one scene
    assert cli.main(argv) == 2  # the run is there: no --overwrite
    bad = ["humans", "calibrate", "--out", str(tmp_path / "x")]
    assert cli.main([*bad, "--data", "eth_ucy", "--scenes", "atlantis"]) == 2
    assert cli.main([*bad, "--model", "collision_free_speed_calibrated"]) == 2  # the Jülich fit starts from defaults
    assert cli.main([*bad, "--evaluations", "0"]) == 2
    assert not (tmp_path / "x" / "fit.json").exists()


# ---------------------------------------------------------------- walking groups in the arena


def _hall(tmp_path, paired: bool, human_model: str = "social_force"):
    """A 20 x 6 m hall, the robot standing aside; two walkers abreast 0.7 m apart, wanting 0.9
    and 1.4 m/s, and a third walking alone (``paired``: the first two walk together)."""
    import json

    from socialnav.jaxsim.scenes import env as env_lib
    from socialnav.jaxsim.scenes.spec import load_scene

    walk = lambda y, speed: {"behaviour": "walk", "from": [-8, y], "to": [8.5, y], "speed_mps": speed}
    people = [walk(0.0, 0.9), walk(0.7, 1.4), {**walk(-2.0, 1.1)}]
    if paired:
        people[0]["walks_with"] = 1
    scene = {
        "name": "hall", "bounds_m": [-10, 10, -3, 3], "timeout_s": 30,
        "walls": [[-10, 10, -3, -2.9], [-10, 10, 2.9, 3], [-10, -9.9, -3, 3], [9.9, 10, -3, 3]],
        "robot": {"start": [0, 2.4], "yaw_deg": 0, "goal": [2, 2.4]}, "people": people,
        "rule": {"type": "min_distance", "distance_m": 0.45},
    }  # fmt: skip
    path = tmp_path / f"hall_{paired}.json"
    path.write_text(json.dumps(scene))
    spec = load_scene(path)
    return spec, env_lib.make_env(spec, env_lib.EnvConfig(human_model=human_model))


@pytest.mark.slow
@pytest.mark.parametrize("model", ["social_force", "collision_free_speed_calibrated"])
def test_walkers_declared_a_pair_in_a_scene_walk_together_in_the_arena(tmp_path, model):
    from socialnav.jaxsim.scenes.variant import sample_variant

    gaps = {}
    for paired in (True, False):
        spec, env = _hall(tmp_path, paired, model)
        assert env.walking_groups == paired
        variant = jax.tree_util.tree_map(jnp.asarray, sample_variant(spec, 0, 0))
        np.testing.assert_array_equal(np.asarray(variant.walking_group)[:3], [0, 0, -1] if paired else [-1] * 3)

        def step(state, _, env=env):
            state, _ = env.step(state, jnp.zeros(2))
            return state, state.people.xy

        state, _ = jax.jit(env.reset)(jax.random.key(0), variant)
        _, xy = jax.jit(lambda s, env=env: jax.lax.scan(step, s, None, length=120))(state)
        gaps[paired] = np.linalg.norm(np.asarray(xy)[20:, 0] - np.asarray(xy)[20:, 1], axis=-1)
    assert gaps[True].max() <= 1.1, gaps[True].max()
    assert gaps[False][-1] > 3.0  # 0.5 m/s apart
