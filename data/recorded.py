"""Real pedestrian trajectories shipped with the package, in one table (``pedestrians/``).

Two datasets (``pedestrians/README.md`` gives the sources, citations and licenses;
``scripts/build_pedestrian_data.py`` rebuilds the files from them):

* ``juelich``: the Jülich corridor experiments (nine uni-directional runs ``uo-*`` in a 1.8 m
  corridor, 16 fps; the bi-directional ``bi_corr_400_b_03`` in a 4.1 m corridor and the
  uni-directional ``uni_corr_500_01`` in a 5 m one, 25 fps) and a bottleneck run, each with its
  geometry (walkable area, measurement area) and, for the ``uo`` runs, the frames of its steady
  state as PedPy's notebooks use them;
* ``eth_ucy``: the five ETH/UCY scenes (eth, hotel, univ, zara1, zara2) in eight files at 2.5 Hz,
  with the leave-one-scene-out splits of the trajectory-prediction literature
  (:func:`eth_ucy_split`).

:func:`trajectories` returns ``run, person, frame, t_s, x_m, y_m`` rows (positions in metres,
float64); :func:`run_info` a run's record. A missing or damaged file is one
:class:`RecordedDataError` naming it.
"""

from __future__ import annotations

import functools
import json
from collections.abc import Sequence

import numpy as np

from socialnav.data import DATA_DIR

PEDESTRIANS_DIR = DATA_DIR / "pedestrians"
TRAJECTORIES_FILE = PEDESTRIANS_DIR / "trajectories.parquet"
RUNS_FILE = PEDESTRIANS_DIR / "runs.json"
ETH_UCY_SCENES = ("eth", "hotel", "univ", "zara1", "zara2")
SPLITS = ("train", "val", "test")


class RecordedDataError(ValueError):
    """A shipped data file that is missing or not what the reader expects (names the file)."""


@functools.lru_cache(maxsize=1)
def _runs() -> dict:
    try:
        runs = json.loads(RUNS_FILE.read_text(encoding="utf-8"))
    except (OSError, ValueError) as e:
        raise RecordedDataError(f"{RUNS_FILE}: cannot be read ({e}); reinstall the package") from None
    if not isinstance(runs, dict) or not all(isinstance(r, dict) and "frames_per_s" in r for r in runs.values()):
        raise RecordedDataError(f"{RUNS_FILE}: not the runs' records (a dict of runs with frames_per_s)")
    return runs


def run_names(dataset: str | None = None) -> list[str]:
    """The runs shipped, of one ``dataset`` (``juelich``, ``eth_ucy``) or all."""
    return [name for name, r in _runs().items() if dataset is None or r["dataset"] == dataset]


def run_info(run: str) -> dict:
    """A run's record: ``dataset``, ``frames_per_s``, ``source`` (repository, commit, path, unit),
    ``citation``, ``license``; Jülich runs ``geometry`` (``walkable_polygon_m``, ``obstacles_m``,
    ``measurement_area_m``, ``corridor_width_m``, ``walking_direction``) and
    ``steady_state_frames``; ETH/UCY files ``scene``, ``validation_from_frame``,
    ``test_of_scene``."""
    runs = _runs()
    if run not in runs:
        raise KeyError(f"no recorded run {run!r} (shipped: {', '.join(runs)})")
    return runs[run]


@functools.lru_cache(maxsize=1)
def _table():
    import pandas as pd

    try:
        table = pd.read_parquet(TRAJECTORIES_FILE)
    except Exception as e:  # pyarrow raises several types for a missing or damaged file
        raise RecordedDataError(f"{TRAJECTORIES_FILE}: cannot be read ({type(e).__name__}: {e})") from None
    missing = {"dataset", "run", "person", "frame", "x_mm", "y_mm"} - set(table.columns)
    if missing:
        raise RecordedDataError(f"{TRAJECTORIES_FILE}: columns {sorted(missing)} are missing")
    table["run"] = table["run"].astype(str)
    return table


def frame_numbers_per_s(info: dict) -> float:
    """How far a run's frame number advances in a second (its sample rate times its frame step)."""
    return float(info["frames_per_s"]) * float(info.get("frame_step", 1))


def trajectories(runs: Sequence[str] | str | None = None, dataset: str | None = None):
    """``run, person, frame, t_s, x_m, y_m`` rows of ``runs`` (one name or several; default:
    every run of ``dataset``, or all), sorted by run, person and frame. ``t_s`` is the frame over
    the run's frame numbers per second (the sample rate times ``frame_step``: ETH/UCY's frames
    are those of its 25 fps videos, 10 apart); a person is identified by ``(run, person)``."""
    import pandas as pd

    names = [runs] if isinstance(runs, str) else list(runs) if runs is not None else run_names(dataset)
    for name in names:
        run_info(name)  # a KeyError naming an unknown run
    table = _table()
    rows = table[table["run"].isin(names)]
    # A frame number counts the source's own frames: ETH/UCY's are the 25 fps video's, of which
    # every 10th is annotated (2.5 Hz, ``frame_step`` 10); the Jülich runs number every sample.
    fps = rows["run"].map({name: frame_numbers_per_s(run_info(name)) for name in names})
    return pd.DataFrame(
        {
            "run": rows["run"].to_numpy(),
            "person": rows["person"].to_numpy(np.int64),
            "frame": rows["frame"].to_numpy(np.int64),
            "t_s": rows["frame"].to_numpy(np.float64) / fps.to_numpy(np.float64),
            "x_m": rows["x_mm"].to_numpy(np.float64) / 1000.0,
            "y_m": rows["y_mm"].to_numpy(np.float64) / 1000.0,
        }
    ).reset_index(drop=True)


def eth_ucy_split(scene: str, split: str):
    """The rows of one ETH/UCY leave-one-scene-out split (Trajectron++'s, the field's usual one):
    ``test``, the ``scene``'s own files whole; ``train`` and ``val``, the other scenes' files
    (and the two files no scene tests on) before and from their ``validation_from_frame``."""
    if scene not in ETH_UCY_SCENES:
        raise KeyError(f"no ETH/UCY scene {scene!r} (one of {', '.join(ETH_UCY_SCENES)})")
    if split not in SPLITS:
        raise KeyError(f"no split {split!r} (one of {', '.join(SPLITS)})")
    files = run_names("eth_ucy")
    if split == "test":
        return trajectories([f for f in files if run_info(f).get("test_of_scene") == scene])
    others = [f for f in files if run_info(f).get("test_of_scene") != scene]
    rows = trajectories(others)
    cut = rows["run"].map({f: run_info(f)["validation_from_frame"] for f in others})
    keep = rows["frame"] < cut if split == "train" else rows["frame"] >= cut
    return rows[keep.to_numpy()].reset_index(drop=True)


__all__ = [
    "ETH_UCY_SCENES",
    "PEDESTRIANS_DIR",
    "RecordedDataError",
    "eth_ucy_split",
    "frame_numbers_per_s",
    "run_info",
    "run_names",
    "trajectories",
]
