"""The GSCL model the package ships (``data/gscl/default``): what its card says, measured again.

In a file of its own (about two minutes: the card's held-out test set regenerated and the rule
suite at the card's size), so that a test session on two workers runs it beside the rest of the
GSCL tests rather than after them.
"""

from __future__ import annotations

import json

import pytest

from socialnav.models import checkpoints, evaluation, inference, quality


@pytest.mark.slow
def test_the_shipped_model_meets_the_quality_bar_and_the_rule_suite_as_its_card_says():
    """The model the package ships (data/gscl/default, what 'gscl' runs without --gscl-run):
    measured again here on its recipe's held-out test set and the held-out rule suite."""
    model = inference.SocialCostModel.load()
    card = json.loads((inference.DEFAULT_MODEL / inference.CARD_FILE).read_text())
    checks = evaluation.check_model(model, card["baselines"], card["rules_scenes_per_kind"], card["rules_seed"])
    assert checks["meets_quality"] and checks["test_mse"] <= quality.PAPER_TEST_MSE
    assert checks["meets_rules"], min(checks["rules_pass_by_check"].values())
    assert checks["test_mse"] == pytest.approx(card["test_mse"], rel=1e-3)
    assert model.config == checkpoints.load_config(inference.DEFAULT_MODEL)
