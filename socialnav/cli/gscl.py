"""``socialnav gscl``: GSCL's social cost-map learner on the command line (seed 002).

socialnav gscl generate --out runs/gscl.npz                 # the paper's 24,200 pairs in one file
socialnav gscl generate --out big.npz --scale 100 --backend ray --shard-samples 8192   # on a Ray cluster
socialnav gscl train --out runs/gscl                        # the CPU recipe; run again to resume
socialnav gscl train --out runs/gscl-paper --paper          # the paper's recipe (for a GPU)
socialnav gscl evaluate --run runs/gscl                     # MSE per family + predictions.png
socialnav gscl rules --run runs/gscl                        # the held-out rule suite + rules.png
socialnav gscl export --run runs/gscl --out my_model         # the model alone, checked, for --gscl-run
"""

from __future__ import annotations

import argparse
import json
import pathlib
import time

from socialnav import backend as backend_lib
from socialnav import gscl_shards
from socialnav.backend import BackendError, add_backend_options
from socialnav.cli.argtypes import (
    non_negative_float,
    non_negative_int,
    output_folder,
    positive_float,
    positive_int,
    probability,
    seed_int,
    unet_widths,
)
from socialnav.common import progress as progress_lib
from socialnav.common import runfolder
from socialnav.common.atomic import write_text_atomic
from socialnav.common.memory import shortfall
from socialnav.common.runfolder import RunFolderError
from socialnav.locking import locks_folder


def _count(text: str) -> tuple[str, int]:
    name, _, n = text.partition("=")
    try:
        value = int(n)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected FAMILY=N, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"a count must be >= 0, got {text!r}")
    return name, value


# Training options that make up a TrainConfig (None = not given on the command line).
_TRAIN_OPTIONS = (
    "features",
    "epochs",
    "batch_size",
    "learning_rate",
    "schedule",
    "fresh_samples",
    "seed",
    "coords",
    "composites",
    "group_scale",
    "closed_l_hallways",
    "cost_weight",
    "pair_weight",
    "forbidden_weight",
    "objective",
    "temperature",
    "paths_per_map",
    "demonstrations",
    "reading",
    "init_from",
    "forbidden_features",
    "freeze_graded",
)


