"""``schedule.json``: ordered ``slots`` ``{name, clock, working, destinations: {waypoint: p}}``
(and ``pedsim_name``, the slot's name in PeopleFlow's own files, which nothing reads)."""

from __future__ import annotations

import dataclasses
import pathlib

import numpy as np

from socialnav.jaxsim.scenario.errors import ScenarioError
from socialnav.jaxsim.scenario.jsonio import field, list_field, only_fields, read_json

FILE = "schedule.json"
PROBABILITY_TOLERANCE = 1e-6


@dataclasses.dataclass(frozen=True)
class Schedule:
    """names, clock (S,), working (S,) bool, destination_p (S, W) rows summing to 1."""

    names: tuple[str, ...]
    clock: tuple[str, ...]
    working: np.ndarray
    destination_p: np.ndarray


def load_schedule(folder: pathlib.Path, index: dict[str, int], human_allowed: np.ndarray) -> Schedule:
    file = folder / FILE
    top = read_json(file)
    only_fields(top, file, "", ("slots",))
    slots = list_field(top, file, "slots")
    if not slots:
        raise ScenarioError(file, "slots", "no slots")
    names, clock, working, dest_p = [], [], [], []
    for s, slot in enumerate(slots):
        where = f"slots[{s}]"
        only_fields(slot, file, where, ("name", "pedsim_name", "clock", "working", "destinations"))
        names.append(field(slot, file, where, "name", str))
        clock.append(field(slot, file, where, "clock", str))
        working.append(field(slot, file, where, "working", bool))
        row = np.zeros(len(index))
        for name, p in field(slot, file, where, "destinations", dict).items():
            if name not in index:
                raise ScenarioError(file, f"{where}.destinations.{name}", "unknown waypoint")
            if not isinstance(p, (int, float)) or isinstance(p, bool) or not 0 <= p <= 1:
                raise ScenarioError(file, f"{where}.destinations.{name}", f"not a probability: {p!r}")
            if not human_allowed[index[name]]:
                raise ScenarioError(file, f"{where}.destinations.{name}", "waypoint excluded for humans")
            row[index[name]] = p
        if abs(row.sum() - 1.0) > PROBABILITY_TOLERANCE:
            raise ScenarioError(file, f"{where}.destinations", f"probabilities sum to {row.sum():.6f}, expected 1")
        dest_p.append(row)
    return Schedule(tuple(names), tuple(clock), np.asarray(working, bool), np.asarray(dest_p, np.float64))
