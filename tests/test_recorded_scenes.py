"""Recorded crowds in the arena (:mod:`jaxsim.scenes.recording`, a scene's ``recording``): a
replayed crowd is the recording at every step whatever the robot does; a reactive person yields
to a robot standing on their path and goes back to it; windows, slots and held-out draws; bad
scene files refused naming the field."""

from __future__ import annotations

import json

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from socialnav.data import RECORDED_SCENES_DIR, SCENES_DIR, recorded
from socialnav.evaluation.arena import episodes as arena
from socialnav.jaxsim.scenario.errors import ScenarioError
from socialnav.jaxsim.scenes import recording as recording_lib
from socialnav.jaxsim.scenes.spec import load_scene, mirror
from socialnav.jaxsim.scenes.variant import RECORDED_START_CLEAR_M, sample_variant, sample_variants

HOTEL = RECORDED_SCENES_DIR / "hotel_replayed.json"
HOTEL_REACTIVE = RECORDED_SCENES_DIR / "hotel_reactive.json"


def _batch(variants):
    return jax.tree_util.tree_map(jnp.asarray, variants)


def _compare_with_recording(trajectory, variants):
    """(people_xy, present) of an episode set against the recording at the same steps."""
    t = trajectory.people_xy_m.shape[1]  # the record holds steps 1 .. T
    recording = np.asarray(variants.track_xy)[:, :, 1 : t + 1].transpose(0, 2, 1, 3)
    present = np.asarray(variants.track_present)[:, :, 1 : t + 1].transpose(0, 2, 1)
    return np.asarray(trajectory.people_xy_m), np.asarray(trajectory.people_present), recording, present


@pytest.mark.slow
@pytest.mark.parametrize("robot", ["far away", "standing in the crowd"])
def test_a_replayed_crowd_is_the_recording_at_every_step(robot):
    spec = load_scene(HOTEL)
    setup = arena.setup_scene(spec)
    variants = _batch(sample_variants(spec, 0, 4, n_slots=setup.n_slots))
    if robot == "far away":
        run = arena.counterfactual_function(setup)
    else:
        run = arena.actor_function(setup, arena.STAND_STILL, ())
    xy, present, recording_xy, recording_present = _compare_with_recording(run(variants), variants)
    np.testing.assert_array_equal(present, recording_present)
    assert present.sum() > 100  # people were there to compare
    np.testing.assert_allclose(np.where(present[..., None], xy, 0.0), np.where(present[..., None], recording_xy, 0.0))


def _walker_variant(spec, setup, robot_xy):
    """One recorded person walking along y = -3 at 0.8 m/s from x = -4 for 12 s; the robot at ``robot_xy``."""
    v = sample_variant(spec, 0, 0, n_slots=setup.n_slots)
    n_samples = v.track_xy.shape[1]
    k = np.arange(n_samples)
    track = np.stack([-4.0 + 0.8 * k * recording_lib.RECORD_DT_S, np.full(n_samples, -3.0)], -1)
    xy = np.zeros_like(v.track_xy)
    xy[0] = track
    present = np.zeros_like(v.track_present)
    present[0, :121] = True
    valid = np.zeros_like(v.valid)
    valid[0] = True
    return v.replace(
        track_xy=xy,
        track_present=present,
        valid=valid,
        xy0=xy[:, 0],
        heading0=np.zeros_like(v.heading0),
        robot_xy=np.asarray(robot_xy, np.float32),
    )


