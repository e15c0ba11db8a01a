"""Convert ``../shared/reference/peopleflow`` into the scenario files of ``data/warehouse/``.

Run once (``python scripts/import_peopleflow_reference.py``); the outputs are committed, so a
user never needs the reference folder. Every number written here is traceable to a reference
file; choices where the sources disagree are recorded in ``params.json`` under ``_choices``.
"""

from __future__ import annotations

import json
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
REF = ROOT.parent / "shared" / "reference" / "peopleflow"
OUT = ROOT / "data" / "warehouse"


def waypoint_kind(name: str) -> str:
    """Semantic kind of a waypoint from its PeopleFlow name."""
    for prefix, kind in [
        ("door-", "door"),
        ("corridor-canteen", "canteen"),
        ("corridor", "corridor"),
        ("support", "support"),
        ("office", "office"),
        ("toilet", "toilet"),
        ("table", "canteen"),
        ("wa-", "work_area"),
        ("target", "robot_target"),
        ("charging", "charging_station"),
        ("parking", "parking"),
        ("entrance", "entrance"),
    ]:
        if name.startswith(prefix):
            return kind
    raise ValueError(f"unknown waypoint kind for {name!r}")


def main() -> int:
    graph = json.loads((REF / "derived_waypoint_graph.json").read_text())
    boxes = json.loads((REF / "derived_world_boxes.json").read_text())["boxes"]
    schedule = json.loads((REF / "derived_schedule.json").read_text())["slots"]
    tasks = json.loads((REF / "task_list_experiment.json").read_text())
    OUT.mkdir(parents=True, exist_ok=True)

    waypoints = [
        {
            "id": n["id"],
            "x_m": n["x"],
            "y_m": n["y"],
            "radius_m": n["r"],
            "kind": waypoint_kind(n["id"]),
            "human_destination": bool(n["human_destination"]),
        }
        for n in graph["nodes"]
    ]
    write(
        "waypoints.json",
        {
            "_source": "reference/peopleflow/derived_waypoint_graph.json (nodes); kind derived from the name",
            "waypoints": waypoints,
        },
    )
    write(
        "graph.json",
        {
            "_source": "reference/peopleflow/derived_waypoint_graph.json (184 undirected edges, line-of-sight rule"
            " of PeopleFlow WaypointGraph.py); edge length is recomputed from the waypoints on load",
            "humans_exclude": graph["humans_exclude"],
            "robot_exclude": graph["robot_exclude"],
            "edges": [[e["u"], e["v"]] for e in graph["edges"]],
        },
    )
    walls = []
    for b in boxes:
        yaw_quarters = b["yaw"] / (math.pi / 2)
        if abs(yaw_quarters - round(yaw_quarters)) > 1e-3:
            raise ValueError(f"box {b['link']} is not axis aligned")
        kind = b["kind"].split(" ")[0]
        walls.append(
            {
                "kind": {"delivery": "tray"}.get(kind, kind),
                "name": f"{b['model']}/{b['link']}",
                "xmin_m": b["xmin"],
                "xmax_m": b["xmax"],
                "ymin_m": b["ymin"],
                "ymax_m": b["ymax"],
            }
        )
    write(
        "walls.json",
        {
            "_source": "reference/peopleflow/derived_world_boxes.json (collision boxes of warehouse.world; all are"
            " axis aligned, so the extents are exact)",
            "boxes": walls,
        },
    )
    slot_names = ["H1", "H2", "H3", "H4", "H5", "H6", "H7", "H8", "H9", "H10", "off"]
    write(
        "schedule.json",
        {
            "_source": "reference/peopleflow/derived_schedule.json (<schedule> of warehouse.xml; p>0 only)",
            "slots": [
                {
                    "name": f"S{i + 1}",
                    "pedsim_name": s,
                    "clock": schedule[s]["clock"],
                    "working": s != "off",
                    "destinations": schedule[s]["p"],
                }
                for i, s in enumerate(slot_names)
            ],
        },
    )
    write(
        "tasks.json",
        {
            "_source": "reference/peopleflow/task_list_experiment.json (the randomized goal lists of the paper's"
            " experiments: bottom/top targets alternate; S6 target-7/entrance; S11 the 90-leg cleaning"
            " tour)",
            "robot_start": "charging-station",
            "charging_station": "charging-station",
            "slots": [{"name": f"S{i + 1}", "goals": tasks[s]} for i, s in enumerate(slot_names)],
        },
    )
    return 0


def write(name: str, obj: dict) -> None:
    (OUT / name).write_text(json.dumps(obj, indent=1) + "\n")
    print("wrote", OUT / name)


if __name__ == "__main__":
    sys.exit(main())
