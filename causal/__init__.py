"""causal: simulator logs -> variables -> J-PCMCI+ -> two-slice Bayesian network -> do() tables.

:mod:`causal.extract` (logs through :mod:`common.logschema` to datasets), :mod:`causal.discover`
(J-PCMCI+), :mod:`causal.binning` and :mod:`causal.engine` (the network and its queries),
:mod:`causal.learn` (the job), :mod:`causal.ablation` (seed 000 Sec. 6 from given series),
:mod:`causal.plots`. Imports none of the toolkit's other parts: the tables it writes
(``engine_tables.npz``) are read by the planners through their own reader.
"""
