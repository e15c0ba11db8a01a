"""``socialnav humans validate|predict|calibrate``: the human models against real pedestrians.

    socialnav humans validate --out runs/humans                       # the social force
    socialnav humans validate --models social_force,orca --quick --out runs/humans-quick
    socialnav humans validate --fit runs/calibration/fit.json --out runs/humans-fit   # a fit of one's own
    socialnav humans predict --tracks my_tracks.csv --frames-per-s 25 --models social_force,orca   # your data
    socialnav humans calibrate --model collision_free_speed --out runs/calibration
    socialnav humans calibrate --data joint --model steering_speed_calibrated --out runs/joint

Writes ``summary.json`` (each model's checks against the bar of issue 61), the tables
(``fundamental_diagram.csv``, ``prediction.csv``, ``counterflow.csv``, ``bodies.csv``) and three
pictures, all at once when the run is complete (:mod:`evaluation.humans.validation`).
"""

from __future__ import annotations

import json
import pathlib
import sys
import time

from socialnav.cli.argtypes import (
    comma_names,
    comma_positive_floats,
    non_negative_float,
    non_negative_int,
    output_folder,
    positive_float,
    positive_int,
    seed_int,
)
from socialnav.common import runfolder
from socialnav.common.atomic import write_text_atomic
from socialnav.jaxsim.scenes.people import HUMAN_MODELS
from socialnav.locking import locks_folder

JOB = "socialnav humans validate"
CALIBRATABLE = ("collision_free_speed", "anticipation", "orca", "steering_speed", "power_law",
                "collision_free_speed_calibrated", "anticipation_calibrated", "steering_speed_calibrated",
                "power_law_calibrated")  # fmt: skip


