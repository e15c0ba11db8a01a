"""Run folders as units on the command line: a folder holding a run is refused without
``--overwrite``, which replaces that run whole and nothing else (a user's files beside it are
never touched, nor the job's own inputs); a killed job's temporaries are removed by the next."""

from __future__ import annotations

import json

import numpy as np
import pytest

from socialnav import cli
from socialnav.common import runfolder

SHORT = ["--worlds", "1", "--slots", "1", "--slot-length-s", "60", "--no-progress"]


def _user_files(folder):
    files = {"notes.txt": "my notes", "data/measurements.csv": "t,x\n0,1\n", ".hidden": "mine too"}
    for name, text in files.items():
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_text(text)
    return files


def _untouched(folder, files):
    return all((folder / name).read_text() == text for name, text in files.items())


@pytest.mark.slow
def test_simulate_refuses_a_previous_run_and_overwrite_replaces_it_whole(tmp_path, capsys):
    out = tmp_path / "run"
    assert cli.main(["simulate", "--out", str(out), "--seed", "1", *SHORT]) == 0
    first = (out / "logs.parquet").read_bytes()
    capsys.readouterr()

    assert cli.main(["simulate", "--out", str(out), *SHORT]) == 2
    err = capsys.readouterr().err
    assert "holds a previous run" in err and "--overwrite" in err and err.count("\n") == 1
    assert (out / "logs.parquet").read_bytes() == first  # untouched

    # A later step of the old run, recorded as its own run, and a user's files beside both.
    (out / "causal").mkdir()
    (out / "causal" / "report.json").write_text("{}")
    runfolder.record(out / "causal", "socialnav learn", ["report.json"], marker="report.json")
    mine = _user_files(out)
    (out / "causal" / "my-plot.png").write_text("a picture of mine")
    (out / ".socialnav-tmp-4242-logs.parquet").write_bytes(b"half a file of a killed run")
    assert cli.main(["simulate", "--out", str(out), "--overwrite", *SHORT]) == 0
    assert "removed what a killed job left" in capsys.readouterr().out
    assert json.loads((out / "run.json").read_text())["seed"] == 0
    assert (out / "logs.parquet").read_bytes() != first
    assert not (out / "causal" / "report.json").exists()  # the old run's derived results went with it
    assert (out / "causal" / "my-plot.png").read_text() == "a picture of mine"
    assert _untouched(out, mine)
    listed = runfolder.read_manifest(out)
    assert listed.job == "socialnav simulate" and listed.journal is None
    assert sorted(listed.files) == ["density_by_slot.png", "logs.parquet", "run.json", "snapshot.png"]


def test_a_folder_without_run_json_is_an_incomplete_run(tmp_path, capsys):
    out = tmp_path / "run"
    out.mkdir()
    (out / "logs.parquet").write_bytes(b"")
    runfolder.record(out, "socialnav simulate", ["logs.parquet"], marker="run.json")
    assert cli.main(["simulate", "--out", str(out), *SHORT]) == 2
    assert "incomplete run (no run.json" in capsys.readouterr().err


@pytest.mark.parametrize("overwrite", [False, True])
def test_a_users_file_under_a_result_name_is_never_replaced(tmp_path, capsys, overwrite):
    """No manifest lists it: refused with or without --overwrite, naming it, the file intact."""
    out = tmp_path / "mine"
    out.mkdir()
    (out / "logs.parquet").write_text("my own table")
    assert cli.main(["simulate", "--out", str(out), *SHORT, *(["--overwrite"] if overwrite else [])]) == 2
    err = capsys.readouterr().err
    assert "logs.parquet" in err and "no socialnav job recorded writing" in err and err.count("\n") == 1
    assert (out / "logs.parquet").read_text() == "my own table"
    assert sorted(p.name for p in out.iterdir()) == ["logs.parquet"]


