"""Pictures of GSCL samples and predictions: one row per family, input / target / prediction."""

from __future__ import annotations

import pathlib

import numpy as np

from socialnav.common import figures
from socialnav.common.atomic import write_atomic
from socialnav.models import grid

_CODE_COLOURS = {
    grid.FREE: (1.0, 1.0, 1.0),
    grid.HEADING: (0.98, 0.6, 0.1),
    grid.PERSON: (0.85, 0.1, 0.1),
    grid.GOAL: (0.1, 0.6, 0.1),
    grid.WALL: (0.15, 0.15, 0.15),
}


def input_rgb(image: np.ndarray) -> np.ndarray:
    """(40, 40) pixel codes -> (40, 40, 3) colours (walls dark, people red, heading orange, goal green),
    with the robot's cell (the centre) marked blue."""
    rgb = np.ones(image.shape + (3,))
    for code, colour in _CODE_COLOURS.items():
        rgb[image == code] = colour
    c = grid.GRID // 2
    rgb[c - 1 : c + 1, c - 1 : c + 1] = np.where(
        image[c - 1 : c + 1, c - 1 : c + 1, None] == grid.FREE,
        np.array([0.2, 0.4, 1.0]),
        rgb[c - 1 : c + 1, c - 1 : c + 1],
    )
    return rgb


def family_grid(inputs, targets, family, names, path, predictions=None, per_family: int = 1, mse=None) -> pathlib.Path:
    """Write a PNG with, for each family, ``per_family`` examples as input / target (/ prediction).

    Args:
      inputs / targets / predictions: (N, 40, 40); family: (N,) index into ``names``.
      mse: optional (N,) per-sample MSE written over each prediction.
    """
    present = [i for i in range(len(names)) if np.any(family == i)]
    cols = 2 if predictions is None else 3
    fig = figures.figure(figsize=(1.9 * cols * per_family, 1.9 * len(present)))
    axes = fig.subplots(len(present), cols * per_family, squeeze=False)
    for row, fam in enumerate(present):
        idx = np.flatnonzero(family == fam)[:per_family]
        for k in range(per_family):
            panels = [ax for ax in axes[row, k * cols : (k + 1) * cols]]
            for ax in panels:
                ax.set_xticks([])
                ax.set_yticks([])
            if k >= len(idx):
                for ax in panels:
                    ax.axis("off")
                continue
            n = idx[k]
            panels[0].imshow(input_rgb(np.asarray(inputs[n])), interpolation="nearest")
            panels[1].imshow(targets[n], vmin=0, vmax=1, cmap="magma", interpolation="nearest")
            if predictions is not None:
                panels[2].imshow(predictions[n], vmin=0, vmax=1, cmap="magma", interpolation="nearest")
                if mse is not None:
                    panels[2].text(1, 3, f"MSE {mse[n]:.4f}", color="w", fontsize=6)
            if row == 0:
                for ax, title in zip(panels, ("input", "target", "prediction")):
                    ax.set_title(title, fontsize=8)
        axes[row, 0].set_ylabel(str(names[fam]).replace("_", " "), fontsize=8)
    fig.tight_layout()
    return write_atomic(path, lambda tmp: fig.savefig(tmp, dpi=110, format="png"))