def add_parser(top) -> None:
    humans = top.add_parser("humans", help="the human models against real pedestrian data")
    sub = humans.add_subparsers(dest="humans_command", required=True, metavar="COMMAND")
    v = sub.add_parser(
        "validate",
        help="each human model against the Jülich corridors and ETH/UCY",
        description="Runs each human model where the shipped data was recorded and measures both alike: the "
        "fundamental diagram in a 1.8 m corridor against the Jülich uo runs (PedPy's Voronoi densities), "
        "counterflow against bi_corr_400_b_03 (speed, lane order), ETH/UCY prediction against constant velocity "
        "(test splits: 8 frames observed, 12 predicted), and body overlaps. Writes a run folder and prints the "
        "checks against the bar of issue 61.",
    )
    v.add_argument("--models", type=comma_names, default=None,
                   help="human models (default social_force, none with --fit)")  # fmt: skip
    v.add_argument("--fit", type=pathlib.Path, action="append", default=[], metavar="FIT_JSON",
                   help="a Jülich fit (socialnav humans calibrate's fit.json, or the progress.json of one stopped "
                        "before its end) scored as a model, labelled <its folder>:<method>; may be given more "
                        "than once")  # fmt: skip
    v.add_argument("--fit-method", choices=("both", "gradient", "nelder_mead"), default="both",
                   help="with --fit: the fit's values from which method (default both)")  # fmt: skip
    v.add_argument(
        "--out", type=output_folder, default=pathlib.Path("runs/humans"), help="folder (default runs/humans)"
    )
    v.add_argument("--quick", action="store_true", help="10 m corridors, 30 s: a first look in about a minute a model")
    v.add_argument("--seed", type=seed_int, default=0)
    v.add_argument("--start-draws", type=non_negative_int, default=0,
                   help="measure the diagram that many times more, each from another draw of the corridors' people, "
                        "dense crowds in a disordered packing instead of a lattice: how much the verdict owes to "
                        "the start (default 0)")  # fmt: skip
    v.add_argument("--overwrite", action="store_true", help="replace the run in --out whole once the new one is done")
    v.add_argument("--no-progress", action="store_true", help="print the headline only")
    v.set_defaults(handler=validate)

    p = sub.add_parser(
        "predict",
        help="each human model against your own recording: ETH/UCY's prediction test on a tracks file",
        description="ETH/UCY's prediction test on your own recording (a tracks file: CSV or Parquet rows of frame, "
        "id, x, y, positions in metres; the file socialnav arena-scene and gscl fit-tracks read): every person "
        "present for 20 samples is observed for 8 and predicted for 12 by constant velocity and by each model "
        "(aimed along their last observed velocity, and at their true final position), in open space or between the "
        "walls of --map. Writes "
        "prediction.csv, prediction.png and summary.json and prints a line a predictor.",
    )
    p.add_argument("--tracks", type=pathlib.Path, default=None, help="the recording: a .csv or .parquet tracks file")
    p.add_argument("--frames-per-s", type=positive_float, default=None,
                   help="with --tracks: how far the file's frame numbers advance in a second")  # fmt: skip
    p.add_argument("--run", default=None,
                   help="a shipped recording instead of --tracks (a Jülich run or an ETH/UCY file), between the "
                        "walls of its recorded walkable area where it has one")  # fmt: skip
    p.add_argument("--no-walls", action="store_true", help="with --run: open space even where the run records walls")
    p.add_argument("--models", type=comma_names, default=["social_force"], help="human models (default social_force)")
    _add_map_options(p, "with --tracks: ")
    p.add_argument("--sample-s", type=positive_float, default=0.4,
                   help="the protocol's sample interval: the file is read every this many seconds, to the nearest "
                        "whole number of its frame steps (default 0.4, ETH/UCY's 2.5 Hz)")  # fmt: skip
    p.add_argument("--out", type=output_folder, default=pathlib.Path("runs/humans-predict"),
                   help="folder (default runs/humans-predict)")  # fmt: skip
    p.add_argument("--seed", type=seed_int, default=0)
    p.add_argument("--overwrite", action="store_true", help="replace the run in --out whole once the new one is done")
    p.add_argument("--no-progress", action="store_true", help="print the result lines only")
    p.set_defaults(handler=predict)

    c = sub.add_parser(
        "calibrate",
        help="fit a human model's parameters to the Jülich training runs, by gradient and by Nelder-Mead",
        description="Fits a velocity model's parameters (time gap, repulsion strength and range, body radius; the "
        "anticipation time too) or ORCA's (time horizon, body radius) to the fundamental diagram of the Jülich "
        "training runs (the test runs are never read) by Adam through the crowd step, and by Nelder-Mead on the "
        "same loss as the check. Writes fit.json and curve.png and prints the fitted values; socialnav humans "
        "validate --models <model>_calibrated scores the shipped fit on held-out data. While a fit runs, "
        "progress.json holds what it has found so far (juelich: each method's best point, which socialnav humans "
        "validate --fit <out>/progress.json scores; eth_ucy: the scenes done), replaced by fit.json at the end.",
    )
    c.add_argument("--model", choices=CALIBRATABLE, default="collision_free_speed",
                   help="the model to fit, from its parameters (a _calibrated one: from the Jülich fit)")  # fmt: skip
    c.add_argument("--data", choices=("juelich", "eth_ucy", "joint", "tracks"), default="juelich",
                   help="juelich: the fundamental diagram of the training runs (default); eth_ucy: the prediction "
                        "ADE, one fit a scene on its training split, scored on its test split; joint: both at once "
                        "(the diagram's loss + w x the percent ADE behind constant velocity on the ETH/UCY "
                        "recordings no scene tests on), one fit a --weights value, each scored by the "
                        "validation; tracks: the prediction ADE on your own recording (--tracks, --frames-per-s), "
                        "fitted on its first two thirds and scored on the last")  # fmt: skip
    c.add_argument("--tracks", type=pathlib.Path, default=None,
                   help="with --data tracks: your recording (a tracks file: frame, id, x, y)")  # fmt: skip
    c.add_argument("--frames-per-s", type=positive_float, default=None,
                   help="with --data tracks: how far the file's frame numbers advance in a second")  # fmt: skip
    _add_map_options(c, "with --data tracks: ")
    c.add_argument("--weights", type=comma_positive_floats, default=None,
                   help="with --data joint: the exchange rates w swept (0.03,0.1,0.3,1)")  # fmt: skip
    c.add_argument("--scenes", type=comma_names, default=None, help="with --data eth_ucy: the held-out scenes (all)")
    c.add_argument("--out", type=output_folder, default=pathlib.Path("runs/calibration"), help="folder")
    c.add_argument("--steps", type=positive_int, default=None, help="gradient steps (80; eth_ucy 60 a scene)")
    c.add_argument("--learning-rate", type=positive_float, default=None,
                   help="Adam's, on log-parameters (0.02; eth_ucy 0.2)")  # fmt: skip
    c.add_argument("--evaluations", type=non_negative_int, default=None,
                   help="Nelder-Mead's loss evaluations (250; eth_ucy 60, 0: none; joint 150 a weight)")  # fmt: skip
    c.add_argument("--sample", type=positive_int, default=256,
                   help="eth_ucy: training windows the loss is taken over, drawn once (256)")  # fmt: skip
    c.add_argument("--seed", type=seed_int, default=0)
    c.add_argument("--start-draws", type=non_negative_int, default=0,
                   help="with --data juelich or joint: each density's corridor walked from this many more draws of "
                        "its people, dense crowds in a disordered packing, the loss averaged over the draws (default "
                        "0: one draw, a dense crowd on a lattice)")  # fmt: skip
    c.add_argument("--overwrite", action="store_true", help="replace the run in --out whole once the new one is done")
    c.set_defaults(handler=calibrate)


