"""Build ``data/pedestrians/`` (the real trajectories the human models are measured against) from
the public repositories that distribute them, pinned to one commit each.

    python scripts/build_pedestrian_data.py                  # downloads the files (GitHub, raw)
    python scripts/build_pedestrian_data.py --from-mirror M  # or reads them from local clones:
                                                             # M/PedestrianDynamics+PedPy/repo, ...

Writes ``trajectories.parquet`` (one table: dataset, run, person, frame, x_mm, y_mm) and
``runs.json`` (per run: frame rate, source file and commit, geometry, steady state, split),
then prints their sizes. The package ships the result, so nobody needs to run this: it is the
record of where every number came from (``data/pedestrians/README.md``), and the way to rebuild
or extend the data.

Sources:

* Jülich corridor and bottleneck experiments, as PedPy ships them in ``notebooks/demo-data``
  (PedestrianDynamics/PedPy; the trajectories are the Jülich pedestrian dynamics data archive's,
  CC BY 4.0). The uni-directional corridor runs ``uo-*`` are in cm at 16 fps (PedPy's notebook
  ``fundamental_diagram.ipynb`` loads them so; its steady states and geometry are copied here),
  the bi-directional ``bi_corr_400_b_03`` and ``UNI_CORR_500_01`` at 25 fps (their headers).
* ETH/UCY, as Trajectron++ ships them (StanfordASL/Trajectron-plus-plus,
  ``experiments/pedestrians/raw``): frame, person, x, y in metres, every 10th frame of 25 fps
  video (2.5 Hz). The leave-one-scene-out splits are that repository's: the test scene's files
  whole; the other scenes' files cut at a frame into train (before) and validation (after).
"""

from __future__ import annotations

import argparse
import io
import json
import pathlib
import subprocess
import sys
import urllib.request

import numpy as np
import pandas as pd

ROOT = pathlib.Path(__file__).resolve().parents[1]
OUT = ROOT / "data" / "pedestrians"

PEDPY = ("PedestrianDynamics/PedPy", "8179b4b39e7c1e09eeb6b7d0f4e41f66e98cd6e4")
TRAJECTRON = ("StanfordASL/Trajectron-plus-plus", "1031c7bd1a444273af378c1ec1dcca907ba59830")

