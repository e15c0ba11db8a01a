"""``socialnav arena``: the seeds' methods on the seeds' scenes, in closed loop, many variants each.

socialnav arena --out runs/arena                                   # every scene, every method, 100 variants
socialnav arena --scenes casn_static_person,casn_head_on --methods navfn,casn --variants 20
socialnav arena --scenes my_scene.json --out runs/mine             # a scene file of your own
socialnav arena --gscl-run runs/gscl                               # adds the GSCL method
socialnav arena --held-out                                         # and every scene mirrored, ranges exceeded
socialnav arena --backend ray --shard-variants 25                  # a Ray task per 25 variants of a scene

Writes ``episodes/<scene>.parquet`` (one row per episode: every metric),
``trajectories/<scene>.parquet`` (the first ``--keep-trajectories`` variants, step by step),
``pictures/<scene>_paths.png``, ``_distance.png`` and (with the social band) ``_speed.png``
(variant 0), ``summary.csv`` (one row per scene and method), ``papers.csv`` (the seeds' published
numbers beside ours with our 95 % intervals, for the scenes and methods the run has),
``directions.csv`` (each paper's difference against its baseline and ours, paired by variant,
with a verdict: :func:`evaluation.papers.directions`), ``stats.csv`` (Fisher, Welch ANOVA,
Games-Howell, Hedges' g: :mod:`evaluation.arena_stats`) and ``run.json`` (the settings, the
backend and the shard layout). Work is cut into shards (``--shard-variants`` variants of one
scene; :mod:`socialnav.backend` runs them here or as Ray tasks), each saved atomically under
``shards/`` as it finishes, then joined per scene; a rerun with the same settings computes only
the missing shards and scenes.
"""

from __future__ import annotations

import argparse
import functools
import json
import pathlib
import sys

from socialnav.argtypes import comma_names, output_folder, positive_int
from socialnav.backend import add_backend_options
from socialnav.locking import locks_folder

DEFAULT_METHODS = ("navfn", "snl_small", "snl_large", "snl_matched", "casn", "snape_eband", "snape_social_eband")


def add_parser(sub) -> None:
    p = sub.add_parser(
        "arena",
        help="run navigation methods on the social-navigation scenes, many variants each",
        description="Every chosen method on every chosen scene (data/scenes/*.json or your own files), "
        "N seeded variants each, in closed loop; per-episode metrics, trajectories and a summary.",
    )
    p.add_argument(
        "--scenes", type=comma_names, default=None, help="scene names or .json files (default: all built-in)"
    )
    p.add_argument(
        "--methods",
        type=comma_names,
        default=None,
        help=f"methods (default: {','.join(DEFAULT_METHODS)}; gscl too with --gscl-run)",
    )
    p.add_argument("--variants", type=positive_int, default=100, help="variants per scene (default 100)")
    p.add_argument("--seed", type=int, default=0, help="random seed of the variants (default 0)")
    p.add_argument(
        "--out", type=output_folder, default=pathlib.Path("runs/arena"), help="output folder (default runs/arena)"
    )
    p.add_argument("--gscl-run", type=pathlib.Path, default=None, help="a trained GSCL run folder (enables 'gscl')")
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
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    add_backend_options(p)
    p.set_defaults(handler=run)


def _scene_method(text: str) -> tuple[str, str]:
    scene, sep, method = text.partition(":")
    if not sep or not scene or not method:
        raise argparse.ArgumentTypeError(f"expected SCENE:METHOD, got {text!r}")
    return scene, method


def _scene_files(names, scenes_dir: pathlib.Path) -> list[pathlib.Path]:
    if names is None:
        return sorted(scenes_dir.glob("*.json"))
    files = []
    for name in names:
        path = pathlib.Path(name)
        files.append(path if path.suffix == ".json" else scenes_dir / f"{name}.json")
    return files


