"""What a learnt social cost map charges around people: its costs binned by the distance to the
nearest person and by the side of that person (in front, beside, behind), on the windows of
recorded tracks none of the models read.

    python scripts/track_costs_by_neighbour.py --model tracks=runs/eth_ucy_model \\
        --recording students003 --recording crowds_zara01 --recording crowds_zara02 \\
        --recording biwi_eth --recording biwi_hotel

Each model (``label=folder``; the GSCL model shipped with the package is always added as
``shipped``) is run on the same input windows (``planners.learning.tracks.track_demonstrations`` of the
runs' tracks: one 16 m window a person, from where they start, the others present then with
their headings). Costs are relative to the model's mean cost of free cells more than 3.2 m from
anyone (a cost map's scale is not identified by paths alone), so 1.0 is "what this map charges
away from people". The windows' people gather near their centres (each window is centred on a
walker), so a cost that merely rises towards the centre would look like a cost of people: the
last rows compare near and far cells within one ring around the centre (2-6 m). A person's heading
is the cell their heading code marks next to them.
Prints one table per model; the figures of docs/recorded-crowds.md come from it.
"""

from __future__ import annotations

import argparse
import pathlib

import numpy as np
from scipy import ndimage

from socialnav.models import grid
from socialnav.models.inference import DEFAULT_MODEL, SocialCostModel
from socialnav.planners.learning import tracks

DISTANCE_EDGES_M = (0.4, 0.8, 1.2, 1.6, 2.4, 3.2, 8.0)
NEAR_M = (0.4, 1.6)  # where the side of a person is compared


def neighbour_geometry(maps: np.ndarray):
    """Per window and cell: the distance (m) to the nearest person cell, and the cosine between
    the way from that person to the cell and the person's heading (NaN where the person's heading
    cell is not next to them)."""
    n = len(maps)
    distance = np.full(maps.shape, np.inf, np.float32)
    cosine = np.full(maps.shape, np.nan, np.float32)
    for k in range(n):
        person = maps[k] == grid.PERSON
        if not person.any():
            continue
        d, (ri, ci) = ndimage.distance_transform_edt(~person, return_indices=True)
        distance[k] = d * grid.CELL_M
        heading = np.zeros(maps.shape[1:] + (2,), np.float32)
        for r, c in zip(*np.nonzero(person), strict=True):
            rows, cols = slice(max(r - 1, 0), r + 2), slice(max(c - 1, 0), c + 2)
            ahead = np.argwhere(maps[k][rows, cols] == grid.HEADING)
            if len(ahead):
                dr, dc = ahead[0] + (max(r - 1, 0), max(c - 1, 0)) - (r, c)
                heading[r, c] = (dc, -dr)  # x right, y up
        row, col = np.mgrid[: maps.shape[1], : maps.shape[2]]
        away = np.stack([col - ci, -(row - ri)], -1).astype(np.float32)
        h = heading[ri, ci]
        norm = np.linalg.norm(away, axis=-1) * np.linalg.norm(h, axis=-1)
        cosine[k] = np.where(norm > 0, np.sum(away * h, -1) / np.maximum(norm, 1e-9), np.nan)
    return distance, cosine


RING_M = (2.0, 6.0)


def table(costs: np.ndarray, maps: np.ndarray, distance: np.ndarray, cosine: np.ndarray) -> dict:
    """Relative cost by distance bin, near people by side, and near against far within a ring."""
    free = maps == grid.FREE
    far = free & (distance > 3.2)
    relative = costs / max(float(np.mean(costs[far])), 1e-9)
    rows = {}
    lo = 0.0
    for hi in DISTANCE_EDGES_M:
        pick = free & (distance > lo) & (distance <= hi)
        rows[f"{lo:.1f}-{hi:.1f} m"] = (float(np.mean(relative[pick])), int(pick.sum()))
        lo = hi
    near = free & (distance > NEAR_M[0]) & (distance <= NEAR_M[1])
    for side, pick in (("in front", cosine > 0.5), ("beside", np.abs(cosine) <= 0.5), ("behind", cosine < -0.5)):
        p = near & pick
        rows[f"{side} ({NEAR_M[0]}-{NEAR_M[1]} m)"] = (float(np.mean(relative[p])), int(p.sum()))
    ring = (
        free
        & (np.hypot(grid.CELL_X_M, grid.CELL_Y_M) >= RING_M[0])
        & (np.hypot(grid.CELL_X_M, grid.CELL_Y_M) <= RING_M[1])
    )
    for label, pick in (
        ("ring, near (<=1.6 m)", ring & (distance <= 1.6)),
        ("ring, far (>3.2 m)", ring & (distance > 3.2)),
    ):
        rows[label] = (float(np.mean(relative[pick])), int(pick.sum()))
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--model", action="append", default=[], help="label=folder of a GSCL model (repeatable)")
    parser.add_argument("--recording", action="append", required=True, help="a shipped run (repeatable)")
    parser.add_argument("--windows", type=int, default=400, help="windows drawn from the runs' (default 400)")
    args = parser.parse_args(argv)
    models = {"shipped": DEFAULT_MODEL} | {m.split("=", 1)[0]: pathlib.Path(m.split("=", 1)[1]) for m in args.model}
    maps, _, report = tracks.concatenate(
        [tracks.track_demonstrations(*tracks.recorded_tracks(r)) for r in args.recording]
    )
    pick = np.random.default_rng(0).choice(len(maps), size=min(args.windows, len(maps)), replace=False)
    maps = maps[np.sort(pick)]
    distance, cosine = neighbour_geometry(maps)
    print(f"{len(maps)} windows of {report['used']} tracks ({', '.join(args.recording)})")
    for label, folder in models.items():
        costs = np.asarray(SocialCostModel.load(folder)(maps), np.float32)
        print(f"\n{label} ({folder}): mean cost relative to free cells beyond 3.2 m of anyone (cells)")
        for row, (value, n) in table(costs, maps, distance, cosine).items():
            print(f"  {row:<24} {value:6.2f}  ({n})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