# PedPy's notebooks/fundamental_diagram.ipynb: the frames of each run's steady state.
UO_STEADY = {
    "uo-050-180-180": (211, 800),
    "uo-060-180-180": (243, 771),
    "uo-070-180-180": (203, 1113),
    "uo-100-180-180": (200, 790),
    "uo-145-180-180": (300, 1097),
    "uo-180-180-070": (500, 1399),
    "uo-180-180-095": (400, 1350),
    "uo-180-180-120": (300, 1099),
    "uo-180-180-180": (400, 1284),
}
# The same notebook's walkable area (a 1.8 m corridor from y = -4 to 4 m, x = 0 to 1.8 m,
# entrance and exit rooms wider) and measurement area (x 0-1.8, y -2-0).
UO_GEOMETRY = {
    "walkable_polygon_m": [
        [2.8, -6.5],
        [2.8, -4],
        [1.8, -4],
        [1.8, 4],
        [2.8, 4],
        [2.8, 8],
        [-1, 8],
        [-1, 4],
        [0, 4],
        [0, -4],
        [-1, -4],
        [-1, -6.5],
    ],
    "measurement_area_m": [[0, -2], [0, 0], [1.8, 0], [1.8, -2]],
    "corridor_width_m": 1.8,
    "walking_direction": [0.0, -1.0],
}
# PedPy's notebooks/fundamental_diagram_at_measurement_line.ipynb ("bidirectional 2",
# "unidirectional 1"): corridors along x, walls as obstacles; the measurement area chosen here,
# 2 m of the corridor around its middle (the notebook measures at the line x = 0).
BI_GEOMETRY = {
    "walkable_polygon_m": [[-6.5, 6.5], [-6.5, -1.5], [5.5, -1.5], [5.5, 6.5]],
    "obstacles_m": [
        [[-5.0, 0.0], [5.0, 0.0], [5.0, -1.0], [-5.0, -1.0]],
        [[-5.0, 4.1], [5.0, 4.1], [5.0, 5.0], [-5.0, 5.0]],
    ],
    "measurement_area_m": [[-1, 0], [1, 0], [1, 4.1], [-1, 4.1]],
    "corridor_width_m": 4.1,
    "walking_direction": [1.0, 0.0],
}
UNI500_GEOMETRY = {
    "walkable_polygon_m": [[-6.5, 6.5], [-6.5, -1.5], [6.5, -1.5], [6.5, 6.5]],
    "obstacles_m": [
        [[-6.0, 0.0], [5.0, 0.0], [5.0, -1.0], [-6.0, -1.0]],
        [[-6.0, 5.0], [5.0, 5.0], [5.0, 6.0], [-6.0, 6.0]],
    ],
    "measurement_area_m": [[-1, 0], [1, 0], [1, 5], [-1, 5]],
    "corridor_width_m": 5.0,
    "walking_direction": [-1.0, 0.0],
}
JUELICH_RUNS = {  # run: (path in PedPy, frames per second, metres per unit, geometry, kind)
    **{
        name: (f"notebooks/demo-data/uni-directional/{name}.txt", 16.0, 0.01, UO_GEOMETRY, "corridor, one way")
        for name in UO_STEADY
    },
    "bi_corr_400_b_03": (
        "notebooks/demo-data/bi-directional/bi_corr_400_b_03.txt",
        25.0,
        0.01,
        BI_GEOMETRY,
        "corridor, both ways",
    ),
    "uni_corr_500_01": (
        "notebooks/demo-data/uni-directional/traj_UNI_CORR_500_01.txt",
        25.0,
        1.0,
        UNI500_GEOMETRY,
        "corridor, one way",
    ),
    "bottleneck_040_c_56": ("notebooks/demo-data/bottleneck/040_c_56_h-.txt", 25.0, 1.0, None, "bottleneck"),
}
JUELICH_CITATION = (
    "Forschungszentrum Jülich, pedestrian dynamics data archive (https://ped.fz-juelich.de/da), CC BY 4.0; "
    "corridors: Zhang, Klingsch, Schadschneider, Seyfried (2011), J. Stat. Mech. P06004 (uni-directional) and "
    "Zhang et al. (2012), J. Stat. Mech. P02002 (bi-directional); the uo runs: Seyfried et al. (2010), "
    "Pedestrian and Evacuation Dynamics 2008, 145-156"
)

ETH_UCY_FILES = {  # file: scene
    "biwi_eth": "eth",
    "biwi_hotel": "hotel",
    "students001": "univ",
    "students003": "univ",
    "uni_examples": "univ",  # training only (in no scene's test split)
    "crowds_zara01": "zara1",
    "crowds_zara02": "zara2",
    "crowds_zara03": "zara2",  # training only
}
ETH_UCY_TEST = {  # scene: its test files (Trajectron++'s raw/<scene>/test)
    "eth": ["biwi_eth"],
    "hotel": ["biwi_hotel"],
    "univ": ["students001", "students003"],
    "zara1": ["crowds_zara01"],
    "zara2": ["crowds_zara02"],
}
ETH_UCY_CITATION = (
    "Pellegrini, Ess, Schindler, van Gool (2009), You'll never walk alone, ICCV (ETH: biwi_eth, biwi_hotel); "
    "Lerner, Chrysanthou, Lischinski (2007), Crowds by example, Computer Graphics Forum 26(3) (UCY: students, "
    "crowds_zara); as distributed by Trajectron++ (Salzmann et al. 2020, MIT license) for research use"
)


def _reader(mirror: pathlib.Path | None):
    def read(repo_commit: tuple[str, str], path: str) -> str:
        repo, commit = repo_commit
        if mirror is not None:
            git = mirror / repo.replace("/", "+") / "repo"
            return subprocess.run(
                ["git", "-C", str(git), "show", f"{commit}:{path}"], check=True, capture_output=True, text=True
            ).stdout
        url = f"https://raw.githubusercontent.com/{repo}/{commit}/{path}"
        with urllib.request.urlopen(url, timeout=60) as response:
            return response.read().decode("utf-8")

    return read


def _table(text: str, columns: int) -> np.ndarray:
    rows = [line.split() for line in text.splitlines() if line.strip() and not line.lstrip().startswith("#")]
    return np.array([[float(v) for v in row[:columns]] for row in rows], np.float64)


