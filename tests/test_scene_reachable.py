"""A scene's goal reachable from its start past the walls, by a robot of the run's radius, within
its timeout: known answers on hand-made walls and timeouts, every shipped scene, and the arena's
one-line refusal."""

import json
import re

import pytest

from socialnav.cli import main
from socialnav.data import DATA_DIR
from socialnav.jaxsim.params import TIAGO_RADIUS_M
from socialnav.jaxsim.scenes.reachable import scene_problem
from socialnav.jaxsim.scenes.spec import load_scene

SCENES = sorted((DATA_DIR / "scenes").rglob("*.json"))
TOLERANCE_M = 0.3
SPEED_MPS = 0.5  # the arena's robot (jaxsim.scenes.robot.RobotParams)


def _problem(spec, radius_m=TIAGO_RADIUS_M, speed_mps=SPEED_MPS):
    return scene_problem(spec, radius_m, speed_mps, TOLERANCE_M)


def _with_walls(tmp_path, walls, robot_start=None, timeout_s=None, rule=None):
    """Seed 001's static person (a 10 x 6 m room, start (-4, [-0.2, 0.2]), goal (4, 0)) with more
    walls."""
    obj = json.loads((DATA_DIR / "scenes" / "casn_static_person.json").read_text())
    obj["walls"] += walls
    if robot_start is not None:
        obj["robot"]["start"] = robot_start
    if timeout_s is not None:
        obj["timeout_s"] = timeout_s
    if rule is not None:
        obj["rule"] = rule
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(obj))
    return load_scene(path)


@pytest.mark.parametrize("file", SCENES, ids=[f.stem for f in SCENES])
def test_every_shipped_scene_can_be_finished(file):
    assert _problem(load_scene(file)) is None


def test_a_timeout_shorter_than_the_straight_line_at_top_speed_is_named(tmp_path):
    """The farthest draw: from (-4, +-0.2) to within 0.3 m of (4, 0), 8.0025 - 0.3 = 7.70 m,
    15.4 s at 0.5 m/s."""
    field, why = _problem(_with_walls(tmp_path, [], timeout_s=15))
    assert field == "timeout_s" and "15.4 s" in why and "7.70 m" in why
    assert re.search(r"robot\.start \(-4, -?0\.2\)", why)
    assert _problem(_with_walls(tmp_path, [], timeout_s=16)) is None
    assert _problem(_with_walls(tmp_path, [], timeout_s=15), speed_mps=1.0) is None


def test_a_wall_across_the_room_closes_the_way(tmp_path):
    spec = _with_walls(tmp_path, [[2.0, 2.2, -3.0, 3.0]])
    field, why = _problem(spec)
    assert field == "robot.goal" and "(4, 0)" in why and "(-4, 0)" in why and "0.275" in why


@pytest.mark.parametrize("offset_m", [0.0, 0.013, 0.025, 0.037])
def test_a_gap_is_passable_by_the_robots_width_not_by_the_grids_offset(tmp_path, offset_m):
    """A gap 0.4 m wide at the room's top: a 0.275 m robot cannot pass, a 0.15 m one can; a gap
    just wider than the TIAGo (0.56 m) is never refused, wherever it lies on the grid."""
    low = 0.3 + offset_m
    narrow = _with_walls(tmp_path, [[2.0, 2.2, -3.0, low], [2.0, 2.2, low + 0.4, 3.0]])
    assert _problem(narrow)[0] == "robot.goal"
    assert _problem(narrow, radius_m=0.15) is None
    wide = _with_walls(tmp_path, [[2.0, 2.2, -3.0, low], [2.0, 2.2, low + 0.56, 3.0]])
    assert _problem(wide) is None


def test_a_way_round_the_wall_is_found(tmp_path):
    """A wall across most of the room, then a second one: the way winds round both."""
    spec = _with_walls(tmp_path, [[-1.0, -0.8, -3.0, 2.0], [1.0, 1.2, -2.0, 3.0]])
    assert _problem(spec) is None


def test_a_start_with_no_room_for_the_body_is_named(tmp_path):
    """The start in a slot 0.3 m wide: the body fits nowhere within its radius of it."""
    spec = _with_walls(tmp_path, [[-4.85, -3.0, -3.0, -0.15], [-4.85, -3.0, 0.15, 3.0]], robot_start=[-4.0, 0.0])
    field, why = _problem(spec)
    assert field == "robot.start" and "no room" in why


