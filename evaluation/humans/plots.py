"""Pictures of ``socialnav humans validate`` (each test's data beside the models) and of ``calibrate``."""

from __future__ import annotations

import pathlib

import numpy as np

from socialnav.common import figures
from socialnav.evaluation.humans import measures

COLOURS = ("tab:orange", "tab:green", "tab:purple", "tab:red", "tab:brown")


def fundamental_diagram(data: dict, results: dict, path: pathlib.Path) -> pathlib.Path:
    """Speed against density: the Jülich runs' frames (grey dots), each run's mean per bin (grey
    bars: how far the runs agree with each other), their pooled mean +- 1 s.d. per bin (the
    check's band), Weidmann's curve, each model's bins (thin: from its disordered starts, where the
    validation drew them)."""
    fig = figures.figure(figsize=(6.4, 4.4), layout="constrained")
    ax = fig.add_subplot()
    points = data["fd_points"]
    ax.plot(points["density"], points["speed"], ".", color="0.75", ms=2, label="Jülich uo runs (frames)")
    for k, (_, run) in enumerate(points.groupby("run")):
        own = measures.binned(run)
        own = own[own["n"] >= measures.MIN_BIN_FRAMES]
        ax.plot(own["density_bin"], own["speed_mean"], "_", color="0.45", ms=12, mew=1.5,
                label="one run's mean (bins of 100+ frames)" if k == 0 else None)  # fmt: skip
    bins = data["fd_bins"]
    ax.errorbar(
        bins["density_bin"], bins["speed_mean"], bins["speed_sd"], fmt="ks", capsize=3, label="data: mean ± s.d."
    )
    rho = np.linspace(0.3, 4.0, 100)
    ax.plot(rho, measures.weidmann_speed(rho), "k--", lw=1, label="Weidmann (1993)")
    for colour, (name, r) in zip(COLOURS, results.items(), strict=False):
        fd = r["fd_bins"]
        ax.plot(fd["density_bin"], fd["speed_mean"], "o-", color=colour, label=name)
        for k, (_, drawn) in enumerate(r["fd_draws"].groupby("draw")):
            ax.plot(drawn["density_bin"], drawn["speed_mean"], "-", color=colour, lw=0.8, alpha=0.5,
                    label=f"{name}, from disordered starts" if k == 0 else None)  # fmt: skip
    ax.set_xlabel("density (persons/m²), PedPy Voronoi")
    ax.set_ylabel("speed (m/s)")
    ax.set_xlim(0, 4.2)
    ax.set_ylim(0, 1.8)
    ax.legend(fontsize=8)
    ax.set_title("fundamental diagram, 1.8 m corridor", fontsize=10)
    return figures.save(fig, path)


