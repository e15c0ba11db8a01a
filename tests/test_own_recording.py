"""A user's own recording in the arena (``recording.file``, ``socialnav arena-scene``): a tracks
file of a shipped run resamples to that run exactly and makes the shipped scene by the same
rules; a bad file is one error naming the file (and the person, the frames); a scene whose
recording changes is a new scene to a resumed run."""

from __future__ import annotations

import json

import jax
import jax.numpy as jnp
import numpy as np
import pandas as pd
import pytest

from socialnav.cli import main
from socialnav.data import RECORDED_SCENES_DIR, recorded
from socialnav.data.track_file import TrackFileError
from socialnav.evaluation.arena import table
from socialnav.jaxsim.scenario.errors import ScenarioError
from socialnav.jaxsim.scenes import recording as recording_lib
from socialnav.jaxsim.scenes.spec import load_scene
from socialnav.jaxsim.scenes.variant import sample_variants

RUN = "crowds_zara01"  # zara1's test recording: 360 s, up to 21 people at once
FPS = "25"  # its frame numbers are its 25 fps video's (every 10th annotated)


@pytest.fixture(scope="module")
def rows():
    """The run as a tracks file's rows: ``frame, id, x, y``."""
    shipped = recorded.trajectories(RUN)
    return pd.DataFrame({"frame": shipped["frame"], "id": shipped["person"], "x": shipped["x_m"], "y": shipped["y_m"]})


@pytest.fixture
def csv(tmp_path, rows):
    path = tmp_path / "crowd.csv"
    rows.to_csv(path, index=False)
    return path


def test_a_csv_of_a_shipped_run_resamples_to_that_run_exactly(csv):
    mine, shipped = recording_lib.load_recording_file(csv, float(FPS)), recording_lib.load_recording(RUN)
    assert mine.run == "crowd.csv" and mine.n_samples == shipped.n_samples
    for field in ("first", "last", "offset", "xy"):
        np.testing.assert_array_equal(getattr(mine, field), getattr(shipped, field))


def test_the_command_writes_the_shipped_scene_by_the_same_rules_and_refuses_to_overwrite(csv, tmp_path, capsys):
    out = tmp_path / "scenes"
    assert main(["arena-scene", str(csv), "--frames-per-s", FPS, "--name", "zara1", "--out", str(out)]) == 0
    for playback in ("replayed", "reactive"):
        mine = json.loads((out / f"zara1_{playback}.json").read_text())
        shipped = json.loads((RECORDED_SCENES_DIR / f"zara1_{playback}.json").read_text())
        assert mine["recording"].pop("file") == "../crowd.csv" and mine["recording"].pop("frames_per_s") == 25
        assert shipped["recording"].pop("run") == RUN
        mine.pop("source"), shipped.pop("source")
        assert mine == shipped
        spec = load_scene(out / f"zara1_{playback}.json")
        assert spec.recording["file"] == str(csv.resolve()) and spec.n_people_slots == 21
    before = (out / "zara1_replayed.json").read_bytes()
    assert main(["arena-scene", str(csv), "--frames-per-s", FPS, "--name", "zara1", "--out", str(out)]) == 2
    assert "--overwrite" in capsys.readouterr().err and (out / "zara1_replayed.json").read_bytes() == before


def test_a_scene_of_a_user_file_replays_its_windows(csv, tmp_path):
    assert main(["arena-scene", str(csv), "--frames-per-s", FPS, "--out", str(tmp_path)]) == 0
    spec = load_scene(tmp_path / "crowd_replayed.json")
    variants = sample_variants(spec, 0, 3, n_slots=spec.n_people_slots)
    data = recording_lib.load_recording_file(csv, float(FPS))
    n = recording_lib.samples_per_episode(spec.timeout_s)
    for k in range(3):
        first = int(round(float(variants.window_start_s[k]) / recording_lib.RECORD_DT_S))
        xy, present = recording_lib.window(data, first, n, spec.n_people_slots)
        np.testing.assert_array_equal(variants.track_present[k, : spec.n_people_slots], present)
        np.testing.assert_array_equal(variants.track_xy[k, : spec.n_people_slots], xy)
        assert present.any()


