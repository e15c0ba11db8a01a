"""A scene's free parameter swept: one copy of the scene per value, every chosen method on each,
and the success rates against the value as a table and a figure.

    python scripts/scene_sweep.py gscl_crowded_entrance people.start_s 0,0.5 1,2 2,4 4,6 \\
        --methods navfn,snl_small,snl_large,gscl --out runs/entrance-sweep

A paper that leaves a number open (seed 002 gives no timing for the crowded entrance's walkers)
is reported over a range of it, not at one chosen value. ``FIELD`` is a dotted path into the
scene file (``data/scenes/<scene>.json``); where it meets a list it applies to every element
that has the next key (``people.start_s``: every person's start; ``rule.rules.min_share``: every
sub-rule with a share); an integer key picks one element of a list (``walls.4.2``), and several
fields joined by ``+`` are set alike; ``--also FIELD VALUE...`` sets another field with the swept
one, a value per copy (seed 001's crossing walker at the paper's three speeds, each starting so
that at its band's mean speed it meets the robot's line when the scene's own walker does)::

    python scripts/scene_sweep.py casn_crossing people.speed_mps 0.3,0.5 0.55,0.75 0.85,1.15 \\
        --also people.start_s 1.5,3 4.1,5.6 5.55,7.05 --methods navfn,snl_matched,casn --out runs/crossing-speed

With ``--shift`` each value is added to the fields' own numbers, which moves a wall: the
L-hallway's dead end, 0.9 m past the goal in the scene file, moved 0-4 m further (the end wall,
the side walls' and the map's top edge together)::

    python scripts/scene_sweep.py gscl_l_hallway \\
        bounds_m.3+walls.1.3+walls.2.3+walls.3.3+walls.4.2+walls.4.3 0 1 2 4 --shift \\
        --label "dead end moved up (m)" --out runs/hallway-dead-end

Each ``VALUE`` is a number or comma-separated numbers (a range, ``0,0.5`` -> ``[0, 0.5]``; in
brackets where the first is negative, ``[-5,5,-7.25,-7.1]``, so that argparse does not take it
for an option). The copies are written to ``OUT/scenes/`` (named
``<scene>+sweep<k>``, each drawing the scene's own variants: the scene file's ``variants_of``),
``socialnav arena`` runs them into ``OUT/arena`` with the same variants and seed (common random
numbers: variant k of every copy draws what variant k of the scene draws, so a copy that
changes nothing gives the scene's own episodes; a run already there is resumed) and
``OUT/arena/sweep.json`` records the field, the values and the command. Then it prints
``evaluation.arena.markdown.sweep_table`` (``--metric``, default ``social_no_collision``: seed
002's social success, a collision failing the run) and draws ``OUT/sweep.png`` with the 95 %
Wilson intervals. ``python scripts/results_tables.py snapshot OUT/arena NAME`` keeps the table
for the docs (``<!-- results: sweep NAME -->``).
"""

from __future__ import annotations

import argparse
import copy
import json
import pathlib
import shlex
import subprocess
import sys

import pandas as pd

from socialnav.common.atomic import write_text_atomic
from socialnav.data import SCENES_DIR
from socialnav.evaluation.arena.markdown import SWEEP_FILE, sweep_copy_name, sweep_table, sweep_value_label


