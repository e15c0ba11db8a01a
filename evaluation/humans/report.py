"""What the human models' commands write and print: the validation's run folder and headline,
the ETH/UCY fit's summary.

The measuring is elsewhere (:func:`evaluation.humans.validation.validate`, the calibrations);
this module turns their results into files and lines, so that a notebook gets the same folder
and the same text as ``socialnav humans validate`` and ``calibrate``.
"""

from __future__ import annotations

import json
import pathlib

from socialnav.evaluation.humans import measures
from socialnav.evaluation.humans import plots as human_plots

# The entries of a validation's run folder (write_validation writes them all).
VALIDATION_FILES = ("summary.json", "fundamental_diagram.csv", "prediction.csv", "counterflow.csv", "bodies.csv",
                    "pictures")  # fmt: skip


def write_validation(folder: pathlib.Path, data: dict, results: dict, quick: bool, seed: int, fits=None) -> None:
    """Write :data:`VALIDATION_FILES` into ``folder`` (an empty folder): the tables of every test
    with the data beside the models, a picture a test, ``summary.json`` (each model's checks, the
    data's own agreement, and ``fits``: label -> where a fitted model's values came from).

    Args:
      data: :func:`evaluation.humans.validation.reference`'s measures of the recorded data.
      results: model label -> :func:`evaluation.humans.validation.validate`'s result.
      quick, seed: as the models were validated, recorded in the summary.
    """
    import pandas as pd

    fd = [data["fd_bins"].assign(source="data: Jülich uo runs", draw=0)]
    fd += [r["fd_bins"].assign(source=name, draw=0) for name, r in results.items()]
    fd += [r["fd_draws"].assign(source=name) for name, r in results.items() if len(r["fd_draws"])]
    pd.concat(fd, ignore_index=True).to_csv(folder / "fundamental_diagram.csv", index=False)
    prediction = [data["constant_velocity"].assign(model="constant velocity", aim="velocity")]
    prediction += [r["prediction"].assign(model=name) for name, r in results.items()]
    pd.concat(prediction, ignore_index=True).to_csv(folder / "prediction.csv", index=False)
    counter = [{"source": "data: bi_corr_400_b_03", **data["counterflow"]}]
    counter += [{"source": name, **r["counterflow"]} for name, r in results.items()]
    pd.DataFrame(counter).to_csv(folder / "counterflow.csv", index=False)
    bodies = pd.concat([r["bodies"].assign(model=name) for name, r in results.items()], ignore_index=True)
    bodies.to_csv(folder / "bodies.csv", index=False)
    (folder / "pictures").mkdir()
    human_plots.fundamental_diagram(data, results, folder / "pictures" / "fundamental_diagram.png")
    human_plots.prediction(data, results, folder / "pictures" / "prediction.png")
    human_plots.counterflow_and_bodies(data, results, folder / "pictures" / "counterflow_bodies.png")
    summary = {
        "models": {name: r["checks"] for name, r in results.items()},
        "quick": bool(quick),
        "seed": seed,
        "data": {"counterflow": data["counterflow"], "fd_agreement": data["fd_agreement"]},
        "fits": fits or {},
    }
    (folder / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")


def interval(difference) -> str:
    """``[d, low, high]`` as ``+0.012 [+0.004, +0.020]`` (``+0.012 [no interval: ...]`` where the
    windows hold fewer than two blocks to resample: :func:`evaluation.humans.measures.paired_difference`)."""
    d, low, high = difference
    if low != low or high != high:  # NaN
        return f"{d:+.3f} [no interval: fewer than 2 blocks of 20 windows]"
    return f"{d:+.3f} [{low:+.3f}, {high:+.3f}]"


def headline(data: dict, results: dict) -> list[str]:
    """The validation's printed verdicts: the data's own figures, then a line a model (and one for
    its disordered starts where it was measured from them)."""
    lines = []
    cv = data["constant_velocity"]
    c = data["counterflow"]
    lines.append(f"data: counterflow {c['speed_mps']:.2f} m/s, lane order {c['lane_order']:.2f} at "
                 f"{c['density']:.2f} /m²; constant velocity ADE/FDE {cv['ade_m'].mean():.2f} / "
                 f"{cv['fde_m'].mean():.2f} m")  # fmt: skip
    a = data["fd_agreement"]
    t, e = a["training_runs"], a["each_run"]
    lines.append(f"data against its own diagram check: the training runs, scored as a model, inside the test runs' "
                 f"±1 s.d. in {t['inside']} of {t['of']} bins (mean z² {t['z2_mean']:.2f}); each run against the "
                 f"others in {e['inside']} of {e['of']} (mean z² {e['z2_mean']:.2f})")  # fmt: skip
    for name, r in results.items():
        k = r["checks"]
        verdict = lambda ok: "pass" if ok else "FAIL"
        ade, fde = k["eth_ucy_ade_fde"]
        grouped = r["prediction"][r["prediction"]["aim"] == "velocity_groups"]
        lines.append(
            f"{name}: speed inside the data's ±1 s.d. in {k['fd_bins_inside_1sd']} density bins "
            f"(mean z² {k['fd_z2_mean']:.2f}; {verdict(k['fd_pass'])}); "
            f"deepest overlap {k['overlap_max_m']:.2f} m ({verdict(k['overlap_pass'])}); ETH/UCY ADE/FDE {ade:.2f} / "
            f"{fde:.2f} m, ahead in {k['eth_ucy_scenes_ahead']} of 5 scenes (beyond the 95 % interval: ahead in "
            f"{k['eth_ucy_scenes_clearly_ahead']}, behind in {k['eth_ucy_scenes_clearly_behind']}; the average "
            f"minus constant velocity's, 95 % interval: ADE {interval(k['eth_ucy_average_vs_cv']['ade_m'])}, FDE "
            f"{interval(k['eth_ucy_average_vs_cv']['fde_m'])} m; "
            f"{verdict(k['eth_ucy_pass'])}; in walking "
            f"groups {grouped['ade_m'].mean():.2f} / {grouped['fde_m'].mean():.2f} m); with the "
            f"destination ADE {k['destination_ade_m']:.2f} m ({verdict(k['destination_pass'])}); counterflow speed "
            f"x{k['counterflow_speed_ratio']:.2f}, lane order {k['counterflow_lane_order']:.2f} "
            f"({verdict(k['counterflow_pass'])})"
        )
        if "fd_start_draws" in k:
            d = k["fd_start_draws"]
            lines.append(f"  {name}, the diagram from {len(d['bins_inside'])} disordered starts: bins inside "
                         f"{', '.join(map(str, d['bins_inside']))}; mean z² "
                         f"{', '.join(f'{z:.2f}' for z in d['z2_mean'])}; deepest overlap "
                         f"{max(d['overlap_max_m']):.2f} m")  # fmt: skip
    return lines


def trajectory_fit_lines(fit: dict) -> list[str]:
    """An ETH/UCY leave-one-scene-out fit's summary (:func:`evaluation.humans.trajectory_calibration.calibrate`'s
    record): a line a method (constant velocity, the model as given, each fit) with its test ADE/FDE over
    the held-out scenes, the scenes where it is ahead of constant velocity, and for the fits the
    average's difference from constant velocity with its 95 % interval and the scenes where both
    intervals lie below 0."""
    rows, average = fit["scenes"], fit["average_vs_cv"]
    mean = lambda key, k: sum(r[key][k] for r in rows) / len(rows)
    lines = []
    for key, label in (("constant_velocity", "constant velocity"), ("start", "as given"), ("gradient", "fitted"),
                       ("nelder_mead", "Nelder-Mead")):  # fmt: skip
        if key not in rows[0]:
            continue
        ahead = sum(r[key][0] < r["constant_velocity"][0] and r[key][1] < r["constant_velocity"][1] for r in rows)
        scenes = average[key]["by_scene"].values() if key in average else []
        clearly = int(sum(measures.clearly_ahead(v["ade_m"][2], v["fde_m"][2]) for v in scenes))
        against = (f"; the average minus constant velocity's, 95 % interval: ADE {interval(average[key]['ade_m'])}, "
                   f"FDE {interval(average[key]['fde_m'])} m; clearly ahead (both intervals below 0) in {clearly} "
                   "scenes" if key in average else "")  # fmt: skip
        lines.append(f"{label}: test ADE/FDE {mean(key, 0):.3f} / {mean(key, 1):.3f} m over {len(rows)} held-out "
                     "scenes" + ("" if key == "constant_velocity" else f", ahead of constant velocity in {ahead}")
                     + against)  # fmt: skip
    return lines


__all__ = ["VALIDATION_FILES", "headline", "interval", "trajectory_fit_lines", "write_validation"]
