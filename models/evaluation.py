"""Evaluation of a trained GSCL U-Net: on its run's held-out test set, MSE per family beside the
two trivial predictors and a PNG of input / target / prediction for every family
(:func:`evaluate_run`); on the held-out rule suite, pass shares per check (:func:`rules_run`);
both as a model's card when the run's model is exported alone (:func:`exported_model`)."""

from __future__ import annotations

import json
import pathlib

import numpy as np

from socialnav.common import memory
from socialnav.common.atomic import write_text_atomic
from socialnav.models import plots, rules
from socialnav.models.checkpoints import restore
from socialnav.models.inference import rotation_averaged
from socialnav.models.quality import by_family as mse_by_family
from socialnav.models.quality import meets_quality, quality_table
from socialnav.models.steps import compiled, per_sample_mse
from socialnav.models.streams import test_data


def _test_errors(config, params, batch_stats):
    """``(test set, predict, per-sample MSE, MSE per family)`` of weights on their recipe's
    held-out test set (:func:`models.streams.test_data`)."""
    test = test_data(config)
    predict = compiled(config)[3]
    mse = per_sample_mse(predict, params, batch_stats, test["inputs"], test["targets"])
    return test, predict, mse, mse_by_family(mse, test["family"], test["names"])


def evaluate_run(run, step: int | None = None, out=None, examples: int = 2) -> dict:
    """Evaluate a run's checkpoint (the latest by default) on the run's held-out test set.

    Writes ``evaluation.json`` (MSE overall and per family, the trivial predictors', the quality
    verdict) and ``predictions.png`` to ``out`` (default ``run/evaluation``) and returns the same
    dictionary plus ``table`` (text) and ``out``.
    """
    run = pathlib.Path(run)
    config, graphdef, state, meta = restore(run, step)
    test, predict, mse, by_family = _test_errors(config, state["params"], state["batch_stats"])
    baselines = meta["baselines"]
    report = {
        "run": str(run),
        "step": int(meta["step"]),
        "epoch": int(meta["step"]) // config.steps_per_epoch,
        "test_samples": int(len(mse)),
        "test_mse": float(mse.mean()),
        "test_mse_by_family": by_family,
        "baselines": baselines,
        "meets_quality": meets_quality(float(mse.mean()), by_family, baselines),
    }
    out = run / "evaluation" if out is None else pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out / "evaluation.json", json.dumps(report, indent=1))
    # The picture: the first ``examples`` test samples of each family.
    pick = np.concatenate([np.flatnonzero(test["family"] == i)[:examples] for i in range(len(test["names"]))])
    predictions = np.asarray(predict(state["params"], state["batch_stats"], test["inputs"][pick]))
    plots.family_grid(
        test["inputs"][pick],
        test["targets"][pick],
        test["family"][pick],
        test["names"],
        out / "predictions.png",
        predictions=predictions,
        per_family=examples,
        mse=mse[pick],
    )
    report["table"] = quality_table(report["test_mse"], by_family, baselines)
    report["out"] = str(out)
    return report


# What a rule-suite run holds at once, per case (its images, expected and rule-blind maps and
# regions, then its predictions and the scoring's float64 copies), and its time. Measured with the
# shipped model on a 2-core AMD EPYC (AVX-512), 15 cases a scene of each kind: peak resident 1.00
# GB at 3,000 cases (--scenes 200), 2.32 GB at 12,000 (800), 1.04 GB at 3,000 with --rotations 4,
# so about 147 kB a case over 0.56 GB; the memory constants are taken above every one. Whole runs
# 30.8 s and 100.2 s, and 82.9 s at 3,000 cases with four rotations: about 1.8 ms a case to draw
# and score it and 5.8 ms a case for each rotation's prediction, after about 8 s of loading and
# compiling. A machine busy with other work took 2.6 times as long.
RULES_BYTES_PER_CASE = 160_000
RULES_BASE_BYTES = 0.8e9
RULES_START_S = 8.0
RULES_DRAW_S_PER_CASE = 0.0018
RULES_PREDICT_S_PER_CASE = 0.0058