@pytest.mark.parametrize(
    "edit, fps, words",
    [
        (lambda r: r.assign(x=r["x"] * 1000), 25, r"person \d+ moves .* m/s between frames \d+ and \d+ .*metres"),
        (lambda r: r, 2500, r"moves .* m/s .* at 2500 frames a second .*the rate of the frame numbers"),
        (lambda r: r.groupby("id").head(1), 25, "nobody is seen for 0.1 s or more"),
        (lambda r: r.iloc[[0, 1, 2, 1]], 25, "appears twice in frame"),
        (lambda r: r.rename(columns={"frame": "t"}), 25, "column 'frame' is missing"),
    ],
)
def test_a_bad_recording_file_is_one_error_naming_the_file(rows, tmp_path, edit, fps, words):
    path = tmp_path / "bad.csv"
    edit(rows).to_csv(path, index=False)
    with pytest.raises(TrackFileError, match=words) as e:
        recording_lib.load_recording_file(path, fps)
    assert str(path) in str(e.value)


@pytest.mark.parametrize(
    "mutate, words",
    [
        (lambda s: s["recording"].update(file="gone.csv"), "no such file"),
        (lambda s: s["recording"].update(run=RUN), "either 'run'"),
        (lambda s: s["recording"].pop("file"), "either 'run'"),
        (lambda s: s["recording"].update(file=3), "expected a file's path"),
        (lambda s: s.update(bounds_m=[0, 10, 0, 10]), r"outside bounds_m \[0, 10, 0, 10\]"),
        (lambda s: s["recording"].pop("frames_per_s"), "missing field"),
        (lambda s: s["recording"].update(frames_per_s=[20, 30]), "one number"),
        (lambda s: s["recording"].update(frames_per_s=0), "expected a value in"),
    ],
)
def test_a_scene_whose_recording_file_cannot_be_played_is_refused_naming_the_field(csv, tmp_path, mutate, words):
    assert main(["arena-scene", str(csv), "--frames-per-s", FPS, "--out", str(tmp_path)]) == 0
    scene = json.loads((tmp_path / "crowd_replayed.json").read_text())
    mutate(scene)
    path = tmp_path / "edited.json"
    path.write_text(json.dumps(scene))
    with pytest.raises(ScenarioError, match=words) as e:
        load_scene(path)
    assert e.value.field.startswith("recording") and str(path) in str(e.value)


def test_a_recording_too_crowded_for_a_scene_writes_no_scene(rows, tmp_path, capsys):
    crowd = tmp_path / "crowd.csv"
    copies = [rows.assign(id=rows["id"] + 10_000 * k, x=rows["x"] + 0.01 * k) for k in range(7)]  # 147 at once
    pd.concat(copies).to_csv(crowd, index=False)
    assert main(["arena-scene", str(crowd), "--frames-per-s", FPS, "--out", str(tmp_path / "scenes")]) == 2
    assert "up to 147 people at once: 128 allowed" in capsys.readouterr().err
    assert not list((tmp_path / "scenes").iterdir())


def test_the_scene_digest_changes_with_the_recording_file_and_not_without_one(csv, tmp_path):
    assert main(["arena-scene", str(csv), "--frames-per-s", FPS, "--out", str(tmp_path)]) == 0
    scene = tmp_path / "crowd_replayed.json"
    settings = {"metrics_version": 1, "socialnav_version": "x"}
    before = table.scene_digest(scene, False, settings, recording_file=csv)
    assert table.scene_digest(scene, False, settings) != before
    assert table.scene_digest(scene, False, settings, recording_file=csv) == before
    csv.write_text(csv.read_text() + "99999,0,1.0,1.0\n")  # one more row
    assert table.scene_digest(scene, False, settings, recording_file=csv) != before
    spec = load_scene(scene)
    assert table.user_recording_file(spec.recording) == csv.resolve()