def add_parser(top) -> None:
    parser = top.add_parser(
        "gscl",
        help="GSCL's learned social cost maps: generate data, train, evaluate (seed 002)",
        description="GSCL (seed 002): generate the procedural dataset, train the U-Net, evaluate a run.",
    )
    sub = parser.add_subparsers(dest="gscl_command", required=True)

    gen = sub.add_parser(
        "generate",
        help="write a dataset of (input map, target cost map) pairs to a .npz file (and a .json of how it was made)",
    )
    gen.add_argument("--out", type=output_folder, required=True, help="the .npz file to write")
    gen.add_argument("--seed", type=seed_int, default=0, help="random seed (default 0)")
    gen.add_argument(
        "--scale",
        type=positive_float,
        default=1.0,
        help="multiply the paper's count of every family (default 1: 24,200 pairs)",
    )
    gen.add_argument(
        "--count",
        type=_count,
        action="append",
        default=[],
        metavar="FAMILY=N",
        help="samples of one family (repeatable; overrides --scale for it)",
    )
    gen.add_argument("--preview", type=pathlib.Path, default=None, help="also write a PNG with one sample per family")
    gen.add_argument(
        "--shard-samples",
        type=positive_int,
        default=None,
        help="samples per shard, rounded up to a multiple of 1024 (default: one shard per family; "
        "a Ray task per shard with --backend ray)",
    )
    gen.add_argument("--no-progress", action="store_true", help="hide the progress bar (sharded runs)")
    gen.add_argument("--overwrite", action="store_true", help="replace an existing --out file")
    add_backend_options(gen)

    tr = sub.add_parser("train", help="train the U-Net (resumes the run in --out if there is one)")
    tr.add_argument(
        "--out", type=output_folder, default=pathlib.Path("runs/gscl"), help="run folder (default runs/gscl)"
    )
    tr.add_argument(
        "--paper",
        action="store_true",
        help="the paper's recipe: 32/64/128/256, batch 32, Adam 1e-3 constant, 20 epochs on one fixed split",
    )
    tr.add_argument("--features", type=unet_widths, default=None, help="U-Net widths, e.g. 16,32,64,128")
    tr.add_argument("--epochs", type=positive_int, default=None)
    tr.add_argument("--batch-size", type=positive_int, default=None)
    tr.add_argument("--learning-rate", type=positive_float, default=None, help="Adam's peak learning rate")
    tr.add_argument("--schedule", choices=("constant", "cosine"), default=None)
    tr.add_argument(
        "--fresh-samples",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="new training samples every epoch (default on; --no-fresh-samples reuses one split)",
    )
    tr.add_argument(
        "--coords", action=argparse.BooleanOptionalAction, default=None, help="coordinate input channels (default on)"
    )
    tr.add_argument("--seed", type=seed_int, default=None)
    tr.add_argument(
        "--composites",
        type=non_negative_int,
        default=None,
        help="composite samples (two scenes in one) per the paper's 24,200 (default 10000; --paper: 0)",
    )
    tr.add_argument(
        "--group-scale",
        type=positive_int,
        default=None,
        help="the group and non-group families' samples times this (default 2; --paper: 1)",
    )
    tr.add_argument(
        "--closed-l-hallways",
        type=non_negative_int,
        default=None,
        help="L-hallways closed by a wall 0.3-3 m past the goal, per the paper's 24,200 (default 0)",
    )
    tr.add_argument(
        "--cost-weight",
        type=non_negative_float,
        default=None,
        help="training loss: each pixel's squared error weighed by 1 + this x its target (default 10; 0: plain MSE)",
    )
    tr.add_argument(
        "--pair-weight",
        type=non_negative_float,
        default=None,
        help="training loss: add this x |target - twin's target| to the weight of a group and the same circle "
        "facing out, a queue and the same queue with the goal elsewhere (default 20; --paper: 0)",
    )
    tr.add_argument(
        "--forbidden-weight",
        type=non_negative_float,
        default=None,
        help="training loss: the weight of the forbidden head's cross-entropy (the queue's U, learnt as a "
        "classification) beside the graded costs' MSE (default 1; > 0 for a 'maps' run)",
    )
    tr.add_argument(
        "--objective",
        choices=("maps", "paths"),
        default=None,
        help="maps: regression on the generator's target maps (seed 002, the default); paths: maximum-entropy "
        "IRL through the soft planner from exact plans on those maps, the maps themselves never in the loss",
    )
    tr.add_argument(
        "--temperature",
        type=positive_float,
        default=None,
        help="--objective paths: the soft planner's temperature in NavFn cost units (default 2; below 9.6)",
    )
    tr.add_argument(
        "--paths-per-map",
        type=positive_int,
        default=None,
        help="--objective paths: demonstrations planned on each map (default 4)",
    )
    tr.add_argument(
        "--demonstrations",
        choices=("paths", "cells"),
        default=None,
        help="--objective paths: paths (the default), --paths-per-map exact plans to each map's goal; cells, the "
        "exact planner's move out of every free cell, each once (docs/irl.md)",
    )
    tr.add_argument(
        "--reading",
        choices=("graded", "layer"),
        default=None,
        help="--objective paths: how costs are priced, the targets' and the network's: graded (the default), every "
        "cost graded; layer, as the GSCL layer reads them, the queue's U lethal (docs/irl.md)",
    )
    tr.add_argument(
        "--init-from",
        default=None,
        metavar="MODEL",
        help="start from this model's weights (an exported model such as data/gscl/default, or a run's folder): "
        "fine-tuning; a model with one output starts the forbidden head's graded channel, the head starts fresh",
    )
    tr.add_argument(
        "--forbidden-features",
        type=unet_widths,
        default=None,
        help="the forbidden head as a separate U-Net of these widths, e.g. 8,16,32,64 (default: a second "
        "output channel of the main network)",
    )
    tr.add_argument(
        "--freeze-graded",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="train the separate forbidden branch only, the graded network kept as --init-from drew it "
        "(needs --init-from and --forbidden-features)",
    )
    tr.add_argument(
        "--stop-when-good",
        action="store_true",
        help="stop at the first epoch that meets the quality bar (test MSE <= 0.0033 and <= 1/10 of "
        "the better trivial predictor in every family) and passes the held-out rule suite (every check "
        "on >= 95 %% of its scenes)",
    )
    tr.add_argument("--no-progress", action="store_true", help="hide the progress bar")

    ev = sub.add_parser("evaluate", help="MSE per family of a run's checkpoint and a PNG of its predictions")
    ev.add_argument(
        "--run", type=pathlib.Path, default=pathlib.Path("runs/gscl"), help="run folder (default runs/gscl)"
    )
    ev.add_argument("--step", type=int, default=None, help="checkpoint step (default: the latest)")
    ev.add_argument("--out", type=output_folder, default=None, help="output folder (default RUN/evaluation)")
    ev.add_argument("--examples", type=positive_int, default=2, help="examples per family in the PNG (default 2)")
    ru = sub.add_parser(
        "rules",
        help="the held-out rule suite: each family's rule checked on scenes no generator drew (models.rules)",
    )
    ru.add_argument(
        "--run",
        type=pathlib.Path,
        default=pathlib.Path("runs/gscl"),
        help="run folder, or an exported model's (socialnav gscl export; the shipped one: data/gscl/default, "
        "with --out) (default runs/gscl)",
    )
    ru.add_argument("--step", type=int, default=None, help="checkpoint step (default: the latest)")
    ru.add_argument("--scenes", type=positive_int, default=100, help="scenes of each kind (default 100)")
    ru.add_argument(
        "--seed",
        type=non_negative_int,
        default=None,
        help="draw the suite's scenes from this seed (default: the suite's own, which training checks every epoch)",
    )
    ru.add_argument(
        "--rotations",
        type=int,
        choices=(1, 4),
        default=1,
        help="score the model averaged over the 4 quarter turns of its input (default 1: the model alone)",
    )
    ru.add_argument("--out", type=output_folder, default=None, help="output folder (default RUN/evaluation)")
    ru.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    ex = sub.add_parser(
        "export",
        help="a run's model alone (no optimiser state, ~2 MB), checked against the quality bar and the rule suite",
        description="Write a training run's model (the latest checkpoint, or --step) to --out as config.json, "
        "weights.msgpack and model.json (how it was made and what it reached: the quality bar on the recipe's "
        "test set and the held-out rule suite, both measured here). --gscl-run of arena, layers and policy train "
        "takes the folder; the model shipped with the package (data/gscl/default) was made this way.",
    )
    ex.add_argument(
        "--run", type=pathlib.Path, default=pathlib.Path("runs/gscl"), help="run folder (default runs/gscl)"
    )
    ex.add_argument("--step", type=int, default=None, help="checkpoint step (default: the latest)")
    ex.add_argument("--out", type=output_folder, required=True, help="the model's folder")
    ex.add_argument(
        "--overwrite", action="store_true", help="replace the model in --out whole (only once the new one is complete)"
    )
    ex.add_argument("--scenes", type=positive_int, default=400, help="rule-suite scenes of each kind (default 400)")
    ex.add_argument(
        "--seed",
        type=non_negative_int,
        default=1,
        help="the rule suite's draw (default 1: scenes no training epoch is scored on; the suite's own seed "
        "is the one training checks every epoch)",
    )
    ex.set_defaults(handler=_export)

    ft = sub.add_parser(
        "fit-tracks",
        help="a cost model learnt from people's tracks by maximum-entropy IRL through the soft planner",
        description="Read tracks (CSV or Parquet: frame, id, x, y in metres) and the walls (a ROS map_server "
        "YAML and its image), or the real pedestrians shipped with the package (--recording), or walk the people "
        "of arena scenes with no robot (--scene), make each track a "
        "demonstration on the GSCL network's 16 m window from where the "
        "person starts (planners.learning.tracks), and fit the U-Net to them "
        "(planners.learning.irl_fit). Writes an exported model "
        "(config.json, weights.msgpack, model.json with the report of tracks used and left out) that --gscl-run "
        "of arena, layers and policy train takes.",
    )
    ft.add_argument("--tracks", type=pathlib.Path, default=None, help="CSV or Parquet with frame, id, x, y")
    ft.add_argument("--map", type=pathlib.Path, default=None, help="ROS map YAML (image, resolution, origin)")
    ft.add_argument(
        "--scene",
        action="append",
        default=None,
        help="instead of --tracks and --map: the people of this arena scene (a built-in name or a JSON file; "
        "repeatable), walked by the arena's crowd model with no robot",
    )
    ft.add_argument(
        "--recording",
        action="append",
        default=None,
        help="instead of --tracks and --map: a shipped recorded run (an ETH/UCY file such as students001, or a "
        "Jülich run; repeatable), its people's tracks and its walls where the data has them (ETH/UCY has none)",
    )
    ft.add_argument(
        "--variants", type=positive_int, default=50, help="--scene: variants of each scene walked (default 50)"
    )
    ft.add_argument("--out", type=output_folder, required=True, help="the model's folder")
    ft.add_argument(
        "--overwrite", action="store_true", help="replace the model in --out whole (only once the new one is complete)"
    )
    ft.add_argument("--steps", type=positive_int, default=2000, help="gradient steps (default 2000)")
    ft.add_argument("--batch-size", type=positive_int, default=32, help="tracks per step (default 32)")
    ft.add_argument(
        "--temperature",
        type=positive_float,
        default=4.0,
        help="the soft planner's temperature in NavFn cost units (default 4: people are noisier than exact "
        "plans; below 9.6)",
    )
    ft.add_argument(
        "--min-on-map",
        type=probability,
        default=0.8,
        help="--tracks: the least share of the positions that must lie on the --map's extent (default 0.8; "
        "fewer means the two are in different frames or units)",
    )
    ft.add_argument("--seed", type=seed_int, default=0)
    ft.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    ft.set_defaults(handler=_fit_tracks)
    ru.set_defaults(handler=_rules)
    gen.set_defaults(handler=_generate)
    tr.set_defaults(handler=_train)
    ev.set_defaults(handler=_evaluate)


