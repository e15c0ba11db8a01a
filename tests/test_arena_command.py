"""The ``socialnav arena`` command: bad input refused, tables written, a run resumed, other
settings refused."""

import dataclasses
import json

import pandas as pd
import pytest

from socialnav.common.memory import available_bytes


def test_arena_command_refuses_bad_input(tmp_path, capsys):
    from socialnav import cli

    assert cli.main(["arena", "--out", str(tmp_path / "a"), "--methods", "teleport"]) == 2
    assert "unknown teleport" in capsys.readouterr().err
    assert cli.main(["arena", "--out", str(tmp_path / "a"), "--methods", "gscl", "--gscl-run", str(tmp_path)]) == 2
    assert "neither a GSCL training run" in capsys.readouterr().err
    assert cli.main(["arena", "--out", str(tmp_path / "a"), "--scenes", "nowhere"]) == 2
    assert "nowhere.json" in capsys.readouterr().err
    with pytest.raises(SystemExit):  # a method twice would be counted twice: n doubled, no new episode
        cli.main(["arena", "--out", str(tmp_path / "a"), "--methods", "navfn,casn,navfn"])
    assert "'navfn' is given twice" in capsys.readouterr().err
    assert not (tmp_path / "a").exists()


def test_a_table_request_refuses_a_method_or_a_scene_named_twice():
    from socialnav.data import SCENES_DIR
    from socialnav.evaluation.arena import table
    from socialnav.jaxsim.scenes.spec import load_scene

    spec = load_scene(SCENES_DIR / "casn_static_person.json")
    with pytest.raises(ValueError, match=r"TableRequest.methods: 'navfn' named twice"):
        table.TableRequest(specs=(spec,), methods=("navfn", "casn", "navfn"))
    with pytest.raises(ValueError, match=r"TableRequest.scenes: 'casn_static_person' named twice"):
        table.TableRequest(specs=(spec, spec), methods=("navfn",))
    assert table.TableRequest(specs=(spec,), methods=("navfn", "casn")).methods == ("navfn", "casn")


def test_the_scene_pictures_read_the_nearest_person_and_the_row_from_the_trajectories_alone(tmp_path):
    """The distance and speed pictures need no scene: the nearest present person (a 3-4-5
    triangle; an absent person nearer is passed over) and the row's name come from the frame."""
    import matplotlib.image

    from socialnav.evaluation.arena import plots

    frame = pd.DataFrame({
        "scene": "casn_head_on@held_out", "method": "snape_social_eband", "variant": 0,
        "t_s": [0.1, 0.2, 0.3], "robot_x": 0.0, "robot_y": 0.0, "robot_speed": [0.2, 0.4, 0.6],
        "speed_gain": 1.0, "reached": [False, False, True],
        "p0_x": 3.0, "p0_y": 4.0, "p0_present": True,
        "p1_x": 0.5, "p1_y": 0.0, "p1_present": [False, True, False],
    })  # fmt: skip
    assert plots.nearest_distance(frame).tolist() == [5.0, 0.5, 5.0]
    assert plots._scene_name(frame) == "casn_head_on@held_out" and plots._scene_name(frame.iloc[:0]) == ""
    for drawn in (
        plots.distance_figure(frame, tmp_path / "distance.png"),
        plots.speed_figure(frame, "snape_social_eband", tmp_path / "speed.png"),
    ):
        height, width, _ = matplotlib.image.imread(drawn).shape
        assert height > 100 and width > 100