def rules_size(scenes_per_kind: int, rotations: int = 1) -> tuple[int, float, float]:
    """``(cases, bytes held at once, seconds)`` of a rule-suite run of ``scenes_per_kind`` scenes of
    each kind, scored over ``rotations`` turns of the input: estimates from the measurements above."""
    cases = scenes_per_kind * rules.cases_per_scene()
    seconds = RULES_START_S + cases * (RULES_DRAW_S_PER_CASE + rotations * RULES_PREDICT_S_PER_CASE)
    return cases, RULES_BASE_BYTES + RULES_BYTES_PER_CASE * cases, seconds


def rules_size_problem(scenes_per_kind: int) -> str | None:
    """Why a rule-suite run of ``scenes_per_kind`` scenes of each kind does not fit this machine's
    memory (past 80 % of what is available), naming how many scenes fit; None where it fits or the
    memory is not known."""
    cases, needed, _ = rules_size(scenes_per_kind)
    available = memory.shortfall(needed)
    if available is None:
        return None
    fit = memory.units_that_fit(available, RULES_BASE_BYTES, RULES_BYTES_PER_CASE * rules.cases_per_scene())
    return (
        f"{cases:,} cases need about {needed / 1e9:.1f} GB at once, this machine has {available / 1e9:.1f} GB "
        f"available; at most {fit:,} scenes of each kind fit"
    )


def rules_run(
    run,
    step: int | None = None,
    out=None,
    scenes_per_kind: int = 100,
    seed: int | None = None,
    rotations: int = 1,
    report_scenes=None,
) -> dict:
    """Score a model on the held-out rule suite (:mod:`models.rules`, ``scenes_per_kind`` scenes
    of each kind, drawn from ``seed``: the suite's own, :data:`models.rules.SUITE_SEED`, by
    default; training evaluates that one after every epoch, so another seed gives scenes no run
    was ever stopped or chosen on); ``rotations=4`` scores the model averaged over the four
    quarter turns of its input (:func:`models.inference.rotation_averaged`).

    ``run`` is a training run's folder (its latest checkpoint, or ``step``'s) or an exported
    model's (``socialnav gscl export``; the shipped model's :data:`models.inference.DEFAULT_MODEL`
    too; ``step`` must then be None). The model predicts as the cost layer and the export's card
    read it (:meth:`models.inference.SocialCostModel.function`), as training's check after every
    epoch does: a model without the forbidden head (graded targets, the paths objective) scaled
    into the graded range by :func:`models.inference.output_scale`.

    Writes ``rules.json`` (pass share and mean contrasts per check and per rule, the MSE against
    the expected maps, the verdict) and ``rules.png`` to ``out`` (default ``run/evaluation``) and
    returns the same dictionary plus ``table`` (text) and ``out``. ``step`` in it is the
    checkpoint's, or an exported model's card's (None without one).

    ``report_scenes(done, total)``, if given, follows the drawing of the scenes (most of the time).

    Raises:
      FileNotFoundError, ValueError: no run, no checkpoint, none restorable; an exported model
        with a ``step``, or whose weights do not load (the file named); a suite past the memory
        available (:func:`rules_size_problem`), before the model is loaded.
    """
    from socialnav.models.inference import WEIGHTS_FILE, SocialCostModel, read_card

    problem = rules_size_problem(scenes_per_kind)
    if problem:
        raise ValueError(f"scenes_per_kind={scenes_per_kind}: {problem}")
    run = pathlib.Path(run)
    if (run / WEIGHTS_FILE).is_file():
        if step is not None:
            raise ValueError(f"{run}: an exported model has no checkpoints to choose a step from")
        model = SocialCostModel.load(run)
        step = read_card(run).get("step")
    else:
        config, graphdef, state, meta = restore(run, step)
        model = SocialCostModel(graphdef, state["params"], state["batch_stats"], config)
        step = int(meta["step"])
    seed = rules.SUITE_SEED if seed is None else seed
    if report_scenes is None:
        cases = rules.build_suite(scenes_per_kind, seed=seed)
    else:  # drawn afresh, reporting; not kept
        cases = rules.draw_suite(scenes_per_kind, seed=seed, report=report_scenes)
    suite = rules.evaluate(rotation_averaged(model.function, rotations), cases)
    report = {
        "run": str(run),
        "step": step,
        "scenes_per_kind": scenes_per_kind,
        "seed": seed,
        "rotations": rotations,
        "pass_fraction": rules.PASS_FRACTION,
        "bar": rules.RULES_BAR,
        "meets_rules": rules.passes(suite),
        **{k: suite[k] for k in ("cases", "mse", "by_check", "by_rule")},
    }
    out = run / "evaluation" if out is None else pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out / "rules.json", json.dumps(report, indent=1))
    rules.plot(cases, suite, out / "rules.png")
    report["table"] = rules.table(suite)
    report["out"] = str(out)
    return report


