"""``socialnav humans validate|calibrate``: the human models against real pedestrians.

    socialnav humans validate --out runs/humans                       # the social force
    socialnav humans validate --models social_force,orca --quick --out runs/humans-quick
    socialnav humans validate --fit runs/calibration/fit.json --out runs/humans-fit   # a fit of one's own
    socialnav humans calibrate --model collision_free_speed --out runs/calibration
    socialnav humans calibrate --data joint --model steering_speed_calibrated --out runs/joint

Writes ``summary.json`` (each model's checks against the bar of issue 61), the tables
(``fundamental_diagram.csv``, ``prediction.csv``, ``counterflow.csv``, ``bodies.csv``) and three
pictures, all at once when the run is complete (:mod:`evaluation.humans.validation`).
"""

from __future__ import annotations

import json
import pathlib
import sys
import time

from socialnav.cli.argtypes import (
    comma_names,
    comma_positive_floats,
    non_negative_int,
    output_folder,
    positive_float,
    positive_int,
    seed_int,
)
from socialnav.common import runfolder
from socialnav.jaxsim.scenes.people import HUMAN_MODELS

JOB = "socialnav humans validate"
CALIBRATABLE = ("collision_free_speed", "anticipation", "orca", "steering_speed", "power_law",
                "collision_free_speed_calibrated", "anticipation_calibrated", "steering_speed_calibrated",
                "power_law_calibrated")  # fmt: skip
RESULTS = ("summary.json", "fundamental_diagram.csv", "prediction.csv", "counterflow.csv", "bodies.csv", "pictures")


def add_parser(top) -> None:
    humans = top.add_parser("humans", help="the human models against real pedestrian data")
    sub = humans.add_subparsers(dest="humans_command", required=True, metavar="COMMAND")
    v = sub.add_parser(
        "validate",
        help="each human model against the Jülich corridors and ETH/UCY",
        description="Runs each human model where the shipped data was recorded and measures both alike: the "
        "fundamental diagram in a 1.8 m corridor against the Jülich uo runs (PedPy's Voronoi densities), "
        "counterflow against bi_corr_400_b_03 (speed, lane order), ETH/UCY prediction against constant velocity "
        "(test splits: 8 frames observed, 12 predicted), and body overlaps. Writes a run folder and prints the "
        "checks against the bar of issue 61.",
    )
    v.add_argument("--models", type=comma_names, default=None,
                   help="human models (default social_force, none with --fit)")  # fmt: skip
    v.add_argument("--fit", type=pathlib.Path, action="append", default=[], metavar="FIT_JSON",
                   help="a Jülich fit (socialnav humans calibrate's fit.json) scored as a model, labelled "
                        "<its folder>:<method>; may be given more than once")  # fmt: skip
    v.add_argument("--fit-method", choices=("both", "gradient", "nelder_mead"), default="both",
                   help="with --fit: the fit's values from which method (default both)")  # fmt: skip
    v.add_argument(
        "--out", type=output_folder, default=pathlib.Path("runs/humans"), help="folder (default runs/humans)"
    )
    v.add_argument("--quick", action="store_true", help="10 m corridors, 30 s: a first look in about a minute a model")
    v.add_argument("--seed", type=seed_int, default=0)
    v.add_argument("--start-draws", type=non_negative_int, default=0,
                   help="measure the diagram that many times more, each from another draw of the corridors' people, "
                        "dense crowds in a disordered packing instead of a lattice: how much the verdict owes to "
                        "the start (default 0)")  # fmt: skip
    v.add_argument("--overwrite", action="store_true", help="replace the run in --out whole once the new one is done")
    v.add_argument("--no-progress", action="store_true", help="print the headline only")
    v.set_defaults(handler=validate)

    c = sub.add_parser(
        "calibrate",
        help="fit a human model's parameters to the Jülich training runs, by gradient and by Nelder-Mead",
        description="Fits a velocity model's parameters (time gap, repulsion strength and range, body radius; the "
        "anticipation time too) or ORCA's (time horizon, body radius) to the fundamental diagram of the Jülich "
        "training runs (the test runs are never read) by Adam through the crowd step, and by Nelder-Mead on the "
        "same loss as the check. Writes fit.json and curve.png and prints the fitted values; socialnav humans "
        "validate --models <model>_calibrated scores the shipped fit on held-out data.",
    )
    c.add_argument("--model", choices=CALIBRATABLE, default="collision_free_speed",
                   help="the model to fit, from its parameters (a _calibrated one: from the Jülich fit)")  # fmt: skip
    c.add_argument("--data", choices=("juelich", "eth_ucy", "joint"), default="juelich",
                   help="juelich: the fundamental diagram of the training runs (default); eth_ucy: the prediction "
                        "ADE, one fit a scene on its training split, scored on its test split; joint: both at once "
                        "(the diagram's loss + w x the percent ADE behind constant velocity on the ETH/UCY "
                        "recordings no scene tests on), one fit a --weights value, each scored by the "
                        "validation")  # fmt: skip
    c.add_argument("--weights", type=comma_positive_floats, default=None,
                   help="with --data joint: the exchange rates w swept (0.03,0.1,0.3,1)")  # fmt: skip
    c.add_argument("--scenes", type=comma_names, default=None, help="with --data eth_ucy: the held-out scenes (all)")
    c.add_argument("--out", type=output_folder, default=pathlib.Path("runs/calibration"), help="folder")
    c.add_argument("--steps", type=positive_int, default=None, help="gradient steps (80; eth_ucy 60 a scene)")
    c.add_argument("--learning-rate", type=positive_float, default=None,
                   help="Adam's, on log-parameters (0.02; eth_ucy 0.2)")  # fmt: skip
    c.add_argument("--evaluations", type=non_negative_int, default=None,
                   help="Nelder-Mead's loss evaluations (250; eth_ucy 60, 0: none; joint 150 a weight)")  # fmt: skip
    c.add_argument("--sample", type=positive_int, default=256,
                   help="eth_ucy: training windows the loss is taken over, drawn once (256)")  # fmt: skip
    c.add_argument("--seed", type=seed_int, default=0)
    c.add_argument("--start-draws", type=non_negative_int, default=0,
                   help="with --data juelich or joint: each density's corridor walked from this many more draws of "
                        "its people, dense crowds in a disordered packing, the loss averaged over the draws (default "
                        "0: one draw, a dense crowd on a lattice)")  # fmt: skip
    c.add_argument("--overwrite", action="store_true", help="replace the run in --out whole once the new one is done")
    c.set_defaults(handler=calibrate)


