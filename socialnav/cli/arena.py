"""``socialnav arena``: the seeds' methods on the seeds' scenes, in closed loop, many variants each.

socialnav arena --out runs/arena                                   # every scene, every method, 100 variants
socialnav arena --scenes casn_static_person,casn_head_on --methods navfn,casn --variants 20
socialnav arena --scenes my_scene.json --out runs/mine             # a scene file of your own
socialnav arena --gscl-run runs/gscl                               # GSCL with your own model, not the shipped one
socialnav arena --params my_params.toml                            # the robot's and layers' parameters
socialnav arena --human-fit runs/calibration-mine/fit.json         # people as your calibration fitted them
socialnav arena --held-out                                         # and every scene mirrored, ranges exceeded
socialnav arena --turned                                           # and every scene turned a quarter turn
socialnav arena --gscl-rotations 4                                 # GSCL's map averaged over 4 quarter turns
socialnav arena --backend ray --shard-variants 25                  # a Ray task per 25 variants of a scene

Writes ``episodes/<scene>.parquet`` (one row per episode: every metric),
``trajectories/<scene>.parquet`` (the first ``--keep-trajectories`` variants, step by step),
``pictures/<scene>_paths.png``, ``_distance.png`` and (with the social band) ``_speed.png``
(variant 0), ``summary.csv`` (one row per scene and method), ``papers.csv`` (the seeds' published
numbers beside ours with our 95 % intervals, for the scenes and methods the run has),
``directions.csv`` (each paper's difference against its baseline and ours, paired by variant,
with a verdict: :func:`evaluation.arena.papers.directions`; ``directions_held_out.csv`` the same
on the held-out rows, with ``--held-out``; ``directions_turned.csv`` on the turned rows, with
``--turned``), ``papers_stats.csv`` (seed 002's Table 2,
its Games-Howell p and Hedges' g beside ours: :func:`evaluation.arena.papers.stats_comparison`),
``stats.csv`` (Fisher, Welch ANOVA,
Games-Howell, Hedges' g: :mod:`evaluation.arena.stats`) and ``run.json`` (the settings, the
backend and the shard layout). Work is cut into shards (``--shard-variants`` variants of one
scene; :mod:`socialnav.backend` runs them here or as Ray tasks), each saved atomically under
``shards/`` as it finishes, then joined per scene; a rerun with the same settings computes only
the missing shards and scenes.

This module parses and checks the arguments and prints the tables; the run folder's work (the
settings and digests, the shards, the joins, the tables) is
:mod:`socialnav.evaluation.arena.table`, which Python calls the same way.
"""

from __future__ import annotations

import argparse
import pathlib
import shlex
import sys

from socialnav.backend import add_backend_options
from socialnav.cli.argtypes import comma_names, output_folder, positive_int, seed_int
from socialnav.jaxsim.scenes.people import HUMAN_MODELS
from socialnav.locking import locks_folder

DEFAULT_METHODS = (
    "navfn",
    "snl_small",
    "snl_large",
    "snl_matched",
    "casn",
    "snape_eband",
    "snape_social_eband",
    "orca",
    "social_force",
    "dwa",
    "gscl",
)
POLICY_METHOD = "ppo"  # the rows of --policy-run


