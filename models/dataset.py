"""GSCL's procedural dataset (seed 002 Sec. 4.1): (input map, target cost map) pairs, 40 x 40.

:func:`generate` vmaps each family's sampler (:mod:`models.families`) over keys folded from one
seed, in fixed chunks (one compilation per family whatever the size), so a dataset is
deterministic by seed and fast enough to make fresh rather than read from disk. A dataset can be
written to one ``.npz`` file (:func:`save`, atomic) and read back (:func:`load`) for users who
want a file; training makes its samples fresh instead (:mod:`models.streams`).
"""

from __future__ import annotations

import functools
import pathlib

import jax
import jax.numpy as jnp
import numpy as np

from socialnav.common.atomic import write_bytes_atomic
from socialnav.models import families, grid
from socialnav.models.families import COMPOSITE, FAMILIES, PAIRED_WITH

# Paper's sample counts per family (Sec. 4.1; the hallway's 5000 split over its three kinds).
PAPER_COUNTS = {
    "corner": 2000,
    "proxemics": 1000,
    "group": 4500,
    "non_group": 4500,
    "hallway_straight": 1667,
    "hallway_l": 1667,
    "hallway_people": 1666,
    "queue": 3600,
    "non_queue": 3600,
}
KEYS = ("inputs", "targets", "family", "names")


CHUNK = 1024  # samples per generator call: one compilation per family serves every dataset size


@functools.cache
def batched_sampler(name: str):
    """``keys (B,) -> (inputs (B, 40, 40), targets (B, 40, 40))`` of family ``name``, jitted (the
    composite's from :data:`batched_composite`, the program its contrast comes from too)."""
    if name == COMPOSITE:
        return lambda keys: batched_composite(keys)[:2]
    return jax.jit(jax.vmap(FAMILIES[name]))


# ``keys (B,) -> (inputs, targets, contrast)``, each (B, 40, 40), of the composite family
# (:func:`models.families.composite_with_contrast`): one program for its samples and its contrast, since it
# holds every candidate family twice and takes longer to compile than all of them together.
batched_composite = jax.jit(jax.vmap(families.composite_with_contrast))


def _as_key(seed) -> jax.Array:
    """An int seed or a JAX key -> a typed JAX key."""
    if isinstance(seed, (int, np.integer)):
        return jax.random.key(int(seed))
    if isinstance(seed, jax.Array) and jnp.issubdtype(seed.dtype, jax.dtypes.prng_key):
        return seed
    raise TypeError(f"seed must be an int or a jax.random.key, got {type(seed).__name__}")


# Families drawn from their partner's keys: sample i of ``non_queue`` is sample i of ``queue``'s
# layout with the goal elsewhere, sample i of ``non_group`` the same circle facing out. Training then
# sees the same people with and without the rule, which is the contrast the rule suite
# (:mod:`models.rules`) measures; with independent keys the queue's U stayed weak (README).
# PAIRED_WITH (from models.families) names them.


def pair_contrast(data: dict[str, np.ndarray], seed=None) -> np.ndarray:
    """(N, 40, 40) float32: ``|target - twin's target|`` for each sample of a paired family and its
    partner (:data:`PAIRED_WITH`), 0 for every other sample: the cells where the rule (the group's
    zone, the queue's U) and the headings it comes with change the cost. With ``seed`` (the one
    ``data`` was generated from), composites get the same for each of their two scenes that has a
    twin (:func:`models.families.composite_with_contrast`).

    ``data`` must be in :func:`generate`'s order (each family's samples by index, before any
    shuffle): sample ``i`` of a twin is paired with sample ``i`` of its partner, the first
    ``min`` of their two counts (sample ``i`` is the same whatever the counts)."""
    contrast = np.zeros(data["targets"].shape, np.float32)
    names = list(data["names"])
    for twin, partner in PAIRED_WITH.items():
        if twin not in names or partner not in names:
            continue
        rows_t = np.flatnonzero(data["family"] == names.index(twin))
        rows_p = np.flatnonzero(data["family"] == names.index(partner))
        n = min(len(rows_t), len(rows_p))
        diff = np.abs(data["targets"][rows_t[:n]] - data["targets"][rows_p[:n]])
        contrast[rows_t[:n]] = diff
        contrast[rows_p[:n]] = diff
    if seed is not None and COMPOSITE in names:
        rows = np.flatnonzero(data["family"] == names.index(COMPOSITE))
        parts = _in_chunks(lambda keys: batched_composite(keys)[2], family_keys(seed, COMPOSITE, len(rows)))
        contrast[rows] = np.concatenate(parts)
    return contrast


def _family_base(seed, family: str) -> jax.Array:
    return jax.random.fold_in(_as_key(seed), list(FAMILIES).index(PAIRED_WITH.get(family, family)))


def family_keys(seed, family: str, n: int, first: int = 0) -> jax.Array:
    """(n,) keys of samples ``first .. first + n - 1`` of a family: sample ``i`` of a family is
    the same whatever the other counts."""
    base = _family_base(seed, family)
    return jax.vmap(lambda i: jax.random.fold_in(base, i))(jnp.arange(first, first + n))