@pytest.mark.skipif(available_bytes() is None, reason="no /proc/meminfo here: no memory check")
def test_run_table_refuses_a_table_no_machine_holds_before_writing(tmp_path):
    from socialnav.data import SCENES_DIR
    from socialnav.evaluation.arena import table
    from socialnav.jaxsim.scenes.spec import load_scene

    request = table.TableRequest(specs=(load_scene(SCENES_DIR / "casn_static_person.json"),), methods=("navfn",),
                                 variants=10**12)  # fmt: skip
    with pytest.raises(table.TableTooLarge, match=r"TableRequest.variants 1,000,000,000,000: about .* GB at once"):
        table.run_table(tmp_path / "out", request)
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_arena_command_writes_tables_resumes_and_refuses_other_settings(tmp_path, capsys):
    from socialnav import cli

    out = tmp_path / "run"
    args = ["arena", "--out", str(out), "--scenes", "casn_static_person", "--methods", "navfn,casn", "--variants", "2"]
    assert cli.main([*args, "--no-progress", "--keep-trajectories", "1"]) == 0
    episodes = pd.read_parquet(out / "episodes" / "casn_static_person.parquet")
    assert len(episodes) == 4 and set(episodes["method"]) == {"navfn", "casn"}
    assert (out / "pictures" / "casn_static_person_paths.png").exists()
    summary = pd.read_csv(out / "summary.csv")
    assert list(summary["method"]) == ["navfn", "casn"]
    stamp = (out / "episodes" / "casn_static_person.parquet").stat().st_mtime_ns
    assert cli.main([*args, "--no-progress", "--keep-trajectories", "1"]) == 0  # resumed: nothing recomputed
    assert (out / "episodes" / "casn_static_person.parquet").stat().st_mtime_ns == stamp
    assert cli.main([*args[:-1], "3", "--no-progress"]) == 2
    assert "other settings" in capsys.readouterr().err


def test_the_table_made_from_python_is_the_one_the_command_makes_and_resumes(tmp_path, capsys):
    """``evaluation.arena.table.run_table`` is the command's work without the command (the command
    calls it): the command run after it on the same folder finds every scene done (nothing
    recomputed, the same summary), and a request with other settings is refused with the folder
    named."""
    from socialnav import cli
    from socialnav.common import runfolder
    from socialnav.data import SCENES_DIR
    from socialnav.evaluation.arena import table
    from socialnav.jaxsim.scenes.spec import load_scene

    out = tmp_path / "run"
    request = table.TableRequest(
        specs=(load_scene(SCENES_DIR / "casn_static_person.json"),), methods=("navfn",), variants=2
    )
    episodes, tables = table.run_table(out, request)
    assert list(episodes["variant"]) == [0, 1] and set(episodes["method"]) == {"navfn"}
    assert list(tables) == ["summary.csv", "stats.csv"]  # no paper compares NavFn alone in this scene
    assert (out / "trajectories" / "casn_static_person.parquet").exists()
    stamp = (out / "episodes" / "casn_static_person.parquet").stat().st_mtime_ns
    summary = (out / "summary.csv").read_text()
    from socialnav.common.machine import compiler_host

    assert json.loads((out / "run.json").read_text())["host"] == compiler_host()  # noted: GSCL rounds per ISA
    args = ["arena", "--out", str(out), "--scenes", "casn_static_person", "--methods", "navfn", "--variants", "2"]
    assert cli.main([*args, "--no-progress"]) == 0
    assert (out / "episodes" / "casn_static_person.parquet").stat().st_mtime_ns == stamp
    assert (out / "summary.csv").read_text() == summary
    with pytest.raises(table.SettingsConflict, match="other settings .*variants"):
        table.run_table(out, dataclasses.replace(request, variants=3))
    foreign = tmp_path / "mine"
    foreign.mkdir()
    (foreign / "summary.csv").write_text("a file of the user's\n")
    with pytest.raises(runfolder.NotOurs, match="summary.csv"):
        table.run_table(foreign, request)
    assert (foreign / "summary.csv").read_text() == "a file of the user's\n"


def test_the_time_estimate_is_a_range_that_grows_with_the_work():
    """``estimate_s``: a low and a high end; more variants, methods or the held-out rows cost
    more; compilation alone is paid once per program, whatever the variants."""
    from socialnav.data import SCENES_DIR
    from socialnav.evaluation.arena.table import COMPILE_S_PER_PROGRAM, STARTUP_S, estimate_s
    from socialnav.jaxsim.scenes.spec import load_scene

    specs = [load_scene(SCENES_DIR / f"{n}.json") for n in ("casn_head_on", "gscl_group")]
    timeouts = [spec.timeout_s for spec in specs]
    low, high = estimate_s(timeouts, 3, 6, False)
    assert STARTUP_S < low < high
    assert estimate_s(timeouts, 3, 60, False)[0] > low and estimate_s(timeouts, 4, 6, False)[1] > high
    more_low, more_high = estimate_s(timeouts, 3, 6, True)
    assert more_low > low and more_high > high
    assert estimate_s(timeouts, 3, 6, True, turned=True)[0] > more_low  # its own programs and episodes
    programs = len(specs) * (3 + 2)
    assert low - STARTUP_S == pytest.approx(programs * COMPILE_S_PER_PROGRAM[0] + (40 + 60) * 6 * 3 / 6000.0)


