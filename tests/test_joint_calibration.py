"""One human-model fit to both kinds of data (:mod:`evaluation.humans.joint_calibration`): what it reads,
its prediction term on a known answer, the fit's plumbing and the command's bad input."""

from __future__ import annotations

import dataclasses

import jax
import numpy as np
import pytest

from socialnav.data import recorded
from socialnav.evaluation.humans import calibration as hc
from socialnav.evaluation.humans import joint_calibration as jc
from socialnav.evaluation.humans import validation as hv


def test_the_eth_ucy_windows_come_from_no_test_split_and_stop_at_each_files_validation_cut():
    assert set(jc.TRAIN_RECORDINGS) == {"uni_examples", "crowds_zara03"}
    tested = {run for scene in recorded.ETH_UCY_SCENES for run in recorded.eth_ucy_split(scene, "test")["run"]}
    assert not tested & set(jc.TRAIN_RECORDINGS)
    cut = jc.training_windows()
    whole = hv.windows_of(recorded.trajectories(list(jc.TRAIN_RECORDINGS)))
    assert 0 < len(cut.start) < len(whole.start)
    assert set(np.round(cut.frame_s, 6)) == {0.4}


def _tiny(model: hv.HumanModel, windows: int = 48) -> jc.JointData:
    """Short corridors at three training densities and the first ``windows`` training windows."""
    size = dict(length_m=6.0, warmup_steps=60, measured_steps=20)
    data = jc.joint_data(model, **size)
    corridors = data.corridors
    keep = [0, len(corridors.densities) // 2, len(corridors.densities) - 1]
    corridors = dataclasses.replace(
        corridors,
        densities=tuple(corridors.densities[k] for k in keep),
        speed_data=corridors.speed_data[keep],
        sd_data=corridors.sd_data[keep],
        starts=tuple(corridors.starts[k] for k in keep),
    )
    return dataclasses.replace(data, corridors=corridors, windows=data.windows.take(np.arange(windows)))


def test_a_lone_walker_is_predicted_as_constant_velocity_so_the_model_trails_it_by_nothing():
    """Known answer: with one person in every window nobody interacts, the model walks on at
    the last observed velocity, and its ADE is constant velocity's."""
    model = hc.named_model("steering_speed_calibrated")
    all_windows = jc.training_windows()
    alone = np.flatnonzero(np.asarray(all_windows.present).sum(axis=1) == 1)
    assert len(alone) >= 5
    windows = all_windows.take(alone)
    ade_cv, _ = hv.measures.ade_fde(windows.constant_velocity[windows.complete], windows.future[windows.complete])
    ade = jc.prediction_ade(model, windows, jax.random.key(0))
    assert float(ade) == pytest.approx(float(ade_cv.mean()), rel=5e-4)


@pytest.mark.slow
def test_each_weights_fit_is_at_least_as_good_as_its_start_and_is_the_model_it_returns():
    model = hc.named_model("steering_speed_calibrated")
    data = _tiny(model)
    key = jax.random.key(0)
    rows = jc.sweep(model, data, (0.01, 10.0), evaluations=16, log=lambda *_: None)
    for row in rows:
        start = row["start_fd_loss"] + row["weight"] * row["start_behind_pct"]
        fitted = row["fd_loss"] + row["weight"] * row["behind_pct"]
        assert fitted <= start + 1e-4
        # the returned model is the point the search found: its loss is what the row says
        again = jc.joint_loss(row["model"], data, hc.theta_of(row["model"]), key, row["weight"])
        assert float(again) == pytest.approx(fitted, rel=1e-3, abs=1e-3)
        assert set(row["values"]) == set(hc.FITTED["steering_speed"])


@pytest.mark.parametrize(
    "extra",
    [
        ["--weights", "1"],  # with the Jülich fit
        ["--data", "joint", "--model", "orca"],
        ["--data", "joint", "--scenes", "hotel"],
        ["--data", "joint", "--evaluations", "0"],
        ["--data", "joint", "--steps", "10"],  # Nelder-Mead alone
        ["--data", "eth_ucy", "--start-draws", "2"],  # no corridors there
    ],
)
def test_the_joint_commands_bad_input_is_refused_before_anything_is_written(tmp_path, extra):
    from socialnav import cli

    out = tmp_path / "fit"
    assert cli.main(["humans", "calibrate", "--out", str(out), *extra]) == 2
    assert not (out / "fit.json").exists()


def test_a_weight_that_is_not_a_positive_number_is_refused_by_the_parser(capsys):
    from socialnav import cli

    for text in ("0", "-1", "a", "1,,2", "nan"):
        with pytest.raises(SystemExit):
            cli.main(["humans", "calibrate", "--data", "joint", "--weights", text])
        assert "--weights" in capsys.readouterr().err