def set_field(scene: dict, path: str, value, shift: bool = False) -> int:
    """Set ``path`` (dotted) in ``scene`` to ``value`` in place, through lists (each element that
    has the next key; an integer key picks one element: ``walls.4.2``); with ``shift``, add
    ``value`` to the number (or to each number of the list) there instead. ``path`` may name
    several fields joined by ``+``, each set alike. Returns how many places were set. Raises
    ValueError naming the path where nothing was set, or a shift of something not numbers."""
    if "+" in path:
        return sum(set_field(scene, part, value, shift) for part in path.split("+"))

    def moved(old):
        if not shift:
            return copy.deepcopy(value)
        if isinstance(old, (int, float)) and not isinstance(old, bool):
            return old + value
        if isinstance(old, list) and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in old):
            return [v + value for v in old]
        raise ValueError(f"{path}: {json.dumps(old)} is not a number or a list of numbers to shift")

    def walk(node, keys) -> int:
        key = keys[0]
        if isinstance(node, list) and key.lstrip("-").isdigit():
            index = int(key)
            if not -len(node) <= index < len(node):
                return 0
            if len(keys) == 1:
                node[index] = moved(node[index])
                return 1
            return walk(node[index], keys[1:])
        if isinstance(node, list):
            return sum(walk(item, keys) for item in node if isinstance(item, dict) and key in item)
        if not isinstance(node, dict) or key not in node:
            return 0
        if len(keys) == 1:
            node[key] = moved(node[key])
            return 1
        return walk(node[key], keys[1:])

    n = walk(scene, path.split("."))
    if n == 0:
        raise ValueError(f"{path}: no such field in scene {scene.get('name')!r}")
    return n


def parse_value(text: str):
    """``"2"`` -> 2.0, ``"0,0.5"`` -> [0.0, 0.5], ``"[-5,5]"`` -> [-5.0, 5.0] (brackets make a
    list of numbers starting with a minus sign a value to argparse, not an option); ValueError
    naming the text otherwise."""
    bracketed = text.startswith("[") and text.endswith("]")
    try:
        numbers = [float(part) for part in (text[1:-1] if bracketed else text).split(",")]
    except ValueError:
        raise ValueError(f"{text!r}: a number or comma-separated numbers") from None
    return numbers[0] if len(numbers) == 1 and not bracketed else numbers


def sweep_copies(
    scene_file: pathlib.Path,
    field: str,
    values: list,
    folder: pathlib.Path,
    shift: bool = False,
    also: tuple[tuple[str, list], ...] = (),
) -> list[pathlib.Path]:
    """One scene file per value in ``folder``, named ``<scene>+sweep<k>``, its ``source`` saying
    what was changed (``shift``: each value added to the field's own, :func:`set_field`).
    ``also``: ``(field, values)`` pairs set with the swept field, copy ``k`` taking value ``k``
    of each (a walker's start moved with its speed, say); ValueError where their counts differ."""
    for other, other_values in also:
        if len(other_values) != len(values):
            raise ValueError(f"--also {other}: {len(other_values)} values for {len(values)} swept values")
    base = json.loads(scene_file.read_text())
    folder.mkdir(parents=True, exist_ok=True)
    files = []
    for k, value in enumerate(values):
        scene = copy.deepcopy(base)
        set_field(scene, field, value, shift)
        changes = [f"{field} {'moved by' if shift else '='} {json.dumps(value)}"]
        for other, other_values in also:
            set_field(scene, other, other_values[k], shift)
            changes.append(f"{other} {'moved by' if shift else '='} {json.dumps(other_values[k])}")
        scene["name"] = sweep_copy_name(base["name"], k)
        scene["variants_of"] = base.get("variants_of", base["name"])  # the scene's own draws
        change = ", ".join(changes)
        scene["source"] = f"{base['name']} with {change} (scripts/scene_sweep.py)"
        path = folder / f"{scene['name']}.json"
        path.write_text(json.dumps(scene, indent=1) + "\n")
        files.append(path)
    return files