def build(mirror: pathlib.Path | None) -> None:
    read = _reader(mirror)
    frames, runs = [], {}
    for run, (path, fps, scale, geometry, kind) in JUELICH_RUNS.items():
        a = _table(read(PEDPY, path), 4)  # id, frame, x, y
        frames.append(
            pd.DataFrame(
                {
                    "dataset": "juelich",
                    "run": run,
                    "person": a[:, 0],
                    "frame": a[:, 1],
                    "x_m": a[:, 2] * scale,
                    "y_m": a[:, 3] * scale,
                }
            )
        )
        runs[run] = {
            "dataset": "juelich",
            "kind": kind,
            "frames_per_s": fps,
            "source": {
                "repository": PEDPY[0],
                "commit": PEDPY[1],
                "path": path,
                "unit": "cm" if scale == 0.01 else "m",
            },
            "geometry": geometry,
            "steady_state_frames": list(UO_STEADY[run]) if run in UO_STEADY else None,
            "citation": JUELICH_CITATION,
            "license": "CC BY 4.0",
        }
    # biwi_eth's frame numbers are its original annotation's (every 6th frame, 0.4 s apart: 15 a
    # second), linearly interpolated by Social-LSTM's authors to every 10th; a sample of this file
    # is therefore 10 / 15 = 0.67 s, not 0.4 s (Trajectron++ issue #67, sgan issue #84; read at
    # 0.4 s its people walk at a median 2.45 m/s, at 0.67 s at 1.47 m/s, hotel's 1.27).
    ETH_UCY_SAMPLES_PER_S = {"biwi_eth": 1.5}
    for file, scene in ETH_UCY_FILES.items():
        a = _table(read(TRAJECTRON, f"experiments/pedestrians/raw/raw/all_data/{file}.txt"), 4)  # frame, id, x, y
        val = _table(read(TRAJECTRON, f"experiments/pedestrians/raw/raw/val/{file}_val.txt"), 1)
        frames.append(
            pd.DataFrame(
                {"dataset": "eth_ucy", "run": file, "person": a[:, 1], "frame": a[:, 0], "x_m": a[:, 2], "y_m": a[:, 3]}
            )
        )
        runs[file] = {
            "dataset": "eth_ucy",
            "scene": scene,
            "frames_per_s": ETH_UCY_SAMPLES_PER_S.get(file, 2.5),
            "frame_step": 10,
            "source": {
                "repository": TRAJECTRON[0],
                "commit": TRAJECTRON[1],
                "path": f"experiments/pedestrians/raw/raw/all_data/{file}.txt",
                "unit": "m",
            },
            "validation_from_frame": int(val[:, 0].min()),  # frames before: train; from it: validation
            "test_of_scene": next((s for s, files in ETH_UCY_TEST.items() if file in files), None),
            "citation": ETH_UCY_CITATION,
            "license": "research use (the original ETH and UCY releases); redistributed by Trajectron++ (MIT)",
        }
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pd.concat(frames, ignore_index=True)
    # Millimetres as integers, delta-encoded along each person's track (1.2 MB; float32 metres
    # took 5.6 MB): finer than either dataset's accuracy (about a centimetre).
    table["x_mm"] = np.round(table.pop("x_m") * 1000.0).astype(np.int32)
    table["y_mm"] = np.round(table.pop("y_m") * 1000.0).astype(np.int32)
    table = table.astype({"person": np.int32, "frame": np.int32})
    table = table.sort_values(["dataset", "run", "person", "frame"], kind="stable").reset_index(drop=True)
    OUT.mkdir(parents=True, exist_ok=True)
    buffer = io.BytesIO()
    delta = {c: "DELTA_BINARY_PACKED" for c in ("person", "frame", "x_mm", "y_mm")}
    pq.write_table(
        pa.Table.from_pandas(table, preserve_index=False),
        buffer,
        compression="zstd",
        compression_level=19,
        use_dictionary=["dataset", "run"],
        column_encoding=delta,
    )
    (OUT / "trajectories.parquet").write_bytes(buffer.getvalue())
    (OUT / "runs.json").write_text(json.dumps(runs, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    print(f"{len(table):,} rows from {len(runs)} runs: trajectories.parquet {len(buffer.getvalue()) / 1e6:.2f} MB")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--from-mirror", type=pathlib.Path, default=None, help="folder of local clones (owner+name/repo)")
    args = ap.parse_args()
    build(args.from_mirror)
    return 0


if __name__ == "__main__":
    sys.exit(main())
