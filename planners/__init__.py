"""planners: planning alone.

Seed 000's waypoint planners: route tables (:mod:`planners.routes`: shortest path and any arc
costs, one function), the causal costs, A* and the abort decision (:mod:`planners.waypoint`,
Eq. 8-10), and the typed reader of the causal engine's tables (:mod:`planners.tables`). Cost
layers, grid and local planners (seeds 001, 002, 004) join here in later issues.
"""
