"""Real pedestrians and the human models measured against them: the shipped data and its splits,
the measures on hand-made answers, the velocity models' bodies, and the protocols' known
figures (constant velocity on ETH/UCY, the Jülich diagram)."""

from __future__ import annotations

import dataclasses
import json
import re

import jax
import jax.numpy as jnp
import numpy as np
import pandas as pd
import pytest

from socialnav.data import recorded
from socialnav.evaluation.humans import measures
from socialnav.evaluation.humans import validation as hv
from socialnav.jaxsim import power_law, speed_model
from socialnav.jaxsim.grid import Grid
from socialnav.jaxsim.walkers import Aims, RobotDisc, Walkers

# ---------------------------------------------------------------- the data


def test_the_shipped_runs_read_back_in_metres_with_their_records():
    assert len(recorded.run_names("juelich")) == 12 and len(recorded.run_names("eth_ucy")) == 8
    rows = recorded.trajectories("uo-180-180-120")
    assert list(rows.columns) == ["run", "person", "frame", "t_s", "x_m", "y_m"]
    info = recorded.run_info("uo-180-180-120")
    assert info["frames_per_s"] == 16.0 and info["license"] == "CC BY 4.0" and info["source"]["commit"]
    # The corridor (x 0-1.8 m) holds the walkers; they walk towards -y at about walking speed.
    first = rows[rows["person"] == rows["person"].iloc[0]]
    assert 0.0 < first["x_m"].median() < 1.8
    speed = -np.diff(first["y_m"].to_numpy()) / np.diff(first["t_s"].to_numpy())
    assert 0.3 < np.median(speed) < 2.0
    assert np.all(np.diff(first["frame"].to_numpy()) > 0)
    with pytest.raises(KeyError, match="no recorded run 'nowhere'"):
        recorded.trajectories("nowhere")
    # ETH/UCY numbers the frames of its 25 fps videos, every 10th annotated: 0.4 s apart, and
    # its people walk at walking speed in those seconds.
    hotel = recorded.trajectories("biwi_hotel")
    steps = hotel.groupby("person")["t_s"].diff().dropna()
    assert np.allclose(steps.median(), 0.4)
    for run in ("biwi_hotel", "biwi_eth"):  # eth's samples are 0.67 s apart (data/pedestrians/README.md)
        rows = recorded.trajectories(run)
        d = rows.groupby("person")[["x_m", "y_m", "t_s"]].diff().dropna()
        speed = np.hypot(d["x_m"], d["y_m"]) / d["t_s"]
        assert 0.8 < float(np.median(speed[speed > 0.2])) < 1.6, run


def test_eth_ucy_splits_leave_the_test_scene_out_and_cut_the_rest_at_the_validation_frame():
    for scene in recorded.ETH_UCY_SCENES:
        test = recorded.eth_ucy_split(scene, "test")
        train = recorded.eth_ucy_split(scene, "train")
        val = recorded.eth_ucy_split(scene, "val")
        assert set(test["run"]).isdisjoint(train["run"]) and set(test["run"]).isdisjoint(val["run"])
        assert {recorded.run_info(r)["scene"] for r in test["run"]} == {scene}
        for run, g in train.groupby("run"):
            assert (
                g["frame"].max()
                < recorded.run_info(run)["validation_from_frame"]
                <= val[val["run"] == run]["frame"].min()
            )
    # Trajectron++'s row counts of the eth scene's training files (biwi_hotel_train ... uni_examples_train).
    assert len(recorded.eth_ucy_split("eth", "train")) == 4946 + 4307 + 7621 + 3708 + 18353 + 15641 + 2266
    with pytest.raises(KeyError, match="no split"):
        recorded.eth_ucy_split("eth", "everything")


# ---------------------------------------------------------------- measures on known answers


def test_weidmann_speed_at_known_points():
    assert float(measures.weidmann_speed(measures.WEIDMANN_JAM_PER_M2)) == pytest.approx(0.0, abs=1e-9)
    assert float(measures.weidmann_speed(1e-6)) == pytest.approx(measures.WEIDMANN_FREE_MPS, rel=1e-6)
    expected = 1.34 * (1 - np.exp(-1.913 * (1 / 2.0 - 1 / 5.4)))
    assert float(measures.weidmann_speed(2.0)) == pytest.approx(expected)
    assert np.all(np.diff(measures.weidmann_speed(np.linspace(0.5, 5, 20))) < 0)  # speed falls with density


def _frame(xy, people=None, frame=0):
    xy = np.asarray(xy, float)
    people = np.arange(len(xy)) if people is None else people
    return pd.DataFrame({"person": people, "frame": frame, "x_m": xy[:, 0], "y_m": xy[:, 1]})


def test_lane_order_is_one_in_lanes_and_low_in_a_mixture():
    lanes = _frame([[x, y] for y in (0.5, 1.5) for x in np.arange(0, 4, 0.8)])
    direction = {p: (1.0 if lanes["y_m"][p] < 1 else -1.0) for p in lanes["person"]}
    assert measures.lane_order(lanes, direction, (0, 4, 0, 2)) == pytest.approx(1.0)
    mixed = {p: (1.0 if p % 2 else -1.0) for p in lanes["person"]}  # alternating along each lane
    assert measures.lane_order(lanes, mixed, (0, 4, 0, 2)) < 0.2


def test_overlaps_count_pairs_and_depth():
    rows = _frame([[0, 0], [0.35, 0], [3, 3]])  # bodies of 0.2 m: the first two overlap by 5 cm
    got = measures.overlaps(rows, 0.2)
    assert got["pair_frames"] == 1 and got["max_depth_m"] == pytest.approx(0.05)
    assert got["share_people"] == pytest.approx(2 / 3) and got["share_deeper_0_1_m"] == 0.0
    assert measures.overlaps(_frame([[0, 0], [1, 0]]), 0.2)["pair_frames"] == 0
    assert measures.overlaps(_frame([[0, 0], [0.25, 0]]), 0.2)["share_deeper_0_1_m"] == 1.0  # 0.15 m deep


def _runs_at(speeds: dict, spread: float = 0.1, frames: int = 120) -> pd.DataFrame:
    """``run, density, speed`` points: each run's frames at the bins it covers, ``run -> {bin:
    mean speed}``, the speeds spread evenly ``+-spread`` about the mean."""
    wobble = np.linspace(-spread, spread, frames)
    rows = [pd.DataFrame({"run": run, "density": rho, "speed": v + wobble})
            for run, bins in speeds.items() for rho, v in bins.items()]  # fmt: skip
    return pd.concat(rows, ignore_index=True)