def add_parser(sub) -> None:
    p = sub.add_parser(
        "arena",
        help="run navigation methods on the social-navigation scenes, many variants each",
        description="Every chosen method on every chosen scene (data/scenes/*.json or your own files), "
        "N seeded variants each, in closed loop; per-episode metrics, trajectories and a summary.",
    )
    p.add_argument(
        "--scenes",
        type=comma_names,
        default=None,
        help="scene names or .json files (default: the 14 seed scenes); 'recorded' names the recorded-crowd scenes "
        "(data/scenes/recorded: ETH/UCY and Jülich crowds, replayed and reactive; socialnav arena-scene makes them of "
        "your own recording); 'geometry' the seeds' scenes at "
        "angles the papers did not test (data/scenes/geometry: the crossing at 60 and 120 deg)",
    )
    p.add_argument(
        "--methods",
        type=comma_names,
        default=None,
        help=f"methods (default: {','.join(DEFAULT_METHODS)}; gscl runs the model shipped with the package "
        "unless --gscl-run names another)",
    )
    p.add_argument(
        "--actor",
        action="append",
        default=[],
        metavar="MODULE:FUNCTION",
        help="also run your own actor (repeatable): FUNCTION(env) in MODULE (or in a file.py) returns a "
        "socialnav.jaxsim.scenes.actor.Actor or (actor, params); its rows are named FUNCTION",
    )
    p.add_argument(
        "--policy-run",
        type=pathlib.Path,
        default=None,
        metavar="RUN",
        help="also run the policy trained in RUN (socialnav policy train); its rows are named ppo",
    )
    p.add_argument(
        "--human-model",
        choices=HUMAN_MODELS,
        default=None,
        help="how the people move (default social_force, the warehouse's; ORCA, the velocity models with bodies, "
        "the steering speed model, the power law and their _calibrated fits: docs/humans.md measures each against real "
        "pedestrians)",
    )
    p.add_argument(
        "--human-fit",
        default=None,
        metavar="FIT_JSON[:METHOD]",
        help="the people as a calibration fitted them, in place of --human-model: socialnav humans calibrate's "
        "fit.json (of the Jülich corridors or of your own recording, --data tracks), its model with the fitted "
        "constants; METHOD gradient or nelder_mead (default: the one of lower training loss)",
    )
    p.add_argument("--variants", type=positive_int, default=100, help="variants per scene (default 100)")
    p.add_argument(
        "--out", type=output_folder, default=pathlib.Path("runs/arena"), help="output folder (default runs/arena)"
    )
    p.add_argument(
        "--gscl-run",
        type=pathlib.Path,
        default=None,
        help="the GSCL model of method 'gscl': a socialnav gscl train run folder or a socialnav gscl export folder "
        "(default: the model shipped with the package, data/gscl/default)",
    )
    p.add_argument(
        "--gscl-rotations",
        type=int,
        choices=(1, 4),
        default=1,
        help="GSCL's prediction averaged over the 4 quarter turns of its input: a map that turns with the scene, "
        "at 4 times the inference (default 1: the network alone)",
    )
    p.add_argument(
        "--params",
        type=pathlib.Path,
        default=None,
        metavar="FILE.toml",
        help="the robot's limits and the layers' and local planners' parameters ([robot], [casn], [snl], [snape], "
        "[band], [pursuit], [methods.<method>.<section>]; evaluation/arena/params.py); default: the seeds' values",
    )
    p.add_argument(
        "--keep-trajectories",
        type=int,
        default=5,
        help="variants per scene and method whose trajectories are kept (default 5)",
    )
    p.add_argument(
        "--animate",
        type=_scene_method,
        action="append",
        default=[],
        metavar="SCENE:METHOD",
        help="also write pictures/<scene>_<method>.gif of variant 0 (repeatable)",
    )
    p.add_argument(
        "--held-out",
        action="store_true",
        help="also run every scene mirrored with every range drawn just outside itself (rows <scene>@held_out)",
    )
    p.add_argument(
        "--turned",
        action="store_true",
        help="also run every scene turned a quarter turn counter-clockwise, its variants the scene's own turned "
        "(rows <scene>@turned: the orientation alone changes, paired by variant)",
    )
    p.add_argument(
        "--shard-variants",
        type=positive_int,
        default=None,
        help="variants per shard (default: all of a scene's in one; a Ray task per shard with --backend ray)",
    )
    p.add_argument(
        "--overwrite",
        action="store_true",
        help="replace the arena run in --out whole (only once the new one is complete); without it a run with the "
        "same settings is resumed and one with other settings refused",
    )
    p.add_argument("--seed", type=seed_int, default=0, help="random seed of the variants (default 0)")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    add_backend_options(p)
    p.set_defaults(handler=run)


