"""The configuration of a GSCL training run (seed 002 Sec. 4.2): widths, schedule, data sizes.

A frozen, hashable dataclass validated on construction; the paper's recipe is
:meth:`TrainConfig.paper`. ``config.json`` in a run folder is its :meth:`TrainConfig.to_json`.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import optax
from flax import nnx

from socialnav.models import dataset, unet
from socialnav.models.families import CLOSED_L

# Settings added after runs were saved, with the value those runs used.
ADDED_LATER = {
    "composites": 0,
    "cost_weight": 0.0,
    "group_scale": 1,
    "pair_weight": 0.0,
    "objective": "maps",
    "temperature": 2.0,
    "paths_per_map": 4,
    "demonstrations": "paths",
    "reading": "graded",
    "targets": "graded",
    "forbidden_weight": 0.0,
    "init_from": "",
    "forbidden_features": [],
    "freeze_graded": False,
    "closed_l_hallways": 0,
}
OBJECTIVES = ("maps", "paths")
# What the "paths" objective demonstrates on each map: "paths", ``paths_per_map`` exact plans to
# the goal; "cells", the exact planner's move out of every free cell, each once
# (planners.learning.irl.policy_demonstration). scripts/irl_rule_oracle.py shows why the second exists: a
# free grid fitted to 4 exact plans on each rule-suite map keeps almost none of the rules, one
# fitted to every cell's move most of them.
DEMONSTRATIONS = ("paths", "cells")
# How the "paths" objective prices costs (planners.learning.irl.traversal_per_m), the demonstrator's
# targets and the network's output alike: "graded", every cost on NavFn's graded scale (the
# queue's U at 1 is then 5 times a free cell, and exact plans cross it); "layer", as the GSCL
# layer reads a network's costs (graded up to models.social_costs.GRADED_TOP, lethal from
# FORBIDDEN_FROM), so that no demonstration enters the U and the network can learn a lethal level.
READINGS = ("graded", "layer")
# The generator's targets: "graded_forbidden" (today's: graded shapes up to
# models.social_costs.GRADED_TOP, the queue's U at FORBIDDEN) or "graded" (runs saved before:
# every shape graded, peak 1; kept only to read those runs, the generator no longer draws them).
TARGETS = ("graded_forbidden", "graded")
# The soft planner's temperature of the "paths" objective, in NavFn cost units on the network's
# 0.4 m grid (the cheapest move, 0.4 m of free space, costs 20; the soft-min converges for
# tau < 20 / ln 8 = 9.6). Exact plans are noise-free demonstrations and a low temperature fits
# them best: a free 40 x 40 grid learnt from 512 exact plans on a known map planned held-out
# pairs 1.52 / 1.60 / 2.31 % above the optimum at tau 2 / 4 / 8 (scripts/irl_known_map.py;
# README, "Costs learned from paths"). People's tracks, which are noisier, may want a higher one.
PATH_TEMPERATURE = 2.0
MAX_PATH_TEMPERATURE = 20.0 / math.log(8.0)


@dataclasses.dataclass(frozen=True)
class TrainConfig:
    """Static configuration of a training run.

    Attributes:
      features: U-Net widths (3 encoder blocks, bottleneck); :data:`models.unet.CPU_FEATURES` by
        default, :data:`models.unet.PAPER_FEATURES` for the paper's size.
      coords: add the coordinate channels to the input (:mod:`models.unet`).
      epochs: number of epochs (the paper: 20).
      batch_size: samples per step (split over the devices; a multiple of their number).
      learning_rate: Adam's peak learning rate (the paper: 1e-3, constant).
      schedule: ``"constant"`` (the paper) or ``"cosine"`` (linear warm-up, cosine decay to
        ``final_lr_fraction`` of the peak at the last step).
      warmup_steps / final_lr_fraction: of the cosine schedule.
      train_fraction / test_fraction: epoch and test-set sizes as fractions of the paper's
        24,200 samples, family by family (the paper's 70 / 30 split).
      fresh_samples: new training samples every epoch (True) or epoch 0's reused (the paper).
      composites: composite samples (two families' scenes in one, :func:`models.families.sample_composite`)
        per 24,200 of the paper's, scaled like the others (0: the paper's eight families only).
      group_scale: the group and non-group families' sample counts times this (1: the paper's
        4,500 each). 2 by default: circles under 1 m were the held-out suite's weakest cases, and
        the network drew their zone's middle 0.03-0.05 too low where the input fixes it (measured
        by ``scripts/gscl_group_zone.py``); twice the groups raised the zone beside a hallway and
        beside a queue by 2-3 points on a fresh draw for 30 % more training time (README, "The
        held-out rule suite").
      closed_l_hallways: samples of ``hallway_l_closed`` (an L whose second leg ends in a wall
        0.3-3 m past the goal, :mod:`models.families`) per 24,200 of the paper's, scaled like the
        others; 0 by default (the paper's hallways and the shipped model's). The arena's L-hallway
        ends 0.9 m past its goal, a geometry the open L's never show.
      cost_weight: the training loss weighs each pixel's squared error by ``1 + cost_weight *
        target`` (0: the plain MSE of the paper), so the cells a rule makes costly count more than
        the free space that fills most of a map; test errors are always the plain MSE. 10 by
        default: at 10 epochs, 4 and 10 lifted the held-out suite's blind corner beside a queue
        from 85 to 90 and 95 % (README, "The held-out rule suite").
      pair_weight: adds ``pair_weight * |target - twin's target|`` to each pixel's weight in the
        paired families (:data:`models.dataset.PAIRED_WITH`: a group and the same circle facing
        out, a queue and the same queue with the goal elsewhere), on both twins: the cells where
        the rule changes the cost, which the held-out suite's contrasts measure, count more on
        both sides of the contrast (``cost_weight`` alone weighs the facing-in side up, not the
        facing-out one). 20 by default: on 400 fresh scenes of each kind every held-out check
        passed (the zone beside a hallway 92.8 -> 96.0 %, beside a queue 94.8 -> 97.2 %); 0: no
        pair term (runs saved before it, ``--paper``).
      forbidden_weight: the weight of the forbidden head's loss (the mean over pixels of the
        binary cross-entropy of its logits against the forbidden share of the target,
        :func:`models.steps.split_targets`) beside the graded channel's weighted MSE; > 0 for a
        model with the head. ``--paper`` keeps the head and this weight: reading the U as lethal
        is this project's choice, not a change of the paper's network. 1 by default: on short
        runs (2 epochs of a quarter of the data, the queue's U rule check / the corner family's
        test error as a share of the trivial predictor's) 0.01 gave 0 % / 0.44, 0.3 3 % / 0.37,
        1 63 % / 0.41 and 3 69 % / 0.59.
      objective: ``"maps"`` (seed 002: regression on the generator's target maps, the loss
        above) or ``"paths"`` (maximum-entropy IRL through the soft planner,
        :mod:`planners.learning.irl`: the targets are used only to plan ``paths_per_map`` exact
        demonstrations per map, and the loss is their negative log-likelihood under the soft
        planner of the network's costs; the test MSE is then a diagnostic, not the objective).
        A "paths" run is trained by :func:`models.train.train` with the objective passed in
        (``planners.learning.irl.PathObjective``): ``models`` never imports the planners.
      temperature: the soft planner's temperature of the "paths" objective
        (:data:`PATH_TEMPERATURE`, below :data:`MAX_PATH_TEMPERATURE`).
      paths_per_map: demonstrations planned on each map by the "paths" objective.
      demonstrations: what the "paths" objective demonstrates (:data:`DEMONSTRATIONS`): "paths"
        (the default), ``paths_per_map`` exact plans per map; "cells", the exact planner's move out
        of every free cell (``paths_per_map`` is then unused).
      reading: how the "paths" objective prices costs (:data:`READINGS`): "graded" (the default)
        or "layer" (see :attr:`reads_lethal`).
      targets: which targets the run learnt (:data:`TARGETS`); see :attr:`reads_forbidden`.
      init_from: a model folder (an exported model, e.g. the shipped one, or a training run's
        folder) whose weights start this run (:mod:`models.warm_start`: fine-tuning; a source
        with one output starts a model with the forbidden head, whose new channel starts fresh);
        ``""`` (the default): fresh weights drawn from ``seed``. A relative path is read from
        the working directory; a resumed run starts from its checkpoint and never reads it.
      forbidden_features: ``()`` (the default): the forbidden head is a second output channel of
        the U-Net's last layer, sharing its features with the graded costs; four widths: the
        forbidden logit comes from a separate U-Net of those widths
        (:class:`models.unet.UNet`'s ``forbidden_features``), so that the graded network can be
        kept as it is (``freeze_graded``).
      freeze_graded: train the forbidden branch only: the graded network's weights and batch
        statistics stay as ``init_from`` gave them (Adam's updates set to zero, batch norm in
        inference mode, no gradient computed through it), and the loss is the forbidden head's
        cross-entropy alone. Needs ``init_from`` and ``forbidden_features``. Why: a fine-tune of
        the shared network learnt the U but drew the blind corner beside a queue weaker than the
        shipped model (93.5 % against 95.8 % of the rule suite's scenes); a
        frozen graded network keeps every graded cost the source drew.
      seed: seeds the data streams and the initialisation.
      checkpoint_every_steps: orbax checkpoint interval within an epoch (epochs' ends always).
      keep_checkpoints: how many checkpoints orbax keeps.
    """

    features: tuple[int, int, int, int] = unet.CPU_FEATURES
    coords: bool = True
    epochs: int = 10
    batch_size: int = 32
    learning_rate: float = 3e-3
    schedule: str = "cosine"
    warmup_steps: int = 200
    final_lr_fraction: float = 0.02
    train_fraction: float = 0.7
    test_fraction: float = 0.3
    fresh_samples: bool = True
    composites: int = 10000
    group_scale: int = 2
    closed_l_hallways: int = 0
    cost_weight: float = 10.0
    pair_weight: float = 20.0
    forbidden_weight: float = 1.0
    objective: str = "maps"
    temperature: float = PATH_TEMPERATURE
    paths_per_map: int = 4
    demonstrations: str = "paths"
    reading: str = "graded"
    targets: str = "graded_forbidden"
    init_from: str = ""
    forbidden_features: tuple[int, ...] = ()
    freeze_graded: bool = False
    seed: int = 0
    checkpoint_every_steps: int = 500
    keep_checkpoints: int = 2

    def __post_init__(self):
        features = tuple(self.features)
        if len(features) != 4 or not all(isinstance(f, int) and not isinstance(f, bool) and f >= 1 for f in features):
            raise ValueError(f"features must be 4 whole numbers >= 1, got {list(features)}")
        object.__setattr__(self, "features", tuple(int(f) for f in features))
        branch = tuple(self.forbidden_features)
        if branch and (
            len(branch) != 4 or not all(isinstance(f, int) and not isinstance(f, bool) and f >= 1 for f in branch)
        ):
            raise ValueError(f"forbidden_features must be empty or 4 whole numbers >= 1, got {list(branch)}")
        object.__setattr__(self, "forbidden_features", branch)
        for name in ("learning_rate", "final_lr_fraction", "train_fraction", "test_fraction"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"{name} must be finite, got {getattr(self, name)}")
        if self.warmup_steps < 0 or not 0 <= self.final_lr_fraction <= 1:
            raise ValueError("warmup_steps must be >= 0 and final_lr_fraction in [0, 1]")
        if self.schedule not in ("constant", "cosine"):
            raise ValueError(f"schedule must be 'constant' or 'cosine', got {self.schedule!r}")
        for name in ("cost_weight", "pair_weight", "forbidden_weight"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) >= 0):
                raise ValueError(f"{name} must be finite and >= 0, got {getattr(self, name)}")
        if self.targets not in TARGETS:
            raise ValueError(f"targets must be one of {TARGETS}, got {self.targets!r}")
        if self.reads_forbidden and not self.forbidden_weight > 0:
            raise ValueError("forbidden_weight must be > 0 with the forbidden head (a 'maps' run on today's targets)")
        if self.forbidden_features and not self.reads_forbidden:
            raise ValueError("forbidden_features needs the forbidden head (a 'maps' run on today's targets)")
        if self.freeze_graded and not (self.init_from and self.forbidden_features):
            raise ValueError("freeze_graded needs init_from (the graded network to keep) and forbidden_features")
        if self.objective not in OBJECTIVES:
            raise ValueError(f"objective must be one of {OBJECTIVES}, got {self.objective!r}")
        if not 0 < self.temperature < MAX_PATH_TEMPERATURE:
            raise ValueError(f"temperature must be in (0, {MAX_PATH_TEMPERATURE:.2f}), got {self.temperature}")
        if self.demonstrations not in DEMONSTRATIONS:
            raise ValueError(f"demonstrations must be one of {DEMONSTRATIONS}, got {self.demonstrations!r}")
        if self.reading not in READINGS:
            raise ValueError(f"reading must be one of {READINGS}, got {self.reading!r}")
        if self.reading != "graded" and self.objective != "paths":
            raise ValueError("reading 'layer' needs the 'paths' objective (a 'maps' run learns the forbidden head)")
        if self.paths_per_map < 1:
            raise ValueError(f"paths_per_map must be >= 1, got {self.paths_per_map}")
        if self.composites < 0:
            raise ValueError(f"composites must be >= 0, got {self.composites}")
        if self.group_scale < 1:
            raise ValueError(f"group_scale must be >= 1, got {self.group_scale}")
        if self.closed_l_hallways < 0:
            raise ValueError(f"closed_l_hallways must be >= 0, got {self.closed_l_hallways}")
        for name in ("epochs", "batch_size", "checkpoint_every_steps", "keep_checkpoints"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be >= 1, got {getattr(self, name)}")
        if not (0 < self.train_fraction and 0 < self.test_fraction):
            raise ValueError("train_fraction and test_fraction must be > 0")
        if not self.learning_rate > 0:
            raise ValueError(f"learning_rate must be > 0, got {self.learning_rate}")

    @classmethod
    def paper(cls, **overrides) -> TrainConfig:
        """The paper's recipe: 32/64/128/256, batch 32, Adam 1e-3 constant, 20 epochs over one
        fixed 70 % split (batch size not given in the paper; 32 assumed)."""
        base = dict(
            features=unet.PAPER_FEATURES,
            batch_size=32,
            learning_rate=1e-3,
            schedule="constant",
            fresh_samples=False,
            epochs=20,
            composites=0,
            group_scale=1,
            cost_weight=0.0,
            pair_weight=0.0,
        )
        return cls(**{**base, **overrides})

    @property
    def reads_forbidden(self) -> bool:
        """Whether the model has the forbidden head (:mod:`models.unet`) and its costs are read
        with a forbidden level (the "maps" objective on today's targets: from
        :data:`models.social_costs.FORBIDDEN_FROM` up lethal). A model that learnt graded costs
        only (older runs; the "paths" objective, whose soft planner reads every cost as graded)
        has one output and is scaled into the graded range when loaded."""
        return self.targets == "graded_forbidden" and self.objective == "maps"

    @property
    def reads_lethal(self) -> bool:
        """Whether the model's costs are read as they are, lethal from
        :data:`models.social_costs.FORBIDDEN_FROM` up: a model with the forbidden head, or a
        "paths" model learnt with ``reading == "layer"``, whose soft planner priced its one output
        exactly so. Any other model is scaled into the graded range when loaded
        (:func:`models.inference.output_scale`)."""
        return self.reads_forbidden or (self.objective == "paths" and self.reading == "layer")

    @property
    def counts(self) -> dict[str, int]:
        """Samples per family of the whole (train + test) set: the paper's (groups and non-groups
        times :attr:`group_scale`), plus the composites and the closed L-hallways."""
        groups = {f: dataset.PAPER_COUNTS[f] * self.group_scale for f in ("group", "non_group")}
        extra = {"composite": self.composites, CLOSED_L: self.closed_l_hallways}
        return {**dataset.PAPER_COUNTS, **groups, **{name: n for name, n in extra.items() if n}}

    @property
    def train_counts(self) -> dict[str, int]:
        return dataset.scaled_counts(self.train_fraction, self.counts)

    @property
    def test_counts(self) -> dict[str, int]:
        return dataset.scaled_counts(self.test_fraction, self.counts)

    @property
    def steps_per_epoch(self) -> int:
        return max(1, sum(self.train_counts.values()) // self.batch_size)

    @property
    def total_steps(self) -> int:
        return self.epochs * self.steps_per_epoch

    def to_json(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d["features"] = list(self.features)
        d["forbidden_features"] = list(self.forbidden_features)
        return d

    @classmethod
    def from_json(cls, d: Any, source: str = "config.json") -> TrainConfig:
        """A configuration from its JSON object; ``ValueError`` naming ``source`` and the field
        (unknown or missing keys, a wrong type, a value out of range)."""
        if not isinstance(d, dict):
            raise ValueError(f"{source}: top level must be a JSON object, got {type(d).__name__}")
        fields = {f.name: f for f in dataclasses.fields(cls)}
        unknown = sorted(set(d) - set(fields))
        if unknown:
            raise ValueError(f"{source}: field '{unknown[0]}': unknown setting")
        d = {**ADDED_LATER, **d}  # runs written before a setting existed had its old value
        missing = sorted(set(fields) - set(d))
        if missing:
            raise ValueError(f"{source}: field '{missing[0]}': missing")
        kinds = {
            "features": list,
            "coords": bool,
            "fresh_samples": bool,
            "schedule": str,
            "objective": str,
            "targets": str,
            "reading": str,
            "init_from": str,
            "forbidden_features": list,
        }
        for name, value in d.items():
            want = kinds.get(name, type(getattr(cls, name)))
            ok = isinstance(value, want) and not (want is not bool and isinstance(value, bool))
            if want is float:
                ok = isinstance(value, (int, float)) and not isinstance(value, bool)
            if not ok:
                raise ValueError(f"{source}: field '{name}': expected {want.__name__}, got {value!r}")
        try:
            return cls(**{**d, "features": tuple(d["features"]), "forbidden_features": tuple(d["forbidden_features"])})
        except ValueError as e:
            raise ValueError(f"{source}: {e}") from None


def learning_rate_schedule(config: TrainConfig) -> optax.Schedule:
    """Adam's learning rate per step: constant, or linear warm-up then cosine decay."""
    if config.schedule == "constant":
        return optax.constant_schedule(config.learning_rate)
    warmup = min(config.warmup_steps, max(config.total_steps - 1, 0))
    return optax.warmup_cosine_decay_schedule(
        0.0,
        config.learning_rate,
        warmup,
        max(config.total_steps, warmup + 1),
        end_value=config.learning_rate * config.final_lr_fraction,
    )


def network_args(config: TrainConfig) -> tuple[tuple[str, object], ...]:
    """:class:`models.unet.UNet`'s arguments for ``config`` (its widths and heads), as sorted
    ``(name, value)`` pairs: hashable, so that a compiled program can be keyed on them."""
    return tuple(
        sorted(
            {
                "features": config.features,
                "coords": config.coords,
                "forbidden_head": config.reads_forbidden,
                "forbidden_features": config.forbidden_features or None,
            }.items()
        )
    )


def make_model(config: TrainConfig) -> unet.UNet:
    """A freshly initialised U-Net of ``config``'s widths (seeded by ``config.seed``)."""
    return unet.UNet(**dict(network_args(config)), rngs=nnx.Rngs(config.seed))