def _generate(args) -> int:
    from socialnav.models import dataset

    if args.out.suffix != ".npz":
        raise SystemExit(f"socialnav gscl generate: --out must end in .npz, got {args.out}")
    counts = dataset.scaled_counts(args.scale)
    for name, n in args.count:
        if name not in dataset.FAMILIES:
            raise SystemExit(f"socialnav gscl generate: unknown family {name!r}; known: {', '.join(dataset.FAMILIES)}")
        counts[name] = n
    if sum(counts.values()) == 0:
        smallest = 1 / min(n for n in dataset.scaled_counts(1.0).values() if n > 0)
        raise SystemExit(
            f"socialnav gscl generate: --scale {args.scale:g} gives 0 samples in every family "
            f"(the smallest scale that gives one is about {smallest:.2g}); nothing written"
        )
    _check_dataset_target(args.out, args.overwrite)
    n = sum(counts.values())
    needed = n * DATASET_BYTES_PER_SAMPLE
    available = shortfall(needed)
    if available is not None:
        raise SystemExit(
            f"socialnav gscl generate: --scale {args.scale:g}: {n:,} samples need about {needed / 1e9:.1f} GB at once "
            f"(the dataset is one array in memory before it is written), this machine has {available / 1e9:.1f} GB "
            "available; lower --scale or --count (the shards of --shard-samples are joined in memory too)"
        )
    seconds = n / GENERATED_PER_S + 25
    print(f"gscl generate: {n:,} samples, about {seconds:.0f} s and {needed / 1e9:.2f} GB at once", flush=True)
    t0 = time.perf_counter()
    if args.backend == "local" and args.shard_samples is None:
        data = dataset.generate(args.seed, counts)
    else:
        try:
            data = gscl_shards.generate_sharded(args, counts)
        except (BackendError, RunFolderError) as e:
            raise SystemExit(f"socialnav gscl generate: {e}") from None
    dt = time.perf_counter() - t0
    try:
        dataset.save(args.out, data)
    except OSError as e:
        raise SystemExit(f"socialnav gscl generate: cannot write {args.out}: {e.strerror or e}") from None
    provenance = {
        "seed": args.seed,
        "counts": counts,
        "shard_samples": args.shard_samples,
        **backend_lib.describe(args),
        "wall_s": dt,
    }
    write_text_atomic(args.out.with_suffix(".json"), json.dumps(provenance, indent=1) + "\n")
    backend_lib.remove_staging(gscl_shards.staging(args.out))  # the shards live until the dataset is written
    print(f"{len(data['family'])} pairs in {dt:.1f} s (compilation included) -> {args.out} (+ .json: how it was made)")
    for i, name in enumerate(data["names"]):
        print(f"  {name:<18}{int((data['family'] == i).sum()):>7}")
    if args.preview is not None:
        from socialnav.models import plots

        plots.family_grid(data["inputs"], data["targets"], data["family"], data["names"], args.preview)
        print(f"preview -> {args.preview}")
    return 0


