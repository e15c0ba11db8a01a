"""``socialnav arena``: the seeds' methods on the seeds' scenes, in closed loop, many variants each.

socialnav arena --out runs/arena                                   # every scene, every method, 100 variants
socialnav arena --scenes casn_static_person,casn_head_on --methods navfn,casn --variants 20
socialnav arena --scenes my_scene.json --out runs/mine             # a scene file of your own
socialnav arena --gscl-run runs/gscl                               # GSCL with your own model, not the shipped one
socialnav arena --params my_params.toml                            # the robot's and layers' parameters
socialnav arena --held-out                                         # and every scene mirrored, ranges exceeded
socialnav arena --backend ray --shard-variants 25                  # a Ray task per 25 variants of a scene

Writes ``episodes/<scene>.parquet`` (one row per episode: every metric),
``trajectories/<scene>.parquet`` (the first ``--keep-trajectories`` variants, step by step),
``pictures/<scene>_paths.png``, ``_distance.png`` and (with the social band) ``_speed.png``
(variant 0), ``summary.csv`` (one row per scene and method), ``papers.csv`` (the seeds' published
numbers beside ours with our 95 % intervals, for the scenes and methods the run has),
``directions.csv`` (each paper's difference against its baseline and ours, paired by variant,
with a verdict: :func:`evaluation.arena.papers.directions`), ``papers_stats.csv`` (seed 002's Table 2,
its Games-Howell p and Hedges' g beside ours: :func:`evaluation.arena.papers.stats_comparison`),
``stats.csv`` (Fisher, Welch ANOVA,
Games-Howell, Hedges' g: :mod:`evaluation.arena.stats`) and ``run.json`` (the settings, the
backend and the shard layout). Work is cut into shards (``--shard-variants`` variants of one
scene; :mod:`socialnav.backend` runs them here or as Ray tasks), each saved atomically under
``shards/`` as it finishes, then joined per scene; a rerun with the same settings computes only
the missing shards and scenes.
"""

from __future__ import annotations

import argparse
import functools
import hashlib
import json
import pathlib
import sys

from socialnav import actor_spec
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
        "(data/scenes/recorded: ETH/UCY and Jülich crowds, replayed and reactive)",
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
        default="social_force",
        help="how the people move: the warehouse's social force (default), ORCA, or a velocity model with bodies "
        "(collision_free_speed, anticipation, and their _calibrated fits: docs/humans.md measures each against real "
        "pedestrians)",
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


def _scene_files(names, scenes_dir: pathlib.Path, recorded_dir: pathlib.Path | None = None) -> list[pathlib.Path]:
    """The files of ``names`` (None: every seed scene): a ``.json`` path as given, a name in
    ``recorded_dir`` if it is there and in ``scenes_dir`` otherwise (a missing one is reported
    there), :data:`RECORDED` every file of ``recorded_dir``."""
    if names is None:
        return sorted(scenes_dir.glob("*.json"))
    files = []
    for name in names:
        path = pathlib.Path(name)
        if path.suffix == ".json":
            files.append(path)
        elif recorded_dir is not None and name == RECORDED:
            files.extend(sorted(recorded_dir.glob("*.json")))
        elif recorded_dir is not None and (recorded_dir / f"{name}.json").is_file():
            files.append(recorded_dir / f"{name}.json")
        else:
            files.append(scenes_dir / f"{name}.json")
    return files