PREDICT_JOB = "socialnav humans predict"


def _add_map_options(parser, when: str) -> None:
    """``--map`` and ``--min-wall-m2``: the walls of a tracks file's place."""
    parser.add_argument("--map", type=pathlib.Path, default=None,
                        help=f"{when}a ROS map of the place (map_server's YAML and image, in the tracks' frame): the "
                             "models walk between its walls (default: open space, as on ETH/UCY)")  # fmt: skip
    parser.add_argument("--min-wall-m2", type=non_negative_float, default=0.0,
                        help="with --map: leave out the map's occupied pieces smaller than this many square metres "
                             "(a SLAM map's speckle; default 0: every occupied cell is a wall)")  # fmt: skip


PREDICT_FILES = ("prediction.csv", "prediction.png", "summary.json")


@locks_folder(lambda args: args.out, "humans predict")
def predict(args) -> int:
    import numpy as np

    from socialnav.evaluation.humans import calibration as hc
    from socialnav.evaluation.humans import own_recording
    from socialnav.evaluation.humans import plots as human_plots

    def fail(message: str) -> int:
        print(f"{PREDICT_JOB}: {message}", file=sys.stderr)
        return 2

    unknown = [m for m in args.models if m not in HUMAN_MODELS]
    if unknown:
        return fail(f"--models: unknown {', '.join(unknown)} (known: {', '.join(HUMAN_MODELS)})")
    t0 = time.perf_counter()
    read = _prediction_input(args)  # the files first: a bad one leaves no folder behind
    if isinstance(read, str):
        return fail(read)
    windows, notes, record, label = read
    try:
        runfolder.prepare(args.out, PREDICT_FILES, args.overwrite, marker="summary.json", job=PREDICT_JOB)
        runfolder.check_writable(args.out)
    except runfolder.RunFolderError as e:
        return fail(f"--out {e}")
    say = (
        (lambda what: None)
        if args.no_progress
        else (lambda what: print(f"[{time.perf_counter() - t0:5.0f} s] {what}", flush=True))
    )
    sample_s = float(np.median(windows.frame_s))
    say(f"{label}: {len(windows.frame_s)} windows of 20 samples {sample_s:g} s apart, "
        f"{int(windows.complete.sum())} people scored")  # fmt: skip
    for note in notes:
        say(note)
    models = {name: hc.named_model(name) for name in args.models}
    table = own_recording.predict(models, windows, args.seed, say)
    summary = {
        **record,
        "sample_s": sample_s,
        "windows": len(windows.frame_s),
        "scored": int(windows.complete.sum()),
        "models": list(args.models),
        "seed": args.seed,
        "command": ["socialnav", *getattr(args, "argv", [])],
    }
    try:
        with runfolder.staged(args.out, "summary.json", args.overwrite, job=PREDICT_JOB) as stage:
            table.to_csv(stage / "prediction.csv", index=False)
            human_plots.recording_prediction(
                table, f"{label}: 8 samples observed, 12 predicted, {sample_s:g} s apart",
                stage / "prediction.png",
            )  # fmt: skip
            (stage / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    except runfolder.RunFolderError as e:
        return fail(f"--out {e}")
    print("\n".join(own_recording.headline(table)))
    print(f"wrote {args.out}/{{{', '.join(PREDICT_FILES)}}} in {time.perf_counter() - t0:.0f} s")
    return 0


def _prediction_input(args):
    """``humans predict``'s windows, the lines to print about them, what ``summary.json`` notes of
    the input and its label (``(windows, notes, record, label)``), or why not in one line."""
    import hashlib

    from socialnav.data import recorded
    from socialnav.data.track_file import TrackFileError
    from socialnav.evaluation.humans import own_recording, shipped_windows
    from socialnav.planners.learning.ros_map import MapFileError

    if (args.tracks is None) == (args.run is None):
        return "give --tracks (your recording, with --frames-per-s) or --run (a shipped one), one of them"
    if args.run is not None:
        if args.frames_per_s is not None or args.map is not None or args.min_wall_m2:
            return (
                "--run reads a shipped recording at its own rate, between its recorded walls (no --frames-per-s, "
                "--map, --min-wall-m2)"
            )
        if args.run not in recorded.run_names():
            return f"--run {args.run}: not a shipped recording (known: {', '.join(recorded.run_names())})"
        windows = shipped_windows.run_windows(args.run, args.sample_s, walls=not args.no_walls)
        walls = "left out (--no-walls)" if args.no_walls else "none recorded" if windows.walls is None else "recorded"
        notes = [f"{args.run}: walls {walls}"]
        return windows, notes, {"run": args.run, "walls": windows.walls is not None}, args.run
    if args.no_walls:
        return "--no-walls goes with --run (a tracks file walks in open space unless --map)"
    if args.frames_per_s is None:
        return "--tracks goes with --frames-per-s (how far the file's frame numbers advance in a second)"
    problem = _files_problem(args)
    if problem:
        return problem
    try:
        rows, walls, notes = _tracks_and_walls(args, args.sample_s)
        windows = own_recording.recording_windows(rows, walls)
    except (TrackFileError, MapFileError) as e:
        return str(e)
    except ValueError as e:
        return f"{args.tracks} at --frames-per-s {args.frames_per_s:g}, --sample-s {args.sample_s:g}: {e}"
    record = {"tracks": str(args.tracks), "tracks_sha256": hashlib.sha256(args.tracks.read_bytes()).hexdigest(),
              "frames_per_s": args.frames_per_s, **_map_record(args.map)}  # fmt: skip
    return windows, notes, record, args.tracks.name


CALIBRATE_JOB = "socialnav humans calibrate"
PROGRESS = "progress.json"  # what a running fit has found so far, replaced by fit.json at its end
CALIBRATE_RESULTS = ("fit.json", "curve.png", "held_out", PROGRESS)


@locks_folder(lambda args: args.out, "humans calibrate")
def calibrate(args) -> int:
    from socialnav.evaluation.humans import calibration as hc
    from socialnav.evaluation.humans import plots as human_plots
    from socialnav.evaluation.humans import validation as hv

    recording_options = (args.tracks, args.frames_per_s, args.map, args.min_wall_m2 or None)
    if args.data == "tracks" or any(option is not None for option in recording_options):
        problem = _read_recording(args)  # before --out is made: a bad file leaves no folder behind
        if problem:
            print(f"socialnav humans calibrate: {problem}", file=sys.stderr)
            return 2
    try:
        runfolder.prepare(args.out, CALIBRATE_RESULTS, args.overwrite, marker="fit.json", job=CALIBRATE_JOB)
        runfolder.check_writable(args.out)
    except runfolder.PreviousRun as e:
        message = str(e)
        if (args.out / PROGRESS).exists() and not (args.out / "fit.json").exists():
            message = (f"{args.out} holds a fit stopped before its end ({PROGRESS}: what it had found; a Jülich fit's "
                       f"best points are scored by socialnav humans validate --fit {args.out / PROGRESS}); pass "
                       "--overwrite to start again, or choose another --out")  # fmt: skip
        print(f"socialnav humans calibrate: --out {message}", file=sys.stderr)
        return 2
    except runfolder.RunFolderError as e:
        print(f"socialnav humans calibrate: --out {e}", file=sys.stderr)
        return 2
    if args.data != "joint" and args.weights is not None:
        print("socialnav humans calibrate: --weights goes with --data joint", file=sys.stderr)
        return 2
    if args.data == "eth_ucy" and args.start_draws:
        print(
            "socialnav humans calibrate: --start-draws goes with --data juelich or joint (corridors)", file=sys.stderr
        )
        return 2
    if args.data == "eth_ucy":
        return _calibrate_trajectories(args)
    if args.data == "tracks":
        return _calibrate_recording(args)
    if args.data == "joint":
        return _calibrate_joint(args)
    if args.model.endswith("_calibrated") or args.scenes is not None:
        what = "--model " + args.model if args.model.endswith("_calibrated") else "--scenes"
        print(f"socialnav humans calibrate: {what} goes with --data eth_ucy (the Jülich fit starts from a model's "
              "own defaults)", file=sys.stderr)  # fmt: skip
        return 2
    args.steps = args.steps or 80
    args.learning_rate = args.learning_rate or 0.02
    args.evaluations = 250 if args.evaluations is None else args.evaluations
    if args.evaluations == 0:
        print("socialnav humans calibrate: --evaluations must be >= 1 with --data juelich (its search is the check "
              "of the gradient's fit)", file=sys.stderr)  # fmt: skip
        return 2
    t0 = time.perf_counter()
    model = hv.HumanModel(args.model)
    if _past_memory(model, args.start_draws, gradient=True):
        return 2
    corridors = hc.training_corridors(model, args.seed, start_draws=args.start_draws)
    print(f"{args.model}: fitting {', '.join(hc.FITTED[args.model])} to the runs {', '.join(hc.TRAIN_RUNS)} "
          f"(densities {', '.join(f'{d:g}' for d in corridors.densities)} /m², {1 + args.start_draws} "
          f"draw{'s' if args.start_draws else ''} of each corridor's people)", flush=True)  # fmt: skip
    save_progress = _progress_saver(args.out)
    fit, histories = hc.calibrate(
        model, corridors, args.steps, args.learning_rate, args.evaluations, args.seed, progress=save_progress
    )
    try:
        # --overwrite or not, the run's own progress.json (prepare refused any other) goes as fit.json arrives.
        replace = args.overwrite or (args.out / PROGRESS).exists()
        with runfolder.staged(args.out, "fit.json", replace, job=CALIBRATE_JOB) as stage:
            human_plots.calibration_curve(histories, f"{args.model} on the Jülich training runs", stage / "curve.png")
            (stage / "fit.json").write_text(json.dumps(fit, indent=1) + "\n")
    except runfolder.RunFolderError as e:
        print(f"socialnav humans calibrate: --out {e}", file=sys.stderr)
        return 2
    for label in ("gradient", "nelder_mead"):
        print(f"{label}: loss {fit['start']['loss']:.2f} -> {fit[label]['loss']:.2f}, {fit[label]['values']}")
    print(f"wrote {args.out}/{{fit.json, curve.png}} in {time.perf_counter() - t0:.0f} s")
    return 0


def _past_memory(model, start_draws: int, gradient: bool) -> bool:
    """Whether a fit over ``1 + start_draws`` draws of each training corridor would not fit in the
    memory available (said in one line), checked before any is drawn. One draw, the default, is
    not checked (its program is the size of the validation's)."""
    from socialnav.evaluation.humans import calibration as hc
    from socialnav.evaluation.humans import minimise

    if not start_draws:
        return False
    try:
        hc.refuse_past_memory(model, hc.training_bins()["density_bin"], start_draws, gradient)
    except minimise.FitTooLarge as e:
        print(f"socialnav humans calibrate: --start-draws {start_draws}: {e}", file=sys.stderr)
        return True
    return False


def _progress_saver(out: pathlib.Path):
    """``save(record)``: writes ``record`` as ``out/progress.json`` (atomically) and lists it in the
    folder's manifest when it first appears, so that the commit of ``fit.json`` replaces it as the
    run's own file."""

    def save(record: dict) -> None:
        first = not (out / PROGRESS).exists()
        write_text_atomic(out / PROGRESS, json.dumps(record, indent=1) + "\n")
        if first:
            runfolder.record(out, CALIBRATE_JOB, [PROGRESS], marker="fit.json")

    return save


def _calibrate_trajectories(args) -> int:
    """``--data eth_ucy``: :func:`evaluation.humans.trajectory_calibration.calibrate`."""
    from socialnav.data import recorded
    from socialnav.evaluation.humans import calibration as hc
    from socialnav.evaluation.humans import report
    from socialnav.evaluation.humans import trajectory_calibration as tc

    scenes = args.scenes or list(recorded.ETH_UCY_SCENES)
    unknown = [s for s in scenes if s not in recorded.ETH_UCY_SCENES]
    if unknown:
        print(f"socialnav humans calibrate: --scenes: unknown {', '.join(unknown)} "
              f"(known: {', '.join(recorded.ETH_UCY_SCENES)})", file=sys.stderr)  # fmt: skip
        return 2
    t0 = time.perf_counter()
    model = hc.named_model(args.model)
    print(f"{args.model}: fitting {', '.join(tc.FITTED[model.name])} to ETH/UCY, one fit a held-out scene "
          f"({', '.join(scenes)}), on its training split", flush=True)  # fmt: skip
    evaluations = 60 if args.evaluations is None else args.evaluations
    try:
        fit = tc.calibrate(model, scenes, args.steps or 60, args.learning_rate or 0.2, evaluations, args.sample,
                           seed=args.seed, name=args.model, progress=_progress_saver(args.out))  # fmt: skip
    except tc.FitTooLarge as e:
        print(f"socialnav humans calibrate: --sample {args.sample}: {e}", file=sys.stderr)
        return 2
    replace = args.overwrite or (args.out / PROGRESS).exists()
    title = f"{args.model} on ETH/UCY, leave one scene out"
    return _write_trajectory_fit(args, fit, title, report.trajectory_fit_lines(fit), replace, t0)


def _write_trajectory_fit(args, fit: dict, title: str, lines: list[str], replace: bool, t0: float) -> int:
    """A prediction fit's ``fit.json`` and ``curve.png`` committed to ``--out`` as one, then its
    ``lines`` printed."""
    from socialnav.evaluation.humans import plots as human_plots

    try:
        with runfolder.staged(args.out, "fit.json", replace, job=CALIBRATE_JOB) as stage:
            human_plots.trajectory_fit(fit["scenes"], title, stage / "curve.png")
            (stage / "fit.json").write_text(json.dumps(fit, indent=1) + "\n")
    except runfolder.RunFolderError as e:
        print(f"socialnav humans calibrate: --out {e}", file=sys.stderr)
        return 2
    print("\n".join(lines))
    print(f"wrote {args.out}/{{fit.json, curve.png}} in {time.perf_counter() - t0:.0f} s")
    return 0


def _files_problem(args) -> str | None:
    """Why ``--tracks``, ``--map`` and ``--min-wall-m2`` cannot be read (a file that is not
    there, a speck area without a map), or None."""
    if not args.tracks.is_file():
        return f"--tracks {args.tracks}: no such file"
    if args.map is not None and not args.map.is_file():
        return f"--map {args.map}: no such file"
    if args.min_wall_m2 and args.map is None:
        return "--min-wall-m2 goes with --map"
    return None


def _tracks_and_walls(args, sample_s: float):
    """``(rows, walls, notes)``: the tracks file's rows read every ``sample_s`` seconds, the wall
    field of ``--map`` (None without one) and the lines to print about it. Raises what
    :func:`own_recording.recording_rows` and :func:`own_recording.recording_walls` raise."""
    from socialnav.evaluation.humans import own_recording

    rows = own_recording.recording_rows(args.tracks, args.frames_per_s, sample_s)
    if args.map is None:
        return rows, None, []
    walls, notes = own_recording.recording_walls(args.tracks, args.map, rows, min_wall_m2=args.min_wall_m2)
    return rows, walls, notes


def _map_record(map_file: pathlib.Path | None) -> dict:
    """What a run notes of its ``--map`` (nothing without one: earlier runs' records unchanged):
    the YAML's path and the SHA-256 of the YAML's text and the occupancy it reads."""
    if map_file is None:
        return {}
    import hashlib

    import numpy as np

    from socialnav.planners.learning.ros_map import read_ros_map

    occupancy, _, _ = read_ros_map(map_file)  # read before: a bad map was refused
    digest = hashlib.sha256(map_file.read_bytes())
    digest.update(np.ascontiguousarray(occupancy).tobytes())
    return {"map": str(map_file), "map_sha256": digest.hexdigest()}


def _read_recording(args) -> str | None:
    """``--data tracks``: why its options or file cannot be used (None: they can; the file's rows
    are then ``args.tracks_windows``, the fit's and the test's prediction windows), checked before
    the run folder is made."""
    from socialnav.data.track_file import TrackFileError
    from socialnav.evaluation.humans import own_recording
    from socialnav.planners.learning.ros_map import MapFileError

    if args.data != "tracks" or args.tracks is None or args.frames_per_s is None:
        return "--data tracks goes with --tracks and --frames-per-s (both; --map too if given), and they with it"
    if args.start_draws or args.scenes is not None or args.weights is not None:
        return "--data tracks fits one recording (no --start-draws, --scenes, --weights)"
    if args.model.startswith("power_law"):
        return ("--data tracks fits the velocity models and ORCA (the power law's gradient is not finite over a "
                "recording's windows: docs/humans.md)")  # fmt: skip
    problem = _files_problem(args)
    if problem:
        return problem
    try:
        rows, walls, args.map_notes = _tracks_and_walls(args, own_recording.SAMPLE_S)
        args.tracks_windows = own_recording.split_windows(rows, walls)  # the fit's and the test's; each scores someone
    except (TrackFileError, MapFileError) as e:
        return str(e)
    except ValueError as e:
        return f"{args.tracks} at --frames-per-s {args.frames_per_s:g}: {e}"
    return None


def _calibrate_recording(args) -> int:
    """``--data tracks``: :func:`evaluation.humans.own_recording.calibrate` on the user's file
    (read by :func:`_read_recording`)."""
    from socialnav.evaluation.humans import calibration as hc
    from socialnav.evaluation.humans import own_recording
    from socialnav.evaluation.humans import trajectory_calibration as tc

    t0 = time.perf_counter()
    try:
        model = hc.named_model(args.model)
        print(f"{args.model}: fitting {', '.join(tc.FITTED[model.name])} to {args.tracks} (its first two thirds; "
              "scored on the last)", flush=True)  # fmt: skip
        for note in getattr(args, "map_notes", []):
            print(note, flush=True)
        evaluations = 60 if args.evaluations is None else args.evaluations
        fit = own_recording.calibrate(model, *args.tracks_windows, args.model, args.tracks.name, args.steps or 60,
                                      args.learning_rate or 0.2, evaluations, args.sample, args.seed)  # fmt: skip
    except tc.FitTooLarge as e:
        print(f"socialnav humans calibrate: --sample {args.sample}: {e}", file=sys.stderr)
        return 2
    fit["tracks"] = str(args.tracks)
    fit.update(_map_record(args.map))
    title = f"{args.model} on {args.tracks.name}"
    return _write_trajectory_fit(args, fit, title, own_recording.calibration_lines(fit), args.overwrite, t0)


def _calibrate_joint(args) -> int:
    """``--data joint``: :func:`evaluation.humans.joint_calibration.calibrate`, each fit scored by the
    validation (:func:`evaluation.humans.validation.validate`) on held-out data."""
    from socialnav.evaluation.humans import calibration as hc
    from socialnav.evaluation.humans import joint_calibration as jc
    from socialnav.evaluation.humans import plots as human_plots
    from socialnav.evaluation.humans import report

    if args.scenes is not None:
        print("socialnav humans calibrate: --scenes goes with --data eth_ucy", file=sys.stderr)
        return 2
    if args.model.startswith("orca"):
        print("socialnav humans calibrate: --data joint fits the velocity models (ORCA's Jülich and ETH/UCY fits "
              "are apart)", file=sys.stderr)  # fmt: skip
        return 2
    if args.evaluations == 0:
        print("socialnav humans calibrate: --evaluations must be >= 1 with --data joint", file=sys.stderr)
        return 2
    if args.steps is not None or args.learning_rate is not None:
        print("socialnav humans calibrate: --data joint fits by Nelder-Mead alone (no --steps, --learning-rate)",
              file=sys.stderr)  # fmt: skip
        return 2
    t0 = time.perf_counter()
    say = lambda what: print(f"[{time.perf_counter() - t0:5.0f} s] {what}", flush=True)
    model, weights = hc.named_model(args.model), args.weights or jc.WEIGHTS
    if _past_memory(model, args.start_draws, gradient=False):  # the joint fit is Nelder-Mead's alone
        return 2
    fit, reference, results = jc.calibrate(model, weights, args.evaluations or 150, args.seed, args.start_draws, say,
                                           name=args.model)  # fmt: skip
    try:
        with runfolder.staged(args.out, "fit.json", args.overwrite, job=CALIBRATE_JOB) as stage:
            human_plots.joint_tradeoff(fit["weights"], reference, f"{args.model}: one fit, both data",
                                       stage / "curve.png")  # fmt: skip
            (stage / "held_out").mkdir()
            report.write_validation(stage / "held_out", reference, results, quick=False, seed=args.seed)
            (stage / "fit.json").write_text(json.dumps(fit, indent=1) + "\n")
    except runfolder.RunFolderError as e:
        print(f"socialnav humans calibrate: --out {e}", file=sys.stderr)
        return 2
    print("\n".join(report.headline(reference, results)))
    print(f"wrote {args.out}/{{fit.json, curve.png, held_out}} in {time.perf_counter() - t0:.0f} s")
    return 0


@locks_folder(lambda args: args.out, "humans validate")
def validate(args) -> int:
    from socialnav.evaluation.humans import calibration as hc
    from socialnav.evaluation.humans import report
    from socialnav.evaluation.humans import validation as hv

    known = list(HUMAN_MODELS)
    names = args.models if args.models is not None else ([] if args.fit else ["social_force"])
    unknown = [m for m in names if m not in known]
    if unknown:
        print(f"socialnav humans validate: --models: unknown {', '.join(unknown)} (known: {', '.join(known)})",
              file=sys.stderr)  # fmt: skip
        return 2
    models = {name: hc.named_model(name) for name in names}
    fits = {}  # label -> where its values came from
    methods = hc.FIT_METHODS if args.fit_method == "both" else (args.fit_method,)
    for path in args.fit:
        try:
            fitted = hc.fitted_models(path, methods)
        except ValueError as e:
            print(f"socialnav humans validate: --fit {e}", file=sys.stderr)
            return 2
        twice = sorted(set(fitted) & set(models))
        if twice:
            print(f"socialnav humans validate: --fit {path}: a second model labelled {twice[0]} (fits in folders of "
                  "one name)", file=sys.stderr)  # fmt: skip
            return 2
        models.update(fitted)
        fits.update({label: {"fit_json": str(path), "values": hc.fitted_values(m)} for label, m in fitted.items()})
    try:
        runfolder.prepare(args.out, report.VALIDATION_FILES, args.overwrite, marker="summary.json", job=JOB)
        runfolder.check_writable(args.out)
    except runfolder.RunFolderError as e:
        print(f"socialnav humans validate: --out {e}", file=sys.stderr)
        return 2
    t0 = time.perf_counter()
    say = (
        (lambda what: None)
        if args.no_progress
        else (lambda what: print(f"[{time.perf_counter() - t0:5.0f} s] {what}", flush=True))
    )
    data = hv.reference(say)
    results = {name: hv.validate(model, data, args.quick, args.seed, say, name, args.start_draws)
               for name, model in models.items()}  # fmt: skip
    try:
        with runfolder.staged(args.out, "summary.json", args.overwrite, job=JOB) as stage:
            report.write_validation(stage, data, results, quick=args.quick, seed=args.seed, fits=fits)
    except runfolder.RunFolderError as e:
        print(f"socialnav humans validate: --out {e}", file=sys.stderr)
        return 2
    print("\n".join(report.headline(data, results)))
    print(f"wrote {args.out}/{{{', '.join(report.VALIDATION_FILES)}}} in {time.perf_counter() - t0:.0f} s")
    return 0
