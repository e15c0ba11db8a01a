"""Warm start: a training run's first weights taken from another GSCL model (fine-tuning).

:attr:`models.config.TrainConfig.init_from` names a model folder (an exported model, such as the
one the package ships, or a training run's folder); :func:`warm_started` copies its weights and
batch statistics into the fresh training state, leaf by leaf, by path. Every leaf must have the
same path and shape in both models, with one exception: an output layer that gains output
channels (the last axis) gets the source's channels copied into its first ones and keeps its
fresh initialisation in the rest. That is how a model with one graded output (older runs) starts
one with the forbidden head (:mod:`models.unet`): the graded channel is the old output on the
same scale (both peak at 1; :func:`models.steps.split_targets`), the forbidden channel starts
from scratch at the head's bias (probability 0.05). A second exception: a separate forbidden
branch (``forbidden_branch``, :mod:`models.unet`), which a one-output source lacks, starts as a
copy of the source's own layers when it has the source's widths, its output layer fresh (so it
starts from features that already see people, lines and goals, and learns only what the U adds:
a fine-tune of the shared network learnt the U within two epochs, fresh branches were far slower,
``docs/arena-results.md``, the queue's fifth try), and fresh when its widths differ.
Adam's state starts from zero as in any run.

Why by hand: flax's ``nnx.replace_by_pure_dict`` copies a whole tree of equal shapes only, and a
fine-tuning run that grows a head is what this project needs.
"""

from __future__ import annotations

import pathlib

import jax
import numpy as np
from flax import nnx

from socialnav.models.unet import BRANCH


def _flat(tree) -> dict[str, np.ndarray]:
    return {jax.tree_util.keystr(k): np.asarray(v) for k, v in jax.tree_util.tree_flatten_with_path(tree)[0]}


def merged_weights(fresh: dict, source: dict, source_name: str) -> dict:
    """``fresh`` (a pure dict of arrays) with every leaf replaced by ``source``'s leaf of the same
    path: equal shapes are copied; a source leaf whose shape differs only by fewer entries on the
    last axis fills that axis's first entries; the leaves of a :data:`BRANCH` the source lacks
    take the source's leaves of the same paths outside the branch when every one but the output
    layer's (``head``, fresh) is shaped alike, and stay fresh otherwise. Returns a new pure dict.

    Raises:
      ValueError: a leaf of ``fresh`` is missing in ``source`` or shaped otherwise, or ``source``
        has a leaf ``fresh`` lacks; the message names ``source_name`` and the leaf.
    """
    want, have = _flat(fresh), _flat(source)
    extra = sorted(set(have) - set(want))
    if extra:
        raise ValueError(f"init_from: {source_name} has {extra[0]}, which this run's model lacks")
    prefix = f"['{BRANCH}']"
    branch = {} if any(k.startswith(prefix) for k in have) else {k: v for k, v in want.items() if k.startswith(prefix)}
    body = {k: v for k, v in branch.items() if not k.startswith(prefix + "['head']")}
    copy = all(np.shape(have.get(k.removeprefix(prefix))) == v.shape for k, v in body.items())
    out = {}
    for path, target in want.items():
        if path in branch:
            out[path] = have[path.removeprefix(prefix)].astype(target.dtype) if copy and path in body else target
            continue
        if path not in have:
            raise ValueError(f"init_from: {source_name} has no {path}, which this run's model needs")
        got = have[path]
        if got.shape == target.shape:
            out[path] = got.astype(target.dtype)
        elif got.ndim == target.ndim and got.shape[:-1] == target.shape[:-1] and got.shape[-1] < target.shape[-1]:
            grown = np.array(target, copy=True)
            grown[..., : got.shape[-1]] = got
            out[path] = grown
        else:
            raise ValueError(
                f"init_from: {source_name}'s {path} is shaped {got.shape}, this run's model needs {target.shape}"
            )
    leaves, treedef = jax.tree_util.tree_flatten_with_path(fresh)
    return jax.tree_util.tree_unflatten(treedef, [out[jax.tree_util.keystr(k)] for k, _ in leaves])


SOURCE_FILE = "init_from.json"  # in a warm-started run's folder: which model it started from


def source_record(path) -> dict:
    """What identifies the model a run starts from: its folder as given, its
    :func:`models.inference.model_identity` and its card's ``made_by`` and ``run`` where it has a
    card; a run writes it as :data:`SOURCE_FILE` when it starts, and ``socialnav gscl export``
    copies it into the exported model's card, so that the source is known after its folder
    changes (the shipped model is replaced by the models fine-tuned from it)."""
    from socialnav.models.inference import model_identity, read_card

    path = pathlib.Path(path)
    card = read_card(path)
    record = {"path": str(path), "identity": model_identity(path)}
    record.update({k: card[k] for k in ("made_by", "run", "step") if k in card})
    return record


def warm_started(state: dict, path) -> dict:
    """``state`` (:func:`models.steps.initial_state`) with its ``params`` and ``batch_stats`` taken
    from the model in folder ``path`` as :func:`merged_weights` says; the optimiser's state and
    the accumulators stay fresh.

    Raises:
      ValueError: ``path`` holds no model, or one whose structure this run cannot start from.
    """
    from socialnav.models.inference import SocialCostModel

    path = pathlib.Path(path)
    source = SocialCostModel.load(path)
    out = dict(state)
    for name, theirs in zip(("params", "batch_stats"), source.weights, strict=True):
        mine = state[name]
        pure = merged_weights(nnx.to_pure_dict(mine), nnx.to_pure_dict(theirs), str(path))
        mine = jax.tree.map(lambda x: x, mine)  # a copy: the caller's state stays as it was
        nnx.replace_by_pure_dict(mine, jax.tree.map(jax.numpy.asarray, pure))
        out[name] = mine
    return out
