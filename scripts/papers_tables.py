"""The papers' tables of an arena run folder in Markdown, as docs/arena-results.md shows them.

    python scripts/papers_tables.py runs/arena > tables.md

Prints, under a line naming the run (its folder, the package and metrics versions, the GSCL
model's digest, the variants and the seed from ``run.json``): ``papers.csv`` (each published number
beside ours and its 95 % interval), ``directions.csv`` (each paper's difference between its method
and a baseline beside ours, paired by variant) and ``papers_stats.csv`` (seed 002's Table 2), each
with a count of its verdicts; where the run has turned rows (``socialnav arena --turned``), each
method's social and goal success (a collision failing the run) on the scenes where the turn moved
it (``--all-turned``: on every scene) beside the same on the scene turned, with the paired
change's interval (:func:`turned_table`), and the papers' differences on the turned rows
(``directions_turned.csv``) with the verdicts the turn changed. Tables in the docs made this way
can be made again from the run.
"""

from __future__ import annotations

import argparse
import json
import pathlib

import pandas as pd

from socialnav.evaluation.arena.run import TURNED


def _source(run: pathlib.Path) -> str:
    info = json.loads((run / "run.json").read_text())
    return (
        f"From `{run.name}`: socialnav {info.get('socialnav_version')}, {info.get('metrics_version')}, "
        f"GSCL model {info.get('gscl_model')}, {info.get('variants')} variants, seed {info.get('seed')}, "
        f"human model {info.get('human_model')}."
    )


def _number(value: float, metric: str) -> str:
    if value != value:
        return "-"
    return f"{value:.0f}" if metric.endswith("success_pct") or metric.endswith("collision_pct") else f"{value:.2f}"