def test_the_prediction_test_on_a_tracks_file_of_a_test_split_gives_the_validation_s_figures(rows, tmp_path):
    from socialnav.evaluation.humans import calibration, validation

    path = tmp_path / "zara1.csv"
    rows.to_csv(path, index=False)
    out = tmp_path / "predict"
    argv = ["humans", "predict", "--tracks", str(path), "--frames-per-s", FPS, "--models", "social_force"]
    assert main([*argv, "--out", str(out), "--no-progress"]) == 0
    table = pd.read_csv(out / "prediction.csv").set_index(["model", "aim"])
    assert json.loads((out / "summary.json").read_text())["sample_s"] == pytest.approx(0.4)
    # zara1's test split is crowds_zara01 whole: the same windows, the same figures
    cv = validation.eth_ucy_prediction(None, "zara1")
    along = validation.eth_ucy_prediction(calibration.named_model("social_force"), "zara1")
    assert table.loc[("constant_velocity", "velocity"), "ade_m"] == pytest.approx(cv["ade_m"], abs=1e-9)
    assert table.loc[("constant_velocity", "velocity"), "samples"] == cv["samples"]
    for key in ("ade_m", "fde_m", "ade_vs_cv_m", "ade_vs_cv_low_m", "ade_vs_cv_high_m"):
        assert table.loc[("social_force", "velocity"), key] == pytest.approx(along[key], abs=1e-6)
    assert table.loc[("social_force", "destination"), "ade_m"] < table.loc[("social_force", "velocity"), "ade_m"]


