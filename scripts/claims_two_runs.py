"""The papers' claims in two arena runs side by side: each run's ``directions.csv`` (a claim's
paired difference with its 95 % interval and verdict, :mod:`evaluation.arena.papers`) joined by claim,
printed as a markdown table with the claims whose verdict differs between the runs counted
(``evaluation.arena.markdown.claims_table``).

    python scripts/claims_two_runs.py runs/arena-sf runs/arena-steer --labels "social force" "steering speed"
    python scripts/claims_two_runs.py runs/arena-sf runs/arena-steer --held-out   # runs made with --held-out

Two runs of the same scenes, variants and seed pair their episodes (common random numbers), so a
claim's difference between the runs is the runs' own (the people's model, say).
"""

from __future__ import annotations

import argparse
import pathlib

import pandas as pd

from socialnav.evaluation.arena.markdown import claims_table


def directions(folder: str, name: str = "directions.csv") -> pd.DataFrame:
    path = pathlib.Path(folder, name)
    if not path.is_file():
        why = "not a finished arena run folder" if name == "directions.csv" else "a run made without --held-out?"
        raise SystemExit(f"{folder}: no {name} ({why})")
    return pd.read_csv(path)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs=2, help="two arena run folders")
    parser.add_argument("--labels", nargs=2, default=None, help="the two columns' names (default: the folders)")
    parser.add_argument(
        "--held-out", action="store_true", help="the claims on the held-out rows (directions_held_out.csv)"
    )
    args = parser.parse_args(argv)
    name = "directions_held_out.csv" if args.held_out else "directions.csv"
    a, b = (directions(r, name) for r in args.runs)
    print(claims_table(a, b, args.labels or args.runs))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
