"""The causal inference engine: discretisation, a two-time-slice Bayesian network on the
discovered structure, maximum likelihood parameters, and the do-queries of seed 000 Eq. 4-7.

* Bins: quantile edges for V, L and D with atoms (e.g. exactly top speed) in bins of their
  own, their number chosen by :func:`elbow_bins` (pyAgrum's own elbow option is broken in
  3.3.1). The expectation of a binned variable uses the mean of
  the data inside each bin, not the interval mid-point.
* Network: nodes ``X0`` (previous sample) and ``Xt`` (current) for every variable, the
  convention of ``pyagrum.lib.dynamicBN``. A discovered link ``X -> Y`` at lag 0 becomes
  ``Xt -> Yt`` and ``X0 -> Y0``; at lag 1 ``X0 -> Yt``. Contexts carry over (``W0 -> Wt`` ...),
  since J-PCMCI+ never reports context-context links. An unoriented same-time link is oriented
  in the order V, L, D (a choice, written into the report), unless that order closes a directed
  cycle with the oriented same-time links (V -> L and D -> V found with L - D, say), in which
  case it takes the other direction; a same-time link that closes a cycle either way is dropped
  (J-PCMCI+ reports such conflicts as 'x-x').
* Parameters: MLE with a negligible smoothing prior (1e-6) so unseen parent combinations do
  not stop the learner.
* Queries: ``E[L | do(V = v), C = c]`` (truncated factorisation, sustained over both slices,
  over the parent configurations of L seen in the data: :meth:`CausalEngine.battery_do`) and
  ``E[D | do(S = s), W = w]`` as a sustained intervention on S0 and St knowing W0 and Wt (a do
  on St alone is biased by D0).
"""

from __future__ import annotations

import dataclasses
import errno
import json
import pathlib
import shutil
import tempfile

import numpy as np
import pandas as pd

from socialnav.causal.binning import Binning
from socialnav.causal.discover import Discovery
from socialnav.causal.extract import Datasets
from socialnav.causal.variables import CONTEXTS, VARIABLES
from socialnav.common.atomic import write_atomic, write_text_atomic

CONTINUOUS = ("V", "L", "D")
SMOOTHING = 1e-6
BN_FILE = "engine.bifxml"
META_FILE = "engine.json"
TABLES_FILE = "engine_tables.npz"


def discretized_variable(name: str, binning: Binning):
    """A pyAgrum variable on ``binning``'s edges; values outside them fall in the end bins."""
    import pyagrum as gum

    var = gum.DiscretizedVariable(name, name, [float(e) for e in binning.edges])
    var.setEmpirical(True)
    return var


@dataclasses.dataclass(frozen=True)
class BatteryDo:
    """E[L | do(V = v), C = c] per period, and the probability of L's parent configurations
    (under the intervention) that the data cover."""

    value: float
    seen_share: float


def _tensor_array(tensor, order) -> np.ndarray:
    """A pyAgrum tensor as a float64 array whose first axes are the nodes ``order`` names, in
    that order (``tolist()`` gives the axes in the reverse order of ``tensor.names``)."""
    names = list(tensor.names)[::-1]
    arr = np.asarray(tensor.tolist(), np.float64)
    return np.moveaxis(arr, [names.index(n) for n in order], list(range(len(order))))


def _state_index(column: pd.Series, variable, binning: Binning | None) -> np.ndarray:
    """The state index of every value of a learning-table column in its pyAgrum variable."""
    if binning is not None:
        return binning.index(column.to_numpy(np.float64))
    labels = {variable.label(i): i for i in range(variable.domainSize())}
    return np.array([labels[str(v)] for v in column.to_numpy()], np.int64)


