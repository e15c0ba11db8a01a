"""Recorded people in a scene: a recording resampled in time, a window of it per variant, its
people dealt to a fixed number of slots.

A scene with a ``recording`` (:mod:`jaxsim.scenes.spec`) replays a run of
:mod:`socialnav.data.recorded` (the ETH/UCY scenes, the Jülich corridors) or a user's own file of
``frame, id, x, y`` rows, the toolkit's tracks file (:func:`load_recording_file`). The run is resampled
once at :data:`RECORD_DT_S` by linear interpolation between its own samples (ETH/UCY's 2.5 Hz,
``biwi_eth``'s 1.5 Hz, the Jülich runs' 16 and 25 fps); a variant is a window of ``timeout_s``
seconds of it, drawn from ``window_within_s`` (held out: from the rest of the run, so a held-out
window shares no recorded second with an evaluated one, :func:`draw_window_start`).

People come and go; the arrays an episode runs on have a fixed number of slots. A slot holds one
person after another, each from their first to their last sample, with at least
:data:`SLOT_GAP_SAMPLES` empty samples between two (the perception's track window then forgets
the first before the second appears: no velocity is estimated across two people). Dealing people
to the free slot with the lowest index in order of their first sample uses exactly as many slots
as the most people (gaps included) present at once, so the run's peak bounds every window
(:func:`slots_needed`).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import pathlib

import numpy as np

from socialnav.jaxsim.scenes.perception import WINDOW

RECORD_DT_S = 0.1  # the resampled recording's step: the env's default step
# Empty samples between two people in one slot: at least the perception's track window, and at
# least a reactive person's look-ahead (:data:`LOOKAHEAD_SAMPLES`), so that neither ever reaches
# from one person to the next.
SLOT_GAP_SAMPLES = max(WINDOW, 10)
LOOKAHEAD_SAMPLES = 10  # a reactive person heads for where they are recorded 1 s ahead
# The fastest a person of a user's recording may move between two of their frames (m/s): a
# sprinter's top speed. The shipped runs' fastest is 5.6 m/s (a tracking jump in
# ``bi_corr_400_b_03``); a file in centimetres or millimetres, or a frame rate several times too
# high, moves people faster.
MAX_SPEED_MPS = 12.0
# The most person-samples a resampled recording may hold (8 bytes each): 160 MB, 55 hours of 100
# people at once. The shipped runs hold at most 0.5 M; a file whose times are in milliseconds
# instead of seconds holds a thousand times its real length.
MAX_RECORDING_SAMPLES = 20_000_000


@dataclasses.dataclass(frozen=True)
class Recording:
    """A run resampled at :data:`RECORD_DT_S` (sample ``k`` at ``k * RECORD_DT_S`` after the run's
    first sample).

    Attributes:
      run: the run's name (:func:`socialnav.data.recorded.run_names`), or a user's file's name.
      first: (N,) int64 each person's first sample; last: (N,) int64 their last (inclusive).
      xy: (S, 2) float32 every person's samples one after another; offset: (N,) int64 where each
        person's begin in ``xy`` (person ``i`` at sample ``k`` is ``xy[offset[i] + k - first[i]]``).
      n_samples: the run's length in samples.
    """

    run: str
    first: np.ndarray
    last: np.ndarray
    xy: np.ndarray
    offset: np.ndarray
    n_samples: int

    @property
    def duration_s(self) -> float:
        return (self.n_samples - 1) * RECORD_DT_S


@functools.lru_cache(maxsize=16)
def load_recording(run: str) -> Recording:
    """The shipped run ``run`` resampled (cached; ``KeyError`` naming an unknown run). A person
    seen in one sample only (no time between two samples to resample) is left out."""
    from socialnav.data import recorded

    return resample(run, recorded.trajectories(run))


def load_recording_file(file: str | pathlib.Path, frames_per_s: float) -> Recording:
    """A user's tracks file (:func:`socialnav.data.track_file.read_tracks`: ``frame, id, x, y``
    rows in a CSV or Parquet file, positions in metres) whose frame numbers advance
    ``frames_per_s`` a second, resampled and named by the file's name; cached while the file's
    path, size and modification time are unchanged.

    Raises :class:`~socialnav.data.track_file.TrackFileError` naming the file for a file that
    cannot be read, a person who moves faster than :data:`MAX_SPEED_MPS` between two of their
    frames (positions not in metres, or the wrong frame rate), nobody seen for
    :data:`RECORD_DT_S` or more, or a recording too long to hold."""
    file = pathlib.Path(file).resolve()
    stat = file.stat() if file.is_file() else None
    return _load_file(file, float(frames_per_s), None if stat is None else (stat.st_size, stat.st_mtime_ns))


@functools.lru_cache(maxsize=16)
def _load_file(file: pathlib.Path, frames_per_s: float, version: tuple[int, int] | None) -> Recording:
    from socialnav.data.track_file import TrackFileError

    rows = file_rows(file, frames_per_s)
    try:
        return resample(file.name, rows)
    except ValueError as e:
        raise TrackFileError(f"{file} at {frames_per_s:g} frames a second: {e}") from None


def file_rows(file: str | pathlib.Path, frames_per_s: float):
    """A user's tracks file as ``person, frame, t_s, x_m, y_m`` rows (a pandas DataFrame;
    ``person`` numbers the file's ids in their sorted order, ``t_s`` is the frame over
    ``frames_per_s``), checked as :func:`load_recording_file` says."""
    import pandas as pd

    from socialnav.data.track_file import TrackFileError, read_tracks

    if not (math.isfinite(frames_per_s) and frames_per_s > 0):
        raise ValueError(f"frames_per_s must be a positive number, got {frames_per_s!r}")
    tracks = read_tracks(file)
    for person, track in tracks.items():
        step_m = np.hypot(np.diff(track[:, 1]), np.diff(track[:, 2]))
        speed = step_m * frames_per_s / np.maximum(np.diff(track[:, 0]), 1)
        if len(speed) and speed.max() > MAX_SPEED_MPS:
            k = int(np.argmax(speed))
            raise TrackFileError(
                f"{file}: person {person} moves {speed[k]:.3g} m/s between frames {track[k, 0]:.0f} and "
                f"{track[k + 1, 0]:.0f} at {frames_per_s:g} frames a second (at most {MAX_SPEED_MPS:g}): x and y "
                "must be in metres and frames_per_s the rate of the frame numbers"
            )
    return pd.concat(
        [
            pd.DataFrame(
                {
                    "person": i,
                    "frame": t[:, 0].astype(np.int64),
                    "t_s": t[:, 0] / frames_per_s,
                    "x_m": t[:, 1],
                    "y_m": t[:, 2],
                }  # fmt: skip
            )
            for i, t in enumerate(tracks.values())
        ],
        ignore_index=True,
    )


def load(recording: dict) -> Recording:
    """The recording of a scene's ``recording`` block (:func:`jaxsim.scenes.spec.load_scene`'s):
    the user's ``file`` at its ``frames_per_s`` if it names one, else the shipped ``run``."""
    file = recording.get("file")
    return load_recording(recording["run"]) if file is None else load_recording_file(file, recording["frames_per_s"])