@pytest.mark.parametrize(("radius_m", "n"), [(0.2, 126), (0.25, 108)])  # 3.5 and 3 /m² in 1.8 m x 20 m
def test_a_dense_crowd_starts_packed_without_rows_and_each_draw_elsewhere(radius_m, n):
    width, length, gap = 1.8, 20.0, 2 * radius_m + 0.05  # random placement cannot fit them
    assert hv._starts(n, width, length, radius_m, np.random.default_rng(0), lattice=False) is None
    draws = [hv.packed_starts(n, width, length, radius_m, np.random.default_rng(seed)) for seed in (0, 1)]
    lattice = hv._starts(n, width, length, radius_m, np.random.default_rng(0))
    for xy in draws:
        d = xy[:, None] - xy[None]
        d[..., 0] = (d[..., 0] + length / 2) % length - length / 2
        distance = np.hypot(d[..., 0], d[..., 1]) + np.eye(n) * 99
        assert distance.min() >= gap - 1e-3  # no two bodies closer than the placement's gap
        assert xy[:, 1].min() >= radius_m + 0.05 - 1e-9 and xy[:, 1].max() <= width - radius_m - 0.05 + 1e-9
        assert np.all((xy[:, 0] >= 0) & (xy[:, 0] < length))
        # in no rows: the lattice's people sit at a few heights (its jitter aside), the packing's at many
        assert len(np.unique(np.round(xy[:, 1], 2))) > 3 * len(np.unique(np.round(lattice[:, 1], 1)))
    assert not np.allclose(draws[0], draws[1])


def test_the_diagrams_band_check_counts_bins_within_one_standard_deviation():
    data = measures.binned(_runs_at({"a": {1.0: 1.2, 2.0: 0.6}}))
    sd = float(data["speed_sd"].iloc[0])
    model = pd.DataFrame({"density_bin": [1.0, 2.0, 3.0], "speed_mean": [1.2 + 0.9 * sd, 0.6 - 1.5 * sd, 0.3]})
    got = measures.against_band(model, data)
    assert list(got["density_bin"]) == [1.0, 2.0]  # a bin the data lacks is not scored
    np.testing.assert_allclose(got["z"], [0.9, -1.5])
    assert list(got["inside"]) == [True, False]


def test_the_data_scored_against_itself_finds_runs_that_disagree():
    # Three training and two test runs; one training run walks its 2 /m² bin 0.4 m/s fast, one test
    # run holds a bin of too few frames to count.
    agree = {1.0: 1.2, 2.0: 0.6}
    points = _runs_at({"t1": agree, "t2": agree, "t3": {2.0: 1.0}, "h1": agree, "h2": agree})
    points = pd.concat([points, _runs_at({"h2": {3.0: 0.3}}, frames=20)], ignore_index=True)
    got = hv.data_agreement(points, train_runs=("t1", "t2", "t3"), test_runs=("h1", "h2"))
    # Pooled, the training runs' 2 /m² bin is 0.733 m/s with the test band 0.6 +- 0.058: outside.
    assert (got["training_runs"]["inside"], got["training_runs"]["of"]) == (1, 2)
    # Each run against the others: t3's one bin is out (0.6 +- 0.058 without it); every other run's
    # 2 /m² bin is in, its band (t3 among the others) 0.7 +- 0.18; h2's 20-frame bin is not counted.
    assert got["each_run"]["runs"]["t3"] == "0 of 1" and got["each_run"]["runs"]["h2"] == "2 of 2"
    assert got["each_run"]["of"] == 9 and got["each_run"]["inside"] == 8


