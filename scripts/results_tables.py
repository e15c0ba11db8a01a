"""The results tables of the README and the docs, made from the runs they came from.

    python scripts/results_tables.py snapshot runs/arena arena   # keep a run's tables: docs/results/arena/
    python scripts/results_tables.py snapshot runs/angles angles --pairs casn:snl_matched   # and two methods paired
    python scripts/results_tables.py write                       # every generated table made again
    python scripts/results_tables.py check                       # exit 1 naming each table that differs

A table in a Markdown page (README.md, docs/*.md) is generated when it stands between

    <!-- results: KIND RUN [OPTION=VALUE ...] -->
    <!-- /results -->

where RUN names a snapshot under ``docs/results/`` and KIND one of :data:`KINDS`. Options:
``success`` takes ``rows=own|held_out|turned``; ``directions`` ``source=...``, one paper's table
(quoted: ``source="seed 002 Table 1"``); ``turned`` ``cells=all`` for every cell, not only those
the turn moved (``cells=moved``); ``sweep`` ``metric=...``; ``claims`` sets the papers' claims of
two runs side by side (``other=NAME``, ``labels="a|b"``, ``rows=own|held_out|turned``, ``source=``
the claims whose source starts so, quoted: ``source="seed 002"``); ``pairs`` (a
snapshot made with ``--pairs A:B``: two methods paired by variant in each scene) takes
``metrics=a,b,...``; ``models`` sets one method's goal / social success in several runs side by
side (the same scenes with another model: ``other=B,C``, ``labels="a|b|c"``, ``method=gscl``);
``speed_classes`` sets seed 001's rows by walker speed beside a sweep of the head-on's or the
crossing's walker speed made with ``--pairs casn:snl_matched``, one copy a class.
``write`` fills each such block with a line naming the run (its command, source commit, GSCL
model, human model, variants and seed: ``run.json``) and the table
(:mod:`socialnav.evaluation.arena.markdown`); ``check`` does the same in memory and names each
block whose text differs (``tests/test_results_tables.py`` runs it, so a page that no longer
says what its run says fails the tests).

A **snapshot** is the part of an arena run folder the tables read, small enough to commit:
``run.json``, the summary's rates and a few means (:data:`SUMMARY_COLUMNS`), the files of
:data:`COPIED` the run has (the papers' comparisons; ``sweep.json`` for a run of
``scripts/scene_sweep.py``) and, for a run with turned rows, ``turned.csv``
(:func:`~socialnav.evaluation.arena.markdown.turned_pairs` of its episodes), and with ``--pairs``
``pairs.csv``. Run folders themselves (episodes, trajectories, pictures) stay out of git.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import re
import shlex
import sys

import pandas as pd

from socialnav.common.atomic import write_text_atomic
from socialnav.common.names import check_name
from socialnav.evaluation.arena import markdown, papers

ROOT = pathlib.Path(__file__).resolve().parent.parent
RESULTS = ROOT / "docs" / "results"
PAGES = ("README.md", "docs/*.md")
RATES = ("goal_success", "social_success", "goal_no_collision", "social_no_collision", "intruded")
MEANS = ("collisions", "intrusions", "d_min_m")
SUMMARY_COLUMNS = (
    "scene",
    "method",
    "n",
    *(f"{r}_{part}" for r in RATES for part in ("pct", "lo", "hi")),
    *(f"{m}{part}" for m in MEANS for part in ("", "_lo", "_hi")),
)
COPIED = (
    "run.json",
    "papers.csv",
    "directions.csv",
    "directions_held_out.csv",
    "directions_turned.csv",
    "papers_stats.csv",
    markdown.SWEEP_FILE,
)
# What a snapshot's paired differences hold (``--pairs``): the rates and the means of the summary.
PAIRED_METRICS = (*RATES, *MEANS)
DIFFERS = "differs from what its run says (python scripts/results_tables.py write)"
BLOCK = re.compile(r"(<!-- results: (?P<spec>[^>]*?) -->\n)(?P<body>.*?)(<!-- /results -->)", re.S)


def snapshot(
    run: pathlib.Path,
    name: str,
    results: pathlib.Path = RESULTS,
    command: str | None = None,
    pairs: tuple[str, ...] = (),
) -> pathlib.Path:
    """Copy what the tables read from the arena run folder ``run`` into ``results/name``
    (replacing an earlier snapshot of that name whole); returns the folder. ``command``: the
    command that made the run, noted in the snapshot's ``run.json`` where the run did not note
    it (a run made before ``socialnav arena`` noted its command). ``pairs``: ``"A:B"`` for each
    two methods whose paired differences per scene are kept (``pairs.csv``, every metric of
    :data:`PAIRED_METRICS` the episodes hold; :func:`~socialnav.evaluation.arena.markdown.method_pairs`)."""
    try:
        check_name(name, "snapshot name")
    except ValueError as e:
        raise SystemExit(str(e)) from None
    for needed in ("run.json", "summary.csv"):
        if not (run / needed).is_file():
            raise SystemExit(f"{run / needed}: no such file (an arena run folder, socialnav arena --out)")
    folder = results / name
    folder.mkdir(parents=True, exist_ok=True)
    earlier = (*COPIED, "summary.csv", "turned.csv", markdown.PAIRS_FILE)  # an earlier snapshot's files only
    for stale in earlier:
        (folder / stale).unlink(missing_ok=True)
    summary = pd.read_csv(run / "summary.csv")
    summary[[c for c in SUMMARY_COLUMNS if c in summary.columns]].to_csv(
        folder / "summary.csv", index=False, float_format="%.6g"
    )
    for file in COPIED[1:]:
        if (run / file).is_file():
            write_text_atomic(folder / file, (run / file).read_text())
    info = json.loads((run / "run.json").read_text())
    if (run / markdown.SWEEP_FILE).is_file():  # a sweep's run: the command that made the sweep, not its arena call
        info["command"] = json.loads((run / markdown.SWEEP_FILE).read_text()).get("command", info.get("command"))
    if command is not None and info.get("command") not in (None, command):
        raise SystemExit(f"{run / 'run.json'}: made by '{info['command']}', not '{command}'")
    info.setdefault("command", command)
    write_text_atomic(folder / "run.json", json.dumps(info, indent=1) + "\n")
    turned = markdown.run_turned_pairs(run)
    if turned is not None:
        turned.to_csv(folder / "turned.csv", index=False, float_format="%.6g")
    if pairs:
        _method_pairs(run, pairs).to_csv(folder / markdown.PAIRS_FILE, index=False, float_format="%.6g")
    return folder


def _method_pairs(run: pathlib.Path, pairs: tuple[str, ...]) -> pd.DataFrame:
    files = sorted((run / "episodes").glob("*.parquet"))
    if not files:
        raise SystemExit(f"{run / 'episodes'}: no episodes (an arena run folder, socialnav arena --out)")
    episodes = pd.concat([pd.read_parquet(f) for f in files], ignore_index=True)
    metrics = [m for m in PAIRED_METRICS if m in episodes.columns]
    frames = []
    for pair in pairs:
        a, sep, b = pair.partition(":")
        if not (sep and a and b):
            raise SystemExit(f"--pairs {pair}: two methods as A:B")
        try:
            frames.append(markdown.method_pairs(episodes, a, b, metrics))
        except ValueError as e:
            raise SystemExit(f"{run / 'episodes'}: {e}") from None
    return pd.concat(frames, ignore_index=True)


def _read(folder: pathlib.Path, file: str) -> pd.DataFrame:
    path = folder / file
    if not path.is_file():
        raise ValueError(f"{path}: no such file")
    return pd.read_csv(path)


def _shown(folder: pathlib.Path) -> str:
    """A snapshot's folder as a page names it: relative to the repository where it lies in it."""
    return str(folder.relative_to(ROOT) if folder.is_relative_to(ROOT) else folder)


