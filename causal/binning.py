"""Discretisation of the continuous variables (V, L, D) for the Bayesian network.

Quantile bins with atoms isolated, the number of bins at the elbow of the within-bin error
(seed 000 Sec. 4.3 discretises with an elbow rule; the paper's networks show an atom bin for the
top speed), and the per-bin data means that turn a posterior into an expectation.
"""

from __future__ import annotations

import dataclasses

import numpy as np


def quantile_edges(x: np.ndarray, k: int) -> np.ndarray:
    """Bin edges for ``k`` bins (fewer where ties merge them): every atom in a bin of its own, the
    other values in quantile bins of their own distribution.

    An atom is a value holding more than ``1/k`` of the data (a robot cruising at exactly its
    top speed, a waypoint that is empty most of the time). It gets a bin of its own, between the
    mid-points to its neighbouring values, as in the paper's networks (top speed bin [0.499;
    0.509)). The remaining ``k - atoms`` bins are quantile bins of the values that are not atoms:
    quantiles of all the data would put most of their edges inside an atom holding 87 % of it
    (the density of a waypoint that is empty 87 % of the time then had two bins, empty and not,
    whatever ``k``). Those edges are values of the data (``inverted_cdf``), so none falls inside
    an atom's bin. At least two bins when ``x`` varies.
    """
    x = np.asarray(x, np.float64)
    lo, hi = float(x.min()), float(x.max())
    if lo == hi:
        raise ValueError("cannot bin a constant series")
    values, counts = np.unique(x, return_counts=True)
    is_atom = counts > len(x) / k
    edges = [lo, hi]
    for i in np.flatnonzero(is_atom):
        if i > 0:
            edges.append((values[i - 1] + values[i]) / 2)
        if i + 1 < len(values):
            edges.append((values[i] + values[i + 1]) / 2)
    rest = x[~np.isin(x, values[is_atom])]
    n_rest = k - int(is_atom.sum())
    if rest.size and n_rest >= 2:
        inner = np.quantile(rest, np.linspace(0, 1, n_rest + 1)[1:-1], method="inverted_cdf")
        # an edge at a value puts it in the upper bin; one just above the rest's minimum would
        # leave that value alone in a bin
        edges.extend(inner[inner > rest.min()])
    edges = np.unique(np.asarray(edges, np.float64))
    if len(edges) < 3:  # one atom and nothing else to split: split the distinct values in two
        above = x[x > lo]
        mid = float(above.min())
        edges = np.unique(np.array([lo, (lo + mid) / 2, hi]))
    return edges


def within_bin_sse(x: np.ndarray, edges: np.ndarray) -> float:
    """Sum of squared deviations from each bin's mean (the elbow's cost)."""
    idx = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, len(edges) - 2)
    sums = np.bincount(idx, weights=x, minlength=len(edges) - 1)
    counts = np.bincount(idx, minlength=len(edges) - 1)
    means = np.divide(sums, counts, out=np.zeros_like(sums), where=counts > 0)
    return float(np.sum((x - means[idx]) ** 2))


def elbow_bins(x: np.ndarray, k_min: int = 2, k_max: int = 8) -> int:
    """Number of quantile bins at the elbow of the within-bin SSE curve.

    The elbow is the ``k`` farthest from the straight line joining the curve's end points
    (both axes scaled to [0, 1]), the usual "knee" rule.
    """
    ks = np.arange(k_min, k_max + 1)
    sse = np.array([within_bin_sse(x, quantile_edges(x, k)) for k in ks])
    if sse[0] <= sse[-1] + 1e-12:
        return int(k_min)
    xs = (ks - ks[0]) / (ks[-1] - ks[0])
    ys = (sse - sse[-1]) / (sse[0] - sse[-1])
    dist = np.abs(ys - (1 - xs))  # distance (up to a constant) from the chord y = 1 - x
    return int(ks[np.argmax(dist)])


@dataclasses.dataclass
class Binning:
    """Edges and per-bin data means of one continuous variable."""

    edges: np.ndarray
    means: np.ndarray

    @classmethod
    def fit(cls, x: np.ndarray, k: int | None = None) -> Binning:
        x = np.asarray(x, np.float64)
        return cls.from_edges(x, quantile_edges(x, k or elbow_bins(x)))

    @classmethod
    def from_edges(cls, x: np.ndarray, edges) -> Binning:
        """Given ("expert") edges; the per-bin means come from ``x``."""
        x = np.asarray(x, np.float64)
        edges = np.asarray(edges, np.float64)
        idx = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, len(edges) - 2)
        counts = np.bincount(idx, minlength=len(edges) - 1)
        sums = np.bincount(idx, weights=x, minlength=len(edges) - 1)
        mids = (edges[:-1] + edges[1:]) / 2
        return cls(edges, np.where(counts > 0, sums / np.maximum(counts, 1), mids))

    def index(self, x) -> np.ndarray:
        return np.clip(np.searchsorted(self.edges, x, side="right") - 1, 0, len(self.edges) - 2)
