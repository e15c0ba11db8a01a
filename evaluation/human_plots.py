"""Pictures of ``socialnav humans validate``: each test's data beside the models."""

from __future__ import annotations

import pathlib

import numpy as np

from socialnav.common import figures
from socialnav.evaluation import pedestrian_measures as measures

COLOURS = ("tab:orange", "tab:green", "tab:purple", "tab:red", "tab:brown")


def fundamental_diagram(data: dict, results: dict, path: pathlib.Path) -> pathlib.Path:
    """Speed against density: the Jülich runs' frames (grey dots), their mean +- 1 s.d. per bin,
    Weidmann's curve, each model's bins."""
    fig = figures.figure(figsize=(6.4, 4.4), layout="constrained")
    ax = fig.add_subplot()
    points = data["fd_points"]
    ax.plot(points["density"], points["speed"], ".", color="0.75", ms=2, label="Jülich uo runs (frames)")
    bins = data["fd_bins"]
    ax.errorbar(
        bins["density_bin"], bins["speed_mean"], bins["speed_sd"], fmt="ks", capsize=3, label="data: mean ± s.d."
    )
    rho = np.linspace(0.3, 4.0, 100)
    ax.plot(rho, measures.weidmann_speed(rho), "k--", lw=1, label="Weidmann (1993)")
    for colour, (name, r) in zip(COLOURS, results.items(), strict=False):
        fd = r["fd_bins"]
        ax.plot(fd["density_bin"], fd["speed_mean"], "o-", color=colour, label=name)
    ax.set_xlabel("density (persons/m²), PedPy Voronoi")
    ax.set_ylabel("speed (m/s)")
    ax.set_xlim(0, 4.2)
    ax.set_ylim(0, 1.8)
    ax.legend(fontsize=8)
    ax.set_title("fundamental diagram, 1.8 m corridor", fontsize=10)
    return figures.save(fig, path)


def prediction(data: dict, results: dict, path: pathlib.Path) -> pathlib.Path:
    """ADE and FDE per ETH/UCY scene: constant velocity and each model (aimed along its velocity;
    hatched: given the true destination)."""
    scenes = list(data["constant_velocity"]["scene"])
    fig = figures.figure(figsize=(8.0, 3.6), layout="constrained")
    series = [("constant velocity", data["constant_velocity"], "0.5", "")]
    for colour, (name, r) in zip(COLOURS, results.items(), strict=False):
        p = r["prediction"]
        series.append((name, p[p["aim"] == "velocity"], colour, ""))
        series.append((f"{name}, true destination", p[p["aim"] == "destination"], colour, "//"))
    width = 0.8 / len(series)
    for k, metric in enumerate(("ade_m", "fde_m")):
        ax = fig.add_subplot(1, 2, k + 1)
        x = np.arange(len(scenes) + 1)
        for j, (label, frame, colour, hatch) in enumerate(series):
            values = frame.set_index("scene").loc[scenes, metric].to_numpy()
            values = np.append(values, values.mean())
            ax.bar(x + (j - len(series) / 2 + 0.5) * width, values, width, color=colour, hatch=hatch, label=label,
                   edgecolor="k", lw=0.3)  # fmt: skip
        ax.set_xticks(x, [*scenes, "mean"], fontsize=8)
        ax.set_ylabel(metric.split("_")[0].upper() + " (m)")
        if k == 0:
            ax.legend(fontsize=7)
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
