"""Pictures of the causal pipeline: the discovered graph (seed 000 Fig. 8) and the ablation's
estimation errors (Fig. 13)."""

from __future__ import annotations

import pathlib

import numpy as np
import pandas as pd
from matplotlib.patches import Circle, FancyArrowPatch

from socialnav.causal.discover import Discovery
from socialnav.causal.variables import CONTEXTS, VARIABLES
from socialnav.common import figures

# Fig. 8 layout: battery subgraph left, density subgraph right; contexts on the outside.
LAYOUT = {
    "O": (0.0, 1.0),
    "C": (0.0, 0.0),
    "V": (1.0, 1.0),
    "L": (1.0, 0.0),
    "W": (2.6, 1.0),
    "S": (2.6, 0.0),
    "D": (3.6, 0.5),
}


def graph_figure(discovery: Discovery, path: str | pathlib.Path, title: str | None = None) -> pathlib.Path:
    """The graph as a PNG like seed 000 Fig. 8: contexts grey, system variables orange, arrow
    width by strength, self-lags as the node border width, lags written on links."""
    names = sorted({k.cause for k in discovery.links} | {k.effect for k in discovery.links} | set(VARIABLES))
    pos = {n: LAYOUT.get(n, (1.8, -0.8 - 0.4 * i)) for i, n in enumerate(names)}
    strengths = [abs(k.strength) for k in discovery.links] or [1.0]
    top = max(strengths)
    fig = figures.figure(figsize=(7.5, 3.6))
    ax = fig.subplots()
    self_lag = {k.effect: k for k in discovery.links if k.cause == k.effect}
    for n in names:
        x, y = pos[n]
        colour = "#c8c8c8" if n in CONTEXTS else "#f4a259"
        width = 1.0 + 5.0 * abs(self_lag[n].strength) / top if n in self_lag else 1.0
        ax.add_patch(Circle((x, y), 0.22, facecolor=colour, edgecolor="#333", lw=width, zorder=3))
        ax.text(x, y, n, ha="center", va="center", fontsize=12, zorder=4)
        if n in self_lag:
            ax.text(x, y + 0.3, str(self_lag[n].lag), ha="center", fontsize=8, color="#333")
    for k in discovery.links:
        if k.cause == k.effect:
            continue
        arrow = FancyArrowPatch(
            pos[k.cause],
            pos[k.effect],
            arrowstyle="-|>" if k.oriented else "-",
            mutation_scale=14,
            shrinkA=16,
            shrinkB=16,
            lw=0.8 + 4.0 * abs(k.strength) / top,
            color="#444",
            connectionstyle="arc3,rad=0.12" if k.lag else "arc3",
            zorder=2,
        )
        ax.add_patch(arrow)
        mx, my = (np.add(pos[k.cause], pos[k.effect])) / 2
        ax.text(mx, my + 0.06, str(k.lag), fontsize=8, color="#1f4e79", ha="center")
    ax.set_xlim(-0.5, 4.1)
    ax.set_ylim(-0.5, 1.5)
    ax.set_aspect("equal")
    ax.axis("off")
    ax.set_title(title or f"J-PCMCI+ ({discovery.test}, alpha {discovery.alpha}, tau_max {discovery.tau_max})")
    return figures.save(fig, path)


def ablation_figure(
    summary: pd.DataFrame, path: str | pathlib.Path, distance_m: float, speed_mps: float
) -> pathlib.Path:
    """Mean absolute error with standard deviation per obstacle probability (seed 000 Fig. 13)."""
    x = np.arange(len(summary))
    fig = figures.figure(figsize=(6.5, 3.6))
    ax = fig.subplots()
    ax.bar(
        x - 0.18,
        summary.mae_bayesian,
        0.36,
        yerr=summary.sd_bayesian,
        capsize=3,
        color="#4c72b0",
        label="Bayesian, E[L | V]",
    )
    ax.bar(
        x + 0.18,
        summary.mae_causal,
        0.36,
        yerr=summary.sd_causal,
        capsize=3,
        color="#dd8452",
        label="causal, E[L | do(V)]",
    )
    ax.set_xticks(x, [f"{p:.0%}" for p in summary.p])
    ax.set_xlabel("obstacle probability per leg")
    ax.set_ylabel("|L_ref - L_hat| (battery %)")
    ax.set_title(f"Battery use for {distance_m:.0f} m at {speed_mps} m/s: estimation error")
    ax.legend()
    return figures.save(fig, path)
