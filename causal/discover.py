"""Causal discovery with J-PCMCI+ (tigramite), the links as a plain table, a picture, a score.

``tigramite`` traps (``shared/notes/causal-stack.md``) handled here: ``pc_alpha`` is always one
float (``None`` or a list silently runs plain PCMCI+ without the contexts); the datasets go in
as ``analysis_mode='multiple'``; a same-time link appears twice in the graph ('-->' one way,
'<--' the other), so only '-->' entries are read, and direction comes from ``graph``, not from
the symmetric ``p_matrix``.
"""

from __future__ import annotations

import dataclasses
import json
import pathlib
import time

import numpy as np

from socialnav.causal.variables import CONTEXTS, GROUND_TRUTH, VARIABLES, node_classification
from socialnav.common.atomic import write_text_atomic

TESTS = ("parcorr", "regression")


@dataclasses.dataclass(frozen=True)
class Link:
    """``cause(t - lag) -> effect(t)``; ``oriented`` False for an unoriented same-time link."""

    cause: str
    effect: str
    lag: int
    strength: float
    p_value: float
    oriented: bool = True

    @property
    def label(self) -> str:
        """``X->Y``, ``X(t-1)->Y``, or ``X-Y`` for an unoriented link."""
        arrow = "->" if self.oriented else "-"
        return f"{self.cause}(t-{self.lag}){arrow}{self.effect}" if self.lag else f"{self.cause}{arrow}{self.effect}"


@dataclasses.dataclass
class Discovery:
    """What J-PCMCI+ found.

    Attributes:
      links: the links, directed ones as cause -> effect.
      test, alpha, tau_max: the settings.
      n_samples: total samples over all datasets; seconds: wall time.
    """

    links: list[Link]
    test: str
    alpha: float
    tau_max: int
    n_samples: int
    seconds: float

    def as_set(self) -> set[tuple[str, str, int]]:
        return {(k.cause, k.effect, k.lag) for k in self.links if k.oriented}

    def save(self, path: str | pathlib.Path) -> pathlib.Path:
        """Write the links and settings as JSON (a plain file any tool reads)."""
        obj = {
            "test": self.test,
            "alpha": self.alpha,
            "tau_max": self.tau_max,
            "n_samples": self.n_samples,
            "seconds": self.seconds,
            "links": [dataclasses.asdict(k) for k in self.links],
        }
        return write_text_atomic(path, json.dumps(obj, indent=1))

    @classmethod
    def load(cls, path: str | pathlib.Path) -> Discovery:
        obj = json.loads(pathlib.Path(path).read_text())
        return cls(
            [Link(**k) for k in obj["links"]],
            obj["test"],
            obj["alpha"],
            obj["tau_max"],
            obj["n_samples"],
            obj["seconds"],
        )


def run_jpcmciplus(
    data: dict[int, np.ndarray], *, names=VARIABLES, test: str = "parcorr", alpha: float = 0.01, tau_max: int = 1
) -> Discovery:
    """J-PCMCI+ over several datasets with the contexts declared as space contexts.

    Args:
      data: {dataset: (T, len(names)) array}.
      test: ``parcorr`` (fast, linear) or ``regression`` (tigramite's RegressionCI for mixed
        continuous / discrete data, as the paper's authors used).
      alpha: the significance level (``pc_alpha``), one float.
    """
    from tigramite import data_processing as pp
    from tigramite.jpcmciplus import JPCMCIplus

    if test not in TESTS:
        raise ValueError(f"test must be one of {TESTS}, got {test!r}")
    if not isinstance(alpha, float) or not 0 < alpha < 1:
        raise ValueError(f"alpha must be one float in (0, 1), got {alpha!r}")
    names = list(names)
    kwargs = {}
    if test == "parcorr":
        from tigramite.independence_tests.parcorr import ParCorr

        ci = ParCorr(significance="analytic")
    else:
        from tigramite.independence_tests.regressionCI import RegressionCI

        ci = RegressionCI(significance="analytic")
        discrete = np.array([n in CONTEXTS for n in names], int)
        kwargs["data_type"] = {k: np.broadcast_to(discrete, v.shape).copy() for k, v in data.items()}
    start = time.perf_counter()
    frame = pp.DataFrame(
        {k: np.asarray(v, np.float64) for k, v in data.items()}, analysis_mode="multiple", var_names=names, **kwargs
    )
    jp = JPCMCIplus(dataframe=frame, cond_ind_test=ci, node_classification=node_classification(names), verbosity=0)
    res = jp.run_jpcmciplus(tau_min=0, tau_max=tau_max, pc_alpha=float(alpha))
    seconds = time.perf_counter() - start
    return Discovery(
        parse_graph(res, names), test, float(alpha), tau_max, int(sum(len(v) for v in data.values())), seconds
    )