def check_model(model, baselines: dict, scenes_per_kind: int = 100, seed: int | None = None) -> dict:
    """A loaded :class:`models.inference.SocialCostModel` against the quality bar (its recipe's
    held-out test set, ``baselines`` the trivial predictors' errors there) and the held-out rule
    suite (``scenes_per_kind`` of each kind from ``seed``, the suite's own by default): what
    ``socialnav gscl export`` writes into ``model.json`` and the shipped model's test re-checks.

    Returns:
      ``{"test_mse", "test_mse_by_family", "meets_quality", "rules_pass_by_check", "meets_rules",
      "rules_scenes_per_kind", "rules_seed"}``.
    """
    _, _, mse, by_family = _test_errors(model.config, *model.weights)
    seed = rules.SUITE_SEED if seed is None else seed
    suite = rules.evaluate(model.function, rules.build_suite(scenes_per_kind, seed=seed))
    return {
        "test_mse": float(mse.mean()),
        "test_mse_by_family": by_family,
        "meets_quality": meets_quality(float(mse.mean()), by_family, baselines),
        "rules_pass_by_check": {k: v["pass_share"] for k, v in suite["by_check"].items()},
        "meets_rules": rules.passes(suite),
        "rules_scenes_per_kind": scenes_per_kind,
        "rules_seed": seed,
    }


def exported_model(run, step: int | None = None, scenes_per_kind: int = 100, seed: int | None = None,
                   log=print) -> tuple:  # fmt: skip
    """A run's model (the latest checkpoint by default) with its card, ready for
    :meth:`models.inference.SocialCostModel.export` (``model.export(folder, card)``): the card says
    how it was made (the step, the parameters, the model it started from where it was warm-started:
    the run's :data:`models.warm_start.SOURCE_FILE`, the hosts it trained on) and what it reaches
    (:func:`check_model`, ``scenes_per_kind`` and ``seed`` its rule suite's).

    Returns:
      ``(model, card)``: the :class:`models.inference.SocialCostModel` and the card (a dict).

    Raises:
      FileNotFoundError, ValueError: no run, no checkpoint, none restorable, or the run's source
        record is not JSON (the file named).
    """
    import datetime

    import jax

    from socialnav.common import __version__
    from socialnav.common.machine import hosts_of
    from socialnav.models import steps, unet
    from socialnav.models.inference import SocialCostModel
    from socialnav.models.warm_start import SOURCE_FILE

    run = pathlib.Path(run)
    config, graphdef, state, meta = restore(run, step)
    source = {}
    if (run / SOURCE_FILE).is_file():
        try:
            source = {"init_from": json.loads((run / SOURCE_FILE).read_text(encoding="utf-8"))}
        except (UnicodeDecodeError, json.JSONDecodeError) as e:
            raise ValueError(f"{run / SOURCE_FILE}: not valid JSON ({e})") from None
    model = SocialCostModel(graphdef, state["params"], state["batch_stats"], config)
    log(f"checking step {int(meta['step'])} against the quality bar and the rule suite ...")
    checks = check_model(model, meta["baselines"], scenes_per_kind=scenes_per_kind, seed=seed)
    card = {
        "made_by": "socialnav gscl train --out RUN (the recipe in config.json"
        + (", started from the model in init_from" if config.init_from else "")
        + "), then socialnav gscl export --run RUN",
        "run": run.name,
        "step": int(meta["step"]),
        "epoch": int(meta["step"]) // config.steps_per_epoch,
        "parameters": unet.parameter_count(steps.abstract_model(config)),  # shapes only: nothing drawn
        "baselines": meta["baselines"],
        **checks,
        **source,
        "trained_on": hosts_of(meta["history"]),
        "exported": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "socialnav_version": __version__,
        "jax_version": jax.__version__,
    }
    return model, card