def prediction(data: dict, results: dict, path: pathlib.Path) -> pathlib.Path:
    """ADE and FDE per ETH/UCY scene: constant velocity and each model (aimed along its velocity;
    dotted: its people walking on in the groups they walked in; hatched: given the true
    destination); a third panel each model's ADE minus constant velocity's (aimed along its
    velocity) with its 95 % interval, below 0 where the model is ahead."""
    scenes = list(data["constant_velocity"]["scene"])
    series = [("constant velocity", data["constant_velocity"], "0.5", "")]
    for colour, (name, r) in zip(COLOURS, results.items(), strict=False):
        p = r["prediction"]
        series.append((name, p[p["aim"] == "velocity"], colour, ""))
        if (p["aim"] == "velocity_groups").any():
            series.append((f"{name}, in walking groups", p[p["aim"] == "velocity_groups"], colour, ".."))
        series.append((f"{name}, true destination", p[p["aim"] == "destination"], colour, "//"))
    fig = figures.figure(figsize=(13.0, 3.6 + 0.18 * (len(series) // 4 + 1)), layout="constrained")
    width = 0.8 / len(series)
    for k, metric in enumerate(("ade_m", "fde_m")):
        ax = fig.add_subplot(1, 3, k + 1)
        x = np.arange(len(scenes) + 1)
        for j, (label, frame, colour, hatch) in enumerate(series):
            values = frame.set_index("scene").loc[scenes, metric].to_numpy()
            values = np.append(values, values.mean())
            ax.bar(x + (j - len(series) / 2 + 0.5) * width, values, width, color=colour, hatch=hatch, label=label,
                   edgecolor="k", lw=0.3)  # fmt: skip
        ax.set_xticks(x, [*scenes, "mean"], fontsize=8)
        ax.set_ylabel(metric.split("_")[0].upper() + " (m)")
    handles, labels = fig.axes[0].get_legend_handles_labels()
    ax = fig.add_subplot(1, 3, 3)
    shift = 0.8 / max(1, len(results))
    for j, (colour, (_, r)) in enumerate(zip(COLOURS, results.items(), strict=False)):
        along = r["prediction"][r["prediction"]["aim"] == "velocity"].set_index("scene").loc[scenes]
        d = along["ade_vs_cv_m"].to_numpy()
        error = [d - along["ade_vs_cv_low_m"].to_numpy(), along["ade_vs_cv_high_m"].to_numpy() - d]
        x = np.arange(len(scenes)) + (j - len(results) / 2 + 0.5) * shift
        ax.errorbar(x, d, error, fmt="o", color=colour, capsize=3, ms=4)
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xticks(np.arange(len(scenes)), scenes, fontsize=8)
    ax.set_ylabel("ADE minus constant velocity's (m), 95 %")
    fig.legend(handles, labels, loc="outside lower center", ncol=min(4, len(series)), fontsize=7)
    fig.suptitle("ETH/UCY test splits: 8 frames observed, 12 predicted", fontsize=10)
    return figures.save(fig, path)


def counterflow_and_bodies(data: dict, results: dict, path: pathlib.Path) -> pathlib.Path:
    """Counterflow speed and lane order against the bi-directional run; each model's deepest
    body overlap per density of the fundamental diagram."""
    fig = figures.figure(figsize=(9.0, 3.2), layout="constrained")
    names = ["data", *results]
    speeds = [data["counterflow"]["speed_mps"], *[r["counterflow"]["speed_mps"] for r in results.values()]]
    lanes = [data["counterflow"]["lane_order"], *[r["counterflow"]["lane_order"] for r in results.values()]]
    colours = ["0.5", *COLOURS[: len(results)]]
    for k, (values, label) in enumerate(((speeds, "speed (m/s)"), (lanes, "lane order"))):
        ax = fig.add_subplot(1, 3, k + 1)
        ax.bar(names, values, color=colours)
        ax.set_ylabel(label)
        ax.tick_params(axis="x", labelsize=7)
    ax = fig.add_subplot(1, 3, 3)
    for colour, (name, r) in zip(COLOURS, results.items(), strict=False):
        b = r["bodies"]
        ax.plot(b["density_target"], b["max_depth_m"], "o-", color=colour, label=name)
    ax.axhline(0.1, color="k", ls=":", lw=1)
    ax.set_xlabel("density (persons/m²)")
    ax.set_ylabel("deepest overlap (m)")
    ax.legend(fontsize=7)
    fig.suptitle(f"counterflow at {data['counterflow']['density']:.2f} /m² (bi_corr_400_b_03); bodies", fontsize=10)
    return figures.save(fig, path)


def calibration_curve(histories: dict, title: str, path: pathlib.Path) -> pathlib.Path:
    """A Jülich fit's loss, best so far, against seconds (log scale), one line a method
    (:func:`evaluation.humans.calibration.calibrate`'s histories)."""
    fig = figures.figure(figsize=(6.0, 3.6), layout="constrained")
    ax = fig.add_subplot()
    for key, label in (("gradient", "gradient (Adam)"), ("nelder_mead", "Nelder-Mead")):
        history = histories[key]
        ax.plot([h[2] for h in history], np.fmin.accumulate([h[1] for h in history]), label=label)
    ax.set_xlabel("seconds")
    ax.set_ylabel("loss (best so far)")
    ax.set_yscale("log")
    ax.legend()
    ax.set_title(title, fontsize=10)
    return figures.save(fig, path)


def trajectory_fit(rows: list[dict], title: str, path: pathlib.Path) -> pathlib.Path:
    """The ETH/UCY fits' loss on their training sample, best so far, against loss evaluations
    (:func:`evaluation.humans.trajectory_calibration.leave_one_scene_out`'s rows): the gradient solid,
    Nelder-Mead dotted, a colour a held-out scene."""
    fig = figures.figure(figsize=(6.4, 3.8), layout="constrained")
    ax = fig.add_subplot()
    for colour, row in zip(COLOURS, rows, strict=False):
        for key, style, label in (("gradient_history", "-", "gradient"), ("nelder_mead_history", ":", "Nelder-Mead")):
            history = row.get(key)
            if history:
                best = np.minimum.accumulate([h[1] for h in history])
                ax.plot(np.arange(1, len(best) + 1), best, style, color=colour, label=f"{row['scene']}: {label}")
    ax.set_xlabel("loss evaluations (a gradient step is one)")
    ax.set_ylabel("ADE on the training sample, best so far (m)")
    ax.legend(fontsize=6, ncol=2)
    ax.set_title(title, fontsize=10)
    return figures.save(fig, path)


def joint_tradeoff(rows: list[dict], data: dict, title: str, path: pathlib.Path) -> pathlib.Path:
    """The joint fits (:func:`evaluation.humans.joint_calibration.sweep`'s rows, each with its held-out
    ``checks`` as ``"held_out"``): left, the two training terms (the diagram's loss against the
    percent ADE behind constant velocity), the start hollow; right, held out, the density bins inside
    the data's ±1 s.d. against the five-scene ADE minus constant velocity's (m, left of 0 is ahead)."""
    fig = figures.figure(figsize=(8.4, 3.6), layout="constrained")
    train, held = fig.subplots(1, 2)
    train.plot(rows[0]["start_behind_pct"], rows[0]["start_fd_loss"], "o", mfc="none", color="k", label="start")
    cv_ade = float(data["constant_velocity"]["ade_m"].mean())
    for colour, row in zip(COLOURS, rows, strict=False):
        label = f"w = {row['weight']:g}"
        train.plot(row["behind_pct"], row["fd_loss"], "o", color=colour, label=label)
        k = row["held_out"]
        inside = int(k["fd_bins_inside_1sd"].split()[0])
        held.plot(
            k["eth_ucy_ade_fde"][0] - cv_ade,
            inside,
            "o",
            color=colour,
            label=f"{label}: ahead in {k['eth_ucy_scenes_ahead']} of 5 scenes",
        )
    train.set_xlabel("training: ADE behind constant velocity (%)")
    train.set_ylabel("training: diagram loss (s.d.²)")
    train.legend(fontsize=7)
    held.axvline(0.0, color="0.6", lw=0.8)
    held.set_xlabel("held out: ETH/UCY ADE - constant velocity's (m)")
    held.set_ylabel("held out: density bins inside ±1 s.d.")
    held.set_ylim(-0.3, len(measures.DENSITY_BINS) + 0.3)
    held.legend(fontsize=7)
    fig.suptitle(title, fontsize=10)
    return figures.save(fig, path)


def recording_prediction(table, title: str, path: pathlib.Path) -> pathlib.Path:
    """A user's recording (:func:`evaluation.humans.own_recording.predict`'s table): ADE and FDE of
    constant velocity and each model (aimed along its velocity; hatched: at the true destination),
    and each model's error minus constant velocity's with its 95 % interval (below 0: ahead)."""
    models = [m for m in dict.fromkeys(table["model"]) if m != "constant_velocity"]
    colours = {"constant_velocity": "0.5", **dict(zip(models, COLOURS * (len(models) // len(COLOURS) + 1)))}
    fig = figures.figure(figsize=(11.0, 3.6), layout="constrained")
    bars = fig.add_subplot(1, 2, 1)
    width = 0.8 / len(table)
    for j, r in enumerate(table.itertuples()):
        hatch = "//" if r.aim == "destination" else ""
        label = r.model if r.aim == "velocity" else f"{r.model}, true destination"
        x = np.arange(2) + (j - len(table) / 2 + 0.5) * width
        bars.bar(x, [r.ade_m, r.fde_m], width, color=colours[r.model], hatch=hatch, label=label, edgecolor="k", lw=0.3)
    bars.set_xticks(np.arange(2), ["ADE", "FDE"])
    bars.set_ylabel("error (m)")
    bars.legend(fontsize=7)
    diff = fig.add_subplot(1, 2, 2)
    scored = table[table["model"] != "constant_velocity"].reset_index(drop=True)
    for j, r in enumerate(scored.itertuples()):
        for k, metric in enumerate(("ade", "fde")):
            d, low, high = (getattr(r, f"{metric}_vs_cv{s}_m") for s in ("", "_low", "_high"))
            x = k + (j - len(scored) / 2 + 0.5) * (0.8 / max(1, len(scored)))
            marker = "s" if r.aim == "destination" else "o"
            diff.errorbar(x, d, [[d - low], [high - d]], fmt=marker, color=colours[r.model], capsize=3, ms=4)
    diff.axhline(0.0, color="0.5", lw=0.8)
    diff.set_xticks(np.arange(2), ["ADE", "FDE"])
    diff.set_ylabel("minus constant velocity's (m)")
    diff.set_title("95 % intervals; below 0: ahead (squares: true destination)", fontsize=8)
    fig.suptitle(title, fontsize=10)
    return figures.save(fig, path)