def _success(folder, rows="own"):
    return markdown.success_table(_read(folder, "summary.csv"), rows=rows)


def _seed002(folder):
    return markdown.seed002_table1(_read(folder, "summary.csv"))


def _papers(folder):
    return markdown.papers_table(_read(folder, "papers.csv"))


def _directions(folder, source=None):
    directions = _read(folder, "directions.csv")
    if source is not None:
        directions = directions[directions["source"] == source]
        if directions.empty:
            raise ValueError(f"source='{source}': no such source in {folder / 'directions.csv'}")
    return markdown.directions_table(directions)


def _directions_turned(folder):
    turned = _read(folder, "directions_turned.csv")
    return (
        markdown.directions_table(turned) + "\n\n" + markdown.verdict_changes(_read(folder, "directions.csv"), turned)
    )


def _stats(folder):
    return markdown.stats_table(_read(folder, "papers_stats.csv"))


def _turned(folder, cells="moved"):
    if cells not in ("moved", "all"):
        raise ValueError(f"cells={cells}: moved or all")
    return markdown.turned_table(_read(folder, "turned.csv"), moved_only=cells == "moved")


def _other_snapshot(folder: pathlib.Path, name: str) -> pathlib.Path:
    """A second snapshot a table reads beside ``folder`` (``other=NAME``); ValueError if there is none."""
    second = folder.parent / name
    if not (second / "run.json").is_file():
        raise ValueError(f"{second}: no snapshot (python scripts/results_tables.py snapshot RUN {name})")
    return second


