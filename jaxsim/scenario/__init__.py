"""The warehouse scenario as files, loaded and validated (see :mod:`jaxsim.scenario.loader`)."""

from socialnav.jaxsim.scenario.errors import ScenarioError
from socialnav.jaxsim.scenario.loader import DATA_ROOT, WAREHOUSE_DIR, Scenario, load_scenario

__all__ = ["DATA_ROOT", "WAREHOUSE_DIR", "Scenario", "ScenarioError", "load_scenario"]