def _distinct_rows(bn, data: pd.DataFrame) -> tuple[pd.DataFrame, np.ndarray]:
    """``data`` as its distinct rows after discretisation, and how often each occurs.

    A continuous column (a :func:`discretized_variable` of ``bn``) becomes its bin's label, the bin
    found as pyAgrum finds it (``[a; b[``, values beyond the ends in the end bins); a missing
    value stays missing; every other column is kept as it is (a value the variable does not have
    is refused by pyAgrum, as before)."""
    import pyagrum as gum

    keys, labels = {}, {}
    for col in data.columns:
        var = bn.variable(col)
        if var.varType() == gum.VarType_DISCRETIZED:
            x = data[col].to_numpy(np.float64)
            ticks = np.asarray(var.ticks(), np.float64)
            index = np.clip(np.searchsorted(ticks, x, side="right") - 1, 0, len(ticks) - 2)
            keys[col] = np.where(np.isnan(x), -1, index)  # -1: the label list's last entry, None (missing)
            labels[col] = np.array([var.label(i) for i in range(var.domainSize())] + [None], dtype=object)
        else:
            keys[col] = data[col].to_numpy()
    counts = pd.DataFrame(keys).value_counts(sort=False, dropna=False).reset_index(name="count")
    distinct = pd.DataFrame(
        {col: labels[col][counts[col].to_numpy()] if col in labels else counts[col] for col in data.columns}
    )
    return distinct, counts["count"].to_numpy()


def learn_mle(bn, data: pd.DataFrame):
    """Maximum likelihood parameters on ``bn``'s structure, with the negligible smoothing prior
    that keeps unseen parent combinations from stopping the learner (notes: keep the learner in
    a variable, chaining its calls segfaulted).

    pyAgrum's learner reads its data from a CSV file; the learner is given each distinct
    discretised row once, weighted by how often it occurs (``setRecordWeight``): the same counts,
    so the same tables bit for bit (tested), without writing and parsing every row (a simulated
    day has millions). The file is written here, in a temporary folder removed once the learner
    has read it: given a DataFrame, pyAgrum writes two files to the system's temporary folder and
    never removes them (pyAgrum 3.3), which a sweep of thousands of runs would pile up."""
    import pyagrum as gum

    distinct, weights = _distinct_rows(bn, data)
    with tempfile.TemporaryDirectory(prefix="socialnav-mle-") as folder:
        csv = pathlib.Path(folder) / "rows.csv"
        try:
            distinct.to_csv(csv, na_rep="?", index=False)  # what pyAgrum's own DataFrame path writes
        except OSError as e:  # pandas names no file: a full temporary folder would be a mystery
            reason = f"{e.strerror or e} (the rows pyAgrum's learner reads, in the temporary folder: TMPDIR chooses it)"
            raise OSError(e.errno, reason, str(csv)) from e
        learner = gum.BNLearner(str(csv), bn)
    for i, weight in enumerate(weights):
        learner.setRecordWeight(i, float(weight))
    learner.useSmoothingPrior(SMOOTHING)
    return learner.learnParameters(bn.dag())


def _reaches(edges: set[tuple[str, str]], start: str, goal: str) -> bool:
    """Whether a directed path leads from ``start`` to ``goal`` over ``edges``."""
    todo, seen = [start], {start}
    while todo:
        here = todo.pop()
        if here == goal:
            return True
        for a, b in edges:
            if a == here and b not in seen:
                seen.add(b)
                todo.append(b)
    return False


def same_time_order(discovery: Discovery) -> set[tuple[str, str]]:
    """The directed same-time links, acyclic: oriented links first, then the unoriented ones in
    the order V, L, D where that keeps the graph acyclic, else reversed, else dropped."""
    order = {v: i for i, v in enumerate(VARIABLES)}
    same = [k for k in discovery.links if k.lag == 0]
    edges: set[tuple[str, str]] = set()
    for k in sorted(same, key=lambda k: not k.oriented):  # oriented links take precedence
        cause, effect = k.cause, k.effect
        if not k.oriented and order[cause] > order[effect]:
            cause, effect = effect, cause
        candidates = [(cause, effect)] if k.oriented else [(cause, effect), (effect, cause)]
        for a, b in candidates:
            if not _reaches(edges, b, a):
                edges.add((a, b))
                break
    return edges