def test_the_arena_names_only_the_files_it_wrote(tmp_path, capsys):
    """A user's own scene has no paper's numbers: the closing line names no papers.csv."""
    import json

    from socialnav import cli
    from socialnav.data import SCENES_DIR

    obj = json.loads((SCENES_DIR / "casn_static_person.json").read_text())
    (tmp_path / "mine.json").write_text(json.dumps({**obj, "name": "mine"}))
    out = tmp_path / "run"
    argv = ["arena", "--out", str(out), "--scenes", str(tmp_path / "mine.json"), "--methods", "navfn"]
    assert cli.main([*argv, "--variants", "2", "--no-progress"]) == 0
    said = [line for line in capsys.readouterr().out.splitlines() if line.startswith("wrote ")][-1]
    assert "summary.csv" in said and "papers.csv" not in said and not (out / "papers.csv").exists()


@pytest.mark.slow
def test_a_held_out_run_writes_the_claims_on_its_held_out_rows(tmp_path, capsys):
    """``--held-out`` on a paper's scene: ``directions_held_out.csv`` holds the scene's claims
    measured on its held-out rows, under the scene's own name, beside ``directions.csv``; with
    ``--turned`` too, ``directions_turned.csv`` the claims on the scene turned, paired by variant."""
    import pandas as pd

    from socialnav import cli

    out = tmp_path / "run"
    argv = ["arena", "--out", str(out), "--scenes", "casn_static_person", "--methods", "casn,snl_matched"]
    assert cli.main([*argv, "--variants", "3", "--held-out", "--turned", "--no-progress"]) == 0
    said = [line for line in capsys.readouterr().out.splitlines() if line.startswith("wrote ")][-1]
    assert "directions.csv" in said and "directions_held_out.csv" in said and "directions_turned.csv" in said
    turned = pd.read_csv(out / "directions_turned.csv")
    assert set(turned["scene"]) == {"casn_static_person"} and (turned["n_pairs"] == 3).all()
    episodes = pd.read_parquet(out / "episodes" / "casn_static_person@turned.parquet")
    assert sorted(episodes["variant"].unique()) == [0, 1, 2] and set(episodes["scene"]) == {"casn_static_person@turned"}
    evaluated = pd.read_csv(out / "directions.csv")
    held_out = pd.read_csv(out / "directions_held_out.csv")
    assert set(held_out["scene"]) == {"casn_static_person"}
    key = ["source", "metric", "proposed", "baseline"]
    assert held_out[key].equals(evaluated[key]) and (held_out["n_pairs"] == 3).all()
    episodes = pd.read_parquet(out / "episodes" / "casn_static_person@held_out.parquet")
    d_min = episodes.pivot(index="variant", columns="method", values="d_min_m")
    row = held_out.set_index("metric").loc["d_min_m"]
    assert row["ours_diff"] == pytest.approx((d_min["casn"] - d_min["snl_matched"]).mean())


def test_gscl_rotations_enter_the_settings_and_digests_only_when_asked(tmp_path, capsys):
    """``--gscl-rotations 4`` is a setting of its own (its digests differ: a run with it is never
    resumed as one without); at 1 the settings hold no such key, so a run made before the option
    resumes; without method gscl the option is refused in one line."""
    from socialnav import cli
    from socialnav.data import SCENES_DIR
    from socialnav.evaluation.arena import table
    from socialnav.jaxsim.scenes.spec import load_scene

    specs = (load_scene(SCENES_DIR / "casn_head_on.json"),)
    plain = table.settings(table.TableRequest(specs=specs, methods=("navfn",), variants=2))
    averaged = table.settings(table.TableRequest(specs=specs, methods=("navfn",), variants=2, gscl_rotations=4))
    assert "gscl_rotations" not in plain and averaged["gscl_rotations"] == 4
    assert plain["scene_digests"] != averaged["scene_digests"]
    argv = ["arena", "--out", str(tmp_path / "run"), "--scenes", "casn_head_on", "--methods", "navfn"]
    assert cli.main([*argv, "--gscl-rotations", "4"]) == 2
    assert "--gscl-rotations: the run has no method gscl" in capsys.readouterr().err
