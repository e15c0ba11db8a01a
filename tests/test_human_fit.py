"""People as a calibration fitted them (``socialnav arena --human-fit``): a fit file (a Jülich fit
or one of a user's recording) read back as a model and its constants, those constants set in the
arena's env and nowhere else, a run's settings and digest carrying them; a bad fit is one error
naming the file and the field."""

from __future__ import annotations

import json
import re

import jax
import jax.numpy as jnp
import numpy as np
import pandas as pd
import pytest

from socialnav.cli import main
from socialnav.data import SCENES_DIR
from socialnav.evaluation.humans import calibration as hc
from socialnav.evaluation.humans import fit_file
from socialnav.jaxsim import humans, speed_model
from socialnav.jaxsim.scenes import env as env_lib
from socialnav.jaxsim.scenes.spec import load_scene
from socialnav.jaxsim.scenes.variant import padded_slots, sample_variant

PRESET = speed_model.CALIBRATED["collision_free_speed_calibrated"]
TRACKS_FIELDS = ["speed.time_gap_s", "speed.neighbor_strength", "speed.neighbor_range_m", "group.gaze_per_rad",
                 "group.attraction_mps2"]  # fmt: skip


def tracks_fit(gradient_loss=0.50, search_loss=0.40, **extra) -> dict:
    """A ``--data tracks`` fit record as ``socialnav humans calibrate`` writes it (its fields)."""
    by_gradient = dict(zip(TRACKS_FIELDS, [0.42, 6.2, 0.064, 6.0, 1.7], strict=True))
    by_search = dict(zip(TRACKS_FIELDS, [0.30, 9.0, 0.020, 0.5, 20.0], strict=True))
    row = {"scene": "mine.csv", "gradient_values": by_gradient, "nelder_mead_values": by_search,
           "sample_loss": {"start": 0.6, "gradient": gradient_loss, "nelder_mead": search_loss}}  # fmt: skip
    return {"model": "collision_free_speed_calibrated", "data": "tracks", "fields": TRACKS_FIELDS, "scenes": [row],
            "complete": True, **extra}  # fmt: skip


def write(folder, record) -> str:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "fit.json"
    path.write_text(record if isinstance(record, str) else json.dumps(record))
    return path


def test_a_fits_values_set_the_models_constants_and_a_value_it_does_not_read_is_refused():
    params = humans.human_params("steering_speed_calibrated", hc.named_model("social_force").crowd)
    fitted = humans.with_values("steering_speed_calibrated", params, {"speed.time_gap_s": 0.5, "group.gaze_per_rad": 2})
    assert float(fitted.speed.time_gap_s) == 0.5 and float(fitted.group.gaze_per_rad) == 2.0
    # everything else as it was: the preset's radius, ORCA's and the power law's untouched
    assert float(fitted.speed.radius_m) == float(params.speed.radius_m) and fitted.orca == params.orca
    for values, words in (
        ({"orca.time_horizon_s": 2.0}, "steering_speed_calibrated reads speed and group, not 'orca'"),
        ({"speed.time_gap": 1.0}, "speed.time_gap: not a field of speed"),
        ({"crowd.dt_s": 0.1}, "crowd"),  # the step is the run's, never a fit's
        ({"speed.time_gap_s": 0.0}, "0.0 is not a finite positive number"),
        ({"speed.time_gap_s": True}, "True is not a finite positive number"),
        ({"speed.time_gap_s": float("nan")}, "nan is not a finite positive number"),
        ({"speed.radius_m": 3.0}, "speed.radius_m: 3.0 m is wider than a person's body (at most 1 m)"),
    ):
        with pytest.raises(ValueError, match=re.escape(words)):
            humans.with_values("steering_speed_calibrated", params, values)
    assert "not a field of crowd" in humans.values_problem("social_force", {"crowd.dt_s": 0.1})


def _walk(env, steps=60):
    """The people's positions after ``steps`` of a standing robot, variant 0 of the env's scene."""
    spec = load_scene(SCENES_DIR / "gscl_group.json")
    variant = jax.tree.map(jnp.asarray, sample_variant(spec, 0, 0, n_slots=padded_slots(spec.n_people_slots)))
    state, _ = jax.jit(env.reset)(jax.random.key(0), variant)
    run = jax.jit(lambda s: jax.lax.scan(lambda c, _: (env.step(c, jnp.zeros(2))[0], None), s, None, length=steps)[0])
    return np.asarray(run(state).people.xy)


