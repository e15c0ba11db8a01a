"""socialnav.evaluation: protocols, metrics, statistics, reports and plots.

Seed 000's experiment as a protocol around the simulator's step
(:mod:`~socialnav.evaluation.protocol`), its orchestration and report
(:mod:`~socialnav.evaluation.warehouse`), the metrics (:mod:`~socialnav.evaluation.metrics`: Hall's
zones, collisions once per encounter), the statistical tests
(:mod:`~socialnav.evaluation.statistics`) and figures. The social-navigation arena, its episodes,
metrics, tables, statistics, plots and the papers' numbers: :mod:`~socialnav.evaluation.arena`.
The human models against real pedestrians, and their calibrations:
:mod:`~socialnav.evaluation.humans`.

Re-exported here: a scene file to the planner's scene, and one scene's benchmark.
"""

from socialnav.evaluation.arena import (
    ArenaConfig,
    ArenaParams,
    SceneSetup,
    planner_scene,
    run_scene,
    scene_from_file,
    setup_scene,
    summary,
)

__all__ = [
    "ArenaConfig",
    "ArenaParams",
    "SceneSetup",
    "planner_scene",
    "run_scene",
    "scene_from_file",
    "setup_scene",
    "summary",
]
