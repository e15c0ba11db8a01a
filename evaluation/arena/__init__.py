"""socialnav.evaluation.arena: the arena, methods x scenes x variants in closed loop, and its tables.

- :mod:`~socialnav.evaluation.arena.episodes`: a scene set up for its methods, episodes as
  compiled programs (one per scene and method, ``vmap`` over variants), spread over devices;
- :mod:`~socialnav.evaluation.arena.params`: every method's dynamic parameters as one pytree;
- :mod:`~socialnav.evaluation.arena.run`: one scene's whole run (:func:`run_scene`), held-out
  rows, a user's actor;
- :mod:`~socialnav.evaluation.arena.nav_metrics`: the per-episode metrics (the field's suites'
  definitions, each with its source);
- :mod:`~socialnav.evaluation.arena.report`: episodes and trajectories as tables, the summary
  with intervals;
- :mod:`~socialnav.evaluation.arena.stats`: the tests between methods;
- :mod:`~socialnav.evaluation.arena.papers`: the seeds' published numbers beside ours;
- :mod:`~socialnav.evaluation.arena.plots`: the pictures;
- :mod:`~socialnav.evaluation.arena.table`: the whole table in a run folder (what
  ``socialnav arena`` runs): settings and digests, shards, per-scene joins, the tables written;
- :mod:`~socialnav.evaluation.arena.actor_spec`: a user's actor factory named
  ``MODULE:FUNCTION`` (``--actor``).

In code the modules are imported under the names they had before they were a folder
(``from socialnav.evaluation.arena import episodes as arena``, ``run as arena_run``, ...).
"""

from socialnav.evaluation.arena.episodes import ArenaConfig, SceneSetup, planner_scene, scene_from_file, setup_scene
from socialnav.evaluation.arena.params import ArenaParams
from socialnav.evaluation.arena.report import summary
from socialnav.evaluation.arena.run import run_scene

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
