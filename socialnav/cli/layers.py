"""``socialnav layers``: pictures of every social cost layer and the path its planner finds.

socialnav layers --out docs/img                          # SNL (two settings), CASN, SNAPE's map
socialnav layers --out docs/img --gscl-run runs/gscl     # the GSCL panel from your own model
"""

from __future__ import annotations

import pathlib
import sys

from socialnav.cli.argtypes import output_folder
from socialnav.locking import locks_folder


def add_parser(top) -> None:
    parser = top.add_parser(
        "layers",
        help="draw the social cost layers and their planned paths on the seeds' scene types",
        description="One PNG per scene type: every cost layer side by side with the path its grid planner finds.",
    )
    parser.add_argument("--out", type=output_folder, default=pathlib.Path("docs/img"), help="folder (default docs/img)")
    parser.add_argument(
        "--gscl-run",
        type=pathlib.Path,
        default=None,
        help="the GSCL model of the GSCL panel: a socialnav gscl train run or a socialnav gscl export folder "
        "(default: the model shipped with the package)",
    )
    parser.set_defaults(handler=run)


JOB = "socialnav layers"


@locks_folder(lambda args: args.out, "layers")
def run(args) -> int:
    from socialnav.common import runfolder
    from socialnav.planners import plots

    names = tuple(f"layers_{name}.png" for name in plots.demo_scenes())
    try:
        runfolder.claim(args.out, JOB, names)
        runfolder.check_writable(args.out)
    except runfolder.RunFolderError as e:
        print(f"socialnav layers: --out: {e}", file=sys.stderr)
        return 2
    from socialnav.models.inference import SocialCostModel

    try:
        model = SocialCostModel.load(args.gscl_run)
    except (FileNotFoundError, ValueError) as e:  # not a model, no checkpoint restorable, a bad config.json
        print(f"socialnav layers: --gscl-run {e}", file=sys.stderr)
        return 2
    for path in plots.write_all(args.out, model):
        runfolder.record(args.out, JOB, [path.name])
        print(f"wrote {path}", file=sys.stdout)
    return 0