CALIBRATE_JOB = "socialnav humans calibrate"
CALIBRATE_RESULTS = ("fit.json", "curve.png", "held_out")


def calibrate(args) -> int:
    import jax

    from socialnav.common import figures
    from socialnav.evaluation.humans import calibration as hc
    from socialnav.evaluation.humans import validation as hv

    try:
        runfolder.prepare(args.out, CALIBRATE_RESULTS, args.overwrite, marker="fit.json", job=CALIBRATE_JOB)
        runfolder.check_writable(args.out)
    except runfolder.RunFolderError as e:
        print(f"socialnav humans calibrate: --out {e}", file=sys.stderr)
        return 2
    if args.data != "joint" and args.weights is not None:
        print("socialnav humans calibrate: --weights goes with --data joint", file=sys.stderr)
        return 2
    if args.data == "eth_ucy" and args.start_draws:
        print(
            "socialnav humans calibrate: --start-draws goes with --data juelich or joint (corridors)", file=sys.stderr
        )
        return 2
    if args.data == "eth_ucy":
        return _calibrate_trajectories(args)
    if args.data == "joint":
        return _calibrate_joint(args)
    if args.model.endswith("_calibrated") or args.scenes is not None:
        what = "--model " + args.model if args.model.endswith("_calibrated") else "--scenes"
        print(f"socialnav humans calibrate: {what} goes with --data eth_ucy (the Jülich fit starts from a model's "
              "own defaults)", file=sys.stderr)  # fmt: skip
        return 2
    args.steps = args.steps or 80
    args.learning_rate = args.learning_rate or 0.02
    args.evaluations = 250 if args.evaluations is None else args.evaluations
    if args.evaluations == 0:
        print("socialnav humans calibrate: --evaluations must be >= 1 with --data juelich (its search is the check "
              "of the gradient's fit)", file=sys.stderr)  # fmt: skip
        return 2
    t0 = time.perf_counter()
    model = hv.HumanModel(args.model)
    corridors = hc.training_corridors(model, args.seed, start_draws=args.start_draws)
    print(f"{args.model}: fitting {', '.join(hc.FITTED[args.model])} to the runs {', '.join(hc.TRAIN_RUNS)} "
          f"(densities {', '.join(f'{d:g}' for d in corridors.densities)} /m², {1 + args.start_draws} "
          f"draw{'s' if args.start_draws else ''} of each corridor's people)", flush=True)  # fmt: skip
    start = float(hc.fd_loss(model, corridors, hc.theta_of(model), jax.random.key(args.seed)))
    by_gradient, gradient_history = hc.fit_gradient(model, corridors, args.steps, args.learning_rate, args.seed)
    by_search, search_history = hc.fit_nelder_mead(model, corridors, args.evaluations, args.seed)
    fit = {
        "model": args.model,
        "train_runs": list(hc.TRAIN_RUNS),
        "test_runs": list(hc.TEST_RUNS),
        "densities": list(corridors.densities),
        "start": {"values": hc.fitted_values(model), "loss": start},
        "gradient": {"values": hc.fitted_values(by_gradient), "loss": min(h[1] for h in gradient_history),
                     "steps": args.steps, "seconds": gradient_history[-1][2]},
        "nelder_mead": {"values": hc.fitted_values(by_search), "loss": min(h[1] for h in search_history),
                        "evaluations": len(search_history), "seconds": search_history[-1][2]},
        "seed": args.seed,
        "start_draws": args.start_draws,
    }  # fmt: skip
    try:
        with runfolder.staged(args.out, "fit.json", args.overwrite, job=CALIBRATE_JOB) as stage:
            fig = figures.figure(figsize=(6.0, 3.6), layout="constrained")
            ax = fig.add_subplot()
            for label, history in (("gradient (Adam)", gradient_history), ("Nelder-Mead", search_history)):
                seconds = [h[2] for h in history]
                ax.plot(seconds, [min(h[1] for h in history[: k + 1]) for k in range(len(history))], label=label)
            ax.set_xlabel("seconds")
            ax.set_ylabel("loss (best so far)")
            ax.set_yscale("log")
            ax.legend()
            ax.set_title(f"{args.model} on the Jülich training runs", fontsize=10)
            figures.save(fig, stage / "curve.png")
            (stage / "fit.json").write_text(json.dumps(fit, indent=1) + "\n")
    except runfolder.RunFolderError as e:
        print(f"socialnav humans calibrate: --out {e}", file=sys.stderr)
        return 2
    for label in ("gradient", "nelder_mead"):
        print(f"{label}: loss {start:.2f} -> {fit[label]['loss']:.2f}, {fit[label]['values']}")
    print(f"wrote {args.out}/{{fit.json, curve.png}} in {time.perf_counter() - t0:.0f} s")
    return 0