def _scene_method(text: str) -> tuple[str, str]:
    scene, sep, method = text.partition(":")
    if not sep or not scene or not method:
        raise argparse.ArgumentTypeError(f"expected SCENE:METHOD, got {text!r}")
    return scene, method


RECORDED = "recorded"  # --scenes recorded: every recorded-crowd scene
GEOMETRY = "geometry"  # --scenes geometry: the seeds' scenes at angles the papers did not test


def _scene_files(
    names, scenes_dir: pathlib.Path, recorded_dir: pathlib.Path | None = None, geometry_dir: pathlib.Path | None = None
) -> list[pathlib.Path]:
    """The files of ``names`` (None: every seed scene): a ``.json`` path as given, a name in
    ``recorded_dir`` or ``geometry_dir`` if it is there and in ``scenes_dir`` otherwise (a missing
    one is reported there), :data:`RECORDED` every file of ``recorded_dir``, :data:`GEOMETRY`
    every file of ``geometry_dir``."""
    if names is None:
        return sorted(scenes_dir.glob("*.json"))
    groups = {RECORDED: recorded_dir, GEOMETRY: geometry_dir}
    files = []
    for name in names:
        path = pathlib.Path(name)
        folder = next((d for d in groups.values() if d is not None and (d / f"{name}.json").is_file()), None)
        if path.suffix == ".json":
            files.append(path)
        elif groups.get(name) is not None:
            files.extend(sorted(groups[name].glob("*.json")))
        elif folder is not None:
            files.append(folder / f"{name}.json")
        else:
            files.append(scenes_dir / f"{name}.json")
    return files


def _duration(seconds: float) -> str:
    return f"{seconds / 60:.1f} min" if seconds >= 90 else f"{seconds:.0f} s"


@locks_folder(lambda args: args.out, "arena")
def run(args) -> int:
    from socialnav.common import runfolder
    from socialnav.evaluation.arena.table import JOB, RESULTS

    try:
        if args.overwrite:
            runfolder.claim(args.out, JOB, RESULTS, overwrite=True, marker="run.json")
            with runfolder.staged(args.out, "run.json", True, job=JOB) as stage:
                code = _run_into(args, stage, shown_as=args.out)
                if code:
                    raise _Failed(code)
            print(_wrote(args.out))
            return 0
        runfolder.claim(args.out, JOB, RESULTS)  # a previous arena run is resumed, not refused
        code = _run_into(args, args.out, shown_as=args.out)
    except _Failed as failed:
        return failed.code
    except (runfolder.RunFolderError, OSError) as e:
        where = f" {e.filename}" if isinstance(e, OSError) and e.filename else ""
        print(f"socialnav arena: cannot write{where}: {getattr(e, 'strerror', None) or e}", file=sys.stderr)
        return 2
    if code == 0:
        print(_wrote(args.out))
    return code


def _wrote(out: pathlib.Path) -> str:
    """The line naming what a finished run holds (``papers.csv``, ``directions.csv`` and
    ``papers_stats.csv`` only where the run has scenes of the papers; ``directions_held_out.csv``
    and ``directions_turned.csv`` where it has their held-out or turned rows too)."""
    from socialnav.evaluation.arena.table import RESULTS

    folder = pathlib.Path(out)
    names = [n for n in RESULTS if n not in ("run.json", "shards") and (folder / n).exists()]
    return f"wrote {out}/" + ", ".join(n + "/" if (folder / n).is_dir() else n for n in names)


class _Failed(Exception):
    """A check of the run failed (already reported); the staged run is dropped."""

    def __init__(self, code: int):
        self.code = code


def _fail(message: str) -> int:
    print(f"socialnav arena: {message}", file=sys.stderr)
    return 2


