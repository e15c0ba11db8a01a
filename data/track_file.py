"""A user's tracks file: the one format the toolkit reads people's recorded positions in.

CSV or Parquet with one row per person and frame and at least the columns ``frame`` (integer),
``id`` (any label), ``x`` and ``y`` (metres). Other columns are ignored; rows may come in any
order. Read by ``socialnav gscl fit-tracks`` (costs learnt from the tracks,
:mod:`planners.learning.tracks`, where only the order of a person's positions matters) and by a
scene's ``recording.file`` (the arena's recorded crowd, :mod:`jaxsim.scenes.recording`, which
takes the frame numbers' rate, ``frames_per_s``, beside the file).
"""

from __future__ import annotations

import csv as csv_format
import pathlib

import numpy as np

REQUIRED_COLUMNS = ("frame", "id", "x", "y")


class TrackFileError(ValueError):
    """A tracks or map file that cannot be used; the message names the file and the field."""


def read_tracks(path) -> dict[object, np.ndarray]:
    """``{id: (T, 3) float64 [frame, x, y]}`` sorted by frame, from a CSV or Parquet file.

    A problem names the file, the column and the row: a CSV's line number (its header is line 1),
    a Parquet file's row counted from 1.

    Raises:
      TrackFileError: unreadable file, a missing or repeated column, an empty id, a frame that is
        not a whole number (or past 2^53, where float64 would merge two), a non-finite or
        true/false position, or a person twice in one frame.
    """
    import pandas as pd

    path = pathlib.Path(path)
    csv = path.suffix.lower() == ".csv"
    try:
        if path.suffix.lower() == ".parquet":
            df = pd.read_parquet(path)
        elif csv:
            df = pd.read_csv(path)
        else:
            raise TrackFileError(f"{path}: tracks must be a .csv or .parquet file")
    except TrackFileError:
        raise
    except Exception as e:  # pandas' and pyarrow's parse errors have no common base
        raise TrackFileError(f"{path}: cannot read ({type(e).__name__}: {e})") from None

    def row(i: int) -> str:
        return f"row {i + 2}" if csv else f"row {i + 1}"

    names = [str(c) for c in df.columns]
    if csv:  # pandas renames a repeated column ("x", "x.1") and reads the first: which was meant?
        with open(path, encoding="utf-8-sig", errors="replace", newline="") as f:
            header = [h.strip() for h in next(csv_format.reader([f.readline()]), [])]  # quoted names too
        twice = [c for c in REQUIRED_COLUMNS if header.count(c) > 1]
        if twice:
            raise TrackFileError(f"{path}: column '{twice[0]}' is given {header.count(twice[0])} times in the header")
    missing = [c for c in REQUIRED_COLUMNS if c not in df.columns]
    if missing:
        found = ", ".join(names[:8]) + (" ..." if len(names) > 8 else "")
        hint = "; is it comma-separated?" if len(names) == 1 and any(s in names[0] for s in ";\t|") else ""
        raise TrackFileError(
            f"{path}: column '{missing[0]}' is missing (need {', '.join(REQUIRED_COLUMNS)}; found {found}){hint}"
        )
    if df.empty:
        raise TrackFileError(f"{path}: no rows")
    empty = df["id"].isna().to_numpy() | (df["id"].astype(str).str.strip() == "").to_numpy()
    if empty.any():
        raise TrackFileError(
            f"{path}: column 'id', {row(int(np.flatnonzero(empty)[0]))}: empty (every row names its person)"
        )
    for col in ("frame", "x", "y"):
        if df[col].dtype == bool:
            raise TrackFileError(f"{path}: column '{col}': true/false values, not numbers")
    frame = pd.to_numeric(df["frame"], errors="coerce").to_numpy(float)
    bad = ~np.isfinite(frame) | (frame % 1 != 0) | (np.abs(frame) > 2.0**53)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise TrackFileError(
            f"{path}: column 'frame', {row(i)}: {df['frame'].iloc[i]!r} is not a whole number (within +-2^53)"
        )
    for col in ("x", "y"):
        v = pd.to_numeric(df[col], errors="coerce").to_numpy(float)
        if not np.isfinite(v).all():
            i = int(np.flatnonzero(~np.isfinite(v))[0])
            value = df[col].iloc[i]
            shown = repr(value) if isinstance(value, str) else str(value)
            what = "is empty" if pd.isna(value) else f"{shown} is not a finite number"
            raise TrackFileError(f"{path}: column '{col}', {row(i)}: {what}")
    dup = df.duplicated(subset=["frame", "id"])
    if dup.any():
        i = int(np.flatnonzero(dup.to_numpy())[0])
        raise TrackFileError(
            f"{path}: columns 'frame', 'id', {row(i)}: person {df['id'].iloc[i]!r} appears twice in frame "
            f"{df['frame'].iloc[i]}"
        )
    table = pd.DataFrame(
        {"frame": frame.astype(np.int64), "id": df["id"], "x": df["x"].astype(float), "y": df["y"].astype(float)}
    )
    return {
        pid: g.sort_values("frame")[["frame", "x", "y"]].to_numpy(np.float64)
        for pid, g in table.groupby("id", sort=True)
    }


__all__ = ["REQUIRED_COLUMNS", "TrackFileError", "read_tracks"]