def papers_table(papers: pd.DataFrame) -> str:
    lines = [
        "| source | scene | method | metric | paper | ours [95 % interval] | paper inside |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in papers.itertuples():
        ours = f"{_number(r.ours, r.metric)} [{_number(r.ours_lo, r.metric)}, {_number(r.ours_hi, r.metric)}]"
        inside = {"True": "yes", "False": "no"}.get(str(r.paper_inside), "-")
        lines.append(
            f"| {r.source} | `{r.scene}` | {r.method} | {r.metric} | {_number(r.paper, r.metric)} | {ours} | {inside} |"
        )
    inside = papers["paper_inside"].astype(str).str.lower() == "true"
    lines.append(f"\n{int(inside.sum())} of {len(papers)} published numbers inside our intervals.")
    return "\n".join(lines)


def directions_table(directions: pd.DataFrame) -> str:
    lines = [
        "| source | scene | metric | proposed - baseline | paper | ours [95 % interval, paired] | verdict |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in directions.itertuples():
        ours = (
            "-" if r.ours_diff != r.ours_diff else f"{r.ours_diff:+.2f} [{r.ours_diff_lo:+.2f}, {r.ours_diff_hi:+.2f}]"
        )
        pair = f"{r.proposed} - {r.baseline}"
        lines.append(f"| {r.source} | `{r.scene}` | {r.metric} | {pair} | {r.paper_diff:+.2f} | {ours} | {r.verdict} |")
    counts = ", ".join(f"{n} {v}" for v, n in directions["verdict"].value_counts().items())
    lines.append(f"\nOf {len(directions)} differences: {counts}.")
    return "\n".join(lines)


def stats_table(stats: pd.DataFrame) -> str:
    def p(v: float) -> str:
        return "≤ .0001" if v <= 1e-4 else f"{v:.4f}"

    lines = [
        "| scene | zone | GSCL against | distance | n | paper: p, g | ours: p, g | verdict |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in stats.itertuples():
        lines.append(
            f"| `{r.scene}` | {r.measure} | {r.baseline} | {r.distance} | {r.n} | {p(r.paper_p)}, {r.paper_g:+.3f} "
            f"| {p(r.ours_p)}, {r.ours_g:+.2f} | {r.verdict} |"
        )
    for distance, g in stats.groupby("distance", sort=False):
        counts = ", ".join(f"{n} {v}" for v, n in g["verdict"].value_counts().items())
        lines.append(f"\n{distance}, {len(g)} cells: {counts}.")
    return "\n".join(lines)


def turned_table(
    episodes: pd.DataFrame, metrics=("social_no_collision", "goal_no_collision"), moved_only: bool = False
) -> str:
    """Each scene and method's success (%, by default with a collision failing the run, seed 002's
    reading) on the scene and on the scene turned, paired by variant:
    ``own -> turned, change [95 % interval]`` (Student t of the per-variant differences, in
    points; ``evaluation.arena.report.mean_interval``), and a count of the cells whose interval
    excludes 0, per method. ``moved_only``: only the rows whose first metric's interval excludes 0
    (the table docs/arena-results.md shows)."""
    from socialnav.evaluation.arena.report import mean_interval

    turned = episodes[episodes["scene"].str.endswith(TURNED)].assign(
        scene=lambda f: f["scene"].str.removesuffix(TURNED)
    )
    own = episodes[episodes["scene"].isin(set(turned["scene"]))]
    key = ["scene", "method", "variant"]
    pairs = own.merge(turned, on=key, suffixes=("", "_turned"))
    lines = [
        "| scene | method | "
        + " | ".join(f"{m.replace('_', ' ')} %: own -> turned, change [95 %]" for m in metrics)
        + " |",
        "|---|---|" + "---|" * len(metrics),
    ]
    moved: dict[str, list[int]] = {}
    for (scene, method), g in pairs.groupby(["scene", "method"], sort=False):
        cells, first_moved = [], False
        for m in metrics:
            a, b = 100.0 * g[m].astype(float), 100.0 * g[f"{m}_turned"].astype(float)
            lo, hi = mean_interval(b - a)
            cells.append(f"{a.mean():.0f} -> {b.mean():.0f}, {(b - a).mean():+.0f} [{lo:+.0f}, {hi:+.0f}]")
            if m == metrics[0]:
                first_moved = bool(lo > 0 or hi < 0)
                count = moved.setdefault(method, [0, 0])
                count[0] += int(first_moved)
                count[1] += 1
        if first_moved or not moved_only:
            lines.append(f"| `{scene}` | {method} | " + " | ".join(cells) + " |")
    lines.append(
        f"\n{metrics[0].replace('_', ' ')} changed by the turn (interval excluding 0), scenes per method: "
        + ", ".join(f"{method} {n} of {total}" for method, (n, total) in moved.items())
        + "."
    )
    return "\n".join(lines)


def verdict_changes(directions: pd.DataFrame, turned: pd.DataFrame) -> str:
    """The papers' differences whose verdict differs on the turned rows, one line each."""
    key = ["source", "scene", "metric", "proposed", "baseline"]
    both = directions.merge(turned, on=key, suffixes=("", "_turned"))
    changed = both[both["verdict"] != both["verdict_turned"]]
    lines = [f"{len(changed)} of {len(both)} verdicts change on the turned rows" + (":" if len(changed) else ".")]
    for r in changed.itertuples():
        lines.append(
            f"- {r.source}, `{r.scene}`, {r.metric}, {r.proposed} - {r.baseline}: {r.verdict} ({r.ours_diff:+.2f}) "
            f"-> {r.verdict_turned} ({r.ours_diff_turned:+.2f})"
        )
    return "\n".join(lines)


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
    print(_source(run))
    for name, table in (
        ("papers.csv", papers_table),
        ("directions.csv", directions_table),
        ("papers_stats.csv", stats_table),
    ):
        if (run / name).is_file():
            print(f"\n`{name}`:\n")
            print(table(pd.read_csv(run / name)))
    turned_files = sorted((run / "episodes").glob(f"*{TURNED}.parquet"))
    if turned_files:
        own_files = [run / "episodes" / f.name.replace(TURNED, "") for f in turned_files]
        episodes = pd.concat([pd.read_parquet(f) for f in [*own_files, *turned_files] if f.is_file()])
        which = "every scene and method" if args.all_turned else "the cells whose social success moved"
        print(f"\nEvery scene turned a quarter turn (`--turned`), paired by variant; {which}:\n")
        print(turned_table(episodes, moved_only=not args.all_turned))
    if (run / "directions_turned.csv").is_file():
        turned = pd.read_csv(run / "directions_turned.csv")
        print("\n`directions_turned.csv`:\n")
        print(directions_table(turned))
        if (run / "directions.csv").is_file():
            print("\n" + verdict_changes(pd.read_csv(run / "directions.csv"), turned))


if __name__ == "__main__":
    main()
