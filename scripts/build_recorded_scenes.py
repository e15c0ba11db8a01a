"""Write the recorded-crowd scenes (``data/scenes/recorded/*.json``) from the shipped pedestrian runs.

    python scripts/build_recorded_scenes.py            # writes the files, prints one line each

One scene per recording and playback mode (``<name>_replayed``, ``<name>_reactive``): the five
ETH/UCY test scenes (``univ`` from ``students003``: ``students001`` needs 76 slots, people at once
with each slot's gaps counted, above the scene format's 64) and the two Jülich corridors that have
room to cross. Every number comes from the recording by the rules of
:mod:`socialnav.jaxsim.scenes.from_recording` (the Jülich corridors with their walkable area and
walls; ETH/UCY ships no map of its walls), so nothing is chosen after seeing a result.

The scenes are committed; this script is their record and rebuilds them.
"""

from __future__ import annotations

import json

from socialnav.data import DATA_DIR, recorded
from socialnav.jaxsim.scenes import from_recording
from socialnav.jaxsim.scenes import recording as recording_lib

OUT = DATA_DIR / "scenes" / "recorded"
ETH_UCY = {
    "eth": "biwi_eth",
    "hotel": "biwi_hotel",
    "univ": "students003",
    "zara1": "crowds_zara01",
    "zara2": "crowds_zara02",
}
JUELICH = {"juelich_bi_corridor": "bi_corr_400_b_03", "juelich_uni_corridor": "uni_corr_500_01"}


def _scene(name: str, run: str, playback: str) -> dict:
    rows = recorded.trajectories(run)
    info = recorded.run_info(run)
    geometry = info.get("geometry")
    if geometry is None:
        source = f"{run} (ETH/UCY, scene {info['scene']}): the robot crosses the main flow"
    else:
        width = float(geometry["corridor_width_m"])
        source = f"{run} (Jülich corridor, {width:g} m wide): the robot crosses the corridor and its flow"
    return from_recording.recorded_scene(
        rows,
        name,
        playback,
        {"run": run},
        recording_lib.load_recording(run).duration_s,
        f"{source}; {playback} (scripts/build_recorded_scenes.py)",
        geometry,
    )


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    for name, run in {**ETH_UCY, **JUELICH}.items():
        for playback in ("replayed", "reactive"):
            scene = _scene(name, run, playback)
            file = OUT / f"{scene['name']}.json"
            file.write_text(json.dumps(scene, indent=1) + "\n")
            data = recording_lib.load_recording(run)
            print(
                f"{file.name}: {run}, {data.duration_s:.0f} s, up to {recording_lib.slots_needed(data)} people, "
                f"timeout {scene['timeout_s']} s"
            )


if __name__ == "__main__":
    main()
