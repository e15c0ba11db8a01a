"""GSCL training runs side by side: recipe, time, test error and the held-out rule suite's checks.

    python scripts/gscl_compare_runs.py runs/a runs/b ...        # one row per run, its last epoch
    python scripts/gscl_compare_runs.py runs/a --epochs           # one row per epoch

Reads each run folder's ``config.json`` and ``metrics.jsonl`` (written by ``socialnav gscl train``
at every epoch's end, :mod:`models.train`), so it works on a run still training and on run folders
copied from another machine. A check is listed under "below the bar" when fewer than
:data:`models.rules.RULES_BAR` of its cases passed (``RULE_SCENES`` scenes of each kind, the
per-epoch suite). Used to compare the recipes of docs/gscl.md ("Recipes that fit in ten minutes").
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))

from socialnav.models import rules
from socialnav.models.checkpoints import load_config


def epochs_of(run: pathlib.Path) -> list[dict]:
    """The per-epoch lines of ``run/metrics.jsonl`` (empty before the first epoch ends)."""
    path = run / "metrics.jsonl"
    if not path.exists():
        return []
    lines = []
    for number, text in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        try:
            lines.append(json.loads(text))
        except json.JSONDecodeError as err:
            raise ValueError(f"{path}: line {number} is not JSON ({err.msg})") from None
    return lines


def row(name: str, config, line: dict) -> dict:
    """One table row: the recipe (widths, batch, epochs) and one epoch's figures."""
    by_check = line.get("rules_pass_by_check", {})
    below = {k: v for k, v in sorted(by_check.items()) if v < rules.RULES_BAR}
    return {
        "run": name,
        "features": ",".join(str(f) for f in config.features),
        "batch": config.batch_size,
        "epoch": f"{line['epoch']}/{config.epochs}",
        "wall_s": line["wall_s"],
        "test_mse": line["test_mse"],
        "quality": "yes" if line["meets_quality"] else "no",
        "rules": "yes" if line.get("meets_rules") else "no",
        "below the bar": ", ".join(f"{k} {100 * v:.0f} %" for k, v in below.items()) or "-",
    }


def format_table(rows: list[dict]) -> str:
    """A plain-text table of ``rows`` (dicts with the same keys)."""
    if not rows:
        return "no epoch has ended in these runs yet"
    cells = [
        [f"{v:.5f}" if k == "test_mse" else f"{v:.0f}" if k == "wall_s" else str(v) for k, v in r.items()] for r in rows
    ]
    header = list(rows[0])
    widths = [max(len(h), *(len(c[i]) for c in cells)) for i, h in enumerate(header)]
    lines = ["  ".join(h.ljust(w) for h, w in zip(header, widths))]
    lines += ["  ".join(c.ljust(w) for c, w in zip(cell, widths)) for cell in cells]
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("runs", type=pathlib.Path, nargs="+", help="training run folders (socialnav gscl train --out)")
    parser.add_argument("--epochs", action="store_true", help="a row for every epoch, not only the last")
    args = parser.parse_args(argv)
    rows = []
    for run in args.runs:
        try:
            config = load_config(run)
            lines = epochs_of(run)
        except (FileNotFoundError, ValueError) as err:
            parser.exit(2, f"gscl_compare_runs: {err}\n")
        rows += [row(run.name, config, line) for line in (lines if args.epochs else lines[-1:])]
    print(format_table(rows))


if __name__ == "__main__":
    main()