def scaled_counts(fraction: float, counts: dict[str, int] | None = None) -> dict[str, int]:
    """``counts`` (default the paper's) times ``fraction``, rounded, per family (e.g. 0.7 / 0.3 splits)."""
    counts = PAPER_COUNTS if counts is None else counts
    return {name: int(round(n * fraction)) for name, n in counts.items()}


def generate(seed, counts: dict[str, int] | None = None) -> dict[str, np.ndarray]:
    """A dataset: ``inputs`` (N, 40, 40) uint8, ``targets`` (N, 40, 40) float32 in [0, 1],
    ``family`` (N,) int8 index into ``names`` (the family names, in order).

    Args:
      seed: an int or a ``jax.random.key``; the dataset is a pure function of it and ``counts``.
      counts: samples per family (default :data:`PAPER_COUNTS`); unknown names raise ValueError.
    """
    counts = dict(PAPER_COUNTS if counts is None else counts)
    unknown = sorted(set(counts) - set(FAMILIES))
    if unknown:
        raise ValueError(f"unknown families {unknown}; known: {list(FAMILIES)}")
    if any(n < 0 for n in counts.values()):
        raise ValueError(f"counts must be >= 0, got {counts}")
    names = [f for f in FAMILIES if counts.get(f, 0) > 0]
    inputs, targets, family = [], [], []
    for idx, name in enumerate(names):
        x, y = generate_range(seed, name, 0, counts[name])
        inputs.append(x)
        targets.append(y)
        family.append(np.full(counts[name], idx, np.int8))
    return assemble(names, inputs, targets, family)


def generate_range(seed, name: str, start: int, stop: int) -> tuple[np.ndarray, np.ndarray]:
    """Samples ``start .. stop - 1`` of family ``name``: (inputs (n, 40, 40) uint8, targets (n, 40,
    40) float32), the same samples as in any dataset that holds them (a shard of a dataset: with
    ``start`` a multiple of :data:`CHUNK` the same bits too, the batches being the same)."""
    parts = _in_chunks(batched_sampler(name), family_keys(seed, name, stop - start, start))
    inputs = [x for x, _ in parts]
    targets = [y.astype(np.float32) for _, y in parts]
    if not inputs:
        return np.zeros((0, grid.GRID, grid.GRID), np.uint8), np.zeros((0, grid.GRID, grid.GRID), np.float32)
    return np.concatenate(inputs), np.concatenate(targets)


def _in_chunks(batched, keys) -> list:
    """``batched`` (a jitted function of (CHUNK,) keys) over ``keys`` in chunks of :data:`CHUNK`,
    the last padded, so one compiled shape serves any count; each chunk's outputs as numpy, cut to
    its keys."""
    parts = []
    for first in range(0, keys.shape[0], CHUNK):
        chunk = keys[first : first + CHUNK]
        n = chunk.shape[0]
        if n < CHUNK:
            chunk = jnp.concatenate([chunk, jnp.broadcast_to(chunk[:1], (CHUNK - n,))])
        parts.append(jax.tree.map(lambda a, n=n: np.asarray(a[:n]), batched(chunk)))
    return parts


def assemble(names, inputs, targets, family) -> dict[str, np.ndarray]:
    """A dataset dict from per-part arrays (in order): see :func:`generate`."""
    if not names:
        empty = np.zeros((0, grid.GRID, grid.GRID))
        return {
            "inputs": empty.astype(np.uint8),
            "targets": empty.astype(np.float32),
            "family": np.zeros(0, np.int8),
            "names": np.asarray([], str),
        }
    return {
        "inputs": np.concatenate(inputs),
        "targets": np.concatenate(targets),
        "family": np.concatenate(family),
        "names": np.asarray(names),
    }


def save(path, data: dict[str, np.ndarray]) -> pathlib.Path:
    """Write a dataset from :func:`generate` to ``path`` (``.npz``, compressed), atomically: the
    file appears complete or not at all. Targets are stored as in memory (float32 in [0, 1])."""
    path = pathlib.Path(path)
    if path.suffix != ".npz":
        raise ValueError(f"dataset files are .npz, got {path}")
    missing = {"inputs", "targets", "family", "names"} - set(data)
    if missing:
        raise ValueError(f"not a dataset: missing {sorted(missing)}")
    return write_bytes_atomic(path, lambda f: np.savez_compressed(f, **{k: np.asarray(data[k]) for k in KEYS}))


def load(path) -> dict[str, np.ndarray]:
    """Read a dataset written by :func:`save`."""
    with np.load(pathlib.Path(path)) as f:
        data = {k: f[k] for k in f.files}
    missing = {"inputs", "targets", "family", "names"} - set(data)
    if missing:
        raise ValueError(f"{path} is not a GSCL dataset: missing {sorted(missing)}")
    return data