def test_a_window_of_frames_is_measured_as_from_every_frame():
    """``voronoi_density_speed`` hands PedPy only the rows a window's points read (each person's
    own rows a speed step either side); the points are the ones every row gives, on a Jülich run's
    frames with people entering and leaving, rows out of frame order and a person missing frames."""
    run = "uo-060-180-180"
    info, g = recorded.run_info(run), recorded.run_info(run)["geometry"]
    rows = recorded.trajectories(run)
    rows = rows[rows["frame"].between(240, 290)]
    gap = rows["person"].iloc[len(rows) // 2]
    rows = rows[~((rows["person"] == gap) & rows["frame"].between(258, 262))].sample(frac=1.0, random_state=0)
    args = (info["frames_per_s"], g["walkable_polygon_m"], g["measurement_area_m"], g["walking_direction"])
    window = (255, 275)
    cut = measures.voronoi_density_speed(rows, *args, frames=window)
    every = measures.voronoi_density_speed(rows, *args)
    every = every[every["frame"].between(*window)].reset_index(drop=True)
    assert len(cut) > 15 and cut["frame"].between(*window).all()
    pd.testing.assert_frame_equal(cut, every, check_exact=True)
    kept = measures._rows_for_frames(rows.rename(columns={"person": "id"}), window, 5)
    assert kept["frame"].min() < window[0] and len(kept) < len(rows)  # the speed's margin kept, the rest cut


def test_the_datas_measures_are_read_back_from_disk_while_their_inputs_are_unchanged(tmp_path, monkeypatch, capsys):
    from socialnav.evaluation.humans import datacache

    monkeypatch.setenv("SOCIALNAV_HUMANS_CACHE", str(tmp_path / "cache"))
    calls = []

    def measure(run):
        calls.append(run)
        return pd.DataFrame({"frame": [7, 8], "density": [0.1, 1 / 3], "speed": [np.nan, 1.25], "run": [run] * 2})

    def counter():
        calls.append("counter")
        return {"density": 0.98, "lane_order": 2 / 3}

    kept, kept_counter = datacache.kept(measure), datacache.kept(counter)
    first = kept("a")
    pd.testing.assert_frame_equal(kept("a"), first, check_exact=True)  # every bit, the NaN, the dtypes
    assert kept_counter() == kept_counter() == {"density": 0.98, "lane_order": 2 / 3}
    kept("b"), kept(run="b")
    assert calls == ["a", "counter", "b", "b"]  # each argument its own value, each computed once
    for stored in (tmp_path / "cache").iterdir():  # a damaged file: computed again and replaced
        stored.write_text('{"key": ')
    kept("a"), kept("a")
    assert calls == ["a", "counter", "b", "b", "a"]
    monkeypatch.setattr(datacache, "inputs_digest", lambda: "the data or the code changed")
    pd.testing.assert_frame_equal(kept("a"), first, check_exact=True)
    assert calls[-1] == "a" and len(calls) == 6
    monkeypatch.setenv("SOCIALNAV_HUMANS_CACHE", "off")
    kept("a"), kept("a")
    assert len(calls) == 8
    (tmp_path / "a file").write_text("")
    for cannot in (tmp_path / "a file" / "cache", tmp_path / "a file"):  # under a file, a file
        monkeypatch.setenv("SOCIALNAV_HUMANS_CACHE", str(cannot))
        pd.testing.assert_frame_equal(kept("a"), first, check_exact=True)
        kept("a")  # computed again, said once
        warned = capsys.readouterr().err.strip()
        assert warned.startswith(f"socialnav: warning: the pedestrian data's cache {cannot}: ") and "\n" not in warned
        assert "SOCIALNAV_HUMANS_CACHE names another folder" in warned
    assert len(calls) == 12


def test_ade_fde_of_a_known_offset():
    truth = np.zeros((2, 12, 2))
    predicted = truth + np.array([0.3, 0.4])
    predicted[1, -1] += [3.0, 4.0]
    ade, fde = measures.ade_fde(predicted, truth)
    np.testing.assert_allclose(fde, [0.5, np.hypot(3.3, 4.4)])
    np.testing.assert_allclose(ade, [0.5, (11 * 0.5 + np.hypot(3.3, 4.4)) / 12])


def test_the_difference_from_constant_velocity_is_bootstrapped_in_blocks_of_overlapping_windows():
    rng = np.random.default_rng(3)
    baseline = rng.uniform(0.2, 1.0, 400)
    # a model 0.1 m better for everyone: no spread at all
    assert measures.paired_difference(baseline - 0.1, baseline, np.arange(400)) == pytest.approx((-0.1, -0.1, -0.1))
    # one difference a person, seen once: the interval holds the mean, about +- 2 standard errors
    diff = rng.normal(-0.02, 0.1, 400)
    mean, low, high = measures.paired_difference(baseline + diff, baseline, np.arange(400), block_windows=1)
    assert mean == pytest.approx(diff.mean()) and low < mean < high
    assert high - low == pytest.approx(2 * 1.96 * diff.std(ddof=1) / 20, rel=0.2)
    # the same people each seen in 20 consecutive windows: blocks of 20 windows keep the width a
    # person-level sample has; windows taken as independent would shrink it by sqrt(20)
    repeated, window = np.repeat(diff, 20), np.arange(400 * 20)
    _, block_low, block_high = measures.paired_difference(
        np.repeat(baseline, 20) + repeated, np.repeat(baseline, 20), window
    )
    _, naive_low, naive_high = measures.paired_difference(
        np.repeat(baseline, 20) + repeated, np.repeat(baseline, 20), window, block_windows=1
    )
    assert block_high - block_low == pytest.approx(high - low, rel=0.2)
    assert naive_high - naive_low < 0.4 * (high - low)


def test_the_five_scene_averages_interval_weighs_every_scene_alike_and_resamples_each_apart():
    rng = np.random.default_rng(4)
    big, small = rng.normal(-0.1, 0.05, 1000), rng.normal(0.3, 0.05, 50)  # 1,000 people and 50
    scenes = [(d, np.zeros_like(d), np.arange(len(d))) for d in (big, small)]
    mean, low, high = measures.mean_paired_difference(scenes, block_windows=1)
    assert mean == pytest.approx((big.mean() + small.mean()) / 2)  # not the pooled mean (about -0.08)
    assert low < mean < high and low < 0.1 < high
    # the spread is the two means' standard errors over two scenes: sqrt(se1² + se2²) / 2
    se = np.sqrt(big.var(ddof=1) / 1000 + small.var(ddof=1) / 50) / 2
    assert high - low == pytest.approx(2 * 1.96 * se, rel=0.25)
    # one scene: the scene's own difference and an interval as wide as paired_difference's
    one = measures.mean_paired_difference(scenes[:1], block_windows=1)
    alone = measures.paired_difference(*scenes[0], block_windows=1)
    assert one[0] == pytest.approx(alone[0]) and one[2] - one[1] == pytest.approx(alone[2] - alone[1], rel=0.15)
    # a scene of one block has no interval
    assert np.isnan(measures.mean_paired_difference([(big[:5], np.zeros(5), np.zeros(5, int))])[1])


# ---------------------------------------------------------------- the velocity models


def _open_field():
    values = np.zeros((2, 2, 3), np.float32)
    values[..., 0] = 1e4
    values[..., 1] = 1.0
    return Grid.of_samples(jnp.asarray(values), -1e4, -1e4, 2e4)


FAR = RobotDisc(jnp.float32(1e4), jnp.float32(1e4), jnp.float32(0.0), jnp.float32(0.0), 0.3)


def _walk(step, xy, aim, speed, n_steps, dt=0.1):
    """Positions (T, N, 2) of people stepped by ``step`` (:func:`_in_the_open`) towards fixed aims."""
    xy = jnp.asarray(xy, jnp.float32)
    v = jnp.zeros_like(xy)
    path = []
    for k in range(n_steps):
        u = jnp.full(xy.shape[0], 0.25 + 0.5 * (k % 2), jnp.float32)
        to = jnp.asarray(aim, jnp.float32) - xy
        people = step(xy, v, to, jnp.asarray(speed, jnp.float32), u)
        xy, v = people.xy_m, people.velocity_mps
        path.append(np.asarray(xy))
    return np.stack(path)


def _in_the_open(model_step, params, field=None, **static):
    """``(xy, v, to, speed, u) -> Walkers``: a model's step of 0.1 s in ``field`` (default: no
    walls), everyone present and moving, the robot far away, ``u`` both uniforms."""

    def step(xy, v, to, s, u):
        everyone = jnp.ones(len(s), bool)
        people, aims = Walkers.of(xy, v, everyone, everyone), Aims(to[:, 0], to[:, 1], s, s)
        return model_step(params, _open_field() if field is None else field, 0.1, people, aims, FAR, (u, u), **static)

    return step


STEPS = {
    "collision_free_speed": _in_the_open(speed_model.step_speed_model, speed_model.SpeedModelParams()),
    "anticipation": _in_the_open(speed_model.step_anticipation, speed_model.AnticipationParams()),
    "steering_speed": _in_the_open(speed_model.step_speed_model, speed_model.SpeedModelParams(),
                                   headings=speed_model.STEERING_HEADINGS),
    # its ten substeps a step: one program, not each operation dispatched in turn
    "power_law": jax.jit(_in_the_open(power_law.step_power_law, power_law.PowerLawParams())),
}  # fmt: skip


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(STEPS))
def test_two_people_head_on_pass_without_their_bodies_overlapping(name):
    path = _walk(STEPS[name], [[0.0, 0.0], [6.0, 0.05]], [[12.0, 0.0], [-6.0, 0.05]], [1.2, 1.2], 150)
    gap = np.linalg.norm(path[:, 0] - path[:, 1], axis=-1)
    assert gap.min() > 2 * 0.2 - 1e-3, gap.min()  # bodies of 0.2 m never overlap
    assert path[-1, 0, 0] > 8.0 and path[-1, 1, 0] < -2.0  # and both got past each other


@pytest.mark.slow
def test_the_speed_model_in_single_file_walks_at_its_headway_over_the_time_gap():
    """Known answer (Tordeux et al. 2016): a file of people 1 m apart, faster ones behind, ends at
    the speed (spacing - 2 r) / T of the headway, whatever their desired speeds above it."""
    xy = [[float(k), 0.0] for k in range(5)]
    path = _walk(STEPS["collision_free_speed"], xy, [[100.0, 0.0]] * 5, [1.5, 1.5, 1.5, 1.5, 0.5], 100)
    speed = (path[-1, :, 0] - path[-2, :, 0]) / 0.1
    assert speed[-1] == pytest.approx(0.5, abs=1e-4)  # the leader, free: its desired speed
    gaps = np.diff(path[-1, :, 0])
    np.testing.assert_allclose(speed[:-1], np.minimum((gaps - 0.4) / 1.0, 1.5), atol=1e-3)


