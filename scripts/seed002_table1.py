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
import math
import pathlib
import sys

import pandas as pd

SCENES = {
    "gscl_l_hallway": "L-hallway",
    "gscl_group": "group",
    "gscl_non_group": "non-group",
    "gscl_crowded_entrance": "crowded entrance",
    "gscl_queue": "queue",
}
METHODS = {"navfn": "NavFn (no layer)", "snl_small": "SNL small", "snl_large": "SNL large", "gscl": "GSCL"}


def _pct(value: float) -> str:
    return "-" if value is None or (isinstance(value, float) and math.isnan(value)) else f"{value:.0f}"


def _cell(row: pd.Series, metric: str) -> str:
    lo, hi = row[f"{metric}_lo"], row[f"{metric}_hi"]
    return f"{row[f'{metric}_pct']:.0f} [{lo:.0f}, {hi:.0f}]"


def table(run: pathlib.Path) -> str:
    """The Markdown table of ``run`` (an arena run's folder)."""
    from socialnav.evaluation.arena.papers import PAPER_ROWS
    from socialnav.evaluation.arena.run import HELD_OUT

    summary_path = run / "summary.csv"
    if not summary_path.is_file():
        raise SystemExit(f"{summary_path}: no such file (an arena run's folder, socialnav arena --out)")
    summary = pd.read_csv(summary_path).set_index(["scene", "method"])
    paper = {(s, m, metric): v for src, s, m, metric, v in PAPER_ROWS if src == "seed 002 Table 1"}
    lines = [
        "| scene | method | paper: goal / social | ours: goal [95 % CI] | ours: social [95 % CI] | held out: social "
        "| goal, collisions allowed |",
        "|---|---|---|---|---|---|---|",
    ]
    for scene, scene_name in SCENES.items():
        for method, method_name in METHODS.items():
            if (scene, method) not in summary.index:
                raise SystemExit(f"{summary_path}: no row for scene {scene}, method {method}")
            row = summary.loc[(scene, method)]
            held_key = (scene + HELD_OUT, method)
            held = summary.loc[held_key] if held_key in summary.index else None
            theirs = f"{_pct(paper.get((scene, method, 'goal_no_collision_pct')))} / "
            theirs += _pct(paper.get((scene, method, "social_no_collision_pct")))
            held_cell = _cell(held, "social_no_collision") if held is not None else "-"
            lines.append(
                f"| {scene_name} | {method_name} | {theirs} | {_cell(row, 'goal_no_collision')} | "
                f"{_cell(row, 'social_no_collision')} | {held_cell} | {_cell(row, 'goal_success')} |"
            )
    return "\n".join(lines)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("run", type=pathlib.Path, help="an arena run's folder (socialnav arena --out)")
    print(table(parser.parse_args(argv).run))


if __name__ == "__main__":
    sys.exit(main())