# Memory a generated sample holds: its input (1,600 bytes) and target (6,400), about three times
# over while the generator's chunks are joined and written.
DATASET_BYTES_PER_SAMPLE = 24_000
# Samples generated per second once compiled (22-36 k pairs/s over the sessions, README "What it
# reaches"); a new process adds about 25 s of compilation.
GENERATED_PER_S = 20_000


def _check_dataset_target(out: pathlib.Path, overwrite: bool) -> None:
    """``--out`` may be written: new, or (with ``--overwrite``) a dataset this command wrote
    (its ``.json`` provenance beside it); never a folder or a user's file. Checked before any work,
    the folder's writability included."""
    from socialnav.common.runfolder import RunFolderError, check_writable

    provenance = out.with_suffix(".json")
    if out.is_dir():
        raise SystemExit(f"socialnav gscl generate: --out {out} is a folder; give the .npz file to write")
    if out.exists() or provenance.exists():
        try:
            ours = set(json.loads(provenance.read_text())) >= {"seed", "counts"}
        except (OSError, ValueError, TypeError):
            ours = False
        if not ours:  # --overwrite would not replace it either: said first
            found = f"{provenance} is not" if provenance.exists() else f"{out} exists without"
            raise SystemExit(
                f"socialnav gscl generate: --out {out}: {found} the record 'gscl generate' writes beside "
                "its datasets, so no file is replaced: move it away or choose another --out"
            )
        if not overwrite:
            existing = ", ".join(str(f) for f in (out, provenance) if f.exists())
            raise SystemExit(f"socialnav gscl generate: --out {out}: {existing} exist(s); pass --overwrite to replace")
    try:
        check_writable(out.parent)
    except RunFolderError as e:
        raise SystemExit(f"socialnav gscl generate: --out {out}: {e}") from None


