"""The commands that join parts: ``socialnav run`` (simulate -> learn -> evaluate, the main job,
then a small arena run so that a newcomer sees the social-navigation table) and ``socialnav
ablation`` (the simulator's series -> the causal pipeline's estimates,
:func:`socialnav.ablation_study.ablation_series`).
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys

from socialnav.ablation_study import ablation_series, memory_problem
from socialnav.causal import ablation as causal_ablation
from socialnav.cli import arena, evaluate, learn, simulate
from socialnav.cli.argtypes import comma_ints, comma_probabilities, output_folder, positive_int, seed_int
from socialnav.common import runfolder
from socialnav.jaxsim.scenario import load_scenario
from socialnav.locking import locks_folder
from socialnav.planners.warehouse.tables import TABLES_FILE


def add_parser(sub) -> None:
    """The parsers of ``run`` and ``ablation``."""
    run = sub.add_parser(
        "run",
        help="the whole pipeline: simulate a day, learn the engine, evaluate the planners, a small arena run",
        description="simulate -> learn -> evaluate on the built-in warehouse, then a small arena run of seed 001's "
        "scenes, into one folder: logs and pictures, causal/ (graph, engine), evaluation/ (tables, figures), "
        "arena/ (episodes, summary, the papers' numbers beside ours).",
    )
    run.add_argument("--worlds", type=positive_int, default=4, help="worlds simulated for learning (default 4)")
    run.add_argument(
        "--learn-worlds", type=comma_ints, default=[0], help="comma-separated worlds the engine learns from (default 0)"
    )
    evaluate.add_evaluation_options(run, default_out=pathlib.Path("runs/warehouse"), replicas=4)
    run.add_argument(
        "--arena-variants",
        type=int,
        default=10,
        help="variants of seed 001's scenes with CASN and its SNL baseline in the last step (default 10; 0: skip)",
    )
    run.set_defaults(handler=run_pipeline)

    abl = sub.add_parser(
        "ablation",
        help="causal vs Bayesian battery estimates (seed 000 Sec. 6)",
        description="The simplified scenario (no workers, obstacles with probability p) for "
        "each p and seed, all in one batched rollout; E[L | V] against E[L | do(V)] "
        "for 60 m at 0.5 m/s; writes ablation.csv, ablation.json and ablation.png.",
    )
    abl.add_argument("--out", type=output_folder, default=pathlib.Path("runs/ablation"), help="output folder")
    abl.add_argument("--seeds", type=positive_int, default=8, help="seeds (worlds) per probability (default 8)")
    abl.add_argument(
        "--probabilities",
        type=comma_probabilities,
        default=list(causal_ablation.PROBABILITIES),
        help="obstacle probabilities (default 0.1,...,0.5)",
    )
    abl.add_argument("--seed", type=seed_int, default=0, help="base random seed (default 0)")
    abl.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    abl.add_argument(
        "--overwrite", action="store_true", help="replace the results in --out (only once the new ones are complete)"
    )
    abl.set_defaults(handler=run_ablation)


@locks_folder(lambda args: args.out, "run")
def run_pipeline(args: argparse.Namespace) -> int:
    """simulate -> learn -> evaluate, each step's output the next one's input."""
    out = args.out
    quiet = ["--no-progress"] if args.no_progress else []
    sim_argv = ["simulate", "--worlds", str(args.worlds), "--seed", str(args.seed), "--out", str(out)]
    steps = [
        ("simulate", simulate.run, sim_argv),
        ("learn", learn.run, ["learn", "--logs", str(out), "--worlds", ",".join(map(str, args.learn_worlds))]),
    ]
    if args.overwrite:  # simulate's --overwrite removes the old run whole; its steps start afresh
        steps = [(name, handler, argv + ["--overwrite"]) for name, handler, argv in steps]
    parser = argparse.ArgumentParser(prog="socialnav run")  # the steps' own parsers, defaults included
    steps_sub = parser.add_subparsers(dest="command", required=True)
    simulate.add_parser(steps_sub)
    learn.add_parser(steps_sub)
    if args.arena_variants < 0:
        print("socialnav run: --arena-variants must be >= 0", file=sys.stderr)
        return 2
    total = 4 if args.arena_variants else 3
    for i, (name, handler, argv) in enumerate(steps, 1):
        print(f"\n=== [{i}/{total}] {name} ===", flush=True)
        code = handler(parser.parse_args(argv + quiet))
        if code:
            return code
    print(f"\n=== [3/{total}] evaluate ===", flush=True)
    code = evaluate.evaluate_with(load_scenario(), out / "causal" / TABLES_FILE, out / "evaluation", args)
    if code or not args.arena_variants:
        return code
    print(f"\n=== [4/{total}] arena: seed 001's scenes, CASN against its SNL baseline ===", flush=True)
    arena.add_parser(steps_sub)
    scenes = "casn_static_person,casn_static_group,casn_head_on,casn_crossing"
    arena_argv = ["arena", "--out", str(out / "arena"), "--scenes", scenes, "--methods", "snl_matched,casn"]
    arena_argv += ["--variants", str(args.arena_variants), "--keep-trajectories", "1", "--seed", str(args.seed)]
    return arena.run(parser.parse_args(arena_argv + quiet))


@locks_folder(lambda args: args.out, "ablation")
def run_ablation(args: argparse.Namespace) -> int:
    results = ("ablation.json", "ablation.csv", "ablation.png")
    problem = memory_problem(len(args.probabilities), args.seeds)  # before the folder is touched
    if problem:
        print(f"socialnav ablation: --seeds {args.seeds}: {problem}", file=sys.stderr)
        return 2
    try:
        runfolder.prepare(args.out, results, args.overwrite, marker="ablation.json", job="socialnav ablation")
    except runfolder.RunFolderError as e:
        print(f"socialnav ablation: {e}", file=sys.stderr)
        return 2
    print(f"simulating {len(args.probabilities)} probabilities x {args.seeds} seeds in one batch ...", flush=True)
    series = ablation_series(args.probabilities, args.seeds, args.seed)
    try:
        with runfolder.staged(args.out, "ablation.json", args.overwrite, job="socialnav ablation") as stage:
            causal_ablation.run(stage, series, progress=not args.no_progress)
    except runfolder.RunFolderError as e:
        print(f"socialnav ablation: {e}", file=sys.stderr)
        return 2
    summary = json.loads((args.out / "ablation.json").read_text())
    print(f"structure found by J-PCMCI+ at p = 0.3: {summary['structure_at_p_0.3']}")
    print(
        f"{'p':>5} {'L_ref':>8} {'L_BN':>8} {'L_CM':>8} {'MAE BN':>14} {'MAE CM':>14}   (battery % for 60 m at 0.5 m/s)"
    )
    for r in summary["summary"]:
        print(
            f"{r['p']:>5.1f} {r['reference']:>8.3f} {r['bayesian']:>8.3f} {r['causal']:>8.3f} "
            f"{r['mae_bayesian']:>7.3f}+-{r['sd_bayesian']:.3f} {r['mae_causal']:>7.3f}+-{r['sd_causal']:.3f}"
        )
    print(f"wrote {args.out}/ablation.csv, ablation.json, ablation.png", file=sys.stdout)
    return 0
