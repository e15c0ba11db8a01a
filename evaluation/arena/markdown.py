"""An arena run's tables in Markdown, as the README and docs/arena-results.md show them.

Every function takes the frames an arena run folder holds (``summary.csv``, ``papers.csv``,
``directions.csv``, ``directions_turned.csv``, ``papers_stats.csv``, a sweep's
:data:`SWEEP_FILE`) or the paired frame :func:`turned_pairs` makes from its episodes
(:func:`run_turned_pairs` reads them), and returns a Markdown table with its count of verdicts
where it has any. ``scripts/results_tables.py`` writes them into the docs from the committed
snapshots of the docs' runs (``docs/results/``) and checks that the docs still say what those
runs say; ``scripts/papers_tables.py``, ``scripts/seed002_table1.py``,
``scripts/claims_two_runs.py`` and ``scripts/scene_sweep.py`` print them for any run folder.

Success is shown with a collision failing the run (``goal_no_collision``,
``social_no_collision``) unless a table says otherwise: seed 002 Sec. 5.3.1's reading, the one
its Table 1 and the arena's verdicts use.
"""

from __future__ import annotations

import math
import pathlib

import pandas as pd

from socialnav.evaluation.arena.papers import PAPER_ROWS, RATES
from socialnav.evaluation.arena.report import mean_interval
from socialnav.evaluation.arena.run import HELD_OUT, TURNED

# Seed 002's Table 1: its scenes and methods in the paper's order, under the paper's names.
SEED002_SCENES = {
    "gscl_l_hallway": "L-hallway",
    "gscl_group": "group",
    "gscl_non_group": "non-group",
    "gscl_crowded_entrance": "crowded entrance",
    "gscl_queue": "queue",
}
SEED002_METHODS = {"navfn": "NavFn (no layer)", "snl_small": "SNL small", "snl_large": "SNL large", "gscl": "GSCL"}

# The rows of a run's summary a table may show: the scene as written, mirrored, turned.
ROWS = {"own": "", "held_out": HELD_OUT, "turned": TURNED}


# A sweep's run (scripts/scene_sweep.py) notes its field and values in this file beside run.json.
SWEEP_FILE = "sweep.json"
# A snapshot's paired differences of two methods per scene (:func:`method_pairs`).
PAIRS_FILE = "pairs.csv"


def source_line(info: dict, where: str, lead: str = "From") -> str:
    """One line naming the run a table came from: its folder (``where``), the command, the source
    commit, the GSCL model's digest, the human model, variants and seed (``run.json``'s fields;
    a field the run did not record is said to be missing, never guessed; the host's instruction
    set where the run recorded it). ``lead`` opens it ("And from" for a table's second run)."""
    commit = info.get("source_commit")
    if commit:
        commit_text = f"commit {commit[:12]}" + (" with uncommitted changes" if info.get("source_dirty") else "")
    else:
        commit_text = "commit not recorded"
    command = info.get("command")
    return (
        f"{lead} `{where}`"
        + (f" (`{command}`)" if command else "")
        + f": {commit_text}, socialnav {info.get('socialnav_version')}, {info.get('metrics_version')}, "
        f"GSCL model {info.get('gscl_model')}"
        + (f" averaged over {info['gscl_rotations']} rotations" if info.get("gscl_rotations", 1) != 1 else "")
        + f", human model {info.get('human_model')}, {info.get('variants')} variants, seed {info.get('seed')}"
        + (f", {info['host']['isa']}" if isinstance(info.get("host"), dict) and info["host"].get("isa") else "")
        + "."
    )


def _number(value: float, metric: str) -> str:
    if value != value:
        return "-"
    return f"{value:.0f}" if metric.endswith("success_pct") or metric.endswith("collision_pct") else f"{value:.2f}"


def _pct(value) -> str:
    return "-" if value is None or (isinstance(value, float) and math.isnan(value)) else f"{value:.0f}"


def _cell(row: pd.Series, metric: str) -> str:
    return f"{row[f'{metric}_pct']:.0f} [{row[f'{metric}_lo']:.0f}, {row[f'{metric}_hi']:.0f}]"


