"""Human models against a user's own recording: the prediction test of ETH/UCY (8 samples
observed, 12 predicted, every person aimed along their last observed velocity or at their true
final position; ADE and FDE against constant velocity, with 95 % intervals) on a tracks file
(``socialnav humans predict``).

The file is the toolkit's tracks file (:mod:`socialnav.data.track_file`), checked as the arena's
recorded crowds check it (:func:`jaxsim.scenes.recording.file_rows`). It is read at the protocol's
sample interval, :data:`SAMPLE_S` by default (ETH/UCY's 2.5 Hz): every k-th frame of the file's
frame step, k the whole number nearest to ``sample_s`` over that step (a file sampled more
coarsely keeps its own step, as ``biwi_eth``'s 2/3 s is kept). Without a map of its walls the
models walk in open space, as on ETH/UCY; with one (a ROS map, :func:`recording_walls`) they
walk between its walls, as the arena's scenes of the file do.
"""

from __future__ import annotations

import pathlib
import time

import pandas as pd

from socialnav.common import memory
from socialnav.evaluation.humans import report, validation
from socialnav.evaluation.humans.shipped_windows import every_sample
from socialnav.jaxsim.scenes import recording

SAMPLE_S = 0.4  # the protocol's sample interval: ETH/UCY's 2.5 Hz
AIMS = ("velocity", "destination")
# Bytes a window holds per person present: the observed and future positions (20 samples of 2
# float64), the constant-velocity prediction (12 of 2 float64) and a model's (12 of 2 float32).
WINDOW_BYTES_PER_PERSON = (20 + 12) * 2 * 8 + 12 * 2 * 4


def recording_rows(file: str | pathlib.Path, frames_per_s: float, sample_s: float = SAMPLE_S) -> pd.DataFrame:
    """The tracks file's rows as :func:`socialnav.data.recorded.trajectories` gives a shipped
    run's (``run`` the file's name, ``person, frame, t_s, x_m, y_m``), read every ``sample_s``
    seconds as the module's docstring says. Raises
    :class:`~socialnav.data.track_file.TrackFileError` (naming the file) for a bad file."""
    file = pathlib.Path(file)
    rows = every_sample(recording.file_rows(file, frames_per_s), frames_per_s, sample_s)
    return pd.DataFrame({"run": file.name, **{c: rows[c].to_numpy() for c in ("person", "frame", "t_s", "x_m", "y_m")}})


def windows_needed_bytes(rows: pd.DataFrame) -> float:
    """About the memory the prediction windows of ``rows`` hold at once: one window a sample,
    each as wide as the most people present at one sample."""
    per_frame = rows.groupby("frame").size()
    return float(len(per_frame) * per_frame.max() * WINDOW_BYTES_PER_PERSON)


# How far past the people the wall field of a map reaches (m): a prediction 12 samples ahead stays
# inside it (an 8 m/s step from the outermost person in 0.4 s samples reaches 38 m, no walker).
WALLS_MARGIN_M = 5.0


def recording_walls(tracks_file, map_file, rows: pd.DataFrame, resolution_m: float = 0.05, min_wall_m2: float = 0.0):
    """``(walls, notes)``: the wall field of ROS map ``map_file`` (:func:`validation.walls_field`;
    None where the map has no wall near the people) over the people of ``rows`` and
    :data:`WALLS_MARGIN_M` around them (its pieces under ``min_wall_m2`` left out:
    :func:`planners.learning.tracks.without_specks`), and the lines to print (how many wall boxes, the share of
    positions inside a wall). Raises :class:`~socialnav.data.track_file.TrackFileError` where
    under 80 % of the positions lie on the map (another frame or other units) and
    :class:`~socialnav.planners.learning.ros_map.MapFileError` for a map that cannot be read."""
    from socialnav.planners.learning.tracks import map_walls

    lo, hi = rows[["x_m", "y_m"]].min().to_numpy(), rows[["x_m", "y_m"]].max().to_numpy()
    bounds = (lo[0] - WALLS_MARGIN_M, hi[0] + WALLS_MARGIN_M, lo[1] - WALLS_MARGIN_M, hi[1] + WALLS_MARGIN_M)
    boxes, in_walls = map_walls(tracks_file, map_file, rows, bounds, min_wall_m2)
    notes = [f"{map_file}: {len(boxes)} wall boxes within {WALLS_MARGIN_M:g} m of the people"]
    if in_walls:
        notes.append(f"{map_file}: {100 * in_walls:.1f} % of the recorded positions lie in its walls (people the "
                     "map does not know of: their predictions start inside a wall)")  # fmt: skip
    return validation.walls_field(boxes, bounds, resolution_m), notes


def recording_windows(rows: pd.DataFrame, walls=None) -> validation.PredictionWindows:
    """The prediction windows of ``rows`` (:func:`validation.windows_of`), walked between
    ``walls`` (:func:`recording_walls`; None: open ground). Raises ``ValueError``
    where nobody is seen in 20 consecutive samples (nothing to score) or the windows would not fit
    in memory."""
    span = validation.PREDICT_OBSERVED + validation.PREDICT_FRAMES
    needed = windows_needed_bytes(rows)
    available = memory.shortfall(needed)
    if available is not None:
        raise ValueError(
            f"its prediction windows hold about {needed / 1e9:.1f} GB at once, this machine has "
            f"{available / 1e9:.1f} GB available: predict a part of the recording at a time"
        )
    seen = rows.groupby("person")["frame"].nunique()
    if seen.max() < span:
        raise ValueError(
            f"nobody is seen in {span} samples ({validation.PREDICT_OBSERVED} observed, "
            f"{validation.PREDICT_FRAMES} predicted); the longest track has {seen.max()}: nothing to score"
        )
    try:
        return validation.windows_of(rows).replace(walls=walls)
    except ValueError as e:  # every track long enough, none in consecutive samples
        raise ValueError(f"nobody is seen in {span} consecutive samples: nothing to score ({e})") from None