def _calibrate_trajectories(args) -> int:
    """``--data eth_ucy``: :func:`evaluation.humans.trajectory_calibration.leave_one_scene_out`."""
    from socialnav.data import recorded
    from socialnav.evaluation.humans import calibration as hc
    from socialnav.evaluation.humans import measures
    from socialnav.evaluation.humans import plots as human_plots
    from socialnav.evaluation.humans import trajectory_calibration as tc

    scenes = args.scenes or list(recorded.ETH_UCY_SCENES)
    unknown = [s for s in scenes if s not in recorded.ETH_UCY_SCENES]
    if unknown:
        print(f"socialnav humans calibrate: --scenes: unknown {', '.join(unknown)} "
              f"(known: {', '.join(recorded.ETH_UCY_SCENES)})", file=sys.stderr)  # fmt: skip
        return 2
    t0 = time.perf_counter()
    model = hc.named_model(args.model)
    fields = tc.FITTED[model.name]
    print(f"{args.model}: fitting {', '.join(fields)} to ETH/UCY, one fit a held-out scene "
          f"({', '.join(scenes)}), on its training split", flush=True)  # fmt: skip
    rows = tc.leave_one_scene_out(
        model, fields, scenes, args.steps or 60, args.learning_rate or 0.2,
        60 if args.evaluations is None else args.evaluations, args.sample, seed=args.seed,
    )  # fmt: skip
    # each method's fits against constant velocity on the average over the held-out scenes, with its interval
    average = {m: tc.average_vs_cv(model, rows, m, fields) for m in ("gradient", "nelder_mead") if m in rows[0]}
    fit = {"model": args.model, "data": "eth_ucy", "fields": list(fields), "start": tc.values_of(model, fields),
           "scenes": rows, "average_vs_cv": average, "seed": args.seed,
           "seconds": round(time.perf_counter() - t0, 1)}  # fmt: skip
    try:
        with runfolder.staged(args.out, "fit.json", args.overwrite, job=CALIBRATE_JOB) as stage:
            human_plots.trajectory_fit(rows, f"{args.model} on ETH/UCY, leave one scene out", stage / "curve.png")
            (stage / "fit.json").write_text(json.dumps(fit, indent=1) + "\n")
    except runfolder.RunFolderError as e:
        print(f"socialnav humans calibrate: --out {e}", file=sys.stderr)
        return 2
    mean = lambda key, k: sum(r[key][k] for r in rows) / len(rows)
    for key, label in (("constant_velocity", "constant velocity"), ("start", "as given"), ("gradient", "fitted"),
                       ("nelder_mead", "Nelder-Mead")):  # fmt: skip
        if key in rows[0]:
            ahead = sum(r[key][0] < r["constant_velocity"][0] and r[key][1] < r["constant_velocity"][1] for r in rows)
            scenes = average[key]["by_scene"].values() if key in average else []
            clearly = int(sum(measures.clearly_ahead(v["ade_m"][2], v["fde_m"][2]) for v in scenes))
            interval = (f"; the average minus constant velocity's, 95 % interval: ADE "
                        f"{_interval(average[key]['ade_m'])}, FDE {_interval(average[key]['fde_m'])} m; clearly "
                        f"ahead (both intervals below 0) in {clearly} scenes" if key in average else "")  # fmt: skip
            print(f"{label}: test ADE/FDE {mean(key, 0):.3f} / {mean(key, 1):.3f} m over {len(rows)} held-out scenes"
                  + ("" if key == "constant_velocity" else f", ahead of constant velocity in {ahead}")
                  + interval)  # fmt: skip
    print(f"wrote {args.out}/{{fit.json, curve.png}} in {time.perf_counter() - t0:.0f} s")
    return 0