def success_table(
    summary: pd.DataFrame, rows: str = "own", metrics=("goal_no_collision", "social_no_collision")
) -> str:
    """Scenes down, methods across, each cell ``goal / social`` success in % (``metrics``, by
    default a collision failing the run) for the rows named by ``rows`` (``own``, ``held_out``
    or ``turned``: :data:`ROWS`); scenes and methods in the run's order."""
    if rows not in ROWS:
        raise ValueError(f"rows='{rows}': one of {', '.join(ROWS)}")
    suffix = ROWS[rows]
    names = summary["scene"].astype(str)
    chosen = summary[names.str.endswith(suffix)] if suffix else summary[~names.str.contains("@", regex=False)]
    if chosen.empty:
        raise ValueError(f"the run has no {rows} rows")
    methods = list(dict.fromkeys(chosen["method"]))
    lines = ["| scene | " + " | ".join(methods) + " |", "|---|" + "---|" * len(methods)]
    for scene, g in chosen.groupby("scene", sort=False):
        by_method = g.set_index("method")
        cells = [
            " / ".join(_pct(by_method.loc[m, f"{metric}_pct"]) for metric in metrics) if m in by_method.index else "-"
            for m in methods
        ]
        lines.append(f"| `{scene}` | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def seed002_table1(summary: pd.DataFrame) -> str:
    """Seed 002's Table 1 beside the run: goal / social success with a collision failing the run
    and their 95 % Wilson intervals, the paper's two numbers, the held-out row's social success
    and goal success with collisions allowed (the arena's ``goal_success``). Raises ValueError
    naming the first scene and method the run lacks."""
    summary = summary.set_index(["scene", "method"])
    paper = {(s, m, metric): v for src, s, m, metric, v in PAPER_ROWS if src == "seed 002 Table 1"}
    lines = [
        "| scene | method | paper: goal / social | ours: goal [95 % CI] | ours: social [95 % CI] | held out: social "
        "| goal, collisions allowed |",
        "|---|---|---|---|---|---|---|",
    ]
    for scene, scene_name in SEED002_SCENES.items():
        for method, method_name in SEED002_METHODS.items():
            if (scene, method) not in summary.index:
                raise ValueError(f"no row for scene {scene}, method {method}")
            row = summary.loc[(scene, method)]
            held_key = (scene + HELD_OUT, method)
            held_cell = _cell(summary.loc[held_key], "social_no_collision") if held_key in summary.index else "-"
            theirs = f"{_pct(paper.get((scene, method, 'goal_no_collision_pct')))} / "
            theirs += _pct(paper.get((scene, method, "social_no_collision_pct")))
            lines.append(
                f"| {scene_name} | {method_name} | {theirs} | {_cell(row, 'goal_no_collision')} | "
                f"{_cell(row, 'social_no_collision')} | {held_cell} | {_cell(row, 'goal_success')} |"
            )
    return "\n".join(lines)


def papers_table(papers: pd.DataFrame) -> str:
    """``papers.csv``: each published number beside ours and its 95 % interval."""
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
    """``directions.csv`` (or ``directions_turned.csv``): each paper's difference between its
    method and a baseline beside ours, paired by variant, with its verdict and their count."""
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
    """``papers_stats.csv``: seed 002's Table 2 (Games-Howell p, Hedges' g) beside ours."""

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


def turned_pairs(episodes: pd.DataFrame, metrics=("social_no_collision", "goal_no_collision")) -> pd.DataFrame:
    """Each scene and method's success (%) on the scene and on the scene turned, paired by
    variant: one row per scene, method and metric with ``own_pct``, ``turned_pct``, the mean
    change ``change_pts`` and its 95 % interval ``change_lo``, ``change_hi`` (Student t of the
    per-variant differences, in points; :func:`evaluation.arena.report.mean_interval`)."""
    turned = episodes[episodes["scene"].str.endswith(TURNED)].assign(
        scene=lambda f: f["scene"].str.removesuffix(TURNED)
    )
    own = episodes[episodes["scene"].isin(set(turned["scene"]))]
    pairs = own.merge(turned, on=["scene", "method", "variant"], suffixes=("", "_turned"))
    rows = []
    for (scene, method), g in pairs.groupby(["scene", "method"], sort=False):
        for m in metrics:
            a, b = 100.0 * g[m].astype(float), 100.0 * g[f"{m}_turned"].astype(float)
            lo, hi = mean_interval(b - a)
            rows.append(
                {
                    "scene": scene,
                    "method": method,
                    "metric": m,
                    "own_pct": a.mean(),
                    "turned_pct": b.mean(),
                    "change_pts": (b - a).mean(),
                    "change_lo": lo,
                    "change_hi": hi,
                }
            )
    return pd.DataFrame(rows)


def run_turned_pairs(run: pathlib.Path) -> pd.DataFrame | None:
    """:func:`turned_pairs` of the arena run folder ``run`` (its scenes' episodes and their
    turned rows' episodes), or None where the run has no turned rows."""
    turned = sorted((run / "episodes").glob(f"*{TURNED}.parquet"))
    if not turned:
        return None
    own = [run / "episodes" / f.name.replace(TURNED, "") for f in turned]
    return turned_pairs(pd.concat([pd.read_parquet(f) for f in [*own, *turned] if f.is_file()]))


def turned_table(pairs: pd.DataFrame, moved_only: bool = False) -> str:
    """:func:`turned_pairs` as ``own -> turned, change [95 % interval]`` per metric (in the
    frame's order of metrics), and a count per method of the scenes whose first metric's interval
    excludes 0. ``moved_only``: only those rows."""
    metrics = list(dict.fromkeys(pairs["metric"]))
    lines = [
        "| scene | method | "
        + " | ".join(f"{m.replace('_', ' ')} %: own -> turned, change [95 %]" for m in metrics)
        + " |",
        "|---|---|" + "---|" * len(metrics),
    ]
    moved: dict[str, list[int]] = {}
    for (scene, method), g in pairs.groupby(["scene", "method"], sort=False):
        by_metric = g.set_index("metric")
        cells = [
            f"{r.own_pct:.0f} -> {r.turned_pct:.0f}, {r.change_pts:+.0f} [{r.change_lo:+.0f}, {r.change_hi:+.0f}]"
            for r in (by_metric.loc[m] for m in metrics)
        ]
        first = by_metric.loc[metrics[0]]
        first_moved = bool(first.change_lo > 0 or first.change_hi < 0)
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


def paired_difference(a: pd.Series, b: pd.Series, metric: str) -> dict:
    """Two methods' values of ``metric`` over the same episodes (aligned by position): their
    means, the mean difference ``a - b`` and its 95 % interval (Student t of the per-episode
    differences); a rate in % and points (:data:`~socialnav.evaluation.arena.papers.RATES`)."""
    scale = 100.0 if metric in RATES else 1.0
    x, y = scale * a.astype(float).to_numpy(), scale * b.astype(float).to_numpy()
    lo, hi = mean_interval(pd.Series(x - y))
    return {"n": len(x), "a": x.mean(), "b": y.mean(), "a - b": (x - y).mean(), "lo": lo, "hi": hi}


def method_pairs(episodes: pd.DataFrame, a: str, b: str, metrics) -> pd.DataFrame:
    """Method ``a`` against method ``b`` in each scene of ``episodes``, paired by variant: one
    row per scene and metric (:func:`paired_difference`) with the methods named. Raises
    ValueError naming a method the episodes lack."""
    for method in (a, b):
        if method not in set(episodes["method"]):
            raise ValueError(
                f"no method {method!r} in the episodes (they have {', '.join(sorted(set(episodes['method'])))})"
            )
    first, second = (episodes[episodes["method"] == m] for m in (a, b))
    both = first.merge(second, on=["scene", "variant"], suffixes=("_a", "_b"))
    rows = []
    for scene, g in both.groupby("scene", sort=True):
        for m in metrics:
            rows.append(
                {
                    "scene": scene,
                    "method_a": a,
                    "method_b": b,
                    "metric": m,
                    **paired_difference(g[f"{m}_a"], g[f"{m}_b"], m),
                }
            )
    return pd.DataFrame(rows)


def pairs_table(pairs: pd.DataFrame, metrics=None, names: dict | None = None) -> str:
    """:func:`method_pairs` rows as one line per scene and pair of methods: for each metric (all
    the frame holds, or ``metrics`` in that order) ``a - b [95 %] (a, b)``, rates in % and
    points. ``names``: what to show for a scene (a sweep's copy: its value). Raises ValueError
    naming a metric the frame lacks."""
    held = list(dict.fromkeys(pairs["metric"]))
    metrics = held if metrics is None else list(metrics)
    missing = [m for m in metrics if m not in held]
    if missing:
        raise ValueError(f"metrics={','.join(missing)}: not in the pairs (they hold {', '.join(held)})")

    def heading(m):
        if m in RATES:
            return f"{m.replace('_', ' ')} %"
        return f"{m.removesuffix('_m').replace('_', ' ')}, m" if m.endswith("_m") else m.replace("_", " ")

    lines = [
        "| scene | a - b | " + " | ".join(f"{heading(m)}: a - b [95 %] (a, b)" for m in metrics) + " |",
        "|---|---|" + "---|" * len(metrics),
    ]
    for (scene, a, b), g in pairs.groupby(["scene", "method_a", "method_b"], sort=False):
        by_metric = g.set_index("metric")
        cells = []
        for m in metrics:
            r = by_metric.loc[m]
            f = ".0f" if m in RATES else ".2f"
            cells.append(f"{r['a - b']:+{f}} [{r['lo']:+{f}}, {r['hi']:+{f}}] ({r['a']:{f}}, {r['b']:{f}})")
        shown = (names or {}).get(scene, f"`{scene}`")
        lines.append(f"| {shown} | {a} - {b} | " + " | ".join(cells) + " |")
    n = pairs["n"].unique()
    lines.append(f"\nPaired by variant ({', '.join(str(int(k)) for k in n)} pairs a scene); Student t intervals.")
    return "\n".join(lines)


def models_table(summaries, labels, method: str = "gscl", metrics=("goal_no_collision", "social_no_collision")) -> str:
    """One method's ``goal / social`` success in % (``metrics``) in several runs side by side, a
    column a run (``labels``): the same scenes run with different models of one method (another
    GSCL model, say). Scenes down in the first run's order; a scene a run lacks is ``-``. Raises
    ValueError when a run has no row of ``method`` or the labels do not match the runs."""
    if len(labels) != len(summaries):
        raise ValueError(f"{len(labels)} labels for {len(summaries)} runs")
    tables = []
    for label, summary in zip(labels, summaries, strict=True):
        rows = summary[summary["method"] == method]
        if rows.empty:
            raise ValueError(f"{label}: no row of method {method}")
        tables.append(rows.set_index("scene"))
    lines = [f"| scene ({method}) | " + " | ".join(labels) + " |", "|---|" + "---|" * len(labels)]
    for scene in tables[0].index:
        cells = [
            " / ".join(_pct(t.loc[scene, f"{m}_pct"]) for m in metrics) if scene in t.index else "-" for t in tables
        ]
        lines.append(f"| `{scene}` | " + " | ".join(cells) + " |")
    return "\n".join(lines)


CLAIM_KEY = ["source", "scene", "metric", "proposed", "baseline"]


def claims_table(a: pd.DataFrame, b: pd.DataFrame, labels=("a", "b")) -> str:
    """Two runs' ``directions.csv`` (or ``directions_held_out.csv``) joined by claim: each
    claim's paired difference with its interval and verdict in both, then the claims whose
    verdict differs between the runs (two runs of the same scenes, variants and seed pair their
    episodes, so the difference is the runs' own: the people's model, say)."""

    def cell(row, suffix: str) -> str:
        return (
            f"{row['ours_diff' + suffix]:+.2f} [{row['ours_diff_lo' + suffix]:+.2f}, "
            f"{row['ours_diff_hi' + suffix]:+.2f}] | {row['verdict' + suffix]}"
        )

    both = a.merge(b, on=CLAIM_KEY, suffixes=("_a", "_b"), how="outer", indicator=True)
    lines = [
        f"| source | scene | metric | proposed - baseline | paper | {labels[0]} | verdict | {labels[1]} | verdict |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for _, row in both.iterrows():
        left = cell(row, "_a") if row["_merge"] != "right_only" else "- | not run"
        right = cell(row, "_b") if row["_merge"] != "left_only" else "- | not run"
        paper = row["paper_diff_a"] if row["_merge"] != "right_only" else row["paper_diff_b"]
        lines.append(
            f"| {row['source']} | `{row['scene']}` | {row['metric']} | {row['proposed']} - {row['baseline']} | "
            f"{paper:+.2f} | {left} | {right} |"
        )
    matched = both[both["_merge"] == "both"]
    changed = matched[matched["verdict_a"] != matched["verdict_b"]]
    ending = ":" if len(changed) else "."
    lines.append(f"\n{len(matched)} claims in both runs; the verdict differs in {len(changed)}{ending}")
    for _, row in changed.iterrows():
        lines.append(
            f"- {row['scene']} {row['metric']} ({row['proposed']} - {row['baseline']}): {row['verdict_a']} -> "
            f"{row['verdict_b']}"
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


def speed_class_table(comparison: pd.DataFrame, sweep: dict) -> str:
    """:func:`evaluation.arena.papers.speed_class_comparison` as one line per speed class and metric:
    the paper's walkers' speeds and ours (``sweep``'s values), each method's value in the paper and
    here [95 %], the difference CASN - SNL matched in both, paired by variant here, and its
    verdict; then the count of verdicts and of the paper's values inside our intervals."""
    lines = [
        "| class: walkers' speed, paper (CASN, SNL); ours (m/s) | metric | CASN: paper, ours [95 %] "
        "| SNL matched: paper, ours [95 %] | CASN - SNL: paper, ours [95 %, paired] | verdict |",
        "|---|---|---|---|---|---|",
    ]
    ours_speed = dict(zip(comparison["copy"].drop_duplicates(), sweep["values"], strict=True))

    def number(value: float, metric: str) -> str:
        return f"{value:.0f}" if metric.endswith("_pct") else f"{value:.2f}"

    for r in comparison.itertuples():
        metric = "d min, m" if r.metric == "d_min_m" else "intruded %"
        speeds = f"{r.speed_class}: {r.casn_paper_speed_mps:.2f}, {r.snl_paper_speed_mps:.2f}; "
        speeds += sweep_value_label(ours_speed[r.copy])
        cells = [
            f"{number(getattr(r, f'{m}_paper'), r.metric)}, {number(getattr(r, f'{m}_ours'), r.metric)} "
            f"[{number(getattr(r, f'{m}_lo'), r.metric)}, {number(getattr(r, f'{m}_hi'), r.metric)}]"
            for m in ("casn", "snl")
        ]
        f = "+.0f" if r.metric.endswith("_pct") else "+.2f"
        diff = f"{r.paper_diff:{f}}, {r.ours_diff:{f}} [{r.ours_diff_lo:{f}}, {r.ours_diff_hi:{f}}]"
        lines.append(f"| {speeds} | {metric} | {cells[0]} | {cells[1]} | {diff} | {r.verdict} |")
    counts = ", ".join(f"{n} {v}" for v, n in comparison["verdict"].value_counts().items())
    inside = int(comparison["casn_inside"].sum() + comparison["snl_inside"].sum())
    lines.append(
        f"\nOf {len(comparison)} differences: {counts}. Of the paper's {2 * len(comparison)} values, "
        f"{inside} inside our interval. {int(comparison['n_pairs'].iloc[0])} variants a class; the paper's "
        "trials per class and method: 5-11."
    )
    return "\n".join(lines)


def sweep_copy_name(scene: str, k: int) -> str:
    """The name of a sweep's copy ``k`` of ``scene`` (``scripts/scene_sweep.py``)."""
    return f"{scene}+sweep{k}"


def sweep_copy_labels(sweep: dict) -> dict[str, str]:
    """Each copy's name -> ``<scene>, <label>: <value>`` (``sweep`` as :data:`SWEEP_FILE` holds it)."""
    label = sweep.get("label") or sweep["field"]
    return {
        sweep_copy_name(sweep["scene"], k): f"`{sweep['scene']}`, {label}: {sweep_value_label(v)}"
        for k, v in enumerate(sweep["values"])
    }


def sweep_value_label(value) -> str:
    """A swept value as a table shows it: ``2`` or a range ``0-0.5``."""
    return "-".join(f"{v:g}" for v in value) if isinstance(value, list) else f"{value:g}"


def sweep_table(summary: pd.DataFrame, sweep: dict, metric: str = "social_no_collision") -> str:
    """Values down, methods across: ``metric`` in % with its 95 % interval per copy of the scene
    (``sweep``: ``{"scene", "field", "values"}`` and optionally ``"label"``, the swept value's
    name, as :data:`SWEEP_FILE` holds them). Raises ValueError naming a copy and method the
    summary lacks, or a metric it does not hold."""
    if f"{metric}_pct" not in summary.columns:
        raise ValueError(f"metric={metric}: not a rate the summary holds")
    rows = summary.set_index(["scene", "method"])
    methods = list(dict.fromkeys(summary["method"]))
    lines = [
        f"| {sweep.get('label') or sweep['field']} | " + " | ".join(methods) + " |",
        "|---|" + "---|" * len(methods),
    ]
    for k, value in enumerate(sweep["values"]):
        name = sweep_copy_name(sweep["scene"], k)
        cells = []
        for m in methods:
            if (name, m) not in rows.index:
                raise ValueError(f"no row for {name}, method {m}")
            cells.append(_cell(rows.loc[(name, m)], metric))
        lines.append(f"| {sweep_value_label(value)} | " + " | ".join(cells) + " |")
    n = int(summary["n"].iloc[0])
    lines.append(f"\n{metric.replace('_', ' ')} %, [95 % Wilson interval], {n} variants a cell.")
    return "\n".join(lines)
