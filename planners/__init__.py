"""planners: waypoint planners of seed 000 (shortest path, causal A* with the abort decision).

Grid planners and social cost layers (seeds 001, 002, 004) join in later issues.
"""