@locks_folder(lambda args: args.out, "arena")
def run(args) -> int:
    from common.atomic import write_atomic, write_text_atomic
    from data import SCENES_DIR
    from jaxsim.scenario.errors import ScenarioError
    from jaxsim.scenes.spec import load_scene
    from planners.stack import METHODS
    from socialnav import backend as backend_lib

    if str(args.out) in ("", "."):
        print("socialnav arena: --out must name a folder, not the working directory", file=sys.stderr)
        return 2
    if args.shard_variants is None:
        args.shard_variants = args.variants
    if args.keep_trajectories < 0:
        print("socialnav arena: --keep-trajectories must be >= 0", file=sys.stderr)
        return 2
    methods = list(args.methods) if args.methods else list(DEFAULT_METHODS) + (["gscl"] if args.gscl_run else [])
    unknown = [m for m in methods if m not in METHODS]
    if unknown:
        print(
            f"socialnav arena: --methods: unknown {', '.join(unknown)} (known: {', '.join(METHODS)})", file=sys.stderr
        )
        return 2
    for scene_name, method in args.animate:
        if method not in methods:
            print(f"socialnav arena: --animate {scene_name}:{method}: {method} is not among --methods", file=sys.stderr)
            return 2
    if args.animate and args.keep_trajectories < 1:
        print("socialnav arena: --animate needs --keep-trajectories >= 1", file=sys.stderr)
        return 2
    if "gscl" in methods and args.gscl_run is None:
        print("socialnav arena: --methods gscl needs --gscl-run RUN (a trained GSCL run folder)", file=sys.stderr)
        return 2
    try:
        specs = [load_scene(f) for f in _scene_files(args.scenes, SCENES_DIR)]
    except ScenarioError as e:
        print(f"socialnav arena: {e}", file=sys.stderr)
        return 2
    if args.gscl_run is not None:
        if not (args.gscl_run / "checkpoints").is_dir():
            print(
                f"socialnav arena: {args.gscl_run}: no checkpoints/ folder (train one with socialnav gscl train)",
                file=sys.stderr,
            )
            return 2
        args.gscl_run = args.gscl_run.resolve()  # a Ray worker may start elsewhere
        _gscl_predict(args.gscl_run)  # loads it here first: a bad run fails before any work

    import pandas as pd

    from common import __version__
    from evaluation import arena_report, arena_stats, nav_metrics, papers

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
        "metrics_version": nav_metrics.VERSION,
        "socialnav_version": __version__,
    }
    meta = args.out / "run.json"
    if meta.exists():
        try:
            previous = json.loads(meta.read_text())
        except (OSError, json.JSONDecodeError):
            previous = None
        if not isinstance(previous, dict) or {k: previous.get(k) for k in settings} != settings:
            print(
                f"socialnav arena: {args.out} holds a run with other settings ({meta}); choose another --out",
                file=sys.stderr,
            )
            return 2
    args.out.mkdir(parents=True, exist_ok=True)
    # The backend is recorded, not compared: both give the same episodes for the same shards.
    write_text_atomic(meta, json.dumps({**settings, **backend_lib.describe(args)}, indent=1) + "\n")

    runs = [(spec, False) for spec in specs] + ([(spec, True) for spec in specs] if args.held_out else [])
    names = [spec.name + (arena_report.HELD_OUT if held_out else "") for spec, held_out in runs]
    shards = []
    for (spec, held_out), name in zip(runs, names, strict=True):
        if (args.out / "episodes" / f"{name}.parquet").exists():
            continue  # the whole scene is done
        for first in range(0, args.variants, args.shard_variants):
            n = min(args.shard_variants, args.variants - first)
            shards.append(
                backend_lib.Shard(
                    name=f"{name}[{first}:{first + n}]",
                    output=_shard_file(args.out, name, first),
                    args=(spec, held_out, first, n, tuple(methods), args.seed, args.keep_trajectories, args.gscl_run),
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
        episodes_file = args.out / "episodes" / f"{name}.parquet"
        if not episodes_file.exists():
            _finish_scene(args, spec, held_out, name, methods)
        frames.append(pd.read_parquet(episodes_file))
    summary = arena_report.summary(pd.concat(frames, ignore_index=True))
    write_atomic(args.out / "summary.csv", lambda tmp: summary.to_csv(tmp, index=False))
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
    with pd.option_context("display.width", 200, "display.max_rows", 500):
        print(summary[shown].round(2).to_string(index=False))
    statistics = arena_stats.scene_statistics(pd.concat(frames, ignore_index=True))
    write_atomic(args.out / "stats.csv", lambda tmp: statistics.to_csv(tmp, index=False))
    compared = papers.comparison(summary).dropna(subset=["ours"])
    if len(compared):
        write_atomic(args.out / "papers.csv", lambda tmp: compared.to_csv(tmp, index=False))
        print("\nthe papers' numbers and ours (95 % intervals):")
        with pd.option_context("display.width", 200, "display.max_rows", 500):
            print(compared.round(2).to_string(index=False))
    turned = papers.directions(pd.concat(frames, ignore_index=True))
    if len(turned):
        write_atomic(args.out / "directions.csv", lambda tmp: turned.to_csv(tmp, index=False))
        print("\ndo the papers' differences reproduce? (proposed - baseline, paired by variant)")
        with pd.option_context("display.width", 200, "display.max_rows", 500):
            print(turned.round(2).to_string(index=False))
    print(f"wrote {args.out}/summary.csv, stats.csv, papers.csv, directions.csv, episodes/ and trajectories/")
    return 0


def _shard_file(out: pathlib.Path, name: str, first: int) -> pathlib.Path:
    return out / "shards" / name / f"{first:06d}.parquet"


@functools.lru_cache(maxsize=4)
def _gscl_predict(run: pathlib.Path | None):
    if run is None:
        return None
    from models.inference import SocialCostModel

    return SocialCostModel.load(run).function


def compute_shard(spec, held_out, first, n, methods, seed, keep_trajectories, gscl_run):
    """One shard: every method on variants ``first .. first + n - 1`` of a scene (a Ray task with
    ``--backend ray``): ``(episodes frame, trajectories frame or None)``."""
    from evaluation import arena_report

    keep = max(0, min(n, keep_trajectories - first))
    return arena_report.run_scene(spec, list(methods), n, seed, first, keep, _gscl_predict(gscl_run), held_out=held_out)


def _save_shard(shard, result) -> None:
    from common.atomic import write_atomic

    episodes, trajectories = result
    if trajectories is not None:
        write_atomic(shard.output.with_suffix(".trajectories.parquet"), trajectories.to_parquet)
    write_atomic(shard.output, episodes.to_parquet)  # last: its presence marks the shard done


def _finish_scene(args, spec, held_out, name, methods) -> None:
    """Join a scene's shards into ``episodes/<name>.parquet`` and ``trajectories/``, draw its
    pictures, then remove the shards (the episodes file last: its presence marks the scene done)."""
    import shutil

    import pandas as pd

    from common.atomic import write_atomic
    from evaluation import arena_plots
    from jaxsim.scenes.spec import mirror

    folder = args.out / "shards" / name
    parts = sorted(folder.glob("[0-9]*[0-9].parquet"))
    episodes = pd.concat([pd.read_parquet(f) for f in parts], ignore_index=True)
    kept = [pd.read_parquet(f) for f in sorted(folder.glob("*.trajectories.parquet"))]
    order = {m: k for k, m in enumerate(methods)}
    episodes = episodes.sort_values(["method", "variant"], key=lambda c: c.map(order) if c.name == "method" else c)
    episodes = episodes.reset_index(drop=True)
    if kept:
        trajectories = pd.concat(kept, ignore_index=True)
        drawn = mirror(spec) if held_out else spec
        write_atomic(args.out / "trajectories" / f"{name}.parquet", trajectories.to_parquet)
        pictures = args.out / "pictures"
        arena_plots.paths_figure(drawn, trajectories, pictures / f"{name}_paths.png")
        arena_plots.distance_figure(drawn, trajectories, pictures / f"{name}_distance.png")
        if "snape_social_eband" in methods:
            arena_plots.speed_figure(drawn, trajectories, "snape_social_eband", pictures / f"{name}_speed.png")
        for scene_name, method in args.animate:
            if scene_name == name:
                arena_plots.animation(drawn, trajectories, method, pictures / f"{name}_{method}.gif")
    write_atomic(args.out / "episodes" / f"{name}.parquet", episodes.to_parquet)
    shutil.rmtree(folder, ignore_errors=True)
    if args.out.joinpath("shards").is_dir() and not any(args.out.joinpath("shards").iterdir()):
        args.out.joinpath("shards").rmdir()