def resample(run: str, rows) -> Recording:
    """``rows`` (``person, t_s, x_m, y_m``) resampled at :data:`RECORD_DT_S` from their first
    time on, by linear interpolation between each person's samples; a person seen in one sample
    only (no time between two samples to resample) is left out. Raises ``ValueError`` (not naming
    the run) where nothing is left, or the recording is too long to hold."""
    t0 = float(rows["t_s"].min())
    spans = rows.groupby("person", sort=False)["t_s"].agg(["min", "max"])
    total = float(((spans["max"] - spans["min"]) / RECORD_DT_S + 1).sum())
    if total > MAX_RECORDING_SAMPLES:
        raise ValueError(
            f"its people span {total * RECORD_DT_S / 3600:,.1f} person-hours, more than "
            f"{MAX_RECORDING_SAMPLES * RECORD_DT_S / 3600:,.1f}: are the times in seconds?"
        )
    first, last, pieces, offset, at = [], [], [], [], 0
    for _, person in rows.groupby("person", sort=True):
        t = person["t_s"].to_numpy() - t0
        k0, k1 = math.ceil(t[0] / RECORD_DT_S - 1e-6), math.floor(t[-1] / RECORD_DT_S + 1e-6)
        if k1 <= k0:
            continue
        grid = np.arange(k0, k1 + 1) * RECORD_DT_S
        xy = np.stack([np.interp(grid, t, person["x_m"].to_numpy()), np.interp(grid, t, person["y_m"].to_numpy())], 1)
        first.append(k0), last.append(k1), pieces.append(xy.astype(np.float32)), offset.append(at)
        at += len(grid)
    if not first:
        raise ValueError(f"nobody is seen for {RECORD_DT_S:g} s or more: nothing to play back")
    first_a, last_a = np.array(first, np.int64), np.array(last, np.int64)
    order = np.argsort(first_a, kind="stable")  # people in order of appearance: the dealing order
    return Recording(
        run=run,
        first=first_a[order],
        last=last_a[order],
        xy=np.concatenate(pieces),
        offset=np.array(offset, np.int64)[order],
        n_samples=int(last_a.max()) + 1,
    )