def _and_from(run: pathlib.Path) -> str:
    """The source line of a table's second (third ...) run."""
    return markdown.source_line(json.loads((run / "run.json").read_text()), _shown(run), lead="And from")


def _claims(folder, other=None, labels=None, rows="own", source=None):
    if other is None:
        raise ValueError("claims needs other=NAME, the second run's snapshot")
    files = {"own": "directions.csv", "held_out": "directions_held_out.csv", "turned": "directions_turned.csv"}
    if rows not in files:
        raise ValueError(f"rows='{rows}': own, held_out or turned")
    second = _other_snapshot(folder, other)
    names = labels.split("|") if labels else [folder.name, other]
    if len(names) != 2:
        raise ValueError(f"labels='{labels}': two names, as 'a|b'")
    a, b = _read(folder, files[rows]), _read(second, files[rows])
    if source is not None:  # one seed's claims (a run of its scenes and methods only: the rest not run)
        a, b = (d[d["source"].str.startswith(source)] for d in (a, b))
        if a.empty and b.empty:
            raise ValueError(f"source='{source}': no claim's source starts so in either run")
    return _and_from(second) + "\n\n" + markdown.claims_table(a, b, names)


def _models(folder, other=None, labels=None, method="gscl"):
    runs = [folder, *(_other_snapshot(folder, name) for name in (other.split(",") if other else []))]
    names = labels.split("|") if labels else [run.name for run in runs]
    table = markdown.models_table([_read(run, "summary.csv") for run in runs], names, method)
    return "\n\n".join([*(_and_from(run) for run in runs[1:]), table])


def _sweep_of(folder: pathlib.Path) -> dict:
    """A sweep's snapshot's :data:`~socialnav.evaluation.arena.markdown.SWEEP_FILE`; ValueError if it has none."""
    path = folder / markdown.SWEEP_FILE
    if not path.is_file():
        raise ValueError(f"{path}: no such file (a run of scripts/scene_sweep.py)")
    return json.loads(path.read_text())


def _sweep(folder, metric="social_no_collision"):
    return markdown.sweep_table(_read(folder, "summary.csv"), _sweep_of(folder), metric)


def _pairs(folder, metrics=None):
    sweep = folder / markdown.SWEEP_FILE  # a sweep's copies shown by their value
    names = markdown.sweep_copy_labels(json.loads(sweep.read_text())) if sweep.is_file() else None
    return markdown.pairs_table(_read(folder, markdown.PAIRS_FILE), metrics.split(",") if metrics else None, names)


def _speed_classes(folder):
    sweep = _sweep_of(folder)
    copies = [markdown.sweep_copy_name(sweep["scene"], k) for k in range(len(sweep["values"]))]
    comparison = papers.speed_class_comparison(
        _read(folder, "summary.csv"), _read(folder, markdown.PAIRS_FILE), sweep["scene"], copies
    )
    return markdown.speed_class_table(comparison, sweep)