def _train_config(args):
    from socialnav.models.checkpoints import load_config
    from socialnav.models.config import TrainConfig

    given = {k: getattr(args, k) for k in _TRAIN_OPTIONS if getattr(args, k) is not None}
    if (args.out / "config.json").exists() and not given and not args.paper:
        return load_config(args.out)  # resume with the stored settings
    return TrainConfig.paper(**given) if args.paper else TrainConfig(**given)


@locks_folder(lambda args: args.out, "gscl train")
def _train(args) -> int:
    from socialnav.models import train
    from socialnav.models.checkpoints import check_run_folder
    from socialnav.models.quality import quality_table

    try:
        runfolder.claim(args.out, TRAIN_JOB, TRAIN_RESULTS, adopt=_an_earlier_training_run)
        config = _train_config(args)
        check_run_folder(args.out, config)
    except (ValueError, RunFolderError) as err:
        raise SystemExit(f"socialnav gscl train: {err}") from None
    runfolder.record(
        args.out,
        TRAIN_JOB,
        [
            "config.json",
            "baselines.json",
            "metrics.jsonl",
            "checkpoints/",
            *(["init_from.json"] if config.init_from else []),
        ],
    )
    import jax

    print(
        f"training on {jax.devices()[0].platform} x {len(jax.devices())}: features {config.features}, "
        f"{config.epochs} epochs x {config.steps_per_epoch} steps of {config.batch_size}, "
        f"objective {config.objective}, "
        f"{_parameters(config):,} parameters -> {args.out}"
    )
    t0 = time.perf_counter()
    try:
        objective = None
        if config.objective == "paths":
            from socialnav.planners.learning.irl import PathObjective

            objective = PathObjective.of(config)
        line = train.train(
            config,
            args.out,
            progress=not args.no_progress,
            stop_when_good=args.stop_when_good,
            objective=objective,
        )
    except ValueError as err:
        raise SystemExit(f"socialnav gscl train: {err}") from None
    baselines = json.loads((args.out / "baselines.json").read_text())
    if line:
        print(quality_table(line["test_mse"], line["test_mse_by_family"], baselines))
        print(
            f"{'meets' if line['meets_quality'] else 'does not meet'} the quality bar; "
            f"{time.perf_counter() - t0:.0f} s in this call, {line['wall_s']:.0f} s of training in all"
        )
    return 0