def _calibrate_joint(args) -> int:
    """``--data joint``: :func:`evaluation.humans.joint_calibration.sweep`, each fit scored by the
    validation (:func:`evaluation.humans.validation.validate`) on held-out data."""
    from socialnav.evaluation.humans import calibration as hc
    from socialnav.evaluation.humans import joint_calibration as jc
    from socialnav.evaluation.humans import plots as human_plots
    from socialnav.evaluation.humans import validation as hv

    if args.scenes is not None:
        print("socialnav humans calibrate: --scenes goes with --data eth_ucy", file=sys.stderr)
        return 2
    if args.model.startswith("orca"):
        print("socialnav humans calibrate: --data joint fits the velocity models (ORCA's Jülich and ETH/UCY fits "
              "are apart)", file=sys.stderr)  # fmt: skip
        return 2
    if args.evaluations == 0:
        print("socialnav humans calibrate: --evaluations must be >= 1 with --data joint", file=sys.stderr)
        return 2
    if args.steps is not None or args.learning_rate is not None:
        print("socialnav humans calibrate: --data joint fits by Nelder-Mead alone (no --steps, --learning-rate)",
              file=sys.stderr)  # fmt: skip
        return 2
    t0 = time.perf_counter()
    say = lambda what: print(f"[{time.perf_counter() - t0:5.0f} s] {what}", flush=True)
    model = hc.named_model(args.model)
    weights = args.weights or list(jc.WEIGHTS)
    data = jc.joint_data(model, args.seed, start_draws=args.start_draws)
    say(f"{args.model}: fitting {', '.join(hc.FITTED[model.name])} to the runs {', '.join(hc.TRAIN_RUNS)} and "
        f"{len(data.windows.start)} ETH/UCY windows of {', '.join(jc.TRAIN_RECORDINGS)} (constant velocity's ADE "
        f"{data.constant_velocity_ade_m:.3f} m), weights {', '.join(f'{w:g}' for w in weights)}")  # fmt: skip
    rows = jc.sweep(model, data, weights, args.evaluations or 150, args.seed, say)
    reference = hv.reference(say)
    results = {f"w={r['weight']:g}": hv.validate(r.pop("model"), reference, seed=args.seed, progress=say,
                                                 label=f"w={r['weight']:g}") for r in rows}  # fmt: skip
    for row, result in zip(rows, results.values(), strict=True):
        row["held_out"] = result["checks"]
    fit = {"model": args.model, "data": "joint", "fields": list(hc.FITTED[model.name]),
           "train_runs": list(hc.TRAIN_RUNS), "train_recordings": list(jc.TRAIN_RECORDINGS),
           "train_windows": len(data.windows.start), "constant_velocity_ade_m": data.constant_velocity_ade_m,
           "start": hc.fitted_values(model), "weights": rows, "seed": args.seed, "start_draws": args.start_draws,
           "seconds": round(time.perf_counter() - t0, 1)}  # fmt: skip
    try:
        with runfolder.staged(args.out, "fit.json", args.overwrite, job=CALIBRATE_JOB) as stage:
            human_plots.joint_tradeoff(rows, reference, f"{args.model}: one fit, both data", stage / "curve.png")
            (stage / "held_out").mkdir()
            _write(stage / "held_out", reference, results, quick=False, seed=args.seed)
            (stage / "fit.json").write_text(json.dumps(fit, indent=1) + "\n")
    except runfolder.RunFolderError as e:
        print(f"socialnav humans calibrate: --out {e}", file=sys.stderr)
        return 2
    _headline(reference, results)
    print(f"wrote {args.out}/{{fit.json, curve.png, held_out}} in {time.perf_counter() - t0:.0f} s")
    return 0