def parse_graph(res: dict, names) -> list[Link]:
    """tigramite's result dict -> links (each same-time link once)."""
    graph, val, pval = res["graph"], res["val_matrix"], res["p_matrix"]
    links = []
    n, _, taus = graph.shape
    for tau in range(taus):
        for i in range(n):
            for j in range(n):
                g = graph[i, j, tau]
                if g == "-->":
                    links.append(Link(names[i], names[j], tau, float(val[i, j, tau]), float(pval[i, j, tau])))
                elif g in ("o-o", "x-x") and tau == 0 and i < j:
                    links.append(Link(names[i], names[j], 0, float(val[i, j, 0]), float(pval[i, j, 0]), False))
    return links


def _truth_label(edge: tuple[str, str, int], truth) -> str:
    """``C->E``, ``C(t-k)->E``, or ``A<->B`` for a same-time pair that ``truth`` has both ways."""
    c, e, lag = edge
    if lag:
        return f"{c}(t-{lag})->{e}"
    return f"{min(c, e)}<->{max(c, e)}" if (e, c, 0) in truth else f"{c}->{e}"


def score(links: list[Link], truth=GROUND_TRUTH) -> dict[str, float]:
    """Precision, recall and structural Hamming distance against the known graph.

    A predicted link counts as right when its cause, effect and lag are in ``truth``. SHD adds
    one per missing adjacency, one per extra adjacency and one per adjacency with the wrong or
    no orientation. Recall is over ``truth``'s adjacencies: a same-time pair that causes itself
    both ways (feedback within a sampling period, :func:`causal.simulator_graph.pipeline_truth`)
    is one adjacency, found right in either orientation, and named ``A<->B`` when missing. The
    result does not depend on the order ``truth`` is iterated in (a set's changes with Python's
    hash seed from one process to the next).
    """
    adj = lambda a, b, lag: (frozenset((a, b)), lag) if lag == 0 else ((a, b), lag)
    truth_adj = {}
    for t in sorted(truth):  # sorted: a set's order changes from one process to the next
        truth_adj.setdefault(adj(*t), t)
    found_adj = {}
    for k in links:
        found_adj[adj(k.cause, k.effect, k.lag)] = k
    right = sum(1 for k in links if k.oriented and (k.cause, k.effect, k.lag) in truth)
    missing = [t for a, t in truth_adj.items() if a not in found_adj]
    extra = [k for a, k in found_adj.items() if a not in truth_adj]
    misoriented = [
        k for a, k in found_adj.items() if a in truth_adj and not (k.oriented and (k.cause, k.effect, k.lag) in truth)
    ]
    return {
        "precision": right / max(len(links), 1),
        "recall": right / max(len(truth_adj), 1),
        "shd": len(missing) + len(extra) + len(misoriented),
        "missing": [_truth_label(t, truth) for t in sorted(missing)],
        "extra": [k.label for k in extra],
        "misoriented": [k.label for k in misoriented],
    }
