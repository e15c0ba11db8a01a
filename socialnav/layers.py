"""``socialnav layers``: pictures of every social cost layer and the path its planner finds.

socialnav layers --out docs/img                          # SNL (two settings), CASN, SNAPE's map
socialnav layers --out docs/img --gscl-run runs/gscl     # and the GSCL layer of a trained run
"""

from __future__ import annotations

import pathlib
import sys

from socialnav.argtypes import output_folder


def add_parser(top) -> None:
    parser = top.add_parser(
        "layers",
        help="draw the social cost layers and their planned paths on the seeds' scene types",
        description="One PNG per scene type: every cost layer side by side with the path its grid planner finds.",
    )
    parser.add_argument("--out", type=output_folder, default=pathlib.Path("docs/img"), help="folder (default docs/img)")
    parser.add_argument(
        "--gscl-run", type=pathlib.Path, default=None, help="a trained GSCL run folder: adds the GSCL layer's panel"
    )
    parser.set_defaults(handler=run)


def run(args) -> int:
    from planners import plots

    predict = None
    if args.gscl_run is not None:
        if not (args.gscl_run / "checkpoints").is_dir():
            print(f"socialnav layers: {args.gscl_run}: no checkpoints/ folder (train one with socialnav gscl train)")
            return 2
        from models.inference import SocialCostModel

        predict = SocialCostModel.load(args.gscl_run).function
    for path in plots.write_all(args.out, predict):
        print(f"wrote {path}", file=sys.stdout)
    return 0