def test_the_prediction_test_reads_a_fast_tracker_at_the_protocol_s_interval(rows, tmp_path):
    from socialnav.evaluation.humans import own_recording

    fine = rows.assign(frame=rows["frame"] // 10)  # one frame number every 0.4 s: a 2.5 fps tracker
    path = tmp_path / "fine.csv"
    fine.to_csv(path, index=False)
    coarse = own_recording.recording_rows(path, 2.5, sample_s=0.8)  # every other frame
    gaps = np.diff(np.unique(coarse["frame"]))
    assert gaps.min() == 2 and not (gaps % 2).any()  # every other frame (the longer gaps: nobody there)
    assert own_recording.recording_rows(path, 2.5)["frame"].nunique() == fine["frame"].nunique()
    short = rows[rows.groupby("id").cumcount() < 15]
    short.to_csv(path, index=False)
    with pytest.raises(ValueError, match="nobody is seen in 20 samples.*the longest track has 15"):
        own_recording.recording_windows(own_recording.recording_rows(path, 25.0))
    out = tmp_path / "out"
    assert main(["humans", "predict", "--tracks", str(path), "--frames-per-s", FPS, "--out", str(out)]) == 2
    assert not out.exists()  # a bad file leaves no folder behind


def test_the_command_refuses_an_out_that_is_a_file_and_a_name_that_cannot_name_files(csv, tmp_path, capsys):
    a_file = tmp_path / "a-file"
    a_file.write_text("mine")
    assert main(["arena-scene", str(csv), "--frames-per-s", FPS, "--out", str(a_file)]) == 2
    assert "a file, not a folder" in capsys.readouterr().err and a_file.read_text() == "mine"
    assert main(["arena-scene", str(csv), "--frames-per-s", FPS, "--name", "../up", "--out", str(tmp_path)]) == 2
    assert "cannot name the scene files" in capsys.readouterr().err


@pytest.mark.slow  # a PPO update compiled: about 15 s
def test_a_policy_trains_on_a_scene_of_ones_own_and_resumes_from_another_folder(csv, tmp_path, monkeypatch):
    assert main(["arena-scene", str(csv), "--frames-per-s", FPS, "--out", str(tmp_path / "scenes")]) == 0
    tiny = ["--envs-per-scene", "2", "--rollout-steps", "8", "--no-progress"]
    monkeypatch.chdir(tmp_path)
    run = tmp_path / "ppo"
    assert (
        main(["policy", "train", "--out", str(run), "--scenes", "scenes/crowd_reactive.json", "--updates", "1", *tiny])
        == 0
    )
    recorded = json.loads((run / "config.json").read_text())["ppo"]["scenes"]
    assert recorded == [str(tmp_path / "scenes" / "crowd_reactive.json")]  # absolute: found from anywhere
    monkeypatch.chdir(tmp_path / "scenes")
    assert main(["policy", "train", "--out", str(run), "--scenes", "crowd_reactive.json", "--updates", "2", *tiny]) == 0
    lines = (run / "metrics.jsonl").read_text().splitlines()
    assert [json.loads(line)["update"] for line in lines] == [1, 2]


def test_a_start_the_recorded_people_never_leave_is_refused_when_the_scene_is_read(rows, tmp_path):
    frames = np.unique(rows["frame"])
    stander = pd.DataFrame({"frame": frames, "id": 99_999, "x": 2.0, "y": 2.0})  # standing there all along
    path = tmp_path / "crowd.csv"
    pd.concat([rows, stander]).to_csv(path, index=False)
    assert main(["arena-scene", str(path), "--frames-per-s", FPS, "--out", str(tmp_path)]) == 0
    scene = json.loads((tmp_path / "crowd_replayed.json").read_text())
    scene["robot"]["start"] = [[2.0, 2.0], [2.0, 2.0]]  # the start moved onto them
    edited = tmp_path / "edited.json"
    edited.write_text(json.dumps(scene))
    with pytest.raises(ScenarioError, match="no start clear of the recorded people") as e:
        load_scene(edited)
    assert e.value.field == "robot.start" and str(edited) in str(e.value)


def test_the_walls_of_an_occupancy_grid_are_boxes_covering_exactly_its_occupied_cells():
    from socialnav.jaxsim.scenes.from_recording import walls_from_occupancy

    rng = np.random.default_rng(0)
    occupied = rng.random((40, 50)) < 0.3
    occupied[10:20, 5:30] = True  # a block: a few boxes, not 250
    resolution, origin = 0.1, (-1.0, 2.0)
    walls = np.array(walls_from_occupancy(occupied, resolution, origin, [-1.0, 4.0, 2.0, 6.0]))
    centres_x = origin[0] + (np.arange(50) + 0.5) * resolution
    centres_y = origin[1] + (np.arange(40) + 0.5) * resolution
    gx, gy = np.meshgrid(centres_x, centres_y)
    covered = np.zeros_like(occupied)
    for x0, x1, y0, y1 in walls:
        covered |= (gx > x0) & (gx < x1) & (gy > y0) & (gy < y1)
    np.testing.assert_array_equal(covered, occupied)
    assert len(walls) < occupied.sum() / 2
    inside = np.array(walls_from_occupancy(occupied, resolution, origin, [0.0, 1.0, 3.0, 3.5]))  # clipped
    assert inside[:, 0].min() >= 0.0 and inside[:, 1].max() <= 1.0 and inside[:, 2].min() >= 3.0
    assert inside[:, 3].max() <= 3.5 and len(inside) > 0


def _ros_map(folder, walls, res=0.1, origin=(-5.0, -5.0), size=(250, 220)):
    """A ROS map (YAML and PGM) of ``walls`` (boxes, m) in a free room."""
    from PIL import Image

    w, h = size
    image = np.full((h, w), 254, np.uint8)
    for x0, x1, y0, y1 in walls:
        c0, c1 = round((x0 - origin[0]) / res), round((x1 - origin[0]) / res)
        r0, r1 = round((y0 - origin[1]) / res), round((y1 - origin[1]) / res)
        image[h - r1 : h - r0, c0:c1] = 0  # image row 0 at the top
    Image.fromarray(image).save(folder / "map.pgm")
    (folder / "map.yaml").write_text(f"image: map.pgm\nresolution: {res}\norigin: [{origin[0]}, {origin[1]}, 0.0]\n")
    return folder / "map.yaml"


def test_a_map_gives_the_scene_its_walls_and_a_map_in_another_frame_is_refused(csv, tmp_path, capsys):
    map_yaml = _ros_map(tmp_path, [(-5.0, 20.0, -5.0, -1.2), (2.0, 3.0, 12.6, 13.6)])
    out = tmp_path / "scenes"
    assert main(["arena-scene", str(csv), "--frames-per-s", FPS, "--map", str(map_yaml), "--out", str(out)]) == 0
    assert "2 wall boxes" in capsys.readouterr().out
    walls = load_scene(out / "crowd_reactive.json").walls_m
    np.testing.assert_allclose(walls, [[-2.0, 17.0, -2.0, -1.2], [2.0, 3.0, 12.6, 13.6]], atol=1e-4)
    elsewhere = _ros_map(tmp_path, [], origin=(100.0, 100.0))  # the map of another place
    assert (
        main(
            ["arena-scene", str(csv), "--frames-per-s", FPS, "--map", str(elsewhere), "--out", str(out), "--overwrite"]
        )
        == 2
    )
    assert "% of the positions lie on the map" in capsys.readouterr().err
    across = _ros_map(tmp_path, [(5.0, 6.0, -5.0, 17.0)])  # a wall across the crowd's path
    assert (
        main(["arena-scene", str(csv), "--frames-per-s", FPS, "--map", str(across), "--out", str(out), "--overwrite"])
        == 0
    )
    assert "of the recorded positions lie in its walls" in capsys.readouterr().out


def test_a_recording_is_cut_in_time_for_its_calibration_and_the_command_asks_for_the_file(rows, tmp_path, capsys):
    from socialnav.evaluation.humans import own_recording

    path = tmp_path / "zara.csv"
    rows.to_csv(path, index=False)
    train, test = own_recording.split_rows(own_recording.recording_rows(path, 25.0))
    assert train["frame"].max() < test["frame"].min() and len(train) > 2 * len(test) > 0
    out = str(tmp_path / "fit")
    assert main(["humans", "calibrate", "--data", "tracks", "--out", out]) == 2
    assert "--data tracks goes with --tracks and --frames-per-s" in capsys.readouterr().err
    assert main(["humans", "calibrate", "--map", str(path), "--out", out]) == 2  # a map without --data tracks
    assert "--data tracks goes with --tracks and --frames-per-s (both; --map too" in capsys.readouterr().err
    assert main(["humans", "calibrate", "--tracks", str(path), "--frames-per-s", FPS, "--out", out]) == 2
    assert main(["humans", "calibrate", "--data", "tracks", "--tracks", str(path), "--frames-per-s", FPS,
                 "--model", "power_law", "--out", out]) == 2  # fmt: skip
    assert "the power law's gradient" in capsys.readouterr().err


@pytest.mark.slow  # a gradient and a search through the crowd step: about 15 s
def test_a_model_is_calibrated_on_the_first_two_thirds_of_a_recording_and_scored_on_the_rest(rows, tmp_path, capsys):
    path = tmp_path / "zara.csv"
    rows.to_csv(path, index=False)
    out = tmp_path / "fit"
    argv = ["humans", "calibrate", "--data", "tracks", "--tracks", str(path), "--frames-per-s", FPS, "--model",
            "collision_free_speed_calibrated", "--steps", "4", "--evaluations", "6", "--sample", "32"]  # fmt: skip
    walls = _ros_map(tmp_path, [(-5.0, 20.0, -5.0, -1.2)])  # the pavement's edge below the crowd
    assert main([*argv, "--map", str(walls), "--out", str(out)]) == 0
    fit = json.loads((out / "fit.json").read_text())
    said = capsys.readouterr().out
    assert fit["map"] == str(walls) and "1 wall boxes within 5 m of the people" in said
    row = fit["scenes"][0]
    assert fit["data"] == "tracks" and row["scene"] == "zara.csv" and row["sample_windows"] == 32
    assert min(h[1] for h in row["gradient_history"]) <= row["gradient_history"][0][1]
    assert set(fit["vs_cv"]) == {"start", "gradient", "nelder_mead"}
    low, high = fit["vs_cv"]["start"]["ade_m"][1:]
    assert low <= fit["vs_cv"]["start"]["ade_m"][0] <= high
    assert (out / "curve.png").is_file() and "fitted by gradient: test ADE/FDE" in said


def test_a_difference_without_an_interval_says_why_instead_of_printing_nan():
    from socialnav.evaluation.humans import measures, report

    error, baseline = np.array([0.5, 0.4, 0.6]), np.array([0.4, 0.4, 0.4])
    d, low, high = measures.paired_difference(error, baseline, np.array([0, 1, 2]))  # one block of 20 windows
    assert d == pytest.approx(0.1) and np.isnan(low) and np.isnan(high)
    assert report.interval((d, low, high)) == "+0.100 [no interval: fewer than 2 blocks of 20 windows]"
    assert report.interval((0.1, 0.05, 0.15)) == "+0.100 [+0.050, +0.150]"


def _walker_towards(tmp_path, speed_mps=1.25, samples=24):
    """A tracks file of one person walking along +x at y = 5 m from x = 1 m, a sample every 0.4 s
    (frame numbers of a 25 fps video, every 10th)."""
    x = 1.0 + speed_mps * 0.4 * np.arange(samples)
    path = tmp_path / "walker.csv"
    pd.DataFrame({"frame": 10 * np.arange(samples), "id": 1, "x": x, "y": 5.0}).to_csv(path, index=False)
    return path


def test_a_map_keeps_the_predicted_people_out_of_its_walls_and_far_walls_change_nothing(tmp_path, capsys):
    """Known answer: a person walking at a wall 1.5 m ahead of their last observed position is
    predicted (12 samples of 0.4 s, constant velocity 6 m on) to stop before it with the map, and
    to walk through it without; walls far from everyone leave the prediction as in open space."""
    from socialnav.evaluation.humans import calibration, own_recording, validation

    path = _walker_towards(tmp_path)
    rows = own_recording.recording_rows(path, 25.0)
    model = calibration.named_model("collision_free_speed_calibrated")
    predict = validation.window_predictor(model.name, model.dt_s)
    ahead = []
    for walls in ([(6.0, 7.0, 0.0, 10.0)], [(0.0, 20.0, 9.5, 10.0)]):  # across the path; along it, 4.5 m away
        folder = tmp_path / f"map{len(ahead)}"
        folder.mkdir()
        field, notes = own_recording.recording_walls(path, _ros_map(folder, walls, origin=(0.0, 0.0), size=(200, 100)),
                                                     rows)  # fmt: skip
        windows = own_recording.recording_windows(rows, field)
        open_ground = own_recording.recording_windows(rows)
        key = jax.random.key(0)
        ahead.append(
            (np.asarray(predict(model.params, windows, key)), np.asarray(predict(model.params, open_ground, key)))
        )
    (across, through), (beside, alone) = ahead
    first = 0  # the first window: last observed at x = 1 + 7 x 0.5 = 4.5 m
    assert through[first, 0, -1, 0] > 7.0  # open space: on through where the wall is
    assert across[first, 0, :, 0].max() < 6.0 - float(model.radius_m) + 0.05  # with the map: stops before it
    np.testing.assert_allclose(beside, alone, atol=1e-4)  # a wall 4.5 m to the side: nothing changes
    assert "1 wall boxes within 5 m of the people" in notes[0]


def test_the_prediction_command_walks_the_models_between_the_maps_walls_and_records_it(tmp_path, capsys):
    path = _walker_towards(tmp_path)
    across = _ros_map(tmp_path, [(6.0, 7.0, 0.0, 10.0)], origin=(0.0, 0.0), size=(200, 100))
    argv = ["humans", "predict", "--tracks", str(path), "--frames-per-s", FPS, "--models",
            "collision_free_speed_calibrated", "--no-progress"]  # fmt: skip
    assert main([*argv, "--out", str(tmp_path / "open")]) == 0
    assert main([*argv, "--map", str(across), "--out", str(tmp_path / "walls")]) == 0
    scores = {k: pd.read_csv(tmp_path / k / "prediction.csv").set_index(["model", "aim"]) for k in ("open", "walls")}
    along = ("collision_free_speed_calibrated", "velocity")
    assert scores["walls"].loc[along, "ade_m"] != scores["open"].loc[along, "ade_m"]  # the walls changed the walk
    summary = json.loads((tmp_path / "walls" / "summary.json").read_text())
    assert summary["map"] == str(across) and len(summary["map_sha256"]) == 64
    assert "map" not in json.loads((tmp_path / "open" / "summary.json").read_text())
    elsewhere = _ros_map(tmp_path / "open", [], origin=(100.0, 100.0))
    capsys.readouterr()
    assert main([*argv, "--map", str(elsewhere), "--out", str(tmp_path / "x")]) == 2
    assert "% of the positions lie on the map" in capsys.readouterr().err and not (tmp_path / "x").exists()
    assert main([*argv, "--map", str(tmp_path / "none.yaml"), "--out", str(tmp_path / "x")]) == 2
    assert "--map" in capsys.readouterr().err


def test_a_shipped_corridors_walls_are_its_walkable_areas_sides_and_its_ends_stay_open():
    """Known answer (``uo-145-180-180``: a corridor x 0-1.8 m, y -4 to 4 m, wider ends): the wall
    field is 0.9 m at the corridor's middle and 0.05 m beside a side wall, no recorded position
    lies in a wall, and the ends the people walk out of hold no wall (a person 0.1 m from the
    polygon's end is 1 m from any wall). ETH/UCY records none."""
    from socialnav.evaluation.humans import shipped_windows

    field = shipped_windows.run_walls("uo-145-180-180")
    sdf = lambda x, y: float(field.lookup(jnp.float32(x), jnp.float32(y))[0])
    assert sdf(0.9, 0.0) == pytest.approx(0.9, abs=0.03) and sdf(0.05, 0.0) == pytest.approx(0.05, abs=0.03)
    assert sdf(0.9, -6.4) > 0.9 and sdf(0.9, 7.9) > 0.9  # the ends: open
    people = recorded.trajectories("uo-145-180-180")
    inside = np.asarray(field.lookup(jnp.asarray(people["x_m"], jnp.float32), jnp.asarray(people["y_m"], jnp.float32)))
    assert inside[..., 0].min() > 0.0
    assert shipped_windows.run_walls("crowds_zara01") is None


def test_the_prediction_command_reads_a_shipped_run_and_an_eth_ucy_one_gives_the_validations_figures(tmp_path, capsys):
    from socialnav.evaluation.humans import validation

    out = tmp_path / "zara"
    assert (
        main(["humans", "predict", "--run", RUN, "--models", "social_force", "--no-progress", "--out", str(out)]) == 0
    )
    table = pd.read_csv(out / "prediction.csv").set_index(["model", "aim"])
    cv = validation.eth_ucy_prediction(None, "zara1")  # zara1's test split is crowds_zara01 whole
    assert table.loc[("constant_velocity", "velocity"), "ade_m"] == pytest.approx(cv["ade_m"], abs=1e-9)
    assert json.loads((out / "summary.json").read_text())["walls"] is False
    argv = ["humans", "predict", "--out", str(tmp_path / "x")]
    for extra, words in (
        (["--run", RUN, "--tracks", "t.csv"], "one of them"),
        ([], "give --tracks"),
        (["--run", "ghosts"], "--run ghosts: not a shipped recording"),
        (["--run", RUN, "--frames-per-s", "25"], "no --frames-per-s"),
        (["--tracks", "t.csv", "--frames-per-s", "25", "--no-walls"], "--no-walls goes with --run"),
        (["--tracks", "t.csv"], "--tracks goes with --frames-per-s"),
    ):
        assert main([*argv, *extra]) == 2, extra
        assert words in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_a_maps_speckle_is_left_out_by_area_and_its_walls_kept(csv, tmp_path, capsys):
    """Known answer: a wall and 40 one-cell specks (0.01 m² each at 0.1 m): every occupied cell a
    wall by default; with --min-wall-m2 0.05 the specks go and the wall stays, box for box; two
    specks touching at a corner are one piece."""
    from socialnav.planners.learning.tracks import without_specks

    grid = np.zeros((20, 30), bool)
    grid[2:4, 5:25] = True  # a wall of 40 cells: 0.4 m²
    grid[10, 10] = grid[11, 11] = True  # two cells touching at a corner: one piece of 0.02 m²
    np.testing.assert_array_equal(without_specks(grid, 0.1, 0.03), np.isin(np.arange(30), range(5, 25))[None, :]
                                  & np.isin(np.arange(20), (2, 3))[:, None])  # fmt: skip
    assert without_specks(grid, 0.1, 0.02)[11, 11] and without_specks(grid, 0.1, 0.0).sum() == grid.sum()
    rng = np.random.default_rng(0)
    wall = (-5.0, 20.0, -5.0, -1.2)
    specks = [(x, x + 0.1, y, y + 0.1) for x, y in zip(rng.uniform(0, 15, 40).round(1), rng.uniform(0, 12, 40).round(1),
                                                        strict=True)]  # fmt: skip
    speckled = _ros_map(tmp_path, [wall, *specks])
    argv = ["arena-scene", str(csv), "--frames-per-s", FPS, "--map", str(speckled), "--overwrite"]
    assert main([*argv, "--out", str(tmp_path / "all")]) == 0
    assert main([*argv, "--min-wall-m2", "0.05", "--out", str(tmp_path / "clean")]) == 0
    every = load_scene(tmp_path / "all" / "crowd_reactive.json").walls_m
    clean = load_scene(tmp_path / "clean" / "crowd_reactive.json").walls_m
    assert len(clean) == 1 and len(every) > 30  # the wall alone; specks inside the bounds as well
    assert main(["arena-scene", str(csv), "--frames-per-s", FPS, "--min-wall-m2", "0.05", "--out", str(tmp_path)]) == 2
    assert "--min-wall-m2 goes with --map" in capsys.readouterr().err


@pytest.mark.slow  # two predictions of a corridor run by ORCA, and the script's: 10-25 s
def test_the_corridor_prediction_script_writes_the_commands_figures_and_marks_a_fit_run(tmp_path, capsys):
    """``scripts/corridor_prediction.py`` on one run is ``humans predict --run`` on it, between the
    walls and with ``--no-walls``, figure for figure; the table marks a run the Jülich fit read."""
    from tests.script_loader import load

    script = load("corridor_prediction")
    run = "uo-050-180-180"  # one of the Jülich fit's training runs, the lightest corridor
    assert script.main(["--runs", run, "--models", "orca", "--out", str(tmp_path / "table")]) == 0
    rows = pd.read_csv(tmp_path / "table" / "prediction.csv")
    for walls, extra in ((True, []), (False, ["--no-walls"])):
        out = tmp_path / f"walls-{walls}"
        assert main(["humans", "predict", "--run", run, "--models", "orca", "--no-progress", "--out", str(out),
                     *extra]) == 0  # fmt: skip
        command = pd.read_csv(out / "prediction.csv")
        mine = rows[rows["walls"] == walls].drop(columns=["run", "walls", "scored"]).reset_index(drop=True)
        pd.testing.assert_frame_equal(mine, command)
    assert f"| {run} (fit) |" in (tmp_path / "table" / "table.md").read_text()
    assert script.main(["--runs", "ghosts", "--out", str(tmp_path / "x")]) == 2
