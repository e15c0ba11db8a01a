"""socialnav.evaluation: protocols, metrics, statistics, reports and plots.

Seed 000's experiment as a protocol around the simulator's step
(:mod:`~socialnav.evaluation.protocol`), its orchestration and report
(:mod:`~socialnav.evaluation.warehouse`), the metrics (:mod:`~socialnav.evaluation.metrics`: Hall's
zones, collisions once per encounter), the statistical tests
(:mod:`~socialnav.evaluation.statistics`) and figures. The social-navigation arena: episodes
(:mod:`~socialnav.evaluation.arena`), a scene's methods (:mod:`~socialnav.evaluation.arena_run`), their tables
(:mod:`~socialnav.evaluation.arena_report`), its metrics (:mod:`~socialnav.evaluation.nav_metrics`),
parameters (:mod:`~socialnav.evaluation.arena_params`), statistics, plots and the papers' numbers
(:mod:`~socialnav.evaluation.papers`).

Re-exported here: a scene file to the planner's scene, and one scene's benchmark.
"""

from socialnav.evaluation.arena import ArenaConfig, SceneSetup, planner_scene, scene_from_file, setup_scene
from socialnav.evaluation.arena_params import ArenaParams
from socialnav.evaluation.arena_report import summary
from socialnav.evaluation.arena_run import run_scene

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