def test_candidate_headings_keep_straight_first_then_right_before_left():
    np.testing.assert_allclose(speed_model.heading_offsets(5), [0.0, -0.5, 0.5, -1.0, 1.0])
    np.testing.assert_allclose(speed_model.heading_offsets(1), [0.0])


@pytest.mark.slow
def test_the_steering_model_overtakes_a_slower_walker_where_the_published_one_follows():
    """Known answer: behind a walker at 0.5 m/s in open space, the published speed model follows
    at the leader's speed (its heading never leaves the lane); the steering one turns out of the
    lane and passes."""
    xy, aim, speed = [[0.0, 0.0], [2.0, 0.0]], [[100.0, 0.0], [100.0, 0.0]], [1.4, 0.5]
    follows = _walk(STEPS["collision_free_speed"], xy, aim, speed, 200)
    passes = _walk(STEPS["steering_speed"], xy, aim, speed, 200)
    assert follows[-1, 0, 0] < follows[-1, 1, 0]  # still behind after 20 s
    assert passes[-1, 0, 0] > passes[-1, 1, 0] + 5.0  # well past
    assert passes[:, 0, 1].min() < -0.3  # out of the lane: to the right, the tie's side
    gap = np.linalg.norm(passes[:, 0] - passes[:, 1], axis=-1)
    assert gap.min() > 2 * 0.2 - 1e-3  # bodies never overlap while passing


@pytest.mark.slow
def test_the_steering_model_is_the_published_one_where_nobody_is_in_the_way():
    """Bit for bit: people far apart walk as the published speed model walks them."""
    xy = [[0.0, 0.0], [0.0, 5.0], [5.0, -5.0]]
    aim = [[10.0, 3.0], [-10.0, 5.0], [5.0, 10.0]]
    plain = _walk(STEPS["collision_free_speed"], xy, aim, [1.2, 1.3, 0.9], 30)
    steered = _walk(STEPS["steering_speed"], xy, aim, [1.2, 1.3, 0.9], 30)
    np.testing.assert_array_equal(plain, steered)


@pytest.mark.slow
def test_the_steering_model_passes_on_the_side_away_from_a_wall():
    """A slower walker ahead, a wall 0.3 m to the right: the turn to the right (the tie's side)
    would walk into the wall, so the faster one passes on the left and stays inside the corridor."""
    model = hv.HumanModel("steering_speed")
    field = hv.corridor_field(1.8, 40.0)
    step = _in_the_open(speed_model.step_speed_model, model.speed, field, headings=speed_model.STEERING_HEADINGS)
    path = _walk(step, [[0.0, 0.3], [2.0, 0.3]], [[100.0, 0.3], [100.0, 0.3]], [1.4, 0.5], 200)
    assert path[-1, 0, 0] > path[-1, 1, 0] + 3.0
    assert path[:, 0, 1].max() > 0.6 and path[:, 0, 1].min() >= model.speed.radius_m - 1e-3


@pytest.mark.slow
@pytest.mark.parametrize(
    "name", ["collision_free_speed", "anticipation", "steering_speed", "social_force", "power_law"]
)
def test_speed_falls_with_density_in_the_corridor(name):
    model = hv.HumanModel(name)
    speeds = []
    for rho in (0.5, 2.0, 3.5):
        rows, _ = hv.corridor_run(model, rho, length_m=8.0, seconds=12.0)
        late = rows[rows["frame"] > 60].sort_values(["person", "frame"])
        dx = late.groupby("person")["x_m"].diff().to_numpy()
        speeds.append(np.nanmean(np.where(np.abs(dx) < 1.0, dx, np.nan)) / model.dt_s)
    assert speeds[0] > speeds[1] > speeds[2] > 0.0, speeds


def _energy(params, xi, xj, vi, vj, reach):
    """Karamouzas et al.'s E(tau) = k / tau^2 exp(-tau / tau0), tau found from its definition: the
    first time |(x_i - x_j) + (v_i - v_j) t| = R, by the quadratic's smaller root."""
    d, v = xi - xj, vi - vj
    a, b, c = v @ v, d @ v, d @ d - reach**2
    tau = (-b - jnp.sqrt(b * b - a * c)) / a
    return params.strength_m2ps2 / tau**2 * jnp.exp(-tau / params.horizon_s)


@pytest.mark.parametrize(
    "xj, vi, vj",
    [
        ((3.0, 0.2), (1.3, 0.0), (-1.1, 0.1)),
        ((1.2, -0.5), (0.9, 0.3), (0.2, 0.4)),
        ((-2.0, 1.0), (0.0, 0.0), (1.0, -0.6)),
    ],
)
def test_the_power_laws_force_is_minus_the_gradient_of_its_energy(xj, vi, vj):
    """Known answer: the paper's closed-form force on i equals -dE/dx_i, E(tau) differentiated by
    JAX from the definition of the time to collision (three approaches: head-on, overtaking, a
    standing person met by a walker)."""
    params = power_law.PowerLawParams()
    xi, xj, vi, vj = (jnp.asarray(a, jnp.float32) for a in ((0.0, 0.0), xj, vi, vj))
    expected = -jax.grad(_energy, argnums=1)(params, xi, xj, vi, vj, 0.4)
    w, v = (xj - xi)[None, None, :], (vi - vj)[None, None, :]
    (lx, ly), (cx, cy) = power_law.pair_forces(params, w[..., 0], w[..., 1], v[..., 0], v[..., 1],
                                               jnp.full((1, 1), 0.4), jnp.ones((1, 1), bool))  # fmt: skip
    np.testing.assert_allclose([float(lx[0]), float(ly[0])], np.asarray(expected), rtol=2e-3, atol=1e-6)
    assert float(cx[0]) == 0.0 and float(cy[0]) == 0.0  # apart: no contact force
    # the same two walking apart, or side by side at one velocity: no collision ahead, no force
    (lx, ly), _ = power_law.pair_forces(params, w[..., 0], w[..., 1], -v[..., 0], -v[..., 1],
                                        jnp.full((1, 1), 0.4), jnp.ones((1, 1), bool))  # fmt: skip
    assert float(lx[0]) == 0.0 and float(ly[0]) == 0.0