KINDS = {
    "success": _success,
    "seed002_table1": _seed002,
    "papers": _papers,
    "directions": _directions,
    "directions_turned": _directions_turned,
    "stats": _stats,
    "turned": _turned,
    "sweep": _sweep,
    "claims": _claims,
    "pairs": _pairs,
    "models": _models,
    "speed_classes": _speed_classes,
}


def render(spec: str, results: pathlib.Path = RESULTS) -> str:
    """The text of the block ``<!-- results: spec -->``: the run's line and its table. Raises
    ValueError naming what is wrong with ``spec`` (an unknown kind or option, a missing run)."""
    words = shlex.split(spec)
    if len(words) < 2:
        raise ValueError(f"'{spec}': expected KIND RUN [OPTION=VALUE ...]")
    kind, name, *options = words
    if kind not in KINDS:
        raise ValueError(f"'{kind}': not a kind of table ({', '.join(KINDS)})")
    folder = results / name
    if not (folder / "run.json").is_file():
        raise ValueError(f"{folder}: no snapshot (python scripts/results_tables.py snapshot RUN {name})")
    try:
        kwargs = dict(o.split("=", 1) for o in options)
    except ValueError:
        raise ValueError(f"'{spec}': options are OPTION=VALUE") from None
    try:
        table = KINDS[kind](folder, **kwargs)
    except TypeError:
        raise ValueError(f"'{spec}': {kind} takes no option {', '.join(kwargs)}") from None
    return markdown.source_line(json.loads((folder / "run.json").read_text()), _shown(folder)) + "\n\n" + table + "\n\n"


def pages(root: pathlib.Path = ROOT) -> list[pathlib.Path]:
    """The Markdown pages whose generated blocks are kept: README.md and docs/*.md."""
    return sorted(p for pattern in PAGES for p in root.glob(pattern))


def stale_blocks(page: pathlib.Path, results: pathlib.Path = RESULTS) -> tuple[str, list[str]]:
    """The page's text with every generated block made again, and one line per block that
    differed (``page:line: ...``) or could not be made."""
    text = page.read_text()
    problems: list[str] = []

    def again(match: re.Match) -> str:
        line = text.count("\n", 0, match.start()) + 1
        try:
            body = render(match["spec"], results)
        except ValueError as e:
            problems.append(f"{page}:{line}: {e}")
            return match.group(0)
        if body != match["body"]:
            problems.append(f"{page}:{line}: '{match['spec']}' {DIFFERS}")
        return match.group(1) + body + match.group(4)

    return BLOCK.sub(again, text), problems


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="action", required=True)
    snap = sub.add_parser("snapshot", help="keep an arena run's tables under docs/results/NAME")
    snap.add_argument("run", type=pathlib.Path, help="an arena run folder (socialnav arena --out)")
    snap.add_argument("name", help="the snapshot's name, as the pages' blocks give it")
    snap.add_argument("--command", help="the command that made the run, where its run.json does not say")
    snap.add_argument(
        "--pairs", action="append", default=[], metavar="A:B", help="keep method A against B per scene (repeatable)"
    )
    sub.add_parser("write", help="make every generated table in README.md and docs/*.md again")
    sub.add_parser("check", help="exit 1 naming each generated table that differs from its run")
    args = parser.parse_args(argv)
    if args.action == "snapshot":
        print(f"snapshot: {snapshot(args.run, args.name, command=args.command, pairs=tuple(args.pairs))}")
        return 0
    problems = []
    for page in pages():
        text, found = stale_blocks(page)
        problems += found
        if args.action == "write" and text != page.read_text():
            write_text_atomic(page, text)
            print(f"written: {page.relative_to(ROOT)}")
    shown = problems if args.action == "check" else [p for p in problems if not p.endswith(DIFFERS)]
    for p in shown:
        print(p)
    return 1 if shown else 0


if __name__ == "__main__":
    sys.exit(main())