@pytest.mark.slow
@pytest.mark.parametrize("model", ["social_force", "collision_free_speed_calibrated", "orca"])
def test_a_reactive_person_yields_to_a_robot_standing_on_the_path_and_returns_to_it(model):
    spec = load_scene(HOTEL_REACTIVE)
    setup = arena.setup_scene(spec, arena.ArenaConfig.of(model))
    robot_xy = (0.0, -2.95)  # on the path, a hair to its left: the person passes on the right
    v = _batch(_walker_variant(spec, setup, robot_xy))
    tr = arena.actor_function(setup, arena.STAND_STILL, ())(jax.tree_util.tree_map(lambda a: a[None], v))
    xy = np.asarray(tr.people_xy_m)[0, :, 0]  # (T, 2) the walker, steps 1 .. T
    steps = np.arange(1, len(xy) + 1)
    on_track = np.asarray(v.track_xy)[0, steps]
    present = np.asarray(tr.people_present)[0, :, 0]
    assert present[:119].all() and not present[121:].any()  # there while recorded
    gap = np.linalg.norm(xy[:119] - np.asarray(robot_xy), axis=-1) - 0.275 - 0.25
    assert gap.min() > -0.05  # never walks through the robot (bodies touch at most)
    passing = (xy[:119, 0] > -0.5) & (xy[:119, 0] < 0.5)
    assert np.max(np.abs(xy[:119, 1][passing] + 3.0)) > 0.4  # went round it
    # Once past, back on the path: within 0.1 m of the line, and near where the recording has them.
    assert np.abs(xy[110, 1] + 3.0) < 0.1
    assert np.linalg.norm(xy[110] - on_track[110]) < 0.6


@pytest.mark.slow
def test_a_reactive_crowd_without_a_robot_stays_near_its_recording():
    spec = load_scene(HOTEL_REACTIVE)
    setup = arena.setup_scene(spec, arena.ArenaConfig.of("collision_free_speed_calibrated"))
    variants = _batch(sample_variants(spec, 0, 4, n_slots=setup.n_slots))
    xy, present, recording_xy, recording_present = _compare_with_recording(
        arena.counterfactual_function(setup)(variants), variants
    )
    np.testing.assert_array_equal(present, recording_present)  # people come and go as recorded
    apart = np.linalg.norm(xy - recording_xy, axis=-1)[present]
    assert np.median(apart) < 0.1 and np.percentile(apart, 95) < 0.5


