"""The quality bar of GSCL training: the trivial predictors and the comparison with them.

A model meets the bar when its test MSE is at most the paper's 0.0033 and, in every family, at
most a tenth of the better of two trivial predictors (all zeros; the mean training map).
"""

from __future__ import annotations

import numpy as np

PAPER_TEST_MSE = 0.0033


TRIVIAL_RATIO = 0.1  # the model's test MSE must be at most a tenth of the better trivial predictor's


def by_family(values: np.ndarray, family: np.ndarray, names) -> dict[str, float]:
    """Mean of ``values`` per family name."""
    return {str(name): float(values[family == i].mean()) for i, name in enumerate(names) if np.any(family == i)}


def trivial_baselines(train: dict, test: dict) -> dict[str, dict]:
    """Test MSE (overall and per family) of predicting all zeros and of the mean training map."""
    mean_map = train["targets"].mean(axis=0)
    result = {}
    for name, pred in (("zeros", np.zeros_like(mean_map)), ("mean_map", mean_map)):
        mse = np.mean((test["targets"] - pred) ** 2, axis=(1, 2))
        result[name] = {"test_mse": float(mse.mean()), "by_family": by_family(mse, test["family"], test["names"])}
    return result


def meets_quality(
    test_mse: float,
    test_by_family: dict[str, float],
    baselines: dict[str, dict],
    target_mse: float = PAPER_TEST_MSE,
    ratio: float = TRIVIAL_RATIO,
) -> bool:
    """The issue's bar: overall test MSE <= ``target_mse`` and, in every family, at most ``ratio``
    times the better trivial predictor's MSE."""
    if not test_mse <= target_mse:
        return False
    for name, mse in test_by_family.items():
        best = min(b["by_family"][name] for b in baselines.values())
        if not mse <= ratio * best:
            return False
    return True


def quality_table(test_mse: float, test_by_family: dict[str, float], baselines: dict) -> str:
    """A text table: model vs the two trivial predictors per family, and the ratio to the better."""
    rows = [f"{'family':<18}{'model':>10}{'zeros':>10}{'mean map':>10}{'ratio':>8}"]
    for name, mse in test_by_family.items():
        z, m = baselines["zeros"]["by_family"][name], baselines["mean_map"]["by_family"][name]
        rows.append(f"{name:<18}{mse:>10.5f}{z:>10.5f}{m:>10.5f}{mse / min(z, m):>8.3f}")
    z, m = baselines["zeros"]["test_mse"], baselines["mean_map"]["test_mse"]
    rows.append(f"{'all':<18}{test_mse:>10.5f}{z:>10.5f}{m:>10.5f}{test_mse / min(z, m):>8.3f}")
    return "\n".join(rows)