TRAIN_JOB = "socialnav gscl train"
TRAIN_RESULTS = ("config.json", "baselines.json", "metrics.jsonl", "checkpoints", "init_from.json")
EVALUATION_JOB = "socialnav gscl evaluation"  # evaluate and rules share RUN/evaluation


def _an_earlier_training_run(folder: pathlib.Path) -> bool:
    """A training run of socialnav before 0.3 (no manifest): a config.json that reads as a
    TrainConfig (its checkpoints, if any, are orbax's)."""
    from socialnav.models.checkpoints import load_config

    try:
        load_config(folder)
    except (FileNotFoundError, ValueError):
        return False
    return True


def _evaluation_lock(args) -> pathlib.Path | None:
    """The folder ``gscl evaluate`` and ``rules`` lock: ``--out``, else ``RUN/evaluation`` of a
    training run that exists (None otherwise: the handler names what is wrong)."""
    from socialnav.models.inference import WEIGHTS_FILE

    if args.out is not None:
        return args.out
    return args.run / "evaluation" if args.run.is_dir() and not (args.run / WEIGHTS_FILE).is_file() else None


def _evaluation_folder(args, names: tuple[str, ...]) -> pathlib.Path:
    """``--out`` (default RUN/evaluation), checked before the work: a folder this job may write
    ``names`` into."""
    out = args.run / "evaluation" if args.out is None else args.out
    try:
        runfolder.claim(out, EVALUATION_JOB, names)
        runfolder.check_writable(out)
    except RunFolderError as err:
        raise SystemExit(f"socialnav gscl {args.gscl_command}: --out: {err}") from None
    return out


def _parameters(config) -> int:
    from socialnav.models import steps, unet

    return unet.parameter_count(steps.abstract_model(config))  # shapes only: nothing drawn


@locks_folder(_evaluation_lock, "gscl evaluate")
def _evaluate(args) -> int:
    from socialnav.models import evaluation

    names = ("evaluation.json", "predictions.png")
    out = _evaluation_folder(args, names)
    try:
        report = evaluation.evaluate_run(args.run, step=args.step, out=out, examples=args.examples)
    except (FileNotFoundError, ValueError) as err:  # no run, no checkpoint, none restorable
        raise SystemExit(f"socialnav gscl evaluate: {err}") from None
    runfolder.record(out, EVALUATION_JOB, names)
    print(report["table"])
    print(
        f"step {report['step']}: {'meets' if report['meets_quality'] else 'does not meet'} the quality bar; "
        f"-> {report['out']}"
    )
    return 0


