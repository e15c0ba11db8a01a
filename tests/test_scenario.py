"""Loading the built-in warehouse, and one clear error per kind of bad file."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from socialnav.evaluation.protocol import ProtocolConfig
from socialnav.jaxsim.params import TIAGO_RADIUS_M
from socialnav.jaxsim.scenario import WAREHOUSE_DIR, ScenarioError, load_scenario
from socialnav.jaxsim.scenes.robot import RobotParams


def test_builtin_warehouse_matches_the_reference(warehouse):
    s = warehouse
    assert s.n_waypoints == 73 and len(s.edges) == 184 and s.n_slots == 11
    np.testing.assert_allclose(s.destination_p.sum(axis=1), 1.0, atol=1e-9)
    assert not s.slot_working[-1] and s.slot_working[:-1].all()
    assert s.destination_p[-1, s.parking] == 1.0
    assert [len(g) for g in s.robot_goals] == [200] * 10 + [90]
    assert s.waypoint_ids[s.charging_station] == "charging-station"
    assert not s.human_allowed[s.charging_station] and not s.robot_allowed[s.parking]
    p = s.params
    assert p.slot_length_s == 3600 and p.n_workers == 50 and p.robot_max_speed_mps == 0.5
    # K_s: idle for 5 h; K_s + 0.5 K_d: driving at full speed for 4 h; K_c: 2 h charge.
    assert p.battery_static_pct_per_s * 5 * 3600 == pytest.approx(100)
    assert (p.battery_static_pct_per_s + 0.5 * p.battery_dynamic_pct_per_m) * 4 * 3600 == pytest.approx(100)
    assert p.battery_charge_pct_per_s * 2 * 3600 == pytest.approx(100)
    # the warehouse's robot is the TIAGo the protocol's collision radius and the scenes' robot take
    assert p.robot_radius_m == TIAGO_RADIUS_M == ProtocolConfig().collision_radius_m == RobotParams().radius_m


def test_param_overrides(warehouse):
    s = load_scenario(slot_length_s=60.0, n_workers=3)
    assert s.params.slot_length_s == 60.0 and s.params.n_workers == 3
    assert s.params.steps_per_slot == 600


@pytest.fixture()
def scenario_copy(tmp_path):
    dst = tmp_path / "wh"
    shutil.copytree(WAREHOUSE_DIR, dst)
    return dst


def _edit(folder, name, fn):
    path = folder / name
    obj = json.loads(path.read_text())
    fn(obj)
    path.write_text(json.dumps(obj))


def _expect(folder, file, field_part):
    with pytest.raises(ScenarioError) as err:
        load_scenario(folder)
    assert err.value.file.name == file
    assert field_part in err.value.field
    assert file in str(err.value) and field_part in str(err.value)
    return err.value


def test_missing_field(scenario_copy):
    _edit(scenario_copy, "waypoints.json", lambda o: o["waypoints"][5].pop("radius_m"))
    _expect(scenario_copy, "waypoints.json", "waypoints[5].radius_m")


def test_probabilities_not_summing_to_one(scenario_copy):
    _edit(scenario_copy, "schedule.json", lambda o: o["slots"][1]["destinations"].update({"office-1": 0.5}))
    err = _expect(scenario_copy, "schedule.json", "slots[1].destinations")
    assert "sum to" in str(err)


def test_edge_to_unknown_waypoint(scenario_copy):
    _edit(scenario_copy, "graph.json", lambda o: o["edges"].append(["office-1", "office-99"]))
    err = _expect(scenario_copy, "graph.json", "edges[184]")
    assert "office-99" in str(err)


def test_waypoint_inside_a_wall(scenario_copy):
    def move(o):
        wp = next(w for w in o["waypoints"] if w["id"] == "office-1")
        wp["x_m"], wp["y_m"] = -12.0, 4.0  # inside a shelf

    _edit(scenario_copy, "waypoints.json", move)
    err = _expect(scenario_copy, "waypoints.json", "waypoints[29]")
    assert "inside wall" in str(err)


def test_missing_file_and_bad_json(scenario_copy):
    (scenario_copy / "tasks.json").unlink()
    _expect(scenario_copy, "tasks.json", "<file>")
    (scenario_copy / "tasks.json").write_text("{not json")
    _expect(scenario_copy, "tasks.json", "<file>")


def test_missing_or_bad_parameter(scenario_copy):
    _edit(scenario_copy, "params.json", lambda o: o["battery"].pop("obstacle_factor"))
    _expect(scenario_copy, "params.json", "battery.obstacle_factor")
    shutil.copy(WAREHOUSE_DIR / "params.json", scenario_copy / "params.json")
    _edit(scenario_copy, "params.json", lambda o: o["robot"].update({"max_speed_mps": "fast"}))
    _expect(scenario_copy, "params.json", "robot.max_speed_mps")


@pytest.mark.parametrize(
    "file, mutate, field, hint",
    [
        ("waypoints.json", lambda o: o["waypoints"][2].update(speed_mps=0.5), "waypoints[2].speed_mps", None),
        ("walls.json", lambda o: o["boxes"][0].update(xmax=2.0), "boxes[0].xmax", "xmax_m"),
        ("schedule.json", lambda o: o["slots"][1].update(workin=False), "slots[1].workin", "working"),
        ("tasks.json", lambda o: o.update(charging=o["charging_station"]), "charging", "charging_station"),
        ("graph.json", lambda o: o.update(robots_exclude=[]), "robots_exclude", "robot_exclude"),
        ("params.json", lambda o: o.update(batery={"initial_pct": 50}), "batery", "battery"),
    ],
)
def test_a_field_nothing_reads_is_refused(scenario_copy, file, mutate, field, hint):
    """A made-up or misspelt field would change nothing and say nothing; an ``_`` note is fine."""
    _edit(scenario_copy, file, mutate)
    err = _expect(scenario_copy, file, field)
    assert err.field == field and "unknown" in str(err)
    assert (f"did you mean {hint!r}" in str(err)) == (hint is not None)


@pytest.mark.parametrize(
    "file, key, value", [("params.json", "max_speed_mps", "1.2"), ("tasks.json", "robot_start", '"parking"')]
)
def test_a_key_given_twice_is_refused(scenario_copy, file, key, value):
    text = (scenario_copy / file).read_text()
    first = text.index(f'"{key}"')
    (scenario_copy / file).write_text(text[:first] + f'"{key}": {value},\n' + text[first:])
    err = _expect(scenario_copy, file, key)
    assert "given twice" in str(err)


def test_a_note_in_an_underscore_field_is_not_read(scenario_copy, warehouse):
    for file in ("waypoints.json", "walls.json", "schedule.json", "tasks.json", "graph.json", "params.json"):
        _edit(scenario_copy, file, lambda o: o.update(_note="edited for a test"))
    _edit(scenario_copy, "waypoints.json", lambda o: o["waypoints"][0].update(_why="the lot"))
    noted = load_scenario(scenario_copy)
    np.testing.assert_array_equal(noted.waypoint_xy_m, warehouse.waypoint_xy_m)
    assert noted.params == warehouse.params and noted.slot_names == warehouse.slot_names


def test_robot_goal_must_be_known(scenario_copy):
    _edit(scenario_copy, "tasks.json", lambda o: o["slots"][0]["goals"].__setitem__(3, "parking"))
    _expect(scenario_copy, "tasks.json", "slots[0].goals[3]")


def test_a_step_that_would_put_workers_in_walls_is_refused(scenario_copy):
    """``sim.dt_s`` at the workers' top speed past ``WORKER_STEP_MAX_M`` (jaxsim.params: measured)."""
    from socialnav.jaxsim.params import WORKER_STEP_MAX_M

    _edit(scenario_copy, "params.json", lambda o: o["sim"].update(dt_s=0.15, slot_length_s=3600.0))
    err = _expect(scenario_copy, "params.json", "sim.dt_s")
    assert "0.225 m" in str(err) and "at most 0.133 s" in str(err)
    assert load_scenario(dt_s=0.125, slot_length_s=3600.0).params.dt_s == 0.125  # 0.19 m a step
    assert 1.5 * 0.125 <= WORKER_STEP_MAX_M < 1.5 * 0.15