def slots_needed(recording: Recording) -> int:
    """The most people present at once, each person's presence lengthened by
    :data:`SLOT_GAP_SAMPLES`: the slots that hold any window of the run."""
    change = np.zeros(recording.n_samples + SLOT_GAP_SAMPLES + 2, np.int64)
    np.add.at(change, recording.first, 1)
    np.add.at(change, recording.last + SLOT_GAP_SAMPLES + 1, -1)
    return int(np.cumsum(change).max())


def window_starts_s(within_s: tuple[float, float], duration_s: float, run_s: float, held_out: bool):
    """The intervals of window start times (s) a variant draws from: windows of ``duration_s``
    inside ``within_s`` or (``held_out``) wholly outside it within the run's ``run_s``."""
    lo, hi = within_s
    if not held_out:
        return [(lo, hi - duration_s)] if hi - lo >= duration_s else []
    return [(a, b) for a, b in ((0.0, lo - duration_s), (hi, run_s - duration_s)) if b >= a]


def draw_window_start(rng: np.random.Generator, intervals) -> int:
    """A window's first sample, uniform over ``intervals`` (s) of start times (by length)."""
    lengths = np.array([b - a for a, b in intervals], float)
    pick = int(rng.choice(len(intervals), p=lengths / lengths.sum())) if lengths.sum() > 0 else 0
    a, b = intervals[pick]
    return int(round(rng.uniform(a, b) / RECORD_DT_S)) if b > a else int(round(a / RECORD_DT_S))


def window(
    recording: Recording, start: int, n_samples: int, n_slots: int, mirror_y_m: float | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Samples ``start .. start + n_samples - 1`` of the run dealt to ``n_slots`` slots:
    ``(xy (n_slots, n_samples, 2) float32, present (n_slots, n_samples) bool)``; a slot's
    position where it is empty is its last person's last one (or their first, before them).
    ``mirror_y_m``: ``y -> mirror_y_m - y`` (a mirrored scene's recording). Raises ``ValueError``
    if the window needs more slots than ``n_slots`` (never for ``slots_needed``)."""
    end = start + n_samples - 1
    xy = np.zeros((n_slots, n_samples, 2), np.float32)
    present = np.zeros((n_slots, n_samples), bool)
    free_from = np.full(n_slots, -(10**9), np.int64)  # the first sample a slot can take someone
    started = np.zeros(n_slots, bool)
    inside = np.flatnonzero((recording.first <= end) & (recording.last >= start))
    for i in inside:  # in order of appearance
        a, b = max(int(recording.first[i]), start), min(int(recording.last[i]), end)
        open_slots = np.flatnonzero(free_from <= a)
        if len(open_slots) == 0:
            raise ValueError(
                f"recording {recording.run}: the window from sample {start} needs more than {n_slots} slots"
            )
        s = int(open_slots[0])
        lo = recording.offset[i] + a - recording.first[i]
        track = recording.xy[lo : lo + (b - a + 1)]
        ia, ib = a - start, b - start
        if not started[s]:
            xy[s, :ia] = track[0]  # before its first person the slot waits where they appear
        xy[s, ia : ib + 1] = track
        xy[s, ib + 1 :] = track[-1]
        present[s, ia : ib + 1] = True
        free_from[s], started[s] = b + 1 + SLOT_GAP_SAMPLES, True
    if mirror_y_m is not None:
        xy[..., 1] = mirror_y_m - xy[..., 1]
    return xy, present


def empty_tracks(n_slots: int) -> tuple[np.ndarray, np.ndarray]:
    """The tracks of a scene without a recording: one empty sample per slot."""
    return np.zeros((n_slots, 1, 2), np.float32), np.zeros((n_slots, 1), bool)


def samples_per_episode(timeout_s: float) -> int:
    """Samples a window holds: the episode's time and a margin (the arena rounds an episode up to
    whole replanning periods; the step's reference looks one sample ahead)."""
    return int(math.ceil(timeout_s / RECORD_DT_S)) + 12