@locks_folder(_evaluation_lock, "gscl rules")
def _rules(args) -> int:
    from socialnav.models import evaluation, rules
    from socialnav.models.inference import WEIGHTS_FILE

    names = ("rules.json", "rules.png")
    if args.out is None and (args.run / WEIGHTS_FILE).is_file():
        raise SystemExit(
            f"socialnav gscl rules: --out: {args.run} is an exported model, whose folder is not written into; "
            "name an output folder"
        )
    problem = evaluation.rules_size_problem(args.scenes)
    if problem:
        raise SystemExit(f"socialnav gscl rules: --scenes {args.scenes}: {problem}")
    out = _evaluation_folder(args, names)
    cases, needed, seconds = evaluation.rules_size(args.scenes, args.rotations)
    print(
        f"gscl rules: {cases:,} cases ({args.scenes:,} scenes of each kind), about {seconds:.0f} s "
        f"and {needed / 1e9:.1f} GB at once",
        flush=True,
    )
    try:
        with progress_lib.bar("rule suite", unit="scene", enabled=not args.no_progress) as bar:
            report = evaluation.rules_run(
                args.run,
                step=args.step,
                out=out,
                scenes_per_kind=args.scenes,
                seed=args.seed,
                rotations=args.rotations,
                report_scenes=bar.update,
            )
    except (FileNotFoundError, ValueError) as err:  # no run, no checkpoint, none restorable
        raise SystemExit(f"socialnav gscl rules: {err}") from None
    runfolder.record(out, EVALUATION_JOB, names)
    print(report["table"])
    which = "the model" if report["step"] is None else f"step {report['step']}"
    print(
        f"{which}: {'every' if report['meets_rules'] else 'not every'} check passes on "
        f">= {100 * rules.RULES_BAR:.0f} % of its scenes; -> {report['out']}"
    )
    return 0


EXPORT_JOB = "socialnav gscl export"
EXPORT_FILES = ("config.json", "weights.msgpack", "model.json")


FIT_TRACKS_JOB = "socialnav gscl fit-tracks"
FIT_TRACKS_FILES = ("config.json", "weights.msgpack", "model.json", "demonstrations.png")


def _scene_specs(names):
    """The arena scenes named (built-in names or JSON files), loaded and validated."""
    from socialnav.data import DATA_DIR
    from socialnav.jaxsim.scenes.spec import load_scene

    files = [pathlib.Path(n) if n.endswith(".json") else DATA_DIR / "scenes" / f"{n}.json" for n in names]
    missing = [f for f in files if not f.is_file()]
    if missing:
        builtin = ", ".join(sorted(p.stem for p in (DATA_DIR / "scenes").glob("*.json")))
        raise ValueError(f"--scene: no scene {missing[0]} (built-in: {builtin})")
    return [load_scene(f) for f in files]