@pytest.mark.slow
def test_overwrite_on_a_folder_of_user_files_leaves_them(tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    mine = _user_files(out)
    assert cli.main(["simulate", "--out", str(out), "--overwrite", *SHORT]) == 0
    assert _untouched(out, mine) and (out / "run.json").is_file()
    assert cli.main(["simulate", "--out", str(out), "--overwrite", "--seed", "3", *SHORT]) == 0  # and again
    assert _untouched(out, mine) and json.loads((out / "run.json").read_text())["seed"] == 3


@pytest.mark.slow
def test_learn_refuses_to_write_where_it_reads(learned_run, tmp_path, capsys):
    """``learn --logs L --out L --overwrite`` deleted its own logs once; now it is refused."""
    logs = (learned_run / "logs.parquet").read_bytes()
    assert cli.main(["learn", "--logs", str(learned_run), "--out", str(learned_run), "--overwrite"]) == 2
    err = capsys.readouterr().err
    assert "contains the job's input" in err and err.count("\n") == 1
    assert (learned_run / "logs.parquet").read_bytes() == logs
    assert cli.main(["learn", "--logs", str(learned_run), "--out", str(learned_run.parent), "--overwrite"]) == 2
    assert "contains the job's input" in capsys.readouterr().err


@pytest.mark.slow
def test_another_jobs_run_is_not_replaced(learned_run, tmp_path, capsys):
    """evaluate --overwrite into a folder holding a simulate run: refused, the run intact."""
    tables = learned_run / "causal" / "engine_tables.npz"
    sim = tmp_path / "sim"
    assert cli.main(["simulate", "--out", str(sim), *SHORT]) == 0
    before = sorted(p.name for p in sim.iterdir())
    capsys.readouterr()
    argv = ["evaluate", "--tables", str(tables), "--out", str(sim), "--replicas", "1", "--overwrite"]
    assert cli.main(argv) == 2
    assert "holds a run of 'socialnav simulate'" in capsys.readouterr().err
    assert sorted(p.name for p in sim.iterdir()) == before


def _finished_learn_run(folder, scenario):
    """``folder`` as ``simulate`` then ``learn`` leave it, as far as a command can tell before it
    starts work: the two manifests and their files. The logs are not a day's logs (a refusal must
    not read them), the engine's tables well-formed tables of the warehouse's waypoints and slots
    (``evaluate`` checks its ``--tables`` before its output folder)."""
    (folder / "causal").mkdir(parents=True)
    (folder / "run.json").write_text("{}")
    (folder / "logs.parquet").write_text("not read")
    (folder / "causal" / "report.json").write_text("{}")
    np.savez(
        folder / "causal" / "engine_tables.npz",
        density_ppm2=np.zeros((scenario.n_slots, scenario.n_waypoints)),
        battery_pct_per_s=np.array([[-0.006, 0.01], [-0.007, 0.0]]),
        speed_edges_mps=np.array([0.0, 0.3, 0.5]),
        waypoints=np.array(scenario.waypoint_ids),
        slots=np.array(scenario.slot_names),
    )
    runfolder.record(folder, "socialnav simulate", ["run.json", "logs.parquet"], marker="run.json")
    runfolder.record(folder / "causal", "socialnav learn", ["report.json", "engine_tables.npz"], marker="report.json")
    return folder


def test_learn_and_evaluate_refuse_to_replace_their_results(warehouse, tmp_path, capsys):
    """Both refuse before any work (the learned engine is kept as it is)."""
    learned_run = _finished_learn_run(tmp_path / "run", warehouse)
    report = (learned_run / "causal" / "report.json").read_bytes()
    assert cli.main(["learn", "--logs", str(learned_run), "--no-progress"]) == 2
    assert "causal holds a previous run" in capsys.readouterr().err
    assert (learned_run / "causal" / "report.json").read_bytes() == report

    evaluation = tmp_path / "evaluation"
    evaluation.mkdir()
    (evaluation / "summary.json").write_text("{}")
    runfolder.record(evaluation, "socialnav evaluate", ["summary.json"], marker="summary.json")
    tables = learned_run / "causal" / "engine_tables.npz"
    assert cli.main(["evaluate", "--tables", str(tables), "--out", str(evaluation), "--replicas", "1"]) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert (evaluation / "summary.json").read_text() == "{}"


def test_names_that_reach_paths_are_checked(tmp_path):
    assert runfolder.check_name("casn_head_on@held_out", "scene") == "casn_head_on@held_out"
    for bad in ("../../victim", "", ".hidden", "-x", "a/b", "a..b", "x" * 101, "ü" * 101, "é\u0301", None):
        with pytest.raises(ValueError, match="cannot name a file"):
            runfolder.check_name(bad, "scene")
    for unicode in ("Küche", "出口-2", "ü" * 100):  # letters of any script (they named waypoints before)
        assert runfolder.check_name(unicode, "waypoint") == unicode
    with pytest.raises(ValueError, match=r"the character\(s\) ' ', '/' are not allowed"):
        runfolder.check_name("my room/2", "waypoint")
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "link").symlink_to(tmp_path)
    assert runfolder.inside(tmp_path / "out", tmp_path / "out" / "a" / "b.parquet")
    with pytest.raises(runfolder.NotOurs, match="outside the output folder"):
        runfolder.inside(tmp_path / "out", tmp_path / "out" / "link" / "x.parquet")
    with pytest.raises(runfolder.NotOurs, match="outside the output folder"):
        runfolder.inside(tmp_path / "out", tmp_path / "out" / ".." / "x.parquet")


def test_a_scene_whose_name_would_leave_the_folder_is_refused(tmp_path):
    from socialnav.data import SCENES_DIR
    from socialnav.jaxsim.scenario.errors import ScenarioError
    from socialnav.jaxsim.scenes.spec import load_scene

    obj = json.loads((SCENES_DIR / "casn_static_person.json").read_text())
    for name in ("../../victim", "a/b", ""):
        path = tmp_path / "scene.json"
        path.write_text(json.dumps({**obj, "name": name}))
        with pytest.raises(ScenarioError, match="cannot name the scene's result files"):
            load_scene(path)
    bad = {**obj, "robot": {**obj["robot"], "goal": obj["robot"]["start"]}}
    path.write_text(json.dumps(bad))
    with pytest.raises(ScenarioError, match="robot.goal"):
        load_scene(path)