def test_the_windows_resample_the_recording_and_deal_people_to_slots_with_gaps():
    data = recording_lib.load_recording("biwi_hotel")
    rows = recorded.trajectories("biwi_hotel")
    person = rows[rows["person"] == rows["person"].iloc[200]]
    t0 = float(rows["t_s"].min())
    start = int(round((person["t_s"].iloc[0] - t0) / recording_lib.RECORD_DT_S))
    xy, present = recording_lib.window(data, start, 200, recording_lib.slots_needed(data))
    # ETH/UCY samples every 0.4 s: every 4th resampled position is a recorded one.
    (slot,) = [s for s in range(xy.shape[0]) if present[s, 0] and np.allclose(xy[s, 0], person[["x_m", "y_m"]].iloc[0])]
    n = min(len(person), 200 // 4)
    np.testing.assert_allclose(xy[slot, 0 : 4 * n : 4][: len(person)], person[["x_m", "y_m"]].to_numpy()[:n], atol=1e-5)
    # Between two people in one slot, at least SLOT_GAP_SAMPLES empty samples.
    for s in range(xy.shape[0]):
        edges = np.flatnonzero(np.diff(present[s].astype(int)))
        gaps = np.diff(edges)[1::2]  # the empty runs between present runs
        assert np.all(gaps >= recording_lib.SLOT_GAP_SAMPLES)
    mirrored, _ = recording_lib.window(data, start, 200, recording_lib.slots_needed(data), mirror_y_m=2.0)
    np.testing.assert_allclose(mirrored[..., 1], 2.0 - xy[..., 1])
    with pytest.raises(ValueError, match="needs more than 1 slots"):
        recording_lib.window(data, 0, data.n_samples, 1)


def test_windows_are_drawn_inside_their_range_held_out_ones_wholly_outside_and_both_playbacks_share_them():
    spec, reactive = load_scene(HOTEL), load_scene(HOTEL_REACTIVE)
    lo, hi = spec.recording["within_s"]
    for k in range(20):
        v = sample_variant(spec, 3, k)
        assert lo <= float(v.window_start_s) and float(v.window_start_s) + spec.timeout_s <= hi + 1e-3
        w = sample_variant(reactive, 3, k)
        np.testing.assert_array_equal(v.track_xy, w.track_xy)
        np.testing.assert_array_equal(v.robot_xy, w.robot_xy)
        at_start = v.track_present[:, 0]
        assert np.all(np.linalg.norm(v.track_xy[at_start, 0] - v.robot_xy, axis=-1) >= RECORDED_START_CLEAR_M)
        held = sample_variant(mirror(spec), 3, k, held_out=True)
        start = float(held.window_start_s)
        assert start >= hi - 1e-3 or start + spec.timeout_s <= lo + 1e-3


def test_every_shipped_recording_fits_a_scene():
    from socialnav.jaxsim.scenes.spec import MAX_PEOPLE_SLOTS

    slots = {run: recording_lib.slots_needed(recording_lib.load_recording(run)) for run in recorded.run_names()}
    assert max(slots.values()) <= MAX_PEOPLE_SLOTS and slots["students001"] == 76


def test_every_shipped_recorded_scene_loads_and_the_arena_finds_them():
    from socialnav.cli.arena import RECORDED, _scene_files

    files = _scene_files([RECORDED], SCENES_DIR, RECORDED_SCENES_DIR)
    assert len(files) == 14 and {load_scene(f).recording["playback"] for f in files} == {"replayed", "reactive"}
    assert _scene_files(["zara1_reactive"], SCENES_DIR, RECORDED_SCENES_DIR) == [
        RECORDED_SCENES_DIR / "zara1_reactive.json"
    ]
    assert _scene_files(["casn_crossing"], SCENES_DIR, RECORDED_SCENES_DIR) == [SCENES_DIR / "casn_crossing.json"]
    assert all(load_scene(f).recording is None for f in SCENES_DIR.glob("*.json"))


@pytest.mark.parametrize(
    "mutate, field, words",
    [
        (lambda r, o: r.update(run="nowhere"), "recording.run", "no recorded run 'nowhere'"),
        (lambda r, o: r.update(run=3), "recording.run", "expected a run's name"),
        (lambda r, o: r.update(run="students001"), "recording.run", "outside bounds_m"),  # univ's, not hotel's
        (lambda r, o: r.update(playback="replay"), "recording.playback", "expected one of replayed, reactive"),
        (lambda r, o: r.update(window_within_s=[0, 10]), "recording.window_within_s", "shorter than one window"),
        (lambda r, o: r.update(window_within_s=[0, 9000]), "recording.window_within_s[1]", "expected a value in"),
        (lambda r, o: r.update(window_within_s=[10, 710]), "recording.window_within_s", "no held-out window"),
        (lambda r, o: r.pop("window_within_s"), "recording.window_within_s", "missing field"),
        (
            lambda r, o: o["people"].append({"behaviour": "standing", "position": [0, 0], "heading_deg": 0}),
            "people",
            "no scripted people",
        ),
    ],
)
def test_a_bad_recording_gives_one_error_naming_file_and_field(tmp_path, mutate, field, words):
    obj = json.loads(HOTEL.read_text())
    mutate(obj["recording"], obj)
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(obj))
    with pytest.raises(ScenarioError, match=words) as e:
        load_scene(path)
    assert e.value.field == field and str(path) in str(e.value)


@pytest.mark.slow  # two arena runs of one method, compiled twice
def test_dropping_the_compiled_programs_between_scenes_changes_no_episode():
    import pandas as pd

    from socialnav.evaluation.arena import run as arena_run

    if arena.memory_maps() is None:
        pytest.skip("no /proc/self/maps here: the arena never drops its programs")
    spec = load_scene(HOTEL_REACTIVE)
    config = arena.ArenaConfig.of("orca")
    before, _ = arena_run.run_scene(spec, ["orca"], 3, config=config)
    held = arena.memory_maps()[0]
    assert arena.release_programs_if_crowded(share=0.0)
    assert arena.memory_maps()[0] < held  # the programs' code is unmapped
    assert not arena.release_programs_if_crowded()  # far below half the limit now
    key = arena.setup_scene(spec, config).program_key
    assert key == arena.setup_scene(load_scene(HOTEL), config).program_key  # both playbacks: one program
    assert arena.release_programs_if_crowded(share=0.0, key=key)
    assert not arena.release_programs_if_crowded(share=0.0, key=key)  # the same scene's programs are kept
    after, _ = arena_run.run_scene(spec, ["orca"], 3, config=config)
    pd.testing.assert_frame_equal(before, after)