def predict(models: dict, windows: validation.PredictionWindows, seed: int = 0, say=lambda what: None) -> pd.DataFrame:
    """One row per predictor and aim: constant velocity, then each of ``models`` (label ->
    :class:`validation.HumanModel`) aimed along the velocity and at the destination, with
    :func:`validation.prediction_scores`' columns (``ade_m``, ``fde_m``, ``samples``, ``grouped``,
    and for a model its difference from constant velocity with a 95 % interval)."""
    rows = [{"model": "constant_velocity", "aim": "velocity", **validation.prediction_scores(None, windows)}]
    for label, model in models.items():
        for aim in AIMS:
            say(f"{label}, aimed {'along the velocity' if aim == 'velocity' else 'at the destination'}")
            rows.append({"model": label, "aim": aim, **validation.prediction_scores(model, windows, aim, seed)})
    return pd.DataFrame(rows)


def headline(table: pd.DataFrame) -> list[str]:
    """One line per predictor: ADE / FDE and, for a model, how far from constant velocity."""
    lines = []
    for r in table.itertuples():
        line = f"{r.model:>34} {r.aim:>11}: ADE {r.ade_m:.3f} m, FDE {r.fde_m:.3f} m"
        if r.model != "constant_velocity":
            ade = report.interval((r.ade_vs_cv_m, r.ade_vs_cv_low_m, r.ade_vs_cv_high_m))
            fde = report.interval((r.fde_vs_cv_m, r.fde_vs_cv_low_m, r.fde_vs_cv_high_m))
            line += f"; minus constant velocity's: ADE {ade}, FDE {fde}"
        lines.append(line)
    return lines


TRAIN_SHARE = 2 / 3  # a calibration fits on the recording's first two thirds and scores on the rest


def split_rows(rows: pd.DataFrame, train_share: float = TRAIN_SHARE) -> tuple[pd.DataFrame, pd.DataFrame]:
    """``rows`` cut in time: the frames of the first ``train_share`` of the recording's span (the
    fit's) and the rest (its test), so that no window of one shares a sample with the other."""
    frames = rows["frame"].to_numpy()
    cut = frames.min() + train_share * (frames.max() - frames.min())
    return rows[frames < cut], rows[frames >= cut]


def split_windows(rows: pd.DataFrame, walls=None) -> tuple[validation.PredictionWindows, validation.PredictionWindows]:
    """The prediction windows of :func:`split_rows`' two parts, the fit's and the test's, walked
    between ``walls`` (None: open ground); raises ``ValueError`` naming the part where one has
    nothing to score."""
    windows = []
    for part, label in zip(
        split_rows(rows), ("its first two thirds (the fit's)", "its last third (the test)"), strict=True
    ):
        try:
            windows.append(recording_windows(part, walls))
        except ValueError as e:
            raise ValueError(f"{label}: {e}") from None
    return windows[0], windows[1]


def calibrate(model: validation.HumanModel, train: validation.PredictionWindows, test: validation.PredictionWindows,
              name: str, scene: str, steps: int = 60, learning_rate: float = 0.2, evaluations: int = 60,
              sample: int = 256, seed: int = 0, log=print) -> dict:  # fmt: skip
    """``model``'s prediction parameters (the ETH/UCY fit's fields,
    :data:`evaluation.humans.trajectory_calibration.FITTED`) fitted to a user's recording by
    gradient through the crowd step and by Nelder-Mead (:func:`~evaluation.humans.trajectory_calibration.fit_and_score`)
    on ``sample`` windows of its first two thirds (``train``), scored on the last third (``test``),
    which the fit never reads (:func:`split_windows`). Returns the record ``socialnav humans
    calibrate --data tracks`` writes as ``fit.json``: the model (``name``), the fields, their values
    at the start, one row (``"scenes"``, its ``"scene"`` the file's name, ``scene``) and ``"vs_cv"``,
    each method's test ADE and FDE minus constant velocity's with a 95 % interval (the block
    bootstrap)."""
    from socialnav.evaluation.humans import trajectory_calibration as tc

    t0 = time.perf_counter()
    fields = tc.FITTED[model.name]
    row = tc.fit_and_score(model, fields, train, test, steps, learning_rate, evaluations, sample, seed, log,
                           intervals=True)  # fmt: skip
    vs_cv = row.pop("vs_cv")
    return {"model": name, "data": "tracks", "fields": list(fields), "start": tc.values_of(model, fields),
            "scenes": [{"scene": scene, "test_windows": len(test.start), **row}], "vs_cv": vs_cv, "seed": seed,
            "seconds": round(time.perf_counter() - t0, 1), "complete": True}  # fmt: skip


def calibration_lines(fit: dict) -> list[str]:
    """A recording's fit in a line a method: its test ADE/FDE and, for the model, its difference
    from constant velocity with the 95 % interval."""
    row = fit["scenes"][0]
    lines = [f"constant velocity: test ADE/FDE {row['constant_velocity'][0]:.3f} / {row['constant_velocity'][1]:.3f} m "
             f"({row['test_windows']} windows of the last third)"]  # fmt: skip
    for key, label in (("start", "as given"), ("gradient", "fitted by gradient"), ("nelder_mead", "Nelder-Mead")):
        if key in row:
            d = fit["vs_cv"][key]
            lines.append(f"{label}: test ADE/FDE {row[key][0]:.3f} / {row[key][1]:.3f} m; minus constant velocity's: "
                         f"ADE {report.interval(d['ade_m'])}, FDE {report.interval(d['fde_m'])}")  # fmt: skip
    return lines
