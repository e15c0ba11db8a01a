"""The prediction test in every shipped Jülich corridor, between its walls and in open space, for
each human model: the table of ``docs/humans.md``'s "Prediction in the Jülich corridors".

    python scripts/corridor_prediction.py --out runs/corridor-prediction        # 11 runs, 5 models: about 10 min here
    python scripts/corridor_prediction.py --runs uo-180-180-070 --models orca --out runs/one

What ``socialnav humans predict --run RUN`` (and ``--no-walls``) measures, for every run in one go
(:func:`evaluation.humans.shipped_windows.run_windows`, :func:`evaluation.humans.own_recording.predict`):
``prediction.csv`` (a row per run, walls or not, model and aim: ADE, FDE and each model's
difference from constant velocity with its 95 % interval) and ``table.md`` (the differences,
between the walls / in open space, bold where the interval lies below zero; a run the Jülich fit
trained on marked "(fit)").
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

import pandas as pd

RUNS = (
    "uo-050-180-180", "uo-060-180-180", "uo-070-180-180", "uo-100-180-180", "uo-145-180-180", "uo-180-180-070",
    "uo-180-180-095", "uo-180-180-120", "uo-180-180-180", "bi_corr_400_b_03", "uni_corr_500_01",
)  # fmt: skip
MODELS = (
    "social_force",
    "collision_free_speed_calibrated",
    "anticipation_calibrated",
    "steering_speed_calibrated",
    "orca",
)
SHORT = {"social_force": "social force", "collision_free_speed_calibrated": "speed model, cal.",
         "anticipation_calibrated": "anticipation, cal.", "steering_speed_calibrated": "steering, cal.",
         "orca": "ORCA"}  # fmt: skip


def measure(runs, models, seed: int = 0, say=print) -> pd.DataFrame:
    """Every run between its walls and in open space: :func:`own_recording.predict`'s rows with
    ``run``, ``walls`` and ``scored`` added."""
    from socialnav.evaluation.humans import calibration, own_recording, shipped_windows

    named = {name: calibration.named_model(name) for name in models}
    frames = []
    for run in runs:
        for walls in (True, False):
            t0 = time.perf_counter()
            windows = shipped_windows.run_windows(run, walls=walls)
            table = own_recording.predict(named, windows, seed)
            frames.append(table.assign(run=run, walls=walls, scored=int(windows.complete.sum())))
            say(f"{run} {'between its walls' if walls else 'in open space'}: {time.perf_counter() - t0:.0f} s")
    return pd.concat(frames, ignore_index=True)


def markdown(rows: pd.DataFrame, aim: str = "velocity") -> str:
    """The differences from constant velocity (m) of the models aimed by ``aim``, between the
    walls / in open space, a row per run; bold where the 95 % interval lies below zero."""
    from socialnav.evaluation.humans.calibration import TRAIN_RUNS

    models = [m for m in dict.fromkeys(rows["model"]) if m != "constant_velocity"]
    lines = ["| run | scored | constant velocity's ADE (m) | " + " | ".join(SHORT.get(m, m) for m in models) + " |",
             "|---|---|---|" + "---|" * len(models)]  # fmt: skip

    def cell(r) -> str:
        bold = "**" if r["ade_vs_cv_high_m"] < 0 else ""
        return f"{bold}{r['ade_vs_cv_m']:+.3f}{bold}"

    indexed = rows.set_index(["run", "walls", "model", "aim"])
    for run in dict.fromkeys(rows["run"]):
        cv = indexed.loc[(run, True, "constant_velocity", "velocity")]
        cells = [
            f"{cell(indexed.loc[(run, True, m, aim)])} / {cell(indexed.loc[(run, False, m, aim)])}" for m in models
        ]
        name = f"{run} (fit)" if run in TRAIN_RUNS else run
        lines.append(f"| {name} | {int(cv['scored'])} | {cv['ade_m']:.3f} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", default=",".join(RUNS), help="comma-separated shipped runs (default: every corridor)")
    ap.add_argument("--models", default=",".join(MODELS), help="comma-separated human models")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=pathlib.Path, required=True, help="folder for prediction.csv and table.md")
    args = ap.parse_args(argv)
    from socialnav.data import recorded
    from socialnav.jaxsim.humans import HUMAN_MODELS

    runs, models = args.runs.split(","), args.models.split(",")
    unknown = [r for r in runs if r not in recorded.run_names()] + [m for m in models if m not in HUMAN_MODELS]
    if unknown:
        print(f"corridor_prediction: unknown {', '.join(unknown)}", file=sys.stderr)
        return 2
    t0 = time.perf_counter()
    rows = measure(runs, models, args.seed)
    args.out.mkdir(parents=True, exist_ok=True)
    rows.to_csv(args.out / "prediction.csv", index=False)
    text = "".join(f"\naimed {aim}:\n\n{markdown(rows, aim)}" for aim in ("velocity", "destination"))
    (args.out / "table.md").write_text(text)
    print(text)
    print(f"wrote {args.out}/{{prediction.csv, table.md}} in {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