def sweep_figure(summary: pd.DataFrame, sweep: dict, metric: str = "social_no_collision"):
    """``metric`` against the swept value, one line per method with its 95 % intervals."""
    from socialnav.common import figures

    fig = figures.figure(figsize=(5.5, 3.4))
    ax = fig.add_subplot()
    rows = summary.set_index(["scene", "method"])
    x = list(range(len(sweep["values"])))
    for m in dict.fromkeys(summary["method"]):
        r = [rows.loc[(sweep_copy_name(sweep["scene"], k), m)] for k in x]
        y = [row[f"{metric}_pct"] for row in r]
        err = [[v - row[f"{metric}_lo"] for v, row in zip(y, r)], [row[f"{metric}_hi"] - v for v, row in zip(y, r)]]
        ax.errorbar(x, y, yerr=err, marker="o", capsize=3, label=m)
    ax.set_xticks(x, [sweep_value_label(v) for v in sweep["values"]])
    ax.set_xlabel(sweep.get("label") or sweep["field"])
    ax.set_ylabel(f"{metric.replace('_', ' ')} %")
    ax.set_ylim(-3, 103)
    ax.set_title(sweep["scene"], fontsize=10)
    ax.legend(fontsize=8)
    return fig


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scene", help="a scene name (data/scenes/<scene>.json) or a scene file")
    parser.add_argument("field", help="a dotted path into the scene file, e.g. people.start_s (several joined by +)")
    parser.add_argument("values", nargs="+", help="each a number or comma-separated numbers (a range)")
    parser.add_argument("--methods", default="navfn,snl_small,snl_large,gscl", help="socialnav arena's --methods")
    parser.add_argument("--variants", type=int, default=100, help="variants per copy (default 100)")
    parser.add_argument("--metric", default="social_no_collision", help="the rate shown (default social_no_collision)")
    parser.add_argument("--shift", action="store_true", help="add each value to the field's own (move it)")
    parser.add_argument(
        "--also",
        nargs="+",
        action="append",
        default=[],
        metavar="FIELD VALUE",
        help="another field set with the swept one: FIELD and one value per swept value (repeatable)",
    )
    parser.add_argument("--label", help="the swept value's name in the table and figure (default: FIELD)")
    parser.add_argument("--gscl-run", help="socialnav arena's --gscl-run: GSCL with another model than the shipped one")
    parser.add_argument("--out", type=pathlib.Path, required=True, help="the sweep's folder")
    args = parser.parse_args(argv)
    if args.variants < 1:
        parser.error(f"--variants {args.variants}: at least 1")
    scene_file = pathlib.Path(args.scene)
    if not scene_file.is_file():
        scene_file = SCENES_DIR / f"{args.scene}.json"
    if not scene_file.is_file():
        raise SystemExit(f"{args.scene}: no such scene (data/scenes/<name>.json) or file")
    try:
        values = [parse_value(v) for v in args.values]
        also = tuple((words[0], [parse_value(v) for v in words[1:]]) for words in args.also)
        every = [*values, *(v for _, vs in also for v in vs)]
        if args.shift and any(isinstance(v, list) for v in every):
            raise ValueError("--shift: each value one number (an offset)")
        files = sweep_copies(scene_file, args.field, values, args.out / "scenes", args.shift, also)
    except ValueError as e:
        raise SystemExit(f"{scene_file}: {e}") from None
    arena = args.out / "arena"
    arena_args = ["arena", "--scenes", ",".join(map(str, files)), "--methods", args.methods]
    arena_args += ["--variants", str(args.variants), "--out", str(arena)]
    if args.gscl_run:
        arena_args += ["--gscl-run", args.gscl_run]
    done = subprocess.run([sys.executable, "-m", "socialnav", *arena_args], check=False)
    if done.returncode != 0:
        return done.returncode
    sweep = {"scene": json.loads(scene_file.read_text())["name"], "field": args.field, "values": values}
    sweep |= {"shift": args.shift, "label": args.label or args.field, "also": [list(a) for a in also]}
    sweep["command"] = "python scripts/scene_sweep.py " + shlex.join(sys.argv[1:] if argv is None else argv)
    write_text_atomic(arena / SWEEP_FILE, json.dumps(sweep) + "\n")
    summary = pd.read_csv(arena / "summary.csv")
    try:
        print(sweep_table(summary, sweep, args.metric))
    except ValueError as e:
        raise SystemExit(f"{arena / 'summary.csv'}: {e}") from None
    from socialnav.common import figures

    print(f"figure: {figures.save(sweep_figure(summary, sweep, args.metric), args.out / 'sweep.png')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