def test_the_power_laws_wall_force_is_minus_the_gradient_of_its_energy():
    """Known answer: walking at 1.2 m/s straight at a wall 1 m away, a body of 0.2 m meets it in
    tau = 0.8 / 1.2 s; the force is -dE/dd along the wall's normal, E(tau(d)) differentiated by JAX."""
    params = power_law.PowerLawParams()
    energy = lambda d: params.strength_m2ps2 / ((d - 0.2) / 1.2) ** 2 * jnp.exp(-(d - 0.2) / 1.2 / params.horizon_s)
    one = jnp.ones(1)
    (lx, ly), (cx, cy) = power_law.wall_forces(params, one, one, 0 * one, -1.2 * one, 0 * one)
    np.testing.assert_allclose(float(lx[0]), -float(jax.grad(energy)(1.0)), rtol=1e-4)
    assert float(ly[0]) == 0.0 and float(cx[0]) == 0.0  # and no contact 1 m from it
    (lx, _), _ = power_law.wall_forces(params, one, one, 0 * one, 0 * one, 1.2 * one)  # along the wall
    assert float(lx[0]) == 0.0


def test_bodies_in_contact_push_apart_by_helbings_stiffness_and_rub_by_his_friction():
    """Known answer (Helbing, Farkas & Vicsek 2000 per unit mass): two bodies 0.05 m into each
    other, at rest, push i away from j with 1500 x 0.05 = 75 m/s^2; sliding past each other at 1
    m/s, i is also pulled along j's motion with 3000 x 0.05 x 1 = 150 m/s^2."""
    params = power_law.PowerLawParams()
    ones = jnp.ones((1, 1), bool)
    reach = jnp.full((1, 1), 0.4)
    w = jnp.full((1, 1), 0.35)  # j 0.35 m to the right of i: 0.05 m overlap
    zero = jnp.zeros((1, 1))
    _, (cx, cy) = power_law.pair_forces(params, w, zero, zero, zero, reach, ones)
    np.testing.assert_allclose([float(cx[0]), float(cy[0])], [-75.0, 0.0], atol=1e-3)
    _, (cx, cy) = power_law.pair_forces(params, w, zero, zero, jnp.full((1, 1), -1.0), reach, ones)  # j moves +y
    np.testing.assert_allclose([float(cx[0]), float(cy[0])], [-75.0, 150.0], atol=1e-2)


# ---------------------------------------------------------------- the protocols' known figures


@pytest.mark.slow
def test_constant_velocity_on_eth_ucy_matches_the_published_figure():
    """Schöller et al. (2020), "The Simpler the Better": constant velocity ADE/FDE about 0.53 /
    1.15 m over the five test splits; the protocol here (8 observed, 12 predicted, people in all 20
    frames) gives the same to 0.02 m."""
    results = [hv.eth_ucy_prediction(None, scene) for scene in recorded.ETH_UCY_SCENES]
    assert np.mean([r["ade_m"] for r in results]) == pytest.approx(0.53, abs=0.02)
    assert np.mean([r["fde_m"] for r in results]) == pytest.approx(1.15, abs=0.03)
    assert all(r["samples"] > 300 for r in results)


@pytest.mark.slow
def test_prediction_windows_keep_each_runs_sample_interval_and_a_lone_walker_is_read_at_those_times():
    """biwi_eth is sampled every 2/3 s, the other runs every 0.4 s: a window's velocity and its
    horizon are its own run's, and the model's path is read at its own samples (interpolated
    between steps where the interval is not a multiple of the model's step)."""
    assert np.allclose(hv.prediction_windows("eth").frame_s, 2 / 3)  # a tuple: static under jit
    assert np.allclose(hv.prediction_windows("hotel").frame_s, 0.4)
    steps, lo, frac = hv._sample_steps(0.4, 0.1)
    assert steps == 48 and list(lo[:3]) == [3, 7, 11] and not frac.any()
    steps, lo, frac = hv._sample_steps(2 / 3, 0.1)
    assert steps == 80 and lo[0] == 5 and frac[0] == pytest.approx(2 / 3, abs=1e-5) and lo[-1] == 79
    # one free walker per window, at their desired speed, far from anyone: constant velocity,
    # each window at its own interval, in the order given
    n = 4
    frame_s = np.array([0.4, 2 / 3, 0.4, 2 / 3], np.float32)
    start = np.zeros((n, 1, 2), np.float32)
    velocity = np.tile(np.array([[[1.2, 0.0]]], np.float32), (n, 1, 1))
    truth = start[:, :, None] + velocity[:, :, None] * (frame_s[:, None] * np.arange(1, 13))[:, None, :, None]
    one = np.ones((n, 1), bool)
    w = hv.PredictionWindows(start, velocity, np.full((n, 1), 1.2, np.float32), one, start,
                             np.full((n, 1), -1, np.int32), truth, one, truth, tuple(frame_s.tolist()))  # fmt: skip
    model = hv.HumanModel("collision_free_speed")
    predict = hv.window_predictor(model.name, model.dt_s)
    predicted = np.asarray(predict(model.params, w, jax.random.key(0)))
    np.testing.assert_allclose(predicted, truth, atol=0.02)
    # as a calibration calls it: the windows traced, their intervals static
    traced = jax.jit(lambda windows: predict(model.params, windows, jax.random.key(0)))(w)
    np.testing.assert_allclose(np.asarray(traced), predicted, atol=1e-5)


@pytest.mark.slow
def test_the_juelich_diagram_falls_as_weidmanns_does_and_the_command_writes_its_report(tmp_path, capsys):
    points = hv.data_fundamental_diagram(("uo-070-180-180", "uo-180-180-070"))
    bins = measures.binned(points)
    assert len(bins) >= 4 and np.all(np.diff(bins["speed_mean"]) < 0.1)
    assert abs(bins["speed_mean"].iloc[-1] - float(measures.weidmann_speed(bins["density_bin"].iloc[-1]))) < 0.2
    from socialnav import cli

    out = tmp_path / "humans"
    fit = tmp_path / "my-fit" / "fit.json"  # a calibration's own fit scored beside a named model
    fit.parent.mkdir()
    values = {"time_gap_s": 0.75, "neighbor_strength": 10.0, "neighbor_range_m": 0.11, "radius_m": 0.16}
    fit.write_text(json.dumps({"model": "collision_free_speed", "nelder_mead": {"values": values}}))
    argv = ["humans", "validate", "--quick", "--start-draws", "1", "--out", str(out), "--no-progress",
            "--models", "social_force", "--fit", str(fit), "--fit-method", "nelder_mead"]  # fmt: skip
    assert cli.main(argv) == 0
    said = capsys.readouterr().out
    assert "social_force: speed inside the data's" in said and (out / "pictures" / "fundamental_diagram.png").is_file()
    assert "my-fit:nelder_mead: speed inside the data's" in said
    assert "data against its own diagram check" in said and "from 1 disordered starts" in said
    summary = json.loads((out / "summary.json").read_text())
    assert len(summary["models"]["social_force"]["fd_start_draws"]["bins_inside"]) == 1
    assert summary["data"]["fd_agreement"]["each_run"]["of"] >= 9  # every run counts a bin at least
    assert set(pd.read_csv(out / "fundamental_diagram.csv")["draw"]) == {0, 1}
    assert pd.read_csv(out / "prediction.csv")["model"].nunique() == 3
    assert summary["fits"]["my-fit:nelder_mead"] == {"fit_json": str(fit), "values": values}
    difference, low, high = summary["models"]["social_force"]["eth_ucy_average_vs_cv"]["ade_m"]
    ade, cv = summary["models"]["social_force"]["eth_ucy_ade_fde"][0], summary["models"]["social_force"][
        "constant_velocity_ade_fde"][0]  # fmt: skip
    assert difference == pytest.approx(ade - cv, abs=1e-3) and low <= difference <= high
    # The data's measures were kept on disk (evaluation.humans.datacache) and read back bit for bit.
    from_disk, computed = hv._run_fundamental_diagram.__wrapped__, hv._run_fundamental_diagram.__wrapped__.__wrapped__
    pd.testing.assert_frame_equal(from_disk("uo-060-180-180"), computed("uo-060-180-180"), check_exact=True)
    assert cli.main(["humans", "validate", "--quick", "--out", str(out), "--no-progress"]) == 2  # no --overwrite
    assert cli.main(["humans", "validate", "--models", "crowd_of_ghosts", "--out", str(tmp_path / "x")]) == 2


