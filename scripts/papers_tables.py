"""The papers' tables of an arena run folder in Markdown, as docs/arena-results.md shows them.

    python scripts/papers_tables.py runs/arena > tables.md

Prints, under a line naming the run (its folder, the package and metrics versions, the GSCL
model's digest, the variants and the seed from ``run.json``): ``papers.csv`` (each published number
beside ours and its 95 % interval), ``directions.csv`` (each paper's difference between its method
and a baseline beside ours, paired by variant) and ``papers_stats.csv`` (seed 002's Table 2), each
with a count of its verdicts; where the run has turned rows (``socialnav arena --turned``), each
method's social and goal success (a collision failing the run) on the scenes where the turn moved
it (``--all-turned``: on every scene) beside the same on the scene turned, with the paired
change's interval (``evaluation.arena.markdown``), and the papers' differences on the turned rows
(``directions_turned.csv``) with the verdicts the turn changed. Tables in the docs made this way
can be made again from the run.
"""

from __future__ import annotations

import argparse
import json
import pathlib

import pandas as pd

from socialnav.evaluation.arena.markdown import (
    directions_table,
    papers_table,
    run_turned_pairs,
    source_line,
    stats_table,
    turned_table,
    verdict_changes,
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("run", type=pathlib.Path, help="a socialnav arena run folder")
    parser.add_argument(
        "--all-turned", action="store_true", help="every scene and method of the turned rows, not only those moved"
    )
    args = parser.parse_args()
    run = args.run
    if not (run / "run.json").is_file():
        raise SystemExit(f"{run}: no run.json (not a socialnav arena run folder)")
    print(source_line(json.loads((run / "run.json").read_text()), run.name))
    for name, table in (
        ("papers.csv", papers_table),
        ("directions.csv", directions_table),
        ("papers_stats.csv", stats_table),
    ):
        if (run / name).is_file():
            print(f"\n`{name}`:\n")
            print(table(pd.read_csv(run / name)))
    pairs = run_turned_pairs(run)
    if pairs is not None:
        which = "every scene and method" if args.all_turned else "the cells whose social success moved"
        print(f"\nEvery scene turned a quarter turn (`--turned`), paired by variant; {which}:\n")
        print(turned_table(pairs, moved_only=not args.all_turned))
    if (run / "directions_turned.csv").is_file():
        turned = pd.read_csv(run / "directions_turned.csv")
        print("\n`directions_turned.csv`:\n")
        print(directions_table(turned))
        if (run / "directions.csv").is_file():
            print("\n" + verdict_changes(pd.read_csv(run / "directions.csv"), turned))


if __name__ == "__main__":
    main()