def dag_arcs(discovery: Discovery) -> list[tuple[str, str]]:
    """Arcs of the two-slice network from the discovered links (see the module docstring)."""
    arcs = set()
    for cause, effect in same_time_order(discovery):
        arcs.add((f"{cause}t", f"{effect}t"))
        arcs.add((f"{cause}0", f"{effect}0"))
    for k in discovery.links:
        if k.lag == 1:
            arcs.add((f"{k.cause}0", f"{k.effect}t"))
    for c in CONTEXTS:
        arcs.add((f"{c}0", f"{c}t"))
    return sorted(arcs)


@dataclasses.dataclass
class CausalEngine:
    """A learned two-slice network plus what is needed to read expectations off it.

    Attributes:
      bn: the pyAgrum BayesNet.
      bins: {"V" | "L" | "D": Binning}.
      labels: {context: list of state labels} (W labels are waypoint names).
      period_s: sampling period of the data (L is a change per period).
      arcs: the network's arcs.
      support_vc: (V bins, 2) samples seen with each speed bin and charging state.
      support_sw: (S, W labels) samples seen in each slot at each learned waypoint.
      do_support: the rows of Lt's table (its parents' configurations) seen in the data, for
        the positivity of E[L | do(V), C] (:meth:`battery_do`): ``{"axes": Lt's parents,
        "cells": flat indices}``; None for an engine saved before it existed.
    """

    bn: object
    bins: dict[str, Binning]
    labels: dict[str, list[str]]
    period_s: float
    arcs: list[tuple[str, str]]
    support_vc: np.ndarray
    support_sw: np.ndarray
    do_support: dict | None = None

    @classmethod
    def fit(
        cls, datasets: Datasets, discovery: Discovery, n_slots: int, bins: dict[str, int] | None = None
    ) -> CausalEngine:
        """Discretise the datasets and learn the network's parameters by MLE."""
        import pyagrum as gum

        rows = []
        for arr in datasets.data.values():
            prev, cur = arr[:-1], arr[1:]
            frame = {}
            for j, v in enumerate(VARIABLES):
                frame[f"{v}0"], frame[f"{v}t"] = prev[:, j], cur[:, j]
            rows.append(pd.DataFrame(frame))
        table = pd.concat(rows, ignore_index=True)
        first_wp = datasets.waypoints[min(datasets.data)]  # robot series repeat in every waypoint's dataset
        robot = np.concatenate([a for k, a in datasets.data.items() if datasets.waypoints[k] == first_wp])
        binning = {
            "V": Binning.fit(robot[:, VARIABLES.index("V")], (bins or {}).get("V")),
            "L": Binning.fit(robot[:, VARIABLES.index("L")], (bins or {}).get("L")),
            "D": Binning.fit(table["Dt"].to_numpy(), (bins or {}).get("D")),
        }
        w_codes = sorted({int(a[0, VARIABLES.index("W")]) for a in datasets.data.values()})
        code_to_name = {int(datasets.data[k][0, VARIABLES.index("W")]): datasets.waypoints[k] for k in datasets.data}
        labels = {
            "W": [code_to_name[c] for c in w_codes],
            "S": [str(s) for s in range(n_slots)],
            "C": ["0", "1"],
            "O": ["0", "1"],
        }

        bn = gum.BayesNet("causal_engine")
        for slice_ in ("0", "t"):
            for v in VARIABLES:
                name = f"{v}{slice_}"
                bn.add(
                    discretized_variable(name, binning[v])
                    if v in CONTINUOUS
                    else gum.LabelizedVariable(name, name, labels[v])
                )
        arcs = dag_arcs(discovery)
        for a, b in arcs:
            bn.addArc(a, b)
        w_names = np.asarray([code_to_name[c] for c in w_codes], dtype=object)
        data = pd.DataFrame()
        for col in table.columns:
            v = col[:-1]
            if v in CONTINUOUS:
                data[col] = table[col].to_numpy(np.float64)
            elif v == "W":
                data[col] = w_names[np.searchsorted(w_codes, table[col].to_numpy().astype(int))]
            else:
                data[col] = table[col].to_numpy().astype(int).astype(str)
        learned = learn_mle(bn, data)
        n_v = len(binning["V"].means)
        support_vc = np.zeros((n_v, 2), np.int64)
        np.add.at(
            support_vc,
            (binning["V"].index(robot[:, VARIABLES.index("V")]), robot[:, VARIABLES.index("C")].astype(int)),
            1,
        )
        support_sw = np.zeros((n_slots, len(w_codes)), np.int64)
        np.add.at(
            support_sw,
            (table["St"].to_numpy().astype(int), np.searchsorted(w_codes, table["Wt"].to_numpy().astype(int))),
            1,
        )
        axes = sorted(learned.variable(p).name() for p in learned.parents("Lt"))
        states = [_state_index(data[n], learned.variable(n), binning.get(n[:-1])) for n in axes]
        flat = np.ravel_multi_index(states, [learned.variable(n).domainSize() for n in axes]) if axes else [0]
        do_support = {"axes": axes, "cells": np.unique(flat).tolist()}
        return cls(learned, binning, labels, datasets.period_s, arcs, support_vc, support_sw, do_support)

    # -- queries ---------------------------------------------------------------------------
    def _expect(self, tensor, var: str) -> float:
        p = np.asarray(tensor.tolist(), np.float64).ravel()
        return float(np.dot(p / p.sum(), self.bins[var].means))

    def _label(self, node: str, index: int) -> str:
        return self.bn.variable(node).label(int(index))

    def expected_battery_do(self, speed_bin: int, charging: int) -> float:
        """E[L | do(V = v), C = c] per sampling period (Eq. 5-6): :meth:`battery_do`'s sustained
        intervention over the data's support; where its joint would not fit in memory, pyAgrum's
        one-step ``causalImpact`` over every configuration (:meth:`expected_battery_do_pyagrum`)."""
        try:
            return self.battery_do(speed_bin, charging).value
        except MemoryError:
            return self.expected_battery_do_pyagrum(speed_bin, charging)

    def expected_battery_do_pyagrum(self, speed_bin: int, charging: int) -> float:
        """E[L | do(V = v), C = c] as pyAgrum's ``causalImpact`` identifies it (backdoor over O),
        over every parent configuration, seen or not.

        Where ``v`` was never seen with some parent configuration ``z`` (positivity violated:
        an obstacle always slows the robot below top speed, so top speed never meets O = 1),
        L's table row for ``(v, z)`` is the smoothing prior's uniform distribution, and the
        adjustment still weights it by ``P(z | c)``; :meth:`battery_do` leaves those out.
        On some learned graphs (density links into V and L, whose parents include the 69-state
        W) the formula does not fit in memory (``std::bad_alloc``) and the parent adjustment
        without the support restriction is computed instead.
        """
        import pyagrum as gum

        cm = gum.CausalModel(self.bn)
        try:
            _, tensor, _ = gum.causalImpact(
                cm,
                on="Lt",
                doing="Vt",
                knowing={"Ct"},
                values={"Vt": self._label("Vt", speed_bin), "Ct": str(charging)},
            )
        except (MemoryError, Exception) as e:  # pyAgrum raises a bare Exception("std::bad_alloc")
            if "bad_alloc" not in str(e) and not isinstance(e, MemoryError):
                raise
            return self.battery_do(speed_bin, charging, sustained=False, seen_only=False).value
        return self._expect(tensor, "L")

    def battery_do(
        self,
        speed_bin: int,
        charging: int,
        *,
        sustained: bool = True,
        seen_only: bool = True,
        obstacle: int | None = None,
        max_cells: int = 20_000_000,
    ) -> BatteryDo:
        """E[L | do(V = v), C = c] per period by the truncated factorisation of the network: the
        arcs into the intervened speed nodes are cut, they are set to ``v``, and E[Lt] is read
        from the joint posterior of Lt and its parents given ``C = c``.

        ``sustained`` (the default) intervenes on both slices, do(V0 = v, Vt = v): the robot
        *travels* at ``v`` (the planner's arc, the simulator's forced speed), as the engine's
        density query holds S in both slices. ``sustained=False`` is the one-step do(Vt = v)
        of seed 000 Eq. 5, where V0 keeps its observed distribution; on the warehouse at a 1 s
        period, L over the last second then still carries the previous second's speed (a robot
        braking to a stop), and "do(V = 0)" drains more than standing does.

        ``seen_only`` (the default) keeps the sum to the parent configurations of Lt seen in the
        data the engine learnt from (:attr:`do_support`), their probability renormalised: L's
        row for an unseen configuration (top speed with an obstacle: an obstacle always slows
        the robot) is learnt from nothing (the smoothing prior makes it the mean of L's bins),
        and no estimator can identify it from these data (positivity). The answer is then the
        effect where the data speak; :attr:`BatteryDo.seen_share` is the probability they cover.

        ``obstacle`` also conditions on O (in the intervened slices): the engine takes O as an
        exogenous context, so its do(V = v) keeps O's observed distribution, while in the
        simulator the robot meets obstacles by driving (``causal/simulator_graph.py``: V -> O).

        Raises:
          MemoryError: the joint over Lt and its free parents has more than ``max_cells`` cells.
        """
        import pyagrum as gum

        treated = ["V0", "Vt"] if sustained else ["Vt"]
        bn = gum.BayesNet(self.bn)
        for node in treated:
            for parent in list(bn.parents(node)):
                bn.eraseArc(parent, bn.idFromName(node))
            bn.cpt(node).fillWith(1.0).normalizeAsCPT()
        evidence = {node: self._label(node, speed_bin) for node in treated} | {"Ct": str(charging)}
        if obstacle is not None:
            evidence |= {f"O{node[1]}": str(obstacle) for node in treated}
        parents = sorted(self.bn.variable(p).name() for p in self.bn.parents("Lt"))
        free = [n for n in parents if n not in evidence]
        target = ["Lt", *free]
        cells = int(np.prod([self.bn.variable(n).domainSize() for n in target]))
        if cells > max_cells:
            raise MemoryError(f"E[L | do(V), C]: the joint over {target} has {cells} cells (more than {max_cells})")
        ie = gum.LazyPropagation(bn)
        if free:
            ie.addJointTarget(set(target))
        ie.setEvidence(evidence)
        ie.makeInference()
        tensor = ie.jointPosterior(set(target)) if free else ie.posterior("Lt")
        arr = _tensor_array(tensor, target)
        arr = (arr / arr.sum()).reshape(arr.shape[0], -1)  # (L, free parent configurations)
        p_parents = arr.sum(axis=0)
        weight = p_parents
        if seen_only and self.do_support is not None:
            weight = p_parents * self._seen_rows(evidence, free).ravel()
        share = float(weight.sum() / p_parents.sum())
        if share <= 0:
            return BatteryDo(float("nan"), 0.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            p_l_given = np.where(p_parents > 0, arr / p_parents, 0.0)  # L's rows at the given parents
        p_l = p_l_given @ weight
        return BatteryDo(float(np.dot(p_l / p_l.sum(), self.bins["L"].means)), share)

    def _seen_rows(self, evidence: dict[str, str], free: list[str]) -> np.ndarray:
        """(free parents...) bool: Lt's parent configurations seen in the data, the parents in
        ``evidence`` at their given labels."""
        axes = self.do_support["axes"]
        if set(axes) != {self.bn.variable(p).name() for p in self.bn.parents("Lt")}:
            raise ValueError(f"the engine's do_support runs over {axes}, not Lt's parents")
        shape = [self.bn.variable(n).domainSize() for n in axes]
        seen = np.zeros(int(np.prod(shape)), bool)
        seen[np.asarray(self.do_support["cells"], np.int64)] = True
        seen = seen.reshape(shape)
        index = tuple(self.bn.variable(n).index(evidence[n]) if n in evidence else slice(None) for n in axes)
        seen = seen[index]
        kept = [n for n in axes if n not in evidence]
        return np.transpose(seen, [kept.index(n) for n in free]) if free else seen

    def obstacle_share(self, charging: int) -> float:
        """P(Ot = 1 | Ct = c): how often the data's robot has an obstacle, whatever its speed."""
        import pyagrum as gum

        ie = gum.LazyPropagation(self.bn)
        ie.setEvidence({"Ct": str(charging)})
        ie.makeInference()
        p = np.asarray(ie.posterior("Ot").tolist(), np.float64)
        return float(p[1] / p.sum())

    def expected_battery_given(self, speed_bin: int, evidence: dict[str, int] | None = None) -> float:
        """E[L | V = v, ...] by plain conditioning (the Bayesian estimate of seed 000 Eq. 11)."""
        import pyagrum as gum

        ie = gum.LazyPropagation(self.bn)
        ev = {"Vt": int(speed_bin)}
        ev.update({f"{k}t": int(v) for k, v in (evidence or {}).items()})
        ie.setEvidence(ev)
        ie.makeInference()
        return self._expect(ie.posterior("Lt"), "L")

    def expected_density_do(self, slot: int, waypoint: str) -> float:
        """E[D | do(S = s), W = w] (Eq. 7), sustained over both slices."""
        import pyagrum as gum

        cm = gum.CausalModel(self.bn)
        s = str(slot)
        _, tensor, _ = gum.causalImpact(
            cm,
            on="Dt",
            doing={"S0", "St"},
            knowing={"W0", "Wt"},
            values={"S0": s, "St": s, "W0": waypoint, "Wt": waypoint},
        )
        return self._expect(tensor, "D")

    def _slot_is_exogenous(self) -> bool:
        """S0 has no parents and St only S0: then do(S0 = s, St = s) is plain conditioning."""
        parents = lambda n: {self.bn.variable(p).name() for p in self.bn.parents(n)}
        return not parents("S0") and parents("St") <= {"S0"}

    def expected_density_do_all(self, slot: int) -> np.ndarray:
        """E[D | do(S = s), W = w] for every learned waypoint at once.

        When S is exogenous in the learned graph (:meth:`_slot_is_exogenous`, the backdoor
        criterion holds with an empty set) the intervention is read from one joint posterior
        P(Dt, W0, Wt | S0 = s, St = s) by junction-tree inference; otherwise from one
        ``causalImpact`` call with W left free. Both give :meth:`expected_density_do`'s answers
        (the test checks it); the first is ~100x faster on the warehouse's 69-state W.
        """
        import pyagrum as gum

        s = str(slot)
        if self._slot_is_exogenous():
            ie = gum.LazyPropagation(self.bn)
            ie.addJointTarget({"Dt", "W0", "Wt"})
            ie.setEvidence({"S0": s, "St": s})
            ie.makeInference()
            tensor = ie.jointPosterior({"Dt", "W0", "Wt"})
        else:
            cm = gum.CausalModel(self.bn)
            _, tensor, _ = gum.causalImpact(
                cm, on="Dt", doing={"S0", "St"}, knowing={"W0", "Wt"}, values={"S0": s, "St": s}
            )
        arr = _tensor_array(tensor, ("W0", "Wt", "Dt"))
        n_w = arr.shape[0]
        p = arr[np.arange(n_w), np.arange(n_w)]  # W0 = Wt = w: (W, D bins)
        p = p / p.sum(axis=1, keepdims=True)
        return p @ self.bins["D"].means

    def tables(self, all_waypoints: list[str], progress: bool = False) -> dict[str, np.ndarray]:
        """The answers as plain arrays a JAX planner can take without pyAgrum.

        Cells whose conditioning combination never occurs in the data (a fast robot while
        charging, a slot/waypoint pair never sampled) are NaN rather than the smoothing prior.

        Returns:
          density_ppm2: (S, len(all_waypoints)) E[D | do(S), W]; NaN for waypoints not learned.
          battery_pct_per_s: (V bins, 2) E[L | do(V), C] divided by the sampling period.
          speed_mps: (V bins,) mean speed in each bin; speed_edges_mps: (V bins + 1,).
        """
        from socialnav.common import progress as progress_lib

        n_s = len(self.labels["S"])
        density = np.full((n_s, len(all_waypoints)), np.nan)
        learned = set(self.labels["W"])
        col = {w: j for j, w in enumerate(self.labels["W"])}
        for s in progress_lib.iterate(range(n_s), "E[D | do(S), W]", progress):
            per_waypoint = self.expected_density_do_all(s)
            for i, w in enumerate(all_waypoints):
                if w in learned and self.support_sw[s, col[w]] > 0:
                    density[s, i] = per_waypoint[col[w]]
        n_v = len(self.bins["V"].means)
        battery = (
            np.array(
                [
                    [self.expected_battery_do(v, c) if self.support_vc[v, c] else np.nan for c in (0, 1)]
                    for v in range(n_v)
                ]
            )
            / self.period_s
        )
        return {
            "density_ppm2": density,
            "battery_pct_per_s": battery,
            "speed_mps": self.bins["V"].means,
            "speed_edges_mps": self.bins["V"].edges,
        }

    # -- persistence -----------------------------------------------------------------------
    def save(self, folder: str | pathlib.Path) -> pathlib.Path:
        """Write ``engine.bifxml`` (the network) and ``engine.json`` (bins, labels, period)."""
        folder = pathlib.Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        write_atomic(folder / BN_FILE, lambda tmp: _save_bn(self.bn, tmp))
        meta = {
            "period_s": self.period_s,
            "labels": self.labels,
            "arcs": self.arcs,
            "support_vc": self.support_vc.tolist(),
            "support_sw": self.support_sw.tolist(),
            "do_support": self.do_support,
            "bins": {k: {"edges": b.edges.tolist(), "means": b.means.tolist()} for k, b in self.bins.items()},
        }
        write_text_atomic(folder / META_FILE, json.dumps(meta, indent=1))
        return folder

    @classmethod
    def load(cls, folder: str | pathlib.Path) -> CausalEngine:
        import pyagrum as gum

        folder = pathlib.Path(folder)
        meta = json.loads((folder / META_FILE).read_text())
        bn = gum.loadBN(str(folder / BN_FILE))
        bins = {k: Binning(np.asarray(v["edges"]), np.asarray(v["means"])) for k, v in meta["bins"].items()}
        return cls(
            bn,
            bins,
            meta["labels"],
            meta["period_s"],
            [tuple(a) for a in meta["arcs"]],
            np.asarray(meta["support_vc"]),
            np.asarray(meta["support_sw"]),
            meta.get("do_support"),
        )


def _save_bn(bn, path: pathlib.Path) -> None:
    """``gum.saveBN(bn, path)``, its failure as an ``OSError``: pyAgrum's C++ stream says only that
    "writing in the ostream failed", with no errno, so the error says how much room was left
    there (a full disk, the usual cause, shows as 0 MB) and a command reports it in one line
    naming the file (:func:`common.atomic.naming` puts the final name on it)."""
    import pyagrum as gum

    try:
        gum.saveBN(bn, str(path))
    except gum.GumIOError as e:
        free_mb = shutil.disk_usage(path.parent).free / 1e6
        code = errno.ENOSPC if free_mb < 1 else errno.EIO
        raise OSError(code, f"pyAgrum could not write it ({e}); {free_mb:.1f} MB free there") from e