def test_the_env_walks_a_fits_people_and_the_presets_own_values_change_nothing():
    """Known answer: values equal to the preset's give the preset's walk bit for bit; a shorter
    time gap gives another walk (so the values reach the people's step)."""
    spec = load_scene(SCENES_DIR / "gscl_group.json")  # six people, four walking together
    config = env_lib.EnvConfig(human_model="collision_free_speed_calibrated", max_steps=100)
    named = env_lib.make_env(spec, config)
    own = {f"speed.{f}": float(getattr(PRESET, f)) for f in ("time_gap_s", "neighbor_strength", "radius_m")}
    same = env_lib.make_env(spec, config, human_values=own)
    other = env_lib.make_env(spec, config, human_values={"speed.time_gap_s": 0.2, "speed.neighbor_range_m": 0.5})
    assert float(other.human_params().speed.time_gap_s) == pytest.approx(0.2)
    assert float(other.velocity.radius_m) == pytest.approx(float(PRESET.radius_m))  # not fitted: the preset's
    walked = _walk(named)
    assert np.array_equal(walked, _walk(same))
    assert not np.allclose(walked, _walk(other))
    with pytest.raises(ValueError, match="orca reads orca and group"):
        env_lib.make_env(spec, env_lib.EnvConfig(human_model="orca"), human_values={"speed.time_gap_s": 0.3})


def test_a_fit_file_is_read_as_its_model_and_the_method_of_lower_training_loss(tmp_path):
    path = write(tmp_path / "mine", tracks_fit())
    best = fit_file.read_fit(path)
    assert (best.model, best.method, best.training_loss, best.data) == (
        "collision_free_speed_calibrated", "nelder_mead", 0.40, "tracks")  # fmt: skip
    assert best.values["speed.time_gap_s"] == 0.30 and best.label == "mine:nelder_mead"
    assert fit_file.read_fit(write(tmp_path / "other", tracks_fit(0.3, 0.4))).method == "gradient"
    assert fit_file.read_fit(path, "gradient").values["group.gaze_per_rad"] == 6.0
    # a Jülich fit: its fields are its model's own part's
    values = {"time_gap_s": 0.8, "neighbor_strength": 8.5, "neighbor_range_m": 0.12, "radius_m": 0.18}
    juelich = {"model": "collision_free_speed", "gradient": {"values": values, "loss": 2.2},
               "nelder_mead": {"values": {**values, "radius_m": 0.15}, "loss": 2.0}}  # fmt: skip
    point = fit_file.read_fit(write(tmp_path / "juelich", juelich))
    expected = {"speed.time_gap_s": 0.8, "speed.neighbor_strength": 8.5, "speed.neighbor_range_m": 0.12,
                "speed.radius_m": 0.15}  # fmt: skip
    assert point.method == "nelder_mead" and point.values == expected
    # the validation reads a recording's fit too, as the model with its values
    model = hc.fitted_models(path)["mine:gradient"]
    assert model.name == "collision_free_speed" and float(model.speed.time_gap_s) == pytest.approx(0.42)
    assert float(model.speed.radius_m) == pytest.approx(float(PRESET.radius_m))
    assert float(model.group.attraction_mps2) == pytest.approx(1.7)
    assert fit_file.split_option("runs/a:b/fit.json:gradient") == (
        fit_file.pathlib.Path("runs/a:b/fit.json"),
        "gradient",
    )
    assert fit_file.split_option("fit.json") == (fit_file.pathlib.Path("fit.json"), "best")
    assert fit_file.read_option(f"{path.parent}:gradient") == fit_file.read_fit(path, "gradient")  # its folder
    with pytest.raises(ValueError, match="a folder without a fit.json"):
        fit_file.read_option(str(tmp_path))