JOB = "socialnav arena"
# What an arena run leaves at the top of its folder (run.json first, summary.csv last).
RESULTS = (
    "run.json",
    "summary.csv",
    "stats.csv",
    "papers.csv",
    "directions.csv",
    "papers_stats.csv",
    "episodes",
    "trajectories",
    "pictures",
    "shards",
)
# The time printed before a run, as a range on this project's 2-core machine: start-up, then a
# compilation per program (one per scene file and method, and two per scene for the people
# without the robot and the metrics; a held-out mirror shares its scene's), then the simulated
# seconds of every episode. Measured here with no compilation cache
# (SOCIALNAV_JAX_CACHE=off): seed 001's four scenes x 11 methods in 75 s at 2 variants and 89 s
# at 50 (1.2 s a program; the 48 variants more, 84,000 simulated seconds, at 6,000 a second);
# the default table with --held-out x 100 variants took 9.3 min (docs/arena-results.md). The
# ends below widen those figures (a loaded machine, slower scenes); the estimate they replace,
# episodes / 55 per second, said 40 s for a run of minutes. An earlier run's programs in the
# compilation cache can beat the low end.
STARTUP_S = 10.0
COMPILE_S_PER_PROGRAM = (0.7, 2.0)
SIMULATED_S_PER_S = (6000.0, 2000.0)  # the fast end first: it gives the low estimate


def estimate_s(specs, n_methods: int, variants: int, held_out: bool) -> tuple[float, float]:
    """``(low, high)`` seconds a run of ``specs`` x ``n_methods`` x ``variants`` takes here
    (see the constants above)."""
    programs = len(specs) * (n_methods + 2)
    simulated = sum(spec.timeout_s for spec in specs) * (2 if held_out else 1) * variants * n_methods
    return tuple(
        STARTUP_S + programs * c + simulated / rate for c, rate in zip(COMPILE_S_PER_PROGRAM, SIMULATED_S_PER_S)
    )


def _duration(seconds: float) -> str:
    return f"{seconds / 60:.1f} min" if seconds >= 90 else f"{seconds:.0f} s"


# Bytes a finished episode's row costs in the joined tables: 146 measured in memory
# (``memory_usage(deep=True)``, 26 columns, 80 episodes of casn_head_on and casn_crossing), times
# about four for the copies the joins, the summary and the statistics make.
EPISODE_ROW_BYTES = 600


