"""Recorded people in a scene: a shipped recording resampled in time, a window of it per variant,
its people dealt to a fixed number of slots.

A scene with a ``recording`` (:mod:`jaxsim.scenes.spec`) replays a run of
:mod:`socialnav.data.recorded` (the ETH/UCY scenes, the Jülich corridors). The run is resampled
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

import numpy as np

from socialnav.jaxsim.scenes.perception import WINDOW

RECORD_DT_S = 0.1  # the resampled recording's step: the env's default step
# Empty samples between two people in one slot: at least the perception's track window, and at
# least a reactive person's look-ahead (:data:`LOOKAHEAD_SAMPLES`), so that neither ever reaches
# from one person to the next.
SLOT_GAP_SAMPLES = max(WINDOW, 10)
LOOKAHEAD_SAMPLES = 10  # a reactive person heads for where they are recorded 1 s ahead


@dataclasses.dataclass(frozen=True)
class Recording:
    """A run resampled at :data:`RECORD_DT_S` (sample ``k`` at ``k * RECORD_DT_S`` after the run's
    first sample).

    Attributes:
      run: the run's name (:func:`socialnav.data.recorded.run_names`).
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
    """The run ``run`` resampled (cached; ``KeyError`` naming an unknown run). A person seen in
    one sample only (no time between two samples to resample) is left out."""
    from socialnav.data import recorded

    rows = recorded.trajectories(run)
    t0 = float(rows["t_s"].min())
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