# ---------------------------------------------------------------- calibration


def test_a_fits_log_lines_say_how_long_is_left_at_the_pace_after_the_compile():
    """The time left is the steps to go at the mean pace of the steps after the first (which
    compiles), in the unit a person reads; nothing before two steps or after the last."""
    import optax

    from socialnav.common.progress import duration, time_left
    from socialnav.evaluation.humans import minimise

    history = [(0, 1.0, 30.0), (1, 0.9, 32.0), (2, 0.8, 34.0)]  # 30 s to compile, then 2 s a step
    assert time_left(history, 80) == "; about 3 min to go"  # 77 steps x 2 s: 154 s
    assert time_left(history, 30, "at most ") == "; at most about 54 s to go"
    assert time_left(history[:1], 80) == "" and time_left(history, 3) == ""
    assert time_left([(0, 1.0, 30.0), (1, 0.9, 30.1), (2, 0.8, 30.2)], 4) == "; under a second to go"
    assert [duration(s) for s in (0.2, 45, 720, 3 * 3600 + 1800)] == ["under a second", "45 s", "12 min", "3.5 h"]
    said = []
    minimise.adam(minimise.value_and_grad(lambda th: jnp.sum(th**2)), jnp.ones(2), 12, optax.adam(0.1), log=said.append)
    assert re.fullmatch(r"  gradient step 10: loss \d\.\d{3} \(\d+ s; (about \d+ s|under a second) to go\)", said[1])


def test_adam_stops_where_the_gradient_is_not_finite_and_keeps_the_best_so_far():
    import optax

    from socialnav.evaluation.humans import minimise

    said = []
    smooth = minimise.value_and_grad(lambda th: jnp.sum((th - 2.0) ** 2))
    best, history = minimise.adam(smooth, jnp.zeros(2), 30, optax.adam(0.2), log=said.append)
    assert len(history) == 30 and float(jnp.abs(best - 2.0).max()) < 0.5
    # sqrt(theta^2) at 0: a finite loss whose gradient is NaN (0 x inf)
    broken = minimise.value_and_grad(lambda th: jnp.sum(jnp.sqrt(th**2)) + 1.0)
    best, history = minimise.adam(broken, jnp.zeros(2), 30, optax.adam(0.2), log=said.append)
    assert len(history) == 1 and np.all(np.asarray(best) == 0.0)
    assert any("not finite" in line for line in said)


def test_a_trajectory_fit_past_the_machines_memory_is_refused_with_the_windows_that_fit():
    """XLA's count of a compiled program's buffers against the memory available: a share of it
    no program fits in is refused, naming the windows and how many would fit; a whole share is not."""
    import types

    from socialnav.evaluation.humans import trajectory_calibration as tc

    x = jnp.zeros((1000, 1000), jnp.float32)
    compiled = jax.jit(lambda a: (a @ a).sum()).lower(x).compile()
    sample = types.SimpleNamespace(start=np.zeros((512, 75, 2)))  # the shape the message reads
    with pytest.raises(tc.FitTooLarge, match=r"a fit over 512 windows of up to 75 people holds about .* GB at once"):
        tc.refuse_past_memory(compiled, sample, share=1e-9)
    tc.refuse_past_memory(compiled, sample, share=1.0)  # a few megabytes: fits


def test_a_jülich_fit_past_the_machines_memory_is_refused_with_the_draws_that_fit_before_any_is_drawn():
    """The gradient fit's program over ``1 + start_draws`` draws, compiled for the shapes alone:
    what it holds grows with the draws (reverse mode keeps each draw's measured steps), more than
    the loss alone does; a share of memory no program fits in is refused naming the draws and how
    many would fit, a whole share is not."""
    from socialnav.evaluation.humans import calibration as hc
    from socialnav.evaluation.humans import minimise

    model = hv.HumanModel("collision_free_speed")
    size = dict(length_m=6.0, warmup_steps=5, measured_steps=4)
    one, four = (hc.fit_bytes(model, (1.0, 3.0), draws, **size) for draws in (0, 3))
    forward = hc.fit_bytes(model, (1.0, 3.0), 3, gradient=False, **size)
    assert 0 < one < four and forward < four
    said = r"a gradient fit of collision_free_speed over 4 draws of each of 2 corridors holds about .* GB at once, "
    with pytest.raises(minimise.FitTooLarge, match=said + r"this machine has .* GB available: about 0 start draws fit"):
        hc.refuse_past_memory(model, (1.0, 3.0), 3, share=1e-9, **size)
    hc.refuse_past_memory(model, (1.0, 3.0), 3, share=1.0, **size)  # a few megabytes: fits


def _walked_by(truth: hv.HumanModel, fields):
    """Short corridors at 1.5, 2.5 and 3.5 /m² whose "data" is the speed ``truth`` walks there
    (s.d. 0.05 m/s): a calibration's known answer."""
    from socialnav.evaluation.humans import calibration as hc

    size = dict(length_m=6.0, warmup_steps=60, measured_steps=20)
    corridors = hc.corridors_at(truth, (1.5, 2.5, 3.5), np.zeros(3), np.full(3, 0.05), **size)
    key = jax.random.key(0)
    measured = np.asarray(hc.mean_speeds(truth, corridors, hc.theta_of(truth, fields), key, fields=fields))
    return dataclasses.replace(corridors, speed_data=measured)