@locks_folder(lambda args: args.out, "gscl fit-tracks")
def _fit_tracks(args) -> int:
    """A model fitted to a user's tracks, exported with a card of what went into it."""
    import datetime

    from socialnav.models.config import TrainConfig
    from socialnav.planners.learning import ros_map, tracks
    from socialnav.planners.learning.irl_fit import demonstrations_figure, fit_demonstrations

    try:
        config = TrainConfig(
            objective="paths", temperature=args.temperature, batch_size=args.batch_size, seed=args.seed
        )
        given = [bool(args.scene), bool(args.recording), bool(args.tracks or args.map)]
        if sum(given) != 1 or (given[2] and (args.tracks is None or args.map is None)):
            raise ValueError("give --tracks and --map, or --recording, or --scene")
        if args.scene:
            specs = _scene_specs(args.scene)
        elif args.recording:
            from socialnav.data import recorded

            unknown = [r for r in args.recording if r not in recorded.run_names()]
            if unknown:
                raise ValueError(
                    f"--recording: no shipped run {unknown[0]!r} (shipped: {', '.join(recorded.run_names())})"
                )
        else:
            sources = [(tracks.read_tracks(args.tracks), *ros_map.read_ros_map(args.map))]
            tracks.check_on_map(*sources[0], args.tracks, args.map, args.min_on_map)
        runfolder.prepare(args.out, FIT_TRACKS_FILES, args.overwrite, marker="model.json", job=FIT_TRACKS_JOB)
        runfolder.check_writable(args.out)
    except runfolder.RunFolderError as err:
        raise SystemExit(f"socialnav gscl fit-tracks: --out {err}") from None
    except ValueError as err:
        raise SystemExit(f"socialnav gscl fit-tracks: {err}") from None
    if args.scene:
        sources = [tracks.simulated_tracks(spec, args.seed, args.variants) for spec in specs]
    elif args.recording:
        sources = [tracks.recorded_tracks(run) for run in args.recording]
    maps, demos, report = tracks.concatenate([tracks.track_demonstrations(*source) for source in sources])
    left = ", ".join(f"{n} {why}" for why, n in report["left_out"].items()) or "none"
    print(f"{report['used']} of {report['tracks']} tracks made demonstrations (left out: {left})", flush=True)
    try:
        model, history = fit_demonstrations(maps, demos, config, steps=args.steps, progress=not args.no_progress)
    except ValueError as err:
        raise SystemExit(f"socialnav gscl fit-tracks: {err}") from None
    card = {
        "made_by": "socialnav gscl fit-tracks "
        + (
            " ".join(f"--scene {n}" for n in args.scene) + f" --variants {args.variants}"
            if args.scene
            else " ".join(f"--recording {n}" for n in args.recording)
            if args.recording
            else f"--tracks {args.tracks.name} --map {args.map.name}"
        )
        + f" --steps {args.steps} --seed {args.seed}",
        "objective": "maximum-entropy IRL through the soft planner (planners.learning.irl)",
        "temperature": args.temperature,
        "steps": args.steps,
        "tracks": {k: v for k, v in report.items() if k != "ids"},
        "nll_per_path_first_last": [history[0], history[-1]],
        "exported": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
    }
    try:
        with runfolder.staged(args.out, "model.json", args.overwrite, job=FIT_TRACKS_JOB) as stage:
            model.export(stage, card)
            demonstrations_figure(model, maps, demos, stage / "demonstrations.png")
    except runfolder.RunFolderError as err:
        raise SystemExit(f"socialnav gscl fit-tracks: --out {err}") from None
    print(
        f"negative log-likelihood per path {history[0]:.2f} -> {history[-1]:.2f} nats; wrote "
        f"{args.out}/{{{', '.join(FIT_TRACKS_FILES)}}}"
    )
    return 0


@locks_folder(lambda args: args.out, "gscl export")
def _export(args) -> int:
    """The run's model alone, with a card of how it was made and what it reaches
    (:func:`models.evaluation.exported_model`)."""
    from socialnav.models import evaluation

    try:
        runfolder.prepare(args.out, EXPORT_FILES, args.overwrite, marker="model.json", job=EXPORT_JOB)
        runfolder.check_writable(args.out)
        say = lambda what: print(what, flush=True)
        model, card = evaluation.exported_model(args.run, args.step, args.scenes, args.seed, log=say)
    except runfolder.RunFolderError as err:
        raise SystemExit(f"socialnav gscl export: --out {err}") from None
    except (FileNotFoundError, ValueError) as err:  # no run, no checkpoint, none restorable
        raise SystemExit(f"socialnav gscl export: {err}") from None
    try:
        with runfolder.staged(args.out, "model.json", args.overwrite, job=EXPORT_JOB) as stage:
            model.export(stage, card)
    except runfolder.RunFolderError as err:
        raise SystemExit(f"socialnav gscl export: --out {err}") from None
    worst = min(card["rules_pass_by_check"].items(), key=lambda kv: kv[1])
    print(
        f"test MSE {card['test_mse']:.5f}: {'meets' if card['meets_quality'] else 'does not meet'} the quality "
        f"bar; rule suite: {'every' if card['meets_rules'] else 'not every'} check on >= 95 % of its scenes "
        f"(the lowest: {worst[0]} {100 * worst[1]:.0f} %); wrote {args.out}/{{{', '.join(EXPORT_FILES)}}}"
    )
    return 0
