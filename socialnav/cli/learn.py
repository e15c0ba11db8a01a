"""``socialnav learn``: the causal graph and inference engine from simulator logs."""

from __future__ import annotations

import argparse
import pathlib
import sys

from socialnav.causal.extract import LogError
from socialnav.causal.learn import learn
from socialnav.cli.argtypes import (
    comma_ints,
    comma_names,
    non_negative_int,
    open_unit_interval,
    output_folder,
    positive_int,
)
from socialnav.common import runfolder
from socialnav.common.logschema import LOG_FILE, META_FILE
from socialnav.locking import locks_folder


def add_parser(sub) -> None:
    lrn = sub.add_parser(
        "learn",
        help="learn the causal graph and inference engine from simulator logs",
        description="J-PCMCI+ discovery and a pyAgrum inference engine from the logs of "
        "'socialnav simulate'; writes the graph, the engine, its tables and a report.",
    )
    lrn.add_argument(
        "--logs",
        type=pathlib.Path,
        default=pathlib.Path("runs/warehouse"),
        help="folder written by 'socialnav simulate' (default runs/warehouse)",
    )
    lrn.add_argument("--out", type=output_folder, default=None, help="output folder (default: LOGS/causal)")
    lrn.add_argument(
        "--test",
        choices=["parcorr", "regression"],
        default="parcorr",
        help="conditional independence test: parcorr (fast) or regression (RegressionCI, mixed data)",
    )
    lrn.add_argument("--alpha", type=open_unit_interval, default=0.01, help="significance level (default 0.01)")
    lrn.add_argument(
        "--step", type=positive_int, default=None, help="subsampling step in logged samples (default: the Nyquist rule)"
    )
    lrn.add_argument(
        "--max-samples",
        type=non_negative_int,
        default=200_000,
        help="discovery's sample budget (default 200000): J-PCMCI+ runs on as many datasets as it holds, "
        "evenly spaced; the engine learns from all; 0: no budget",
    )
    lrn.add_argument(
        "--worlds", type=comma_ints, default=None, help="comma-separated world ids to learn from (default: all)"
    )
    lrn.add_argument(
        "--waypoints",
        type=comma_names,
        default=None,
        help="comma-separated waypoints to learn (default: every non-empty one)",
    )
    lrn.add_argument(
        "--compare-subsampling",
        action="store_true",
        help="also run discovery on every dataset (no sample budget) and report both",
    )
    lrn.add_argument(
        "--overwrite", action="store_true", help="replace the engine in --out whole (only once the new one is complete)"
    )
    lrn.add_argument("--no-progress", action="store_true", help="print nothing but errors")
    lrn.set_defaults(handler=run)


def _out_folder(args) -> pathlib.Path:
    """``--out``, else ``causal/`` inside the logs' run folder."""
    return args.out or args.logs / "causal"


# What a finished learn leaves in its folder; report.json is written last.
RESULTS = ("report.json", "engine_tables.npz", "engine.json", "engine.bifxml", "discovery.json", "causal_graph.png")
JOB = "socialnav learn"


@locks_folder(_out_folder, "learn", reads=lambda args: [("--logs", args.logs)])
def run(args: argparse.Namespace) -> int:
    out = _out_folder(args)
    try:
        runfolder.check_inputs(out, [args.logs / LOG_FILE, args.logs / META_FILE])
        runfolder.prepare(out, RESULTS, args.overwrite, marker="report.json", job=JOB)
    except runfolder.RunFolderError as e:
        print(f"socialnav learn: {e}", file=sys.stderr)
        return 2
    try:
        with runfolder.staged(out, "report.json", args.overwrite, job=JOB) as stage:
            _learn(args, stage, out)
    except (LogError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except runfolder.RunFolderError as e:
        print(f"socialnav learn: {e}", file=sys.stderr)
        return 2
    return 0


def _learn(args: argparse.Namespace, stage: pathlib.Path, out: pathlib.Path) -> None:
    learn(
        args.logs,
        stage,
        test=args.test,
        alpha=args.alpha,
        step=args.step,
        max_samples=args.max_samples,
        worlds=args.worlds,
        waypoints=args.waypoints,
        compare_subsampling=args.compare_subsampling,
        progress=not args.no_progress,
        shown_as=out,
    )
