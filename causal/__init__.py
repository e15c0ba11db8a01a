"""socialnav.causal: simulator logs -> variables -> J-PCMCI+ -> two-slice Bayesian network -> do() tables.

:mod:`~socialnav.causal.extract` (logs through :mod:`socialnav.common.logschema` to datasets),
:mod:`~socialnav.causal.discover` (J-PCMCI+), :mod:`~socialnav.causal.binning` and
:mod:`~socialnav.causal.engine` (the network and its queries), :mod:`~socialnav.causal.learn` (the
job), :mod:`~socialnav.causal.ablation` (seed 000 Sec. 6), :mod:`~socialnav.causal.simulator_graph`
(the simulator's own causal graph, the referee of discovery) and :mod:`~socialnav.causal.plots`.
Imports none of the toolkit's other parts: the tables it writes (``engine_tables.npz``) are read by
the planners through their own reader.

Re-exported here: discovery, its score and the engine (the job is ``socialnav.causal.learn.learn``).
"""

from socialnav.causal.discover import Discovery, Link, run_jpcmciplus, score
from socialnav.causal.engine import CausalEngine

__all__ = ["CausalEngine", "Discovery", "Link", "run_jpcmciplus", "score"]
