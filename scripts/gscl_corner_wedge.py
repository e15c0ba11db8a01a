"""The held-out rule suite's blind-corner checks by the corner's wedge angle, beside the generator's range.

    python scripts/gscl_corner_wedge.py --run runs/gscl                  # the suite's seed (100) and a fresh draw (400)

The generator draws wedges (the wall block's angle) of :data:`models.families.CORNER_WEDGE_DEG`,
the suite :data:`models.rules.CORNER_WEDGE_DEG`. Prints, for the corner alone and beside a queue, how many scenes
pass below, within and above the generator's range.
"""

from __future__ import annotations

import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))

import numpy as np

from socialnav.models import families, rules
from socialnav.models.inference import SocialCostModel


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--run", type=pathlib.Path, default=pathlib.Path("runs/gscl"), help="run folder")
    args = parser.parse_args(argv)
    model = SocialCostModel.load(args.run)
    (suite_low, suite_high), (low, high) = rules.CORNER_WEDGE_DEG, families.CORNER_WEDGE_DEG
    bands = ((suite_low, low, "narrower"), (low, high, "generator's"), (high, suite_high, "wider"))
    for name, seed, scenes in (("suite's seed", rules.SUITE_SEED, 100), ("fresh draw, seed 1", 1, 400)):
        cases = rules.build_suite(scenes, seed)  # all kinds, so the same scenes as `socialnav gscl rules`
        report = rules.evaluate(model.function, cases)
        for scene in ("corner", "queue+corner"):
            index = [i for i, c in enumerate(cases) if c.scene == scene and c.rule == "blind_corner"]
            wedge = np.array([cases[i].params["wedge_deg"] for i in index])
            passed = report["passed"][index]
            parts = []
            for lo, hi, label in bands:
                sel = (wedge >= lo) & (wedge < hi)
                parts.append(f"{label} ({lo:.0f}-{hi:.0f} deg) {passed[sel].sum()}/{sel.sum()}")
            print(f"{name:<20} {scene:<13} all {100 * passed.mean():5.1f} %   " + "   ".join(parts))


if __name__ == "__main__":
    main()
