"""socialnav.planners.warehouse: seed 000's waypoint planners on the warehouse's graph.

Route tables (:mod:`~socialnav.planners.warehouse.routes`: shortest path and any arc costs), the
causal costs, A* and the abort decision (:mod:`~socialnav.planners.warehouse.waypoint`, Eq. 8-10),
the typed reader of the causal engine's tables (:mod:`~socialnav.planners.warehouse.tables`) and
the causal planner as a warehouse actor (:mod:`~socialnav.planners.warehouse.actors`).
"""

from socialnav.planners.warehouse.actors import CausalParams, causal_planner_actor
from socialnav.planners.warehouse.routes import plan_from_costs, route_table, shortest_path_plan
from socialnav.planners.warehouse.tables import CausalTables, TablesError
from socialnav.planners.warehouse.waypoint import CausalWeights, astar, causal_plan

__all__ = [
    "CausalParams",
    "CausalTables",
    "CausalWeights",
    "TablesError",
    "astar",
    "causal_plan",
    "causal_planner_actor",
    "plan_from_costs",
    "route_table",
    "shortest_path_plan",
]