def _request(args, shown_as: pathlib.Path):
    """The run's :class:`~socialnav.evaluation.arena.table.TableRequest` from the parsed
    arguments, each checked, or the exit code after a one-line error naming the option."""
    from socialnav.common import runfolder
    from socialnav.data import GEOMETRY_SCENES_DIR, RECORDED_SCENES_DIR, SCENES_DIR
    from socialnav.evaluation.arena import actor_spec
    from socialnav.evaluation.arena.episodes import ArenaConfig
    from socialnav.evaluation.arena.run import HELD_OUT, TURNED
    from socialnav.evaluation.arena.table import POLICY_METHOD, TableRequest, gscl_model
    from socialnav.jaxsim.scenario.errors import ScenarioError
    from socialnav.jaxsim.scenes.reachable import refuse_unfinishable
    from socialnav.jaxsim.scenes.spec import load_scene
    from socialnav.planners.reactive.baselines import BASELINES
    from socialnav.planners.stack import METHODS

    known = [*METHODS, *BASELINES]
    if str(args.out) in ("", "."):
        return _fail("--out must name a folder, not the working directory")
    if args.keep_trajectories < 0:
        return _fail("--keep-trajectories must be >= 0")
    methods = list(args.methods) if args.methods else list(DEFAULT_METHODS)
    unknown = [m for m in methods if m not in known]
    if unknown:
        return _fail(f"--methods: unknown {', '.join(unknown)} (known: {', '.join(known)})")
    try:
        actor_specs = [_absolute_spec(spec) for spec in args.actor]
        actor_names = [actor_spec.name(spec) for spec in actor_specs]
        for spec, actor_name in zip(args.actor, actor_names, strict=True):
            if actor_name in known or actor_names.count(actor_name) > 1:
                raise actor_spec.ActorSpecError(
                    f"--actor {spec}: the name {actor_name!r} is taken (a built-in method or another --actor)"
                )
        for spec in actor_specs:
            actor_spec.load(spec)
    except actor_spec.ActorSpecError as e:
        return _fail(str(e))
    methods += actor_names
    policy_digest = None
    if args.policy_run is not None:
        from socialnav.planners.learning import policy_run

        try:
            policy_digest = policy_run.run_digest(args.policy_run)
        except policy_run.PolicyRunError as e:
            return _fail(f"--policy-run {e}")
        if POLICY_METHOD in methods:
            return _fail(f"--policy-run: the name {POLICY_METHOD!r} is taken by an --actor")
        methods.append(POLICY_METHOD)
    for scene_name, method in args.animate:
        if method not in methods:
            return _fail(f"--animate {scene_name}:{method}: {method} is not among --methods")
    if args.animate and args.keep_trajectories < 1:
        return _fail("--animate needs --keep-trajectories >= 1")
    gscl_run = args.gscl_run
    if args.gscl_rotations != 1 and "gscl" not in methods:
        return _fail("--gscl-rotations: the run has no method gscl")
    if "gscl" in methods and gscl_run is None:
        from socialnav.models.inference import DEFAULT_MODEL

        gscl_run = DEFAULT_MODEL
    from socialnav.evaluation.arena import params as arena_params

    try:
        params = arena_params.ArenaParams() if args.params is None else arena_params.load(args.params)
    except arena_params.ParamsFileError as e:
        return _fail(f"--params {e}")
    people = _human_fit(args)
    if isinstance(people, int):
        return people
    files = _scene_files(args.scenes, SCENES_DIR, RECORDED_SCENES_DIR, GEOMETRY_SCENES_DIR)
    try:
        runfolder.check_inputs(shown_as, [*files, gscl_run, args.params, args.policy_run, people and people.file])
        specs = [load_scene(f) for f in files]
        for spec in specs:  # no method could finish it (or break its rule)
            refuse_unfinishable(spec, params.robot, ArenaConfig().env.goal_tolerance_m)
    except (ScenarioError, runfolder.NotOurs) as e:
        return _fail(str(e))
    if actor_specs:  # each factory called once here: a bad one fails before any work
        from socialnav.evaluation.arena import episodes as arena_lib
        from socialnav.evaluation.arena import run as arena_run

        first = arena_lib.setup_scene(specs[0])
        for spec in actor_specs:
            try:
                arena_run.user_actor(actor_spec.load(spec), first.env, first.n_slots)
            except Exception as e:  # the user's code: any error, named in one line
                return _fail(f"--actor {spec}: {type(e).__name__}: {e}")
    seen: dict[str, pathlib.Path] = {}
    for spec in specs:
        if spec.name in seen:
            return _fail(
                f"{spec.file} and {seen[spec.name]} are both named {spec.name!r}: "
                "a run's scenes need different names (their results are filed under it)"
            )
        seen[spec.name] = spec.file
    rows = {
        *seen,
        *([n + HELD_OUT for n in seen] if args.held_out else []),
        *([n + TURNED for n in seen] if args.turned else []),
    }
    for scene_name, _ in args.animate:
        if scene_name not in rows:
            return _fail(f"--animate {scene_name}: not a scene row of this run")
    if gscl_run is not None:
        from socialnav.models.inference import model_problem

        problem = model_problem(gscl_run)
        if problem:
            return _fail(f"--gscl-run {problem}")
        gscl_run = gscl_run.resolve()  # a Ray worker may start elsewhere
        try:
            gscl_model(gscl_run)  # loads it here first: a bad run fails before any work
        except (FileNotFoundError, ValueError) as e:
            return _fail(f"--gscl-run: {e}")
    return TableRequest(
        specs=tuple(specs),
        methods=tuple(methods),
        variants=args.variants,
        seed=args.seed,
        held_out=args.held_out,
        turned=args.turned,
        shard_variants=args.shard_variants,
        keep_trajectories=args.keep_trajectories,
        gscl_run=gscl_run,
        gscl_rotations=args.gscl_rotations,
        human_model=(args.human_model or "social_force") if people is None else people.model,
        human_values=() if people is None else tuple(sorted(people.values.items())),
        human_fit=None if people is None else f"{people.file.resolve()}:{people.method}",
        params_file=args.params,
        params_text=params.text,
        actor_specs=tuple(actor_specs),
        policy_run=args.policy_run,
        policy_digest=policy_digest,
        animate=tuple(args.animate),
    )