@pytest.mark.parametrize(
    ("record", "words"),
    [
        ("{", "not a readable fit.json"),
        ({**tracks_fit(), "data": "eth_ucy"}, "data: a 'eth_ucy' fit holds one fit a scene"),
        ({**tracks_fit(), "model": "ghosts"}, "model: 'ghosts' is not a human model"),
        ({**tracks_fit(), "scenes": []}, "scenes: expected one row"),
        ({**tracks_fit(), "fields": "speed.time_gap_s"}, "fields: expected the list"),
        ({**tracks_fit(), "fields": [*TRACKS_FIELDS, "speed.radius_m"]}, "gradient.values: expected the fields"),
        ({**tracks_fit(), "model": "orca"}, "gradient.values.speed.time_gap_s: orca reads orca and group"),
        (tracks_fit(gradient_loss=float("inf")), "gradient: its training loss inf is not a finite number"),
        (tracks_fit(gradient_loss=None), "gradient.loss: missing, so the better method cannot be told"),
    ],
)
def test_a_bad_fit_file_is_one_error_naming_the_file_and_the_field(tmp_path, record, words):
    path = write(tmp_path / "bad", record)
    with pytest.raises(ValueError, match=re.escape(words)) as e:
        fit_file.read_fit(path)
    assert str(path) in str(e.value)


def test_the_arena_command_refuses_a_bad_human_fit_before_any_work(tmp_path, capsys):
    path = write(tmp_path / "mine", tracks_fit())
    out = tmp_path / "arena"
    argv = ["arena", "--scenes", "casn_head_on", "--methods", "navfn", "--variants", "2", "--out", str(out)]
    for extra, words in (
        (["--human-fit", str(path), "--human-model", "orca"], "leave out --human-model"),
        (["--human-fit", str(tmp_path / "none.json")], "none.json: no such file"),
        (["--human-fit", str(write(tmp_path / "eth", {**tracks_fit(), "data": "eth_ucy"}))], "data: a 'eth_ucy'"),
        (["--human-fit", f"{path}:nelder"], "no such file"),  # not a method: read as part of the name
        (["--human-fit", str(path), "--out", str(tmp_path)], "contains the job's input"),
    ):
        assert main([*argv, *extra]) == 2, extra
        assert words in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.slow  # two small arena runs: about 30 s
def test_an_arena_run_records_the_fit_and_a_run_with_another_fit_is_not_resumed_into_it(tmp_path, capsys):
    path = write(tmp_path / "mine", tracks_fit())
    out = tmp_path / "arena"
    argv = ["arena", "--scenes", "gscl_group", "--methods", "navfn", "--variants", "2", "--keep-trajectories", "2",
            "--out", str(out)]  # fmt: skip
    assert main([*argv, "--human-fit", f"{path}:gradient"]) == 0
    assert "people by collision_free_speed_calibrated as" in capsys.readouterr().out
    run = json.loads((out / "run.json").read_text())
    assert run["human_model"] == "collision_free_speed_calibrated"
    assert run["human_fit"] == f"{path.resolve()}:gradient"
    assert run["human_values"] == fit_file.read_fit(path, "gradient").values
    assert main([*argv, "--human-fit", str(path)]) == 2  # the search's point: other people
    assert "holds a run with" in capsys.readouterr().err
    plain = tmp_path / "plain"
    assert main([*argv[:-1], str(plain), "--human-model", "collision_free_speed_calibrated"]) == 0
    walked = []
    for folder in (out, plain):
        steps = pd.read_parquet(folder / "trajectories" / "gscl_group.parquet")
        walked.append(steps[[c for c in steps.columns if c[0] == "p" and c[-2:] in ("_x", "_y")]].to_numpy())
    assert walked[0].shape == walked[1].shape and not np.allclose(*walked)  # the fit's people walk otherwise


