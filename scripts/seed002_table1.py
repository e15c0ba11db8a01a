"""Seed 002's Table 1 beside an arena run's figures, as a Markdown table (the README's).

    socialnav arena --held-out --out runs/bench            # or only the table's scenes and methods:
    socialnav arena --scenes gscl_l_hallway,gscl_group,gscl_non_group,gscl_crowded_entrance,gscl_queue \
        --methods navfn,snl_small,snl_large,gscl --held-out --out runs/table1
    python scripts/seed002_table1.py runs/table1

Each cell is goal / social success % with their 95 % Wilson intervals (from the run's
``summary.csv``), a collision failing the run as in the paper (Sec. 5.3.1: collisions "prevent
goal completion"); the paper's column is its Table 1 (``evaluation.arena.papers.PAPER_ROWS``); then
the held-out row's social success (the scene mirrored, its ranges drawn just outside
themselves), and goal success with collisions allowed (the arena's ``goal_success``). A missing
run, or one without the table's scenes and methods, is named in one line.
"""

from __future__ import annotations

import argparse
import pathlib
import sys

import pandas as pd


def table(run: pathlib.Path) -> str:
    """The Markdown table of ``run`` (an arena run's folder): ``evaluation.arena.markdown.seed002_table1``."""
    from socialnav.evaluation.arena.markdown import seed002_table1

    summary_path = run / "summary.csv"
    if not summary_path.is_file():
        raise SystemExit(f"{summary_path}: no such file (an arena run's folder, socialnav arena --out)")
    try:
        return seed002_table1(pd.read_csv(summary_path))
    except ValueError as e:
        raise SystemExit(f"{summary_path}: {e}") from None


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("run", type=pathlib.Path, help="an arena run's folder (socialnav arena --out)")
    print(table(parser.parse_args(argv).run))


if __name__ == "__main__":
    sys.exit(main())