def test_the_calibrations_start_draws_add_disordered_corridors_and_the_loss_averages_each_draws():
    """``start_draws``: draw 0 is the single draw's corridor, bit for bit; the others are other
    packings of the same number of people; the loss is each draw's loss averaged over the draws."""
    from socialnav.evaluation.humans import calibration as hc

    model = hv.HumanModel("collision_free_speed")
    size = dict(length_m=6.0, warmup_steps=30, measured_steps=10)
    one = hc.corridors_at(model, (1.0, 3.0), np.array([1.1, 0.4]), np.array([0.1, 0.1]), **size)
    three = hc.corridors_at(model, (1.0, 3.0), np.array([1.1, 0.4]), np.array([0.1, 0.1]), start_draws=2, **size)
    gap = 2 * model.radius_m + 0.05
    for (xy1, _, speed1), (xy3, direction3, speed3) in zip(one.starts, three.starts, strict=True):
        assert xy3.shape[0] == speed3.shape[0] == direction3.shape[0] == 3 and xy3.shape[1:] == xy1.shape[1:]
        np.testing.assert_array_equal(xy3[0], xy1[0])
        np.testing.assert_array_equal(speed3[0], speed1[0])
        for xy in np.asarray(xy3[1:]):  # (a lattice's rows may sit closer than the gap)
            d = xy[:, None] - xy[None]
            d[..., 0] = (d[..., 0] + 3.0) % 6.0 - 3.0
            assert (np.hypot(d[..., 0], d[..., 1]) + np.eye(len(xy)) * 99).min() >= gap - 1e-3
        assert not np.allclose(xy3[1], xy3[2]) and not np.allclose(xy3[0], xy3[1])
    key, theta = jax.random.key(0), hc.theta_of(model)
    speeds = np.asarray(hc.draw_speeds(model, three, theta, key))
    assert speeds.shape == (2, 3) and np.all(speeds[1] < speeds[0].min())  # the dense corridor walks slower
    np.testing.assert_allclose(speeds[:, 0], np.asarray(hc.mean_speeds(model, one, theta, key)), rtol=1e-5)
    each = ((speeds - three.speed_data[:, None]) / three.sd_data[:, None]) ** 2
    assert float(hc.fd_loss(model, three, theta, key)) == pytest.approx(float(each.mean()), rel=1e-5)
    np.testing.assert_allclose(np.asarray(hc.mean_speeds(model, three, theta, key)), speeds.mean(axis=1), rtol=1e-6)


def test_the_eth_ucy_fits_summary_counts_the_scenes_ahead_and_clearly_ahead_of_constant_velocity():
    """A hand-made leave-one-scene-out record of two scenes: the fit is ahead on both errors at a
    (clearly: both intervals below 0) and behind on the FDE at b; the start is ahead nowhere."""
    from socialnav.evaluation.humans import report

    rows = [
        {"scene": "a", "constant_velocity": (0.5, 1.0), "start": (0.6, 1.2), "nelder_mead": (0.4, 0.9)},
        {"scene": "b", "constant_velocity": (0.3, 0.6), "start": (0.3, 0.6), "nelder_mead": (0.2, 0.7)},
    ]
    by_scene = {"a": {"ade_m": [-0.1, -0.15, -0.05], "fde_m": [-0.1, -0.2, -0.01]},
                "b": {"ade_m": [-0.1, -0.2, -0.02], "fde_m": [0.1, 0.05, 0.2]}}  # fmt: skip
    average = {"nelder_mead": {"ade_m": [-0.1, -0.14, -0.06], "fde_m": [0.0, -0.05, 0.05], "by_scene": by_scene}}
    lines = report.trajectory_fit_lines({"scenes": rows, "average_vs_cv": average})
    assert lines[0] == "constant velocity: test ADE/FDE 0.400 / 0.800 m over 2 held-out scenes"
    assert lines[1] == "as given: test ADE/FDE 0.450 / 0.900 m over 2 held-out scenes, ahead of constant velocity in 0"
    assert lines[2].startswith("Nelder-Mead: test ADE/FDE 0.300 / 0.800 m over 2 held-out scenes, ahead of constant "
                               "velocity in 1; the average minus constant velocity's, 95 % interval: ADE -0.100 "
                               "[-0.140, -0.060], FDE +0.000 [-0.050, +0.050] m")  # fmt: skip
    assert lines[2].endswith("clearly ahead (both intervals below 0) in 1 scenes") and len(lines) == 3


def test_a_fit_json_is_read_back_as_its_models_and_a_bad_one_is_refused_naming_the_field(tmp_path):
    from socialnav import cli
    from socialnav.evaluation.humans import calibration as hc

    values = {"time_gap_s": 0.8, "neighbor_strength": 8.5, "neighbor_range_m": 0.12, "radius_m": 0.18,
              "steering_max_rad": 1.5}  # fmt: skip
    fit = {"model": "steering_speed", "gradient": {"values": {**values, "radius_m": 0.19}},
           "nelder_mead": {"values": values}}  # fmt: skip
    path = tmp_path / "run-a" / "fit.json"
    path.parent.mkdir()
    path.write_text(json.dumps(fit))
    models = hc.fitted_models(path)
    assert list(models) == ["run-a:gradient", "run-a:nelder_mead"]
    assert hc.fitted_values(models["run-a:nelder_mead"]) == values
    assert float(models["run-a:gradient"].radius_m) == pytest.approx(0.19)
    assert models["run-a:nelder_mead"].name == "steering_speed"
    assert list(hc.fitted_models(path, ("nelder_mead",))) == ["run-a:nelder_mead"]
    bad = {
        "not json": ("{", "not a readable fit.json"),
        "eth_ucy": (json.dumps({**fit, "data": "eth_ucy"}), "data:"),
        "model": (json.dumps({**fit, "model": "ghosts"}), "model:"),
        "missing": (json.dumps({"model": "steering_speed"}), "gradient.values: missing"),
        "fields": (json.dumps({**fit, "gradient": {"values": {"time_gap_s": 1.0}}}), "gradient.values: expected"),
        "negative": (json.dumps({**fit, "nelder_mead": {"values": {**values, "radius_m": -0.2}}}),
                     "nelder_mead.values.radius_m"),
        "true": (json.dumps({**fit, "gradient": {"values": {**values, "time_gap_s": True}}}),  # was read as 1 s
                 "gradient.values.time_gap_s: True is not a positive number"),
    }  # fmt: skip
    for name, (text, field) in bad.items():
        wrong = tmp_path / name / "fit.json"
        wrong.parent.mkdir()
        wrong.write_text(text)
        with pytest.raises(ValueError, match=re.escape(field)) as e:
            hc.fitted_models(wrong)
        assert str(wrong) in str(e.value)
    out = tmp_path / "report"
    assert cli.main(["humans", "validate", "--fit", str(tmp_path / "fields" / "fit.json"), "--out", str(out)]) == 2
    assert cli.main(["humans", "validate", "--fit", str(path), "--fit", str(path), "--out", str(out)]) == 2
    assert not out.exists()


