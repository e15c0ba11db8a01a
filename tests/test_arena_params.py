"""The arena's parameter file (evaluation/arena/params.py): precedence, one-line errors, the
values reaching the episodes as traced inputs, and the command's --params."""

from __future__ import annotations

import pathlib
import re

import numpy as np
import pytest

from socialnav.data import SCENES_DIR
from socialnav.evaluation.arena import episodes as arena
from socialnav.evaluation.arena import params as arena_params
from socialnav.evaluation.arena import run as arena_run
from socialnav.jaxsim.scenes.robot import RobotParams
from socialnav.jaxsim.scenes.spec import load_scene
from socialnav.planners import stack

ARENA_PAGE = pathlib.Path(__file__).parent.parent / "docs" / "arena.md"


def test_no_file_gives_every_methods_defaults():
    params = arena_params.parse("")
    assert params.robot == RobotParams()
    for method in stack.METHODS:
        assert params.layers_for(method) == stack.layer_params(stack.METHODS[method])


def test_top_level_sections_apply_to_every_method_and_method_sections_to_one():
    params = arena_params.parse(
        """
[robot]
max_speed_mps = 0.7
[snl]
amplitude = 100
[methods.snl_large.snl]
covariance = 0.9
[methods.casn.casn]
personal_radius_m = 1.5
"""
    )
    assert params.robot.max_speed_mps == 0.7 and params.robot.radius_m == RobotParams().radius_m
    small, large = params.layers_for("snl_small"), params.layers_for("snl_large")
    assert small.snl.amplitude == 100.0 and large.snl.amplitude == 100.0
    assert small.snl.covariance == stack.layer_params(stack.METHODS["snl_small"]).snl.covariance  # its own default
    assert large.snl.covariance == 0.9
    assert params.layers_for("casn").casn.personal_radius_m == 1.5
    assert params.layers_for("navfn").casn.personal_radius_m == stack.LayerParams().casn.personal_radius_m


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("[robt]\nradius_m = 0.3", r"\[robt\]: unknown section \(known: robot, snl, casn"),
        ("[robot]\nradius = 0.3", r"\[robot\] radius: unknown field \(known: .*radius_m"),
        ("[casn]\npersonal_radius_m = 'wide'", r"\[casn\] personal_radius_m: expected a finite number, got 'wide'"),
        ("[band]\nk_c = nan", r"\[band\] k_c: expected a finite number"),
        ("[band]\nk_c = true", r"\[band\] k_c: expected a finite number, got True"),
        ("[pursuit]\nlookahead_m = -1", r"\[pursuit\] lookahead_m: must be >= 0"),
        ("[methods.teleport.snl]\namplitude = 1", r"\[methods\.teleport\]: unknown method"),
        ("[methods.casn.orca]\nx = 1", r"\[methods\.casn\.orca\]: unknown section"),
        ("[robot]\nmax_speed_mps = 0", r"\[robot\]: radius_m and max_speed_mps must be > 0"),
        (
            "[robot]\nmax_speed_mps = 3",
            r"\[robot\]: RobotParams\.max_speed_mps 3 m/s .* 0\.3 m, not less than .* through a wall",
        ),
        ("[robot]\nradius_m = 0.04", r"\[robot\]: .* radius_m 0\.04 m: .* below 0\.4 m/s"),
        ("[robot\nmax_speed_mps = 1", r"not TOML"),
    ],
)
def test_a_bad_file_is_one_line_naming_the_file_section_and_field(tmp_path, text, expected):
    path = tmp_path / "mine.toml"
    path.write_text(text)
    with pytest.raises(arena_params.ParamsFileError, match=expected) as raised:
        arena_params.load(path)
    message = str(raised.value)
    assert message.startswith(f"{path}: ") and "\n" not in message


def test_an_unreadable_file_is_named(tmp_path):
    with pytest.raises(arena_params.ParamsFileError, match=r"nowhere\.toml: cannot read it"):
        arena_params.load(tmp_path / "nowhere.toml")


@pytest.mark.slow
def test_the_files_values_reach_the_episodes_without_a_new_compilation():
    """A slower robot takes longer; the pursuit's gain is traced: the same compiled program."""
    spec = load_scene(SCENES_DIR / "casn_static_person.json")
    default = arena_run.run_scene(spec, ["navfn"], 2)[0]
    grid = arena.setup_scene(spec).grid  # the same arguments as episode_function's: its cached actor
    actor = arena.method_actor(stack.METHODS["navfn"], grid, float(RobotParams().radius_m), arena.ArenaConfig(), None)
    program = arena._episode_program(actor)
    compiled = program._cache_size()
    slow = arena_params.parse("[robot]\nmax_speed_mps = 0.3\n[pursuit]\nturn_gain = 1.2")
    slower = arena_run.run_scene(spec, ["navfn"], 2, params=slow)[0]
    assert program._cache_size() == compiled  # traced values: no recompilation
    assert np.all(slower["time_s"].to_numpy() > default["time_s"].to_numpy() + 1.0)
    assert slower["goal_success"].all()


@pytest.mark.slow
def test_a_users_actor_before_a_built_in_method_keeps_the_files_values():
    """The user's actor gets the file's robot limits, and the built-in after it its layers."""
    from socialnav.jaxsim.scenes.actor import Actor

    seen = {}

    def still(env):
        seen["robot"] = env.robot
        return Actor(init=lambda key, obs: (), act=lambda p, s, obs, key: (obs.robot_xy_m * 0.0, s), name="still")

    spec = load_scene(SCENES_DIR / "casn_static_person.json")
    params = arena_params.parse("[robot]\nmax_speed_mps = 0.4\n[pursuit]\nturn_gain = 1.2")
    episodes = arena_run.run_scene(spec, ["still", "navfn"], 2, user_actors={"still": still}, params=params)[0]
    assert seen["robot"].max_speed_mps == 0.4
    assert list(episodes["method"]) == ["still", "still", "navfn", "navfn"]
    assert not episodes[episodes["method"] == "still"]["goal_success"].any()


def test_the_command_refuses_a_bad_file_before_any_work(tmp_path, capsys):
    from socialnav import cli

    bad = tmp_path / "bad.toml"
    bad.write_text("[casn]\npersonal_radius = 1.0\n")
    out = tmp_path / "run"
    assert cli.main(["arena", "--out", str(out), "--scenes", "casn_static_person", "--params", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("socialnav arena: --params ") and f"{bad}: [casn] personal_radius: unknown field" in err
    assert len(err.splitlines()) == 1 and not out.exists()


def test_the_docs_example_file_parses(tmp_path):
    """The arena page's example parameter file is a valid one (its values reach the stacks)."""
    text = ARENA_PAGE.read_text()
    match = re.search(r"<!-- arena-params-example -->\s*```toml\n(.*?)```", text, re.S)
    assert match, "docs/arena.md: the arena parameter example is missing"
    params = arena_params.parse(match.group(1), "docs/arena.md")
    assert params.robot != RobotParams() or params.layers or params.methods
    for method in stack.METHODS:
        params.layers_for(method)  # every section applies to its stacks