def test_a_rule_box_the_robot_cannot_enter_is_named_with_its_place_in_the_rule(tmp_path):
    """A ``visit`` box inside the room's bottom wall, and a ``keep_right`` box in a pocket of the
    room walled off from the start: no method could keep the first, every method keeps the
    second by never entering it. A box reaching into the open room is fine."""
    in_wall = {"type": "visit", "box": [0.0, 1.0, -3.0, -2.9]}
    assert _problem(_with_walls(tmp_path, [], rule=in_wall))[0] == "rule.box"
    walled_off = {"type": "keep_right", "box": [-1.9, -1.1, 1.6, 2.7], "direction_deg": 0}
    rule = {"type": "all", "rules": [{"type": "min_distance", "distance_m": 0.5}, walled_off]}
    # a pocket 1 m x 1.35 m: three walls, the room's own above
    pocket = [[-2.2, -2.0, 1.3, 2.85], [-1.0, -0.8, 1.3, 2.85], [-2.2, -0.8, 1.3, 1.5]]
    field, why = _problem(_with_walls(tmp_path, pocket, rule=rule))
    assert field == "rule.rules[1].box" and "0.275 m" in why
    assert _problem(_with_walls(tmp_path, [], rule=rule)) is None
    reaching_in = {"type": "visit", "box": [0.0, 1.0, -3.0, -1.0]}
    assert _problem(_with_walls(tmp_path, [], rule=reaching_in)) is None


def _gap_argv(tmp_path):
    spec = _with_walls(tmp_path, [[2.0, 2.2, -3.0, 2.45]])  # a 0.4 m gap at the top
    return spec, ["arena", "--scenes", str(spec.file), "--methods", "navfn", "--variants", "2", "--no-progress"]


def test_the_arena_refuses_an_unreachable_goal_in_one_line(tmp_path, capsys):
    spec, argv = _gap_argv(tmp_path)
    assert main([*argv, "--out", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and str(spec.file) in err and "'robot.goal'" in err
    assert not (tmp_path / "a").exists()


@pytest.mark.slow
def test_the_arena_runs_the_same_scene_for_a_robot_that_fits_and_it_arrives(tmp_path):
    """The check reads the robot of the run (``--params``' radius): a 0.15 m robot passes the gap."""
    import pandas as pd

    _, argv = _gap_argv(tmp_path)
    (tmp_path / "small.toml").write_text("[robot]\nradius_m = 0.15\n")
    assert main([*argv, "--params", str(tmp_path / "small.toml"), "--out", str(tmp_path / "a")]) == 0
    summary = pd.read_csv(tmp_path / "a" / "summary.csv")
    assert summary["goal_success_pct"].tolist() == [100.0]


def test_the_python_entries_refuse_it_too_naming_the_file_and_field(tmp_path):
    """The Gymnasium adapter, the arena's table and a scene's setup refuse what the command
    refuses, before anything is written; a horizon the caller sets (``EnvConfig.max_steps``) is
    truncation, not the scene's timeout, so only the walls are checked then."""
    from socialnav.evaluation.arena import episodes, table
    from socialnav.jaxsim.scenario.errors import ScenarioError
    from socialnav.jaxsim.scenes import env as env_lib
    from socialnav.jaxsim.scenes.gym_env import SocialNavEnv

    (tmp_path / "gap").mkdir()
    walled_off, _ = _gap_argv(tmp_path / "gap")
    for make in (
        lambda: SocialNavEnv(walled_off, pool=2),
        lambda: SocialNavEnv(walled_off, pool=2, config=env_lib.EnvConfig(max_steps=5)),
        lambda: episodes.setup_scene(walled_off),
        lambda: table.run_table(tmp_path / "out", table.TableRequest(specs=(walled_off,), methods=("navfn",))),
    ):
        with pytest.raises(ScenarioError, match=r"field 'robot\.goal'") as refused:
            make()
        assert refused.value.file == walled_off.file
    assert not (tmp_path / "out").exists()

    hurried = _with_walls(tmp_path, [], timeout_s=15)
    with pytest.raises(ScenarioError, match=r"field 'timeout_s': 15 s is shorter"):
        SocialNavEnv(hurried, pool=2)
    short_horizon = SocialNavEnv(hurried, pool=2, config=env_lib.EnvConfig(max_steps=5))
    assert short_horizon.action_space.shape == (2,)


def test_a_goal_tolerance_that_reaches_the_start_is_named():
    """Seed 001's static person: start (-4, [-0.2, 0.2]), goal (4, 0), 8 m apart at the least."""
    from socialnav.jaxsim.scenes import env as env_lib
    from socialnav.jaxsim.scenes.gym_env import SocialNavEnv

    spec = load_scene(DATA_DIR / "scenes" / "casn_static_person.json")
    field, why = scene_problem(spec, TIAGO_RADIUS_M, SPEED_MPS, 8.5)
    assert field == "robot.goal" and "8.00 m from robot.start" in why and "goal_tolerance_m" in why
    assert scene_problem(spec, TIAGO_RADIUS_M, SPEED_MPS, 7.9, check_timeout=False) is None
    with pytest.raises(ValueError, match=r"field 'robot\.goal': can be 8\.00 m .* end before the robot moves"):
        SocialNavEnv(spec, pool=2, config=env_lib.EnvConfig(goal_tolerance_m=9.0))