def validate(args) -> int:
    from socialnav.evaluation.humans import calibration as hc
    from socialnav.evaluation.humans import validation as hv

    known = list(HUMAN_MODELS)
    names = args.models if args.models is not None else ([] if args.fit else ["social_force"])
    unknown = [m for m in names if m not in known]
    if unknown:
        print(f"socialnav humans validate: --models: unknown {', '.join(unknown)} (known: {', '.join(known)})",
              file=sys.stderr)  # fmt: skip
        return 2
    models = {name: hc.named_model(name) for name in names}
    fits = {}  # label -> where its values came from
    methods = hc.FIT_METHODS if args.fit_method == "both" else (args.fit_method,)
    for path in args.fit:
        try:
            fitted = hc.fitted_models(path, methods)
        except ValueError as e:
            print(f"socialnav humans validate: --fit {e}", file=sys.stderr)
            return 2
        twice = sorted(set(fitted) & set(models))
        if twice:
            print(f"socialnav humans validate: --fit {path}: a second model labelled {twice[0]} (fits in folders of "
                  "one name)", file=sys.stderr)  # fmt: skip
            return 2
        models.update(fitted)
        fits.update({label: {"fit_json": str(path), "values": hc.fitted_values(m)} for label, m in fitted.items()})
    try:
        runfolder.prepare(args.out, RESULTS, args.overwrite, marker="summary.json", job=JOB)
        runfolder.check_writable(args.out)
    except runfolder.RunFolderError as e:
        print(f"socialnav humans validate: --out {e}", file=sys.stderr)
        return 2
    t0 = time.perf_counter()
    say = (
        (lambda what: None)
        if args.no_progress
        else (lambda what: print(f"[{time.perf_counter() - t0:5.0f} s] {what}", flush=True))
    )
    data = hv.reference(say)
    results = {name: hv.validate(model, data, args.quick, args.seed, say, name, args.start_draws)
               for name, model in models.items()}  # fmt: skip
    try:
        with runfolder.staged(args.out, "summary.json", args.overwrite, job=JOB) as stage:
            _write(stage, data, results, quick=args.quick, seed=args.seed, fits=fits)
    except runfolder.RunFolderError as e:
        print(f"socialnav humans validate: --out {e}", file=sys.stderr)
        return 2
    _headline(data, results)
    print(f"wrote {args.out}/{{{', '.join(RESULTS)}}} in {time.perf_counter() - t0:.0f} s")
    return 0


