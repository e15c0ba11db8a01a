"""Shared fixtures: the built-in warehouse at reduced scale (short slots), built once."""

from __future__ import annotations

import pytest

from jaxsim.scenario import load_scenario
from jaxsim.world import build_world, shortest_path_plan


@pytest.fixture(scope="session")
def warehouse():
    return load_scenario()


@pytest.fixture(scope="session")
def short_day():
    """The warehouse with 60 s slots: a whole day is 6600 steps."""
    scenario = load_scenario(slot_length_s=60.0)
    return scenario, build_world(scenario), shortest_path_plan(scenario)
