"""evaluation: protocols, metrics, statistics, reports and plots.

Seed 000's experiment as a protocol around the simulator's step (:mod:`evaluation.protocol`),
its orchestration and report (:mod:`evaluation.warehouse`), the metrics every protocol shares
(:mod:`evaluation.metrics`: Hall's zones, collisions once per encounter), the statistical tests
(:mod:`evaluation.statistics`), outcome codes and names (:mod:`evaluation.outcomes`) and the
figures (:mod:`evaluation.plots`). The social-navigation benchmark joins here.
"""
