"""The data streams of training: every epoch's samples and the held-out test set, drawn by key.

Every epoch draws its training samples from :func:`models.dataset.generate` with a key folded
from ``(seed, "train", epoch)`` (:attr:`TrainConfig.fresh_samples`; with it off, epoch 0's samples
are reused every epoch, the paper's fixed 70 % split). The test set comes from ``(seed, "test")``,
a key no training epoch uses, in the proportions of the paper's 30 %. Making an epoch of 16,940
pairs takes about a second, less than reading it from disk would.
"""

from __future__ import annotations

import functools

import jax
import numpy as np

from socialnav.models import dataset
from socialnav.models.config import TrainConfig


def _stream_key(seed: int, stream: str, index: int = 0) -> jax.Array:
    streams = ("train", "test", "demonstrations")
    return jax.random.fold_in(jax.random.fold_in(jax.random.key(seed), streams.index(stream)), index)


def demonstration_key(config: TrainConfig, step: int) -> jax.Array:
    """The key of step ``step``'s demonstrations (the "paths" objective: random starts and goals)."""
    return _stream_key(config.seed, "demonstrations", step)


@functools.lru_cache(maxsize=1)  # epoch 0 serves the trivial baselines and then the first epoch
def epoch_data(config: TrainConfig, epoch: int) -> dict[str, np.ndarray]:
    """The shuffled training samples of ``epoch`` (epoch 0's for every epoch without fresh samples),
    with ``contrast`` (:func:`models.dataset.pair_contrast`) when the run weighs its pairs."""
    e = epoch if config.fresh_samples else 0
    key = _stream_key(config.seed, "train", e)
    data = dataset.generate(key, config.train_counts)
    if config.pair_weight:
        data["contrast"] = dataset.pair_contrast(data, key)  # before the shuffle: twins are found by order
    order = np.random.default_rng([config.seed, epoch]).permutation(len(data["family"]))
    shuffled = ("inputs", "targets", "family", "contrast")
    return {**{k: data[k][order] for k in shuffled if k in data}, "names": data["names"]}


def test_data(config: TrainConfig) -> dict[str, np.ndarray]:
    """The held-out test set (a key no training epoch uses), its arrays read-only.

    Kept for the process (the last two recipes'): training, its evaluation and a check of the
    model each ask for the same set, which at the paper's size takes longer to draw than the
    network takes to score it."""
    return dict(_test_set(config.seed, tuple(sorted(config.test_counts.items()))))


@functools.lru_cache(maxsize=2)
def _test_set(seed: int, counts: tuple[tuple[str, int], ...]) -> dict[str, np.ndarray]:
    data = dataset.generate(_stream_key(seed, "test"), dict(counts))  # drawn in FAMILIES' order
    for array in data.values():
        if isinstance(array, np.ndarray):
            array.flags.writeable = False
    return data