@pytest.mark.slow
def test_calibration_recovers_a_known_time_gap_by_gradient_and_by_search(tmp_path):
    """Known answer: the fundamental diagram of the speed model with a time gap of 0.6 s, fitted
    from 1.0 s by gradient through the crowd step and by Nelder-Mead, gives back 0.6 s; the fit's
    record (``calibrate``'s, the command's fit.json) reads back as the two fitted models."""
    from socialnav.evaluation.humans import calibration as hc

    truth = hv.HumanModel("collision_free_speed", speed=speed_model.SpeedModelParams(time_gap_s=0.6))
    fields = ("time_gap_s",)
    corridors = _walked_by(truth, fields)
    assert np.all(np.diff(corridors.speed_data) < 0)  # speed falls with density
    start = hv.HumanModel("collision_free_speed")
    saved = []  # the records a stopped fit would have left, in order
    fit, histories = hc.calibrate(start, corridors, 60, 0.05, 40, log=lambda *_: None, fields=fields,
                                  progress=saved.append)  # fmt: skip
    history = histories["gradient"]
    assert history[-1][1] < 0.05 * history[0][1] and fit["start"]["loss"] == pytest.approx(history[0][1], rel=1e-5)
    assert fit["nelder_mead"]["evaluations"] == len(histories["nelder_mead"]) <= 40 and fit["start_draws"] == 0
    assert fit["gradient"]["loss"] == min(h[1] for h in history) and fit["densities"] == [1.5, 2.5, 3.5]
    path = tmp_path / "known-gap" / "fit.json"
    path.parent.mkdir()
    path.write_text(json.dumps(fit))
    for label, model in hc.fitted_models(path).items():
        assert float(model.speed.time_gap_s) == pytest.approx(0.6, rel=0.05), label
        assert float(model.speed.neighbor_strength) == pytest.approx(float(start.speed.neighbor_strength), rel=1e-4)
    # As it went: each method's best so far, its loss falling; the last record is the fit's points.
    assert fit["complete"] and not any(r["complete"] for r in saved)
    for method in hc.FIT_METHODS:
        losses = [r[method]["loss"] for r in saved if method in r]
        assert losses and all(b <= a for a, b in zip(losses, losses[1:], strict=False))
        assert saved[-1][method]["values"] == fit[method]["values"] and losses[-1] == fit[method]["loss"]
    early = tmp_path / "stopped" / "progress.json"  # stopped during the gradient's descent
    early.parent.mkdir()
    early.write_text(json.dumps(saved[0]))
    assert list(hc.fitted_models(early)) == ["stopped:gradient"]
    with pytest.raises(ValueError, match="no point yet of nelder_mead"):
        hc.fitted_models(early, ("nelder_mead",))


@pytest.mark.slow
def test_a_calibration_killed_mid_fit_leaves_its_best_points_and_the_next_one_says_so(tmp_path):
    """``humans calibrate`` killed during its descent: progress.json holds the best point so far,
    which validate reads as a model; the next calibration into the folder is refused with one line
    that names the file, and with --overwrite it ends with fit.json alone (progress.json gone)."""
    import subprocess
    import sys
    import time

    from socialnav import cli
    from socialnav.common import runfolder
    from socialnav.evaluation.humans import calibration as hc

    out = tmp_path / "cal"
    argv = ["humans", "calibrate", "--model", "collision_free_speed", "--evaluations", "2", "--out", str(out)]
    run = subprocess.Popen([sys.executable, "-m", "socialnav", *argv, "--steps", "500"], stdout=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 240
        while not (out / "progress.json").exists() and run.poll() is None and time.monotonic() < deadline:
            time.sleep(0.5)
    finally:
        run.kill()
        run.wait()
    record = json.loads((out / "progress.json").read_text())
    assert not record["complete"] and "nelder_mead" not in record and record["gradient"]["steps"] >= 1
    (label, model), *_ = hc.fitted_models(out / "progress.json").items()
    assert label == "cal:gradient" and hc.fitted_values(model) == record["gradient"]["values"]
    assert cli.main([*argv, "--steps", "2"]) == 2
    assert cli.main([*argv, "--steps", "2", "--overwrite"]) == 0
    assert not (out / "progress.json").exists() and json.loads((out / "fit.json").read_text())["complete"]
    assert sorted(runfolder.read_manifest(out).files) == ["curve.png", "fit.json"]


@pytest.mark.slow
def test_orcas_parameters_are_fitted_by_a_forward_gradient_through_its_fallback_loop():
    """ORCA's step holds a ``while_loop`` (its third program only for those who need it), which
    reverse mode cannot run through: its gradient is taken forward. From CrowdNav's 0.3 m radius,
    against corridors walked with 0.2 m, the fit lowers the loss to under a tenth."""
    from socialnav.evaluation.humans import calibration as hc
    from socialnav.jaxsim import orca

    fields = ("radius_m",)
    corridors = _walked_by(hv.HumanModel("orca", orca=orca.ORCAParams(radius_m=0.2)), fields)
    start = hv.HumanModel("orca", orca=orca.ORCAParams(radius_m=0.3))
    fitted, history = hc.fit_gradient(start, corridors, 12, 0.05, log=lambda *_: None, fields=fields)
    assert np.isfinite(history[0][1]) and min(h[1] for h in history) < 0.1 * history[0][1]
    assert float(fitted.orca.radius_m) < 0.25


@pytest.mark.slow
@pytest.mark.parametrize(
    "name", ["collision_free_speed", "anticipation", "collision_free_speed_calibrated", "power_law"]
)
def test_a_velocity_model_moves_the_arenas_people_around_a_standing_robot(name):
    """``--human-model``: the arena's env steps its people by the velocity model (or the power
    law); the walker passes the robot without entering its body (a disc of the robot's radius to
    them)."""
    from socialnav.data import SCENES_DIR
    from socialnav.evaluation.arena import episodes as arena
    from socialnav.jaxsim.scenes import env as env_lib
    from socialnav.jaxsim.scenes.spec import load_scene
    from socialnav.jaxsim.scenes.variant import sample_variant

    spec = load_scene(SCENES_DIR / "snape_walking.json")
    setup = arena.setup_scene(spec)
    env = env_lib.make_env(spec, env_lib.EnvConfig(human_model=name, max_steps=300))
    assert (env.velocity is None) == (name == "power_law")  # the power law's constants go by its name
    variant = jax.tree.map(jnp.asarray, sample_variant(spec, 0, 0, n_slots=setup.n_slots))
    state, _ = jax.jit(env.reset)(jax.random.key(0), variant)
    step = jax.jit(env.step)
    start = np.asarray(state.people.xy)
    nearest = np.inf
    for _ in range(200):
        state, ts = step(state, jnp.zeros(2))
        nearest = min(nearest, float(ts.info.nearest_person_m))
    moved = np.linalg.norm(np.asarray(state.people.xy) - start, axis=-1)[np.asarray(variant.valid)]
    assert moved.max() > 2.0 and np.isfinite(np.asarray(state.people.xy)).all()
    radius = float(power_law.params_of(name).radius_m if env.velocity is None else env.velocity.radius_m)
    # nearest_person_m is measured with the arena's 0.25 m bodies; the model's own are smaller
    assert nearest > -(0.25 - radius) - 1e-3, nearest