@pytest.mark.slow  # a one-update PPO run: about 25 s
def test_a_policy_trains_among_a_fits_people_and_a_resume_with_another_fit_is_refused(tmp_path, capsys):
    from socialnav.planners.learning.policy_training import PPOConfig, scene_env

    path = write(tmp_path / "mine", tracks_fit())
    values = tuple(sorted(fit_file.read_fit(path, "gradient").values.items()))
    config = PPOConfig(human_model="collision_free_speed_calibrated", human_values=values)
    assert PPOConfig.from_json(json.loads(json.dumps(config.to_json()))) == config
    assert "human_values" not in PPOConfig().to_json()  # a run without a fit: its config as before
    env = scene_env(load_scene(SCENES_DIR / "gscl_group.json"), config.human_model, config.human_values)
    assert float(env.human_params().speed.time_gap_s) == pytest.approx(0.42)
    with pytest.raises(ValueError, match="human_values: speed.neighbor_range_m: orca reads orca and group"):
        PPOConfig(human_model="orca", human_values=values)
    run = tmp_path / "ppo"
    tiny = [
        "--scenes",
        "gscl_group",
        "--envs-per-scene",
        "2",
        "--rollout-steps",
        "8",
        "--no-progress",
        "--out",
        str(run),
    ]
    assert main(["policy", "train", "--updates", "1", "--human-fit", f"{path}:gradient", *tiny]) == 0
    stored = json.loads((run / "config.json").read_text())["ppo"]
    assert stored["human_model"] == "collision_free_speed_calibrated" and stored["human_values"] == dict(values)
    assert main(["policy", "train", "--updates", "2", "--human-fit", str(path), *tiny]) == 2  # the search's point
    assert "human_values" in capsys.readouterr().err
    assert main(["policy", "train", "--updates", "2", "--human-fit", str(path), "--human-model", "orca", *tiny]) == 2
    assert "leave out --human-model" in capsys.readouterr().err


@pytest.mark.slow  # three warehouse runs of 10 minutes: about 15 s
def test_the_warehouse_workers_walk_a_fit_and_the_run_records_it(tmp_path, capsys):
    """The warehouse day with a fit's constants: values equal to the preset's give the preset's
    log bit for bit, another time gap another log; ``run.json`` records the values."""
    from socialnav.jaxsim import logs
    from socialnav.jaxsim.route_follower import route_follower
    from socialnav.jaxsim.scenario import WAREHOUSE_DIR, load_scenario
    from socialnav.jaxsim.world import build_world
    from socialnav.planners.warehouse.routes import shortest_path_plan

    scenario = load_scenario(WAREHOUSE_DIR)
    with pytest.raises(ValueError, match="social_force reads crowd and group, not 'speed'"):
        build_world(scenario, "social_force", {"speed.time_gap_s": 0.5})
    own = {"speed.time_gap_s": float(PRESET.time_gap_s), "speed.radius_m": float(PRESET.radius_m)}
    logged = {}
    for label, values in (("named", ()), ("own", own), ("other", {"speed.time_gap_s": 0.3})):
        driver = route_follower(shortest_path_plan(scenario), build_world(scenario))
        logs.simulate_to_parquet(scenario, tmp_path / label, driver, n_worlds=1, duration_s=600.0, progress=False,
                                 log_positions=True, human_model="collision_free_speed_calibrated",
                                 human_values=values)  # fmt: skip
        logged[label] = pd.read_parquet(tmp_path / label / "logs.parquet")
    pd.testing.assert_frame_equal(logged["named"], logged["own"], check_exact=True)
    walked = [frame.filter(regex=r"^worker_(x|y)_").to_numpy() for frame in (logged["named"], logged["other"])]
    assert walked[0].size and np.isfinite(walked[0]).any() and not np.allclose(*walked, equal_nan=True)
    assert json.loads((tmp_path / "other" / "run.json").read_text())["human_values"] == {"speed.time_gap_s": 0.3}
    assert "human_values" not in json.loads((tmp_path / "named" / "run.json").read_text())
    path = write(tmp_path / "mine", tracks_fit())
    out = str(tmp_path / "cli")
    assert main(["simulate", "--hours", "0.01", "--human-fit", str(path), "--human-model", "orca", "--out", out]) == 2
    assert "leave out --human-model" in capsys.readouterr().err


def test_an_episode_whose_people_are_lost_to_nan_is_named_where():
    """A present person whose position is not finite would pass the metrics unseen (NaN compares
    false): named with the variant and time (the scene's run stops on it). Absent people's slots
    may hold anything."""
    from socialnav.evaluation.arena.run import lost_people

    xy = np.zeros((2, 5, 3, 2), np.float32)  # 2 episodes, 5 steps, 3 people
    present = np.ones((2, 5, 3), bool)
    present[:, :, 2] = False
    xy[:, :, 2] = np.nan  # an absent slot: not a loss
    assert lost_people(xy, present, 10, 0.1) is None
    xy[1, 3, 1, 0] = np.inf
    assert lost_people(xy, present, 10, 0.1) == "person 1's position is not finite at t = 0.4 s of variant 11"