def _human_fit(args):
    """``--human-fit``'s people (:class:`~socialnav.evaluation.humans.fit_file.FittedPeople`),
    None without it, or the exit status of a one-line refusal."""
    if args.human_fit is None:
        return None
    from socialnav.evaluation.humans import fit_file

    try:
        people = fit_file.for_command(args.human_fit, args.human_model)
    except ValueError as e:
        return _fail(str(e))
    print(f"arena: {fit_file.describe(people)}", flush=True)
    return people


def _command(args) -> dict:
    """The command line as ``run.json`` notes it (not compared: a resumed run notes its own)."""
    argv = getattr(args, "argv", None)
    return {} if argv is None else {"command": "socialnav " + shlex.join(argv)}


def _run_into(args, out: pathlib.Path, shown_as: pathlib.Path) -> int:
    """The table of the parsed ``args`` into ``out`` (:func:`evaluation.arena.table.plan_table`,
    the shards on the chosen backend, :func:`~evaluation.arena.table.finish_table`), its refusals
    in the options' words, its tables printed."""
    from socialnav import backend as backend_lib
    from socialnav.evaluation.arena import table
    from socialnav.jaxsim.scenario.errors import ScenarioError

    request = _request(args, shown_as)
    if isinstance(request, int):
        return request
    n_episodes = len(request.runs) * request.variants * len(request.methods)
    # The backend is recorded, not compared: both give the same episodes for the same shards.
    recorded = {**backend_lib.describe(args), **_command(args)}
    try:
        plan = table.plan_table(out, request, recorded)
    except table.TableTooLarge as e:
        return _fail(
            f"--variants {args.variants}: about {e.needed_bytes / 1e9:.1f} GB at once "
            f"({n_episodes:,} episodes' rows and a shard of {request.per_shard:,} variants in flight), this machine "
            f"has {e.available_bytes / 1e9:.1f} GB available; lower --variants, or --shard-variants for the shards"
        )
    except table.SettingsConflict as e:
        return _fail(
            f"{shown_as} holds a run with {e.conflict} ({shown_as / 'run.json'}); "
            "pass --overwrite to replace it whole, or choose another --out"
        )
    except ScenarioError as e:
        return _fail(str(e))
    timeouts_s = [spec.timeout_s for spec in request.specs]
    low, high = table.estimate_s(timeouts_s, len(request.methods), request.variants, request.held_out, request.turned)
    print(
        f"arena: {len(request.runs)} scene run(s) x {len(request.methods)} method(s) x {request.variants} variant(s) "
        f"= {n_episodes:,} episodes; about {_duration(low)} to {_duration(high)} (on 2 cores, compilation included; "
        f"less with programs an earlier run left in the cache), at most {plan.needed_bytes / 1e9:.2f} GB at once",
        flush=True,
    )
    try:
        backend_lib.run_with_args(
            table.compute_shard, table.save_shard, plan.shards, args, desc="arena", unit="episodes"
        )
    except (backend_lib.BackendError, ScenarioError) as e:  # a variant that cannot be drawn: its scene named
        return _fail(str(e))
    _, tables = table.finish_table(out, request, plan)
    _print_tables(tables, [spec.recording["playback"] for spec in request.specs if spec.recording is not None])
    return 0