def _write(stage: pathlib.Path, data: dict, results: dict, quick: bool, seed: int, fits=None) -> None:
    import pandas as pd

    from socialnav.evaluation.humans import plots as human_plots

    fd = [data["fd_bins"].assign(source="data: Jülich uo runs", draw=0)]
    fd += [r["fd_bins"].assign(source=name, draw=0) for name, r in results.items()]
    fd += [r["fd_draws"].assign(source=name) for name, r in results.items() if len(r["fd_draws"])]
    pd.concat(fd, ignore_index=True).to_csv(stage / "fundamental_diagram.csv", index=False)
    prediction = [data["constant_velocity"].assign(model="constant velocity", aim="velocity")]
    prediction += [r["prediction"].assign(model=name) for name, r in results.items()]
    pd.concat(prediction, ignore_index=True).to_csv(stage / "prediction.csv", index=False)
    counter = [{"source": "data: bi_corr_400_b_03", **data["counterflow"]}]
    counter += [{"source": name, **r["counterflow"]} for name, r in results.items()]
    pd.DataFrame(counter).to_csv(stage / "counterflow.csv", index=False)
    bodies = pd.concat([r["bodies"].assign(model=name) for name, r in results.items()], ignore_index=True)
    bodies.to_csv(stage / "bodies.csv", index=False)
    (stage / "pictures").mkdir()
    human_plots.fundamental_diagram(data, results, stage / "pictures" / "fundamental_diagram.png")
    human_plots.prediction(data, results, stage / "pictures" / "prediction.png")
    human_plots.counterflow_and_bodies(data, results, stage / "pictures" / "counterflow_bodies.png")
    summary = {
        "models": {name: r["checks"] for name, r in results.items()},
        "quick": bool(quick),
        "seed": seed,
        "data": {"counterflow": data["counterflow"], "fd_agreement": data["fd_agreement"]},
        "fits": fits or {},
    }
    (stage / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")


def _interval(difference) -> str:
    """``[d, low, high]`` as ``+0.012 [+0.004, +0.020]``."""
    d, low, high = difference
    return f"{d:+.3f} [{low:+.3f}, {high:+.3f}]"


def _headline(data: dict, results: dict) -> None:
    cv = data["constant_velocity"]
    c = data["counterflow"]
    print(f"data: counterflow {c['speed_mps']:.2f} m/s, lane order {c['lane_order']:.2f} at {c['density']:.2f} /m²; "
          f"constant velocity ADE/FDE {cv['ade_m'].mean():.2f} / {cv['fde_m'].mean():.2f} m")  # fmt: skip
    a = data["fd_agreement"]
    t, e = a["training_runs"], a["each_run"]
    print(f"data against its own diagram check: the training runs, scored as a model, inside the test runs' ±1 s.d. "
          f"in {t['inside']} of {t['of']} bins (mean z² {t['z2_mean']:.2f}); each run against the others in "
          f"{e['inside']} of {e['of']} (mean z² {e['z2_mean']:.2f})")  # fmt: skip
    for name, r in results.items():
        k = r["checks"]
        verdict = lambda ok: "pass" if ok else "FAIL"
        ade, fde = k["eth_ucy_ade_fde"]
        grouped = r["prediction"][r["prediction"]["aim"] == "velocity_groups"]
        print(
            f"{name}: speed inside the data's ±1 s.d. in {k['fd_bins_inside_1sd']} density bins "
            f"(mean z² {k['fd_z2_mean']:.2f}; {verdict(k['fd_pass'])}); "
            f"deepest overlap {k['overlap_max_m']:.2f} m ({verdict(k['overlap_pass'])}); ETH/UCY ADE/FDE {ade:.2f} / "
            f"{fde:.2f} m, ahead in {k['eth_ucy_scenes_ahead']} of 5 scenes (beyond the 95 % interval: ahead in "
            f"{k['eth_ucy_scenes_clearly_ahead']}, behind in {k['eth_ucy_scenes_clearly_behind']}; the average "
            f"minus constant velocity's, 95 % interval: ADE {_interval(k['eth_ucy_average_vs_cv']['ade_m'])}, FDE "
            f"{_interval(k['eth_ucy_average_vs_cv']['fde_m'])} m; "
            f"{verdict(k['eth_ucy_pass'])}; in walking "
            f"groups {grouped['ade_m'].mean():.2f} / {grouped['fde_m'].mean():.2f} m); with the "
            f"destination ADE {k['destination_ade_m']:.2f} m ({verdict(k['destination_pass'])}); counterflow speed "
            f"x{k['counterflow_speed_ratio']:.2f}, lane order {k['counterflow_lane_order']:.2f} "
            f"({verdict(k['counterflow_pass'])})"
        )
        if "fd_start_draws" in k:
            d = k["fd_start_draws"]
            print(f"  {name}, the diagram from {len(d['bins_inside'])} disordered starts: bins inside "
                  f"{', '.join(map(str, d['bins_inside']))}; mean z² {', '.join(f'{z:.2f}' for z in d['z2_mean'])}; "
                  f"deepest overlap {max(d['overlap_max_m']):.2f} m")  # fmt: skip
