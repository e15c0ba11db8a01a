"""Synthetic per-waypoint datasets with the seed-000 graph, for the causal tests.

O->V, C->V, V(t-1)->V, O->L, C->L, V->L, W->D, S->D, D(t-1)->D, nothing else.
"""

from __future__ import annotations

import numpy as np


def episodes(rng, n, p_start, length):
    """A 0/1 series of episodes of ``length`` samples starting with probability ``p_start``."""
    x = np.zeros(n)
    t = 0
    while t < n:
        if rng.random() < p_start:
            x[t : t + length] = 1.0
            t += length
        t += 1
    return x


def seed000_datasets(n_waypoints=6, n_samples=2000, seed=0):
    rng = np.random.default_rng(seed)
    slot = np.minimum(np.arange(n_samples) * 11 // n_samples, 10).astype(float)
    charging = episodes(rng, n_samples, 0.004, 60)
    obstacle = episodes(rng, n_samples, 0.03, 6) * (1 - charging)
    speed = np.zeros(n_samples)
    for t in range(1, n_samples):
        speed[t] = 0.5 * speed[t - 1] + 0.4 * (1 - charging[t]) - 0.3 * obstacle[t] + 0.1 * rng.standard_normal()
    battery = -0.5 * speed - 0.4 * obstacle + 0.6 * charging + 0.1 * rng.standard_normal(n_samples)
    data = {}
    for w in range(n_waypoints):
        density = np.zeros(n_samples)
        for t in range(1, n_samples):
            density[t] = 0.5 * density[t - 1] + 0.3 * w + 0.2 * slot[t] + 0.5 * rng.standard_normal()
        data[w] = np.stack([speed, battery, density, np.full(n_samples, float(w)), slot, charging, obstacle], 1)
    return data
