"""The simulator log's file contract: file names and columns of a ``socialnav simulate`` run.

The simulator (:mod:`jaxsim.logs`) writes it and the causal pipeline (:mod:`causal.extract`)
reads it; neither imports the other, both import this. ``tests/test_contracts.py`` writes a
run with the simulator and reads it back with the causal reader.

A run folder holds:

* :data:`LOG_FILE` (Parquet): one row per logged sample per world. Columns: :data:`ID_COLUMNS`,
  :data:`SETTING_COLUMNS`, :data:`CLOCK_COLUMNS`, :data:`ROBOT_COLUMNS`, then
  ``density_<waypoint>`` (Eq. 3, people / m^2) for every waypoint, ``dist_worker_<i>`` (robot-
  worker centre distance in m, NaN while absent) for every worker, and with positions logged
  ``worker_x_<i>``, ``worker_y_<i>``, ``worker_status_<i>``.
* :data:`META_FILE` (JSON): seed, sizes, ``waypoints`` (names in column order), ``slots``
  (names, index = the ``slot`` column), ``params`` (every simulation parameter), timings.
"""

from __future__ import annotations

LOG_FILE = "logs.parquet"
META_FILE = "run.json"
SCHEMA_VERSION = 1

# (column, numpy dtype) in the order written.
ID_COLUMNS = (("world", "int32"), ("seed", "int64"))
SETTING_COLUMNS = (
    ("dt_s", "float32"),
    ("slot_length_s", "float32"),
    ("n_workers", "int16"),
    ("obstacle_probability", "float32"),
)
CLOCK_COLUMNS = (("time_s", "float64"), ("slot", "int8"))
ROBOT_COLUMNS = (
    ("robot_x_m", "float32"),
    ("robot_y_m", "float32"),
    ("robot_speed_mps", "float32"),
    ("battery_pct", "float32"),
    ("battery_change_pct", "float32"),
    ("charging", "bool"),
    ("obstacle", "bool"),
    ("robot_mode", "int8"),
    ("robot_waypoint", "int16"),
    ("goal_wp", "int16"),
    ("leg_elapsed_s", "float32"),
    ("tasks_started", "int32"),
    ("tasks_succeeded", "int32"),
    ("tasks_failed", "int32"),
    ("stalled_s", "float32"),
    ("n_present", "int16"),
)
# Keys of META_FILE that a reader relies on.
META_KEYS = ("seed", "n_worlds", "waypoints", "slots", "params")


def density_column(waypoint: str) -> str:
    """Column of Eq. (3)'s density at ``waypoint``."""
    return f"density_{waypoint}"


def distance_column(worker: int) -> str:
    """Column of the robot's distance to worker ``worker``."""
    return f"dist_worker_{worker}"


def position_columns(worker: int) -> tuple[str, str, str]:
    """Columns of worker ``worker``'s x, y and status (written with positions logged)."""
    return f"worker_x_{worker}", f"worker_y_{worker}", f"worker_status_{worker}"


def required_columns(waypoints, n_workers: int = 0) -> list[str]:
    """Every column a log of these waypoints and workers has (positions excluded)."""
    names = [c for c, _ in ID_COLUMNS + SETTING_COLUMNS + CLOCK_COLUMNS + ROBOT_COLUMNS]
    return names + [density_column(w) for w in waypoints] + [distance_column(i) for i in range(n_workers)]
