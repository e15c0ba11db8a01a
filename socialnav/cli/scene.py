"""``socialnav arena-scene``: a recorded-crowd scene of your own recording, ready for the arena.

    socialnav arena-scene my_crowd.csv --frames-per-s 25 --out scenes   # scenes/my_crowd_{replayed,reactive}.json
    socialnav arena --scenes scenes/my_crowd_replayed.json,scenes/my_crowd_reactive.json --out runs/mine

The recording is the toolkit's tracks file (:mod:`socialnav.data.track_file`: CSV or Parquet rows
of ``frame, id, x, y``, positions in metres, the format ``socialnav gscl fit-tracks`` reads) and
``--frames-per-s`` the rate its frame numbers advance at. The scenes are written
by the fixed rules of :mod:`socialnav.jaxsim.scenes.from_recording` (the robot crosses the main
flow, bounds the people's extent, windows from the first two thirds, held-out ones from the rest),
name the recording by its path relative to the scene files, and are checked as ``socialnav
arena`` checks a scene before either is written; edit them as any scene (walls, the robot's start
and goal, the rule: ``docs/arena.md``).
"""

from __future__ import annotations

import json
import os
import pathlib
import sys

from socialnav.cli.argtypes import non_negative_float, output_folder, positive_float

JOB = "socialnav arena-scene"


def add_parser(top) -> None:
    parser = top.add_parser(
        "arena-scene",
        help="write the arena's recorded-crowd scenes (replayed, reactive) of your own recording",
        description="Your recording (a tracks file: CSV or Parquet rows of frame, id, x, y, positions in metres; the "
        "format socialnav gscl fit-tracks reads) as two "
        "arena scenes, <name>_replayed.json and <name>_reactive.json, written by the rules the shipped "
        "recorded-crowd scenes follow (docs/recorded-crowds.md).",
    )
    parser.add_argument(
        "tracks", type=pathlib.Path, help="the recording: a tracks file (.csv or .parquet; frame, id, x, y in metres)"
    )
    parser.add_argument(
        "--frames-per-s",
        type=positive_float,
        required=True,
        help="how far the file's frame numbers advance in a second (25 for frames of a 25 fps video, even if "
        "only every 10th is in the file)",
    )
    parser.add_argument(
        "--map",
        type=pathlib.Path,
        default=None,
        metavar="MAP.yaml",
        help="a ROS map of the place (map_server's YAML and image, in the tracks' frame): its walls inside the "
        "scene's bounds become the scene's walls (default: none, open ground)",
    )
    parser.add_argument(
        "--min-wall-m2",
        type=non_negative_float,
        default=0.0,
        help="with --map: leave out the map's occupied pieces smaller than this many square metres (a SLAM map's "
        "speckle; default 0: every occupied cell is a wall)",
    )
    parser.add_argument("--name", default=None, help="the scenes' name (default: the file's name without its suffix)")
    parser.add_argument(
        "--out", type=output_folder, default=pathlib.Path("scenes"), help="folder of the scene files (default scenes)"
    )
    parser.add_argument("--overwrite", action="store_true", help="replace scene files of the same name")
    parser.set_defaults(handler=run)


def run(args) -> int:
    from socialnav.common.atomic import temporary_path
    from socialnav.common.names import SAFE_NAME_RULE, is_safe_name, name_problem
    from socialnav.data.track_file import TrackFileError
    from socialnav.jaxsim.scenario.errors import ScenarioError
    from socialnav.jaxsim.scenes import from_recording
    from socialnav.jaxsim.scenes import recording as recording_lib
    from socialnav.jaxsim.scenes.spec import load_scene
    from socialnav.planners.learning.ros_map import MapFileError
    from socialnav.planners.learning.tracks import map_walls

    def fail(message: str) -> int:
        print(f"{JOB}: {message}", file=sys.stderr)
        return 2

    file = args.tracks
    name = args.name if args.name is not None else file.stem
    if not is_safe_name(name):
        return fail(f"--name {name!r} cannot name the scene files ({name_problem(name)}): use {SAFE_NAME_RULE}")
    if not file.is_file():
        return fail(f"{file}: no such file")
    if args.map is not None and not args.map.is_file():
        return fail(f"--map {args.map}: no such file")
    if args.min_wall_m2 and args.map is None:
        return fail("--min-wall-m2 goes with --map")
    try:
        rows = recording_lib.file_rows(file, args.frames_per_s)
        duration_s = recording_lib.load_recording_file(file, args.frames_per_s).duration_s
        walls, notes = None, []
        if args.map is not None:
            walls, in_walls = map_walls(file, args.map, rows, from_recording.open_ground_bounds(rows), args.min_wall_m2)
            notes = [f"{args.map}: {len(walls)} wall boxes inside the scene's bounds"]
            if in_walls:
                notes.append(f"{args.map}: {100 * in_walls:.1f} % of the recorded positions lie in its walls "
                             "(replayed, those people walk through them; reactive, they are kept out)")  # fmt: skip
        scenes = [
            from_recording.recorded_scene(
                rows,
                name,
                playback,
                {"file": os.path.relpath(file.resolve(), args.out.resolve()), "frames_per_s": args.frames_per_s},
                duration_s,
                f"{file.name} (your recording): the robot crosses the main flow; {playback} ({JOB})",
                walls=walls,
            )
            for playback in from_recording.PLAYBACKS
        ]
    except (TrackFileError, MapFileError) as e:  # names the file
        return fail(str(e))
    except ValueError as e:
        return fail(f"{file} at --frames-per-s {args.frames_per_s:g}: {e}")
    targets = [args.out / f"{scene['name']}.json" for scene in scenes]
    existing = [str(t) for t in targets if t.exists()]
    if existing and not args.overwrite:
        return fail(f"{', '.join(existing)} exist(s): give --overwrite to replace, or another --name or --out")
    if args.out.exists() and not args.out.is_dir():
        return fail(f"--out {args.out}: a file, not a folder")
    staged = [temporary_path(t) for t in targets]  # beside their targets: the recording's path is relative
    try:
        args.out.mkdir(parents=True, exist_ok=True)
        specs = []
        for scene, tmp, target in zip(scenes, staged, targets, strict=True):  # checked as the arena reads them
            tmp.write_text(json.dumps(scene, indent=1) + "\n", encoding="utf-8")
            try:
                specs.append(load_scene(tmp))
            except ScenarioError as e:
                return fail(f"{file}: the scene it makes is refused: {str(e).replace(str(tmp), str(target))}")
        for tmp, target in zip(staged, targets, strict=True):
            os.replace(tmp, target)
    except OSError as e:  # a folder that cannot be made or written (a full disk is named the same way)
        return fail(f"--out {args.out}: cannot write {e.filename or args.out} ({e.strerror or e})")
    finally:
        for tmp in staged:
            tmp.unlink(missing_ok=True)
    for target, spec in zip(targets, specs, strict=True):
        (sx, sy), (gx, gy) = (tuple(sum(r) / 2 for r in spec.robot[k]) for k in ("start", "goal"))
        print(
            f"{target}: {file.name}, {duration_s:.0f} s, up to {spec.n_people_slots} people at once; the robot from "
            f"({sx:.1f}, {sy:.1f}) to ({gx:.1f}, {gy:.1f}) m, timeout {spec.timeout_s:g} s"
        )
    for note in notes:
        print(note)
    print(f"run them: socialnav arena --scenes {','.join(str(t) for t in targets)} --out runs/{name}")
    return 0
