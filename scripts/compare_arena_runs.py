"""Two methods of two arena runs, episode by episode: the paired difference of each metric pooled
over scene groups (and, with ``--by-scene``, per scene), with 95 % intervals.

    python scripts/compare_arena_runs.py runs/a:gscl runs/b:gscl --metrics social_success,goal_success
    python scripts/compare_arena_runs.py runs/angles:casn runs/angles:snl_matched --by-scene   # two methods, one run

Each side is ``RUN_FOLDER:METHOD``. Episodes pair by scene and variant: two runs of the same
scenes, variants and seed draw the same variants (common random numbers), so the difference of a
pair is the methods' (or the models', or the people's) alone. Success rates are in percentage
points. Pools: every scene, and for recorded crowds each playback (``replayed``, ``reactive``)
on the evaluated and the held-out windows apart. Intervals: Student t of the paired differences
(``evaluation.arena.markdown.paired_difference``).
"""

from __future__ import annotations

import argparse
import pathlib

import pandas as pd

from socialnav.evaluation.arena.markdown import paired_difference


def episodes(side: str) -> pd.DataFrame:
    """The episodes of ``RUN:METHOD``."""
    folder, _, method = side.rpartition(":")
    frames = [pd.read_parquet(f) for f in sorted(pathlib.Path(folder, "episodes").glob("*.parquet"))]
    if not frames:
        raise SystemExit(f"{folder}: no episodes/ (not an arena run folder)")
    table = pd.concat(frames, ignore_index=True)
    if method not in set(table["method"]):
        raise SystemExit(f"{side}: no method {method!r} in {folder} (it has {', '.join(sorted(set(table['method'])))})")
    return table[table["method"] == method]


def group_of(scene: str) -> str:
    """A scene's pool: its playback and whether held out, for recorded crowds; else ``seed``."""
    held = "held-out" if scene.endswith("@held_out") else "evaluated"
    base = scene.removesuffix("@held_out")
    for playback in ("replayed", "reactive"):
        if base.endswith(f"_{playback}"):
            return f"{playback}, {held}"
    return f"seed scenes, {held}"


def paired(a: pd.DataFrame, b: pd.DataFrame, metrics, by_scene: bool = False) -> pd.DataFrame:
    """Rows of (pool, metric, n, a's mean, b's mean, mean difference a - b, its interval); with
    ``by_scene`` a pool per scene too, after the groups."""
    both = a.merge(b, on=["scene", "variant"], suffixes=("_a", "_b"))
    both["pool"] = both["scene"].map(group_of)
    pools = [("every scene", both), *both.groupby("pool", sort=True)]
    if by_scene:
        pools += [(f"`{scene}`", g) for scene, g in both.groupby("scene", sort=True)]
    rows = [
        {"pool": pool, "metric": metric, **paired_difference(g[f"{metric}_a"], g[f"{metric}_b"], metric)}
        for pool, g in pools
        for metric in metrics
    ]
    return pd.DataFrame(rows)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("a", help="RUN_FOLDER:METHOD")
    parser.add_argument("b", help="RUN_FOLDER:METHOD")
    parser.add_argument("--metrics", default="social_success,goal_success,collisions", help="comma-separated")
    parser.add_argument("--by-scene", action="store_true", help="each scene's paired difference too")
    args = parser.parse_args(argv)
    table = paired(episodes(args.a), episodes(args.b), args.metrics.split(","), args.by_scene)
    print(f"a = {args.a}, b = {args.b}; rates in %, differences paired by scene and variant")
    print(table.to_string(index=False, float_format=lambda v: f"{v:.2f}"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
