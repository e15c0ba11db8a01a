"""Task outcome codes of seed 000's protocol and their names: the one home of both.

The protocol (:mod:`evaluation.protocol`) writes the codes into its JAX task log; the tables
and metrics (:mod:`evaluation.warehouse`, :mod:`evaluation.metrics`) use the names.
"""

from __future__ import annotations

NOT_RUN, SUCCESS, CONGESTION, BATTERY = -1, 0, 1, 2
OUTCOME_NAMES = {SUCCESS: "success", CONGESTION: "congestion", BATTERY: "battery"}
# Names in code order: the categories of the task table's ``outcome`` column.
OUTCOMES = tuple(OUTCOME_NAMES[code] for code in sorted(OUTCOME_NAMES))