@locks_folder(lambda args: args.out, "arena")
def run(args) -> int:
    from socialnav.common import runfolder

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
    ``papers_stats.csv`` only where the run has scenes of the papers)."""
    names = ["summary.csv", "stats.csv", "papers.csv", "directions.csv", "papers_stats.csv", "episodes/"]
    names += ["trajectories/", "pictures/"]
    there = [n for n in names if (pathlib.Path(out) / n.rstrip("/")).exists()]
    return f"wrote {out}/" + ", ".join(there)


class _Failed(Exception):
    """A check of the run failed (already reported); the staged run is dropped."""

    def __init__(self, code: int):
        self.code = code


def scene_digest(spec_file: pathlib.Path, held_out: bool, settings: dict) -> str:
    """A scene's results are these when this digest matches: the scene file's bytes, the held-out
    flag, and every setting that changes an episode (methods, variants, seed, shard layout, the
    GSCL model, the source files of the ``--actor`` factories, the human model, the ``--params``
    file's text, the metrics' and the toolkit's versions)."""
    h = hashlib.sha256()
    h.update(pathlib.Path(spec_file).read_bytes())
    keys = (
        "methods",
        "variants",
        "seed",
        "shard_variants",
        "keep_trajectories",
        "gscl_model",
        "actor_sources",
        "human_model",
        "params",
    )
    chosen = {k: settings.get(k) for k in keys}
    if settings.get("policy_model") is not None:  # absent without --policy-run: earlier digests stay valid
        chosen["policy_model"] = settings["policy_model"]
    h.update(json.dumps({"held_out": held_out, **chosen}, sort_keys=True).encode())
    h.update(json.dumps([settings["metrics_version"], settings["socialnav_version"]]).encode())
    return h.hexdigest()[:16]


def _run_into(args, out: pathlib.Path, shown_as: pathlib.Path) -> int:
    from socialnav import backend as backend_lib
    from socialnav.common import runfolder
    from socialnav.common.atomic import write_atomic, write_text_atomic
    from socialnav.common.memory import available_bytes
    from socialnav.data import RECORDED_SCENES_DIR, SCENES_DIR
    from socialnav.jaxsim.scenario.errors import ScenarioError
    from socialnav.jaxsim.scenes.spec import load_scene
    from socialnav.planners.reactive.baselines import BASELINES
    from socialnav.planners.stack import METHODS

    known = [*METHODS, *BASELINES]

    if str(args.out) in ("", "."):
        print("socialnav arena: --out must name a folder, not the working directory", file=sys.stderr)
        return 2
    if args.shard_variants is None:
        args.shard_variants = args.variants
    if args.keep_trajectories < 0:
        print("socialnav arena: --keep-trajectories must be >= 0", file=sys.stderr)
        return 2
    methods = list(args.methods) if args.methods else list(DEFAULT_METHODS)
    unknown = [m for m in methods if m not in known]
    if unknown:
        print(f"socialnav arena: --methods: unknown {', '.join(unknown)} (known: {', '.join(known)})", file=sys.stderr)
        return 2
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
        print(f"socialnav arena: {e}", file=sys.stderr)
        return 2
    methods += actor_names
    policy_digest = None
    if args.policy_run is not None:
        from socialnav.planners.learning import policy_run

        try:
            policy_digest = policy_run.run_digest(args.policy_run)
        except policy_run.PolicyRunError as e:
            print(f"socialnav arena: --policy-run {e}", file=sys.stderr)
            return 2
        if POLICY_METHOD in methods:
            print(f"socialnav arena: --policy-run: the name {POLICY_METHOD!r} is taken by an --actor", file=sys.stderr)
            return 2
        methods.append(POLICY_METHOD)
    for scene_name, method in args.animate:
        if method not in methods:
            print(f"socialnav arena: --animate {scene_name}:{method}: {method} is not among --methods", file=sys.stderr)
            return 2
    if args.animate and args.keep_trajectories < 1:
        print("socialnav arena: --animate needs --keep-trajectories >= 1", file=sys.stderr)
        return 2
    if "gscl" in methods and args.gscl_run is None:
        from socialnav.models.inference import DEFAULT_MODEL

        args.gscl_run = DEFAULT_MODEL
    from socialnav.evaluation.arena import params as arena_params

    try:
        params = arena_params.ArenaParams() if args.params is None else arena_params.load(args.params)
    except arena_params.ParamsFileError as e:
        print(f"socialnav arena: --params {e}", file=sys.stderr)
        return 2
    files = _scene_files(args.scenes, SCENES_DIR, RECORDED_SCENES_DIR)
    try:
        runfolder.check_inputs(shown_as, [*files, args.gscl_run, args.params, args.policy_run])
        specs = [load_scene(f) for f in files]
    except ScenarioError as e:
        print(f"socialnav arena: {e}", file=sys.stderr)
        return 2
    except runfolder.NotOurs as e:
        print(f"socialnav arena: {e}", file=sys.stderr)
        return 2
    if actor_specs:  # each factory called once here: a bad one fails before any work
        from socialnav.evaluation.arena import episodes as arena_lib
        from socialnav.evaluation.arena import run as arena_run

        first = arena_lib.setup_scene(specs[0])
        for spec in actor_specs:
            try:
                arena_run.user_actor(actor_spec.load(spec), first.env, first.n_slots)
            except Exception as e:  # the user's code: any error, named in one line
                print(f"socialnav arena: --actor {spec}: {type(e).__name__}: {e}", file=sys.stderr)
                return 2
    seen: dict[str, pathlib.Path] = {}
    for spec in specs:
        if spec.name in seen:
            print(
                f"socialnav arena: {spec.file} and {seen[spec.name]} are both named {spec.name!r}: "
                "a run's scenes need different names (their results are filed under it)",
                file=sys.stderr,
            )
            return 2
        seen[spec.name] = spec.file
    for scene_name, _ in args.animate:
        if scene_name.removesuffix(_HELD_OUT) not in seen:
            print(f"socialnav arena: --animate {scene_name}: not a scene of this run", file=sys.stderr)
            return 2
    runs = [(spec, False) for spec in specs] + ([(spec, True) for spec in specs] if args.held_out else [])
    n_episodes = len(runs) * args.variants * len(methods)
    needed = _memory_bytes(specs, args, len(methods))
    available = available_bytes()
    if available is not None and needed > 0.8 * available:
        print(
            f"socialnav arena: --variants {args.variants}: about {needed / 1e9:.1f} GB at once "
            f"({n_episodes:,} episodes' rows and a shard of {args.shard_variants:,} variants in flight), this machine "
            f"has {available / 1e9:.1f} GB available; lower --variants, or --shard-variants for the shards",
            file=sys.stderr,
        )
        return 2
    if args.gscl_run is not None:
        from socialnav.models.inference import model_problem

        problem = model_problem(args.gscl_run)
        if problem:
            print(f"socialnav arena: --gscl-run {problem}", file=sys.stderr)
            return 2
        args.gscl_run = args.gscl_run.resolve()  # a Ray worker may start elsewhere
        try:
            _gscl_model(args.gscl_run)  # loads it here first: a bad run fails before any work
        except (FileNotFoundError, ValueError) as e:
            print(f"socialnav arena: --gscl-run: {e}", file=sys.stderr)
            return 2

    import pandas as pd

    from socialnav.common import __version__
    from socialnav.evaluation.arena import nav_metrics, papers
    from socialnav.evaluation.arena import report as arena_report
    from socialnav.evaluation.arena import run as arena_run
    from socialnav.evaluation.arena import stats as arena_stats
    from socialnav.models.inference import model_identity

    settings = {
        "scenes": [s.name for s in specs],
        "scene_files": [str(s.file) for s in specs],
        "methods": methods,
        "variants": args.variants,
        "seed": args.seed,
        "keep_trajectories": args.keep_trajectories,
        "held_out": args.held_out,
        "shard_variants": args.shard_variants,
        "gscl_run": None if args.gscl_run is None else str(args.gscl_run),
        "gscl_model": None if args.gscl_run is None else model_identity(args.gscl_run),
        "human_model": args.human_model,
        "params_file": None if args.params is None else str(args.params),
        "params": params.text or None,  # None without a file: earlier runs' digests stay valid
        "actors": actor_specs,
        "actor_sources": [actor_spec.source_digest(spec) for spec in actor_specs],
        **({} if policy_digest is None else {"policy_run": str(args.policy_run), "policy_model": policy_digest}),
        "metrics_version": nav_metrics.VERSION,
        "socialnav_version": __version__,
    }
    names = [spec.name + (arena_run.HELD_OUT if held_out else "") for spec, held_out in runs]
    digests = {name: scene_digest(spec.file, held_out, settings) for (spec, held_out), name in zip(runs, names)}
    settings["scene_digests"] = digests
    settings["scene_file_digests"] = {s.name: hashlib.sha256(s.file.read_bytes()).hexdigest()[:16] for s in specs}
    meta = out / "run.json"
    if meta.exists():
        try:
            previous = json.loads(meta.read_text())
        except (OSError, json.JSONDecodeError):
            previous = None
        differs = [k for k in settings if not isinstance(previous, dict) or previous.get(k) != settings[k]]
        if differs:
            files_before = previous.get("scene_file_digests") or {} if isinstance(previous, dict) else {}
            changed = [n for n, d in settings["scene_file_digests"].items() if files_before.get(n) not in (None, d)]
            what = f"other settings ({', '.join(differs)})"
            if changed:
                what = f"scene file(s) changed since: {', '.join(changed)}"
            print(
                f"socialnav arena: {shown_as} holds a run with {what} ({shown_as / 'run.json'}); "
                "pass --overwrite to replace it whole, or choose another --out",
                file=sys.stderr,
            )
            return 2
    low, high = estimate_s(specs, len(methods), args.variants, args.held_out)
    print(
        f"arena: {len(runs)} scene run(s) x {len(methods)} method(s) x {args.variants} variant(s) = {n_episodes:,} "
        f"episodes; about {_duration(low)} to {_duration(high)} (on 2 cores, compilation included; less with programs "
        f"an earlier run left in the cache), at most {needed / 1e9:.2f} GB at once",
        flush=True,
    )
    out.mkdir(parents=True, exist_ok=True)
    # The backend is recorded, not compared: both give the same episodes for the same shards.
    write_text_atomic(meta, json.dumps({**settings, **backend_lib.describe(args)}, indent=1) + "\n")
    runfolder.record(out, JOB, ["run.json", "shards/"])

    shards = []
    # A scene and its held-out mirror one after the other: they share their compiled programs,
    # which the arena may drop between scenes (evaluation.arena.episodes.release_programs_if_crowded).
    position = {id(spec): k for k, spec in enumerate(specs)}
    order = sorted(range(len(runs)), key=lambda i: (position[id(runs[i][0])], runs[i][1]))
    for (spec, held_out), name in ((runs[i], names[i]) for i in order):
        if _finished(out, name, digests[name]):
            continue  # the whole scene is done, with these settings
        for first in range(0, args.variants, args.shard_variants):
            n = min(args.shard_variants, args.variants - first)
            shards.append(
                backend_lib.Shard(
                    name=f"{name}[{first}:{first + n}]",
                    output=runfolder.inside(out, _shard_file(out, name, digests[name], first)),
                    args=(
                        spec,
                        held_out,
                        first,
                        n,
                        tuple(methods),
                        args.seed,
                        args.keep_trajectories,
                        args.gscl_run,
                        tuple(actor_specs),
                        args.human_model,
                        params.text or "",
                        None if args.policy_run is None else str(args.policy_run.resolve()),
                    ),
                    work=n * len(methods),
                )
            )
    try:
        backend_lib.run_with_args(compute_shard, _save_shard, shards, args, desc="arena", unit="episodes")
    except backend_lib.BackendError as e:
        print(f"socialnav arena: {e}", file=sys.stderr)
        return 2
    frames = []
    for (spec, held_out), name in zip(runs, names, strict=True):
        episodes_file = runfolder.inside(out, out / "episodes" / f"{name}.parquet")
        if not _finished(out, name, digests[name]):
            _finish_scene(args, out, spec, held_out, name, methods, digests[name])
        frames.append(pd.read_parquet(episodes_file))
    episodes = pd.concat(frames, ignore_index=True)
    summary = arena_report.summary(episodes)
    write_atomic(out / "summary.csv", lambda tmp: summary.to_csv(tmp, index=False))
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
    recorded_specs = [spec for spec in specs if spec.recording is not None]
    if recorded_specs:  # among recorded crowds: who caused the collisions, the near misses, the effect on people
        shown[5:6] = ["collisions", "collisions_robot", "collisions_person", "near_misses", "people_deviation_m"]
    with pd.option_context("display.width", 250, "display.max_rows", 500):
        print(summary[shown].round(2).to_string(index=False))
    if any(spec.recording["playback"] == "replayed" for spec in recorded_specs):
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
    statistics = arena_stats.scene_statistics(episodes)
    write_atomic(out / "stats.csv", lambda tmp: statistics.to_csv(tmp, index=False))
    written = ["summary.csv", "stats.csv"]
    if len(summary):
        from socialnav.evaluation.arena import plots as arena_plots

        arena_plots.methods_figure(summary, runfolder.inside(out, out / "pictures" / "methods.png"))
        written.append("pictures/methods.png")
    # The papers' tables, each written and printed where the run has their scenes.
    for name, table, title, digits in (
        ("papers.csv", papers.comparison(summary).dropna(subset=["ours"]),
         "the papers' numbers and ours (95 % intervals)", 2),
        ("directions.csv", papers.directions(episodes),
         "do the papers' differences reproduce? (proposed - baseline, paired by variant)", 2),
        ("papers_stats.csv", papers.stats_comparison(episodes),
         "seed 002 Table 2 (Games-Howell among its four methods; time in the intimate, intimate + personal zones)", 4),
    ):  # fmt: skip
        if not len(table):
            continue
        write_atomic(out / name, lambda tmp, table=table: table.to_csv(tmp, index=False))
        written.append(name)
        print(f"\n{title}:")
        with pd.option_context("display.width", 200, "display.max_rows", 500):
            print(table.round(digits).to_string(index=False))
    runfolder.record(out, JOB, written)
    return 0


_HELD_OUT = "@held_out"


def _memory_bytes(specs, args, n_methods: int) -> float:
    """What a run holds at once: every episode's row in the joined tables, and one shard's
    variants in flight (their trajectories, T steps of the robot and every person slot, and the
    planner's grids, a few (H, W) float32 maps per variant)."""
    from socialnav.evaluation.arena.episodes import ArenaConfig

    config = ArenaConfig()
    scenes = len(specs) * (2 if args.held_out else 1)
    rows = scenes * args.variants * n_methods * EPISODE_ROW_BYTES
    flight = 0.0
    for spec in specs:
        steps = spec.timeout_s / config.dt_s
        xmin, xmax, ymin, ymax = spec.bounds_m
        cells = (xmax - xmin) * (ymax - ymin) / config.grid_resolution_m**2
        per_variant = steps * (48 + 24 * spec.n_people_slots) + 16 * cells * 4
        flight = max(flight, per_variant * min(args.shard_variants or args.variants, args.variants))
    return rows + flight


def _finished(out: pathlib.Path, name: str, digest: str) -> bool:
    """A scene's episodes file exists and was made with these settings (its ``scene_digest``)."""
    import pyarrow.parquet as pq

    path = out / "episodes" / f"{name}.parquet"
    if not path.is_file():
        return False
    try:
        metadata = pq.read_schema(path).metadata or {}
        attrs = json.loads(metadata.get(b"PANDAS_ATTRS", b"{}"))
    except (OSError, ValueError):
        return False
    return attrs.get("scene_digest") == digest


def _shard_file(out: pathlib.Path, name: str, digest: str, first: int) -> pathlib.Path:
    """A shard's episodes file: under a folder named by its scene and the digest of what made it,
    so a shard of an edited scene or of other settings is never joined with these."""
    return out / "shards" / f"{name}-{digest}" / f"{first:06d}.parquet"


@functools.lru_cache(maxsize=4)
def _gscl_model(run: pathlib.Path | None):
    if run is None:
        return None
    from socialnav.models.inference import SocialCostModel

    return SocialCostModel.load(run)


def compute_shard(
    spec,
    held_out,
    first,
    n,
    methods,
    seed,
    keep_trajectories,
    gscl_run,
    actor_specs=(),
    human_model="social_force",
    params_text="",
    policy_run=None,
):
    """One shard: every method on variants ``first .. first + n - 1`` of a scene (a Ray task with
    ``--backend ray``): ``(episodes frame, trajectories frame or None)``. ``actor_specs``: the
    ``--actor`` factories, loaded here (in the worker); ``params_text``: the ``--params`` file's
    text (parsed here, so a worker needs no access to the file); ``policy_run``: a trained
    policy's run folder (``--policy-run``), restored here. The GSCL weights enter the
    episode program traced: a second checkpoint of the same network compiles nothing new."""
    from socialnav.evaluation.arena import params as arena_params
    from socialnav.evaluation.arena import run as arena_run
    from socialnav.evaluation.arena.episodes import ArenaConfig

    keep = max(0, min(n, keep_trajectories - first))
    users = {actor_spec.name(text): actor_spec.load(text) for text in actor_specs}
    if policy_run is not None:
        from socialnav.planners.learning.policy_run import actor_factory

        users[POLICY_METHOD] = actor_factory(policy_run, POLICY_METHOD)
    return arena_run.run_scene(
        spec,
        list(methods),
        n,
        seed,
        first,
        keep,
        _gscl_model(gscl_run),
        ArenaConfig(human_model=human_model),
        held_out=held_out,
        user_actors=users,
        params=arena_params.parse(params_text, "--params") if params_text else None,
    )


def _absolute_spec(spec: str) -> str:
    """``spec`` with a file path made absolute (a Ray worker may start elsewhere)."""
    where, function = actor_spec.split(spec)
    if where.endswith(".py"):
        where = str(pathlib.Path(where).resolve())
    return f"{where}:{function}"


def _save_shard(shard, result) -> None:
    from socialnav.common.atomic import write_atomic

    episodes, trajectories = result
    if trajectories is not None:
        write_atomic(shard.output.with_suffix(".trajectories.parquet"), trajectories.to_parquet)
    write_atomic(shard.output, episodes.to_parquet)  # last: its presence marks the shard done


def _finish_scene(args, out, spec, held_out, name, methods, digest) -> None:
    """Join a scene's shards into ``episodes/<name>.parquet`` and ``trajectories/``, draw its
    pictures, then remove the shards (the episodes file last: its presence, with the scene's
    digest in its metadata, marks the scene done)."""
    import shutil

    import pandas as pd

    from socialnav.common import runfolder
    from socialnav.common.atomic import write_atomic
    from socialnav.evaluation.arena import plots as arena_plots
    from socialnav.jaxsim.scenes.spec import mirror

    folder = runfolder.inside(out, out / "shards" / f"{name}-{digest}")
    parts = sorted(folder.glob("[0-9]*[0-9].parquet"))
    episodes = pd.concat([pd.read_parquet(f) for f in parts], ignore_index=True)
    kept = [pd.read_parquet(f) for f in sorted(folder.glob("*.trajectories.parquet"))]
    order = {m: k for k, m in enumerate(methods)}
    episodes = episodes.sort_values(["method", "variant"], key=lambda c: c.map(order) if c.name == "method" else c)
    episodes = episodes.reset_index(drop=True)
    episodes.attrs = {"scene_digest": digest}
    written = []
    if kept:
        trajectories = pd.concat(kept, ignore_index=True)
        drawn = mirror(spec) if held_out else spec
        write_atomic(runfolder.inside(out, out / "trajectories" / f"{name}.parquet"), trajectories.to_parquet)
        written.append(f"trajectories/{name}.parquet")
        pictures = out / "pictures"
        drawings = [
            (arena_plots.paths_figure, f"{name}_paths.png", ()),
            (arena_plots.distance_figure, f"{name}_distance.png", ()),
        ]
        if "snape_social_eband" in methods:
            drawings.append((arena_plots.speed_figure, f"{name}_speed.png", ("snape_social_eband",)))
        for draw, file, extra in drawings:
            draw(drawn, trajectories, *extra, runfolder.inside(out, pictures / file))
            written.append(f"pictures/{file}")
        for scene_name, method in args.animate:
            if scene_name == name:
                gif = runfolder.inside(out, pictures / f"{name}_{method}.gif")
                arena_plots.animation(drawn, trajectories, method, gif)
                written.append(f"pictures/{gif.name}")
    runfolder.record(out, JOB, [*written, f"episodes/{name}.parquet"])
    write_atomic(runfolder.inside(out, out / "episodes" / f"{name}.parquet"), episodes.to_parquet)
    shutil.rmtree(folder, ignore_errors=True)
    if out.joinpath("shards").is_dir() and not any(out.joinpath("shards").iterdir()):
        out.joinpath("shards").rmdir()