def _print_tables(tables: dict, playbacks: list[str]) -> None:
    """The summary's main columns, the warnings it calls for, and the papers' tables the run wrote
    (``playbacks``: each recorded scene's, ``"replayed"`` or ``"reactive"``)."""
    import pandas as pd

    summary = tables["summary.csv"]
    shown = [
        "scene",
        "method",
        "n",
        "goal_success_pct",
        "social_success_pct",
        "collisions",
        "intrusions",
        "d_min_m",
        "time_s",
    ]
    if playbacks:  # among recorded crowds: who caused the collisions, the near misses, the effect on people
        shown[5:6] = ["collisions", "collisions_robot", "collisions_person", "near_misses", "people_deviation_m"]
    with pd.option_context("display.width", 250, "display.max_rows", 500):
        print(summary[shown].round(2).to_string(index=False))
    if "replayed" in playbacks:
        print(
            "replayed scenes: the people move as recorded and ignore the robot, so every collision there is the "
            "robot's to avoid (collisions_person counts a recorded person walking into it) and the effect on people "
            "is 0 by construction"
        )
    for row in summary[summary.get("invalid_action_pct", pd.Series(0.0, summary.index)) > 0].itertuples():
        print(
            f"socialnav arena: warning: {row.method} gave a NaN or infinite action in {row.invalid_action_pct:.0f} % "
            f"of {row.scene}'s episodes; the robot was stopped on those steps (invalid_action_steps in "
            "episodes/), so those rows measure a stopped robot, not the method",
            file=sys.stderr,
        )
    for name, title, digits in (
        ("papers.csv", "the papers' numbers and ours (95 % intervals)", 2),
        ("directions.csv", "do the papers' differences reproduce? (proposed - baseline, paired by variant)", 2),
        ("directions_held_out.csv", "the same on the held-out variants (each scene mirrored, its ranges exceeded)", 2),
        ("directions_turned.csv", "the same on the turned variants (each scene a quarter turn, the same draws)", 2),
        ("papers_stats.csv", "seed 002 Table 2 (Games-Howell among its four methods; time in the intimate, "
         "intimate + personal zones)", 4),
    ):  # fmt: skip
        if name in tables:
            print(f"\n{title}:")
            with pd.option_context("display.width", 200, "display.max_rows", 500):
                print(tables[name].round(digits).to_string(index=False))


def _absolute_spec(spec: str) -> str:
    """``spec`` with a file path made absolute (a Ray worker may start elsewhere)."""
    from socialnav.evaluation.arena import actor_spec

    where, function = actor_spec.split(spec)
    if where.endswith(".py"):
        where = str(pathlib.Path(where).resolve())
    return f"{where}:{function}"
