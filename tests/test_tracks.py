"""People's tracks as demonstrations (planners.learning.tracks): a planned path written as a track file
comes back as the same moves; the map and the other people are drawn; bad files are named."""

import jax.numpy as jnp
import numpy as np
import pandas as pd
import pytest
from PIL import Image

from socialnav.models import grid
from socialnav.planners.global_planners import grid_planner
from socialnav.planners.learning import irl, ros_map, tracks


def _write_map(folder, occupied_xy_m, size_m=30.0, resolution_m=0.1):
    """A ROS map_server pair: walls at the given (x0, y0, x1, y1) boxes, origin (0, 0)."""
    n = int(size_m / resolution_m)
    occ = np.zeros((n, n), bool)  # row 0 at y = 0
    for x0, y0, x1, y1 in occupied_xy_m:
        occ[int(y0 / resolution_m) : int(y1 / resolution_m), int(x0 / resolution_m) : int(x1 / resolution_m)] = True
    pixels = np.where(occ, 0, 254).astype(np.uint8)[::-1]  # black = occupied, top row = highest y
    Image.fromarray(pixels).save(folder / "map.pgm")
    (folder / "map.yaml").write_text(
        f"image: map.pgm\nresolution: {resolution_m}\norigin: [0.0, 0.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\n"
    )
    return folder / "map.yaml"


@pytest.mark.slow
def test_a_planned_path_written_as_a_track_comes_back_as_the_same_demonstration(tmp_path):
    yaml_path = _write_map(tmp_path, [(12.0, 16.0, 18.0, 16.6)])  # a wall 1-1.6 m above the start
    occupancy, resolution, origin = ros_map.read_ros_map(yaml_path)
    assert occupancy.shape == (300, 300) and resolution == 0.1 and occupancy[160, 150] == 1 and occupancy[100, 150] == 0
    start = np.array([15.0, 15.0])
    # The window the tracks module will draw, and an exact plan on it from the centre over the wall.
    from socialnav.models.inference import input_map

    window = np.asarray(
        input_map(occupancy, resolution, origin, start, np.zeros((0, 2)), np.zeros(0), start + [0.5, 4.0])
    )
    walls = window == grid.WALL
    assert walls.any()
    goal_cell = tuple(int(v) for v in grid.cell_of(0.5 + 0.01, 4.0 + 0.01))
    t = np.where(walls, np.inf, 50.0)
    plan = grid_planner.plan(t, grid.cell_of(0.0, 0.0), goal_cell, grid.CELL_M)
    assert bool(plan.reached)
    cells = np.asarray(plan.path_ij)[: int(plan.path_length)]
    local = np.stack([grid.CELL_X_M[cells[:, 0], cells[:, 1]], grid.CELL_Y_M[cells[:, 0], cells[:, 1]]], axis=1)
    points = np.concatenate([[start], start + local[1:]])
    walker = pd.DataFrame({"frame": np.arange(len(points)), "id": "w", "x": points[:, 0], "y": points[:, 1]})
    bystander = pd.DataFrame({"frame": [0, 1], "id": "b", "x": [13.0, 13.0], "y": [14.0, 13.9]})
    file = tmp_path / "tracks.csv"
    pd.concat([bystander, walker]).sample(frac=1.0, random_state=0).to_csv(file, index=False)

    read = tracks.read_tracks(file)
    assert sorted(read) == ["b", "w"] and np.all(np.diff(read["w"][:, 0]) > 0)
    maps, demos, report = tracks.track_demonstrations(read, occupancy, resolution, origin)
    assert report["ids"] == ["w"] and report["left_out"] == {"fewer than 2 cells": 1}  # b steps 0.1 m in its cell
    np.testing.assert_array_equal(demos.moves[0], np.asarray(irl.path_moves(jnp.asarray(cells))))
    assert tuple(demos.goal_ij[0]) == goal_cell and demos.starts[0][tuple(cells[0])] == 1
    # The walker's view: the wall, the bystander 2 m left and 1 m down heading down, the goal.
    assert np.array_equal(maps[0] == grid.WALL, walls)
    person = tuple(int(v) for v in grid.cell_of(-2.0, -1.0))
    assert maps[0][person] == grid.PERSON and maps[0][person[0] + 1, person[1]] == grid.HEADING
    assert maps[0][goal_cell] == grid.GOAL
    # The likelihood of the demonstration is finite and positive on any cost map.
    nll = float(
        irl.path_nll(
            jnp.full((40, 40), 0.1),
            maps[0],
            irl.Demonstrations(*[a[0] for a in (demos.moves, demos.starts, demos.goal_ij, demos.n_paths)]),
        )
    )
    assert 0 < nll < 1e3


@pytest.mark.slow
def test_a_track_through_a_wall_is_left_out_and_counted(tmp_path):
    yaml_path = _write_map(tmp_path, [(14.0, 16.0, 16.0, 16.6)])
    occupancy, resolution, origin = ros_map.read_ros_map(yaml_path)
    ys = np.linspace(15.0, 18.0, 7)
    through = {"t": np.stack([np.arange(7), np.full(7, 15.0), ys], axis=1)}
    maps, demos, report = tracks.track_demonstrations(through, occupancy, resolution, origin)
    assert len(maps) == 0 and report["left_out"] == {"enters a wall cell": 1}
    around = {"a": np.stack([np.arange(7), np.full(7, 17.0), ys], axis=1)}
    maps, demos, report = tracks.track_demonstrations(around, occupancy, resolution, origin)
    assert len(maps) == 1 and report["used"] == 1 and float(demos.n_paths[0]) == 1


def test_a_track_that_leaves_the_window_ends_where_it_leaves(tmp_path):
    yaml_path = _write_map(tmp_path, [])
    occupancy, resolution, origin = ros_map.read_ros_map(yaml_path)
    xs = np.linspace(5.0, 25.0, 41)  # 20 m straight east: the window reaches 8 m
    maps, demos, _ = tracks.track_demonstrations(
        {"e": np.stack([np.arange(41), xs, np.full(41, 15.0)], axis=1)}, occupancy, resolution, origin
    )
    goal = tuple(int(v) for v in demos.goal_ij[0])
    assert goal[0] == 20 and goal[1] >= 38 and maps[0][goal] == grid.GOAL
    assert float(demos.moves[0].sum()) == goal[1] - 20


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("frame,id,x\n0,a,1.0\n", "column 'y' is missing"),
        ("frame,id,x,y\n0,a,1.0,nan\n", "column 'y', row 2"),
        ("frame,id,x,y\n0.5,a,1.0,2.0\n", "column 'frame', row 2"),
        ("frame,id,x,y\n0,a,1.0,2.0\n1,a,1,2\n0,a,3,3\n", "appears twice in frame 0"),
        ("frame,id,x,y\n", "no rows"),
        # each of these was read without a word: rows dropped, a frame wrapped, a column chosen
        ("frame,id,x,y\n0,a,1,2\n1,,1,3\n", "column 'id', row 3: empty"),
        ("frame,id,x,y\n100000000000000000000,a,1,2\n1,a,1,3\n", "column 'frame', row 2: .*within"),
        ("frame,id,x,y\nTrue,a,1,2\nFalse,a,1,3\n", "column 'frame': true/false"),
        ("frame,id,x,y,x\n0,a,1,2,5\n1,a,1,3,6\n", "column 'x' is given 2 times"),
        ('"frame","id","x","y",x\n0,a,1,2,5\n1,a,1,3,6\n', "column 'x' is given 2 times"),  # quoted names
        ("frame;id;x;y\n0;a;1;2\n", "found frame;id;x;y.*comma-separated"),
    ],
)
def test_bad_track_files_are_named_with_their_field(tmp_path, content, message):
    file = tmp_path / "t.csv"
    file.write_text(content)
    with pytest.raises(tracks.TrackFileError, match=message) as err:
        tracks.read_tracks(file)
    assert str(file) in str(err.value) and "\n" not in str(err.value)


def test_a_parquet_track_file_names_its_rows_from_one(tmp_path):
    """A Parquet file has no header line: its first row is row 1 (a CSV's first row is line 2)."""
    file = tmp_path / "t.parquet"
    pd.DataFrame({"frame": [0, 1, 2], "id": ["a", "a", None], "x": [1.0, 1.0, 1.0], "y": [0.0, 0.1, 0.2]}).to_parquet(
        file
    )
    with pytest.raises(tracks.TrackFileError, match="column 'id', row 3: empty"):
        tracks.read_tracks(file)


def test_a_track_file_of_another_suffix_is_refused(tmp_path):
    with pytest.raises(tracks.TrackFileError, match=r"\.csv or \.parquet"):
        tracks.read_tracks(tmp_path / "t.txt")


def test_a_map_far_from_zero_draws_the_same_windows_as_at_zero(tmp_path):
    """Tracks and map in a world frame far from the origin (UTM: x ~ 5e5 m, y ~ 5e6 m, where
    float32 steps by 0.5 m) make the same windows and demonstrations as the same scene at zero:
    positions are taken from the map's origin in float64 before the windows' float32."""
    yaml_path = _write_map(tmp_path, [(12.0, 16.0, 18.0, 16.6)])
    occupancy, resolution, origin = ros_map.read_ros_map(yaml_path)
    near = {
        p: np.stack([np.arange(20), 12.0 + 0.3 * np.arange(20), 10.0 + 1.1 * p + 0.05 * np.arange(20)], 1)
        for p in range(6)
    }
    shift = np.array([0.0, 500_000.0, 5_000_000.0])
    far = {p: t + shift for p, t in near.items()}
    at_zero = tracks.track_demonstrations(near, occupancy, resolution, origin)
    at_utm = tracks.track_demonstrations(far, occupancy, resolution, (origin[0] + shift[1], origin[1] + shift[2]))
    assert at_zero[2]["used"] == at_utm[2]["used"] >= 4
    np.testing.assert_array_equal(at_zero[0], at_utm[0])
    np.testing.assert_array_equal(np.asarray(at_zero[1].moves), np.asarray(at_utm[1].moves))
    assert (at_zero[0] == grid.WALL).any() and (at_zero[0] == grid.PERSON).any()


def _walks(x_of_frame) -> list[tuple]:
    """Six people walking along x at y = 10-15 m, 20 frames each."""
    return [(f, person, x_of_frame(f), 10.0 + person) for person in range(6) for f in range(20)]


@pytest.mark.parametrize(
    ("where", "x_of_frame", "refused"),
    [
        ("on the map", lambda f: 1.0 + 0.5 * f, False),
        ("the last frame past its edge (95 % on it)", lambda f: 20.0 + 0.55 * f, False),
        ("100 m away", lambda f: 101.0 + 0.5 * f, True),
        ("in centimetres", lambda f: 100.0 * (1.0 + 0.5 * f), True),
        ("at 1e12 m", lambda f: 1e12 + f, True),
    ],
)
def test_tracks_off_the_map_are_refused_before_any_work(tmp_path, where, x_of_frame, refused):
    """Tracks another frame or unit than their map's are refused in one line naming both files
    and where each lies, before any work; a recording a little wider than its map passes."""
    from socialnav import cli

    yaml_path = _write_map(tmp_path, [])  # 30 m x 30 m from the origin
    pd.DataFrame(_walks(x_of_frame), columns=["frame", "id", "x", "y"]).to_csv(tmp_path / "t.csv", index=False)
    occupancy, resolution, origin = ros_map.read_ros_map(yaml_path)
    read = tracks.read_tracks(tmp_path / "t.csv")
    if not refused:
        assert tracks.check_on_map(read, occupancy, resolution, origin) >= tracks.MIN_ON_MAP_SHARE
        return
    with pytest.raises(tracks.TrackFileError, match="lie on the map") as err:
        tracks.check_on_map(read, occupancy, resolution, origin, tmp_path / "t.csv", yaml_path)
    assert "\n" not in str(err.value) and "map.yaml" in str(err.value) and "t.csv" in str(err.value)
    argv = ["gscl", "fit-tracks", "--tracks", str(tmp_path / "t.csv"), "--map", str(yaml_path)]
    with pytest.raises(SystemExit, match="columns 'x', 'y'"):
        cli.main([*argv, "--out", str(tmp_path / "m"), "--steps", "2", "--no-progress"])
    assert not (tmp_path / "m").exists()


@pytest.mark.slow
def test_fit_tracks_command_fits_exports_a_loadable_model_and_names_bad_files(tmp_path, capsys):
    from socialnav import cli
    from socialnav.models.inference import SocialCostModel

    yaml_path = _write_map(tmp_path, [(14.0, 13.0, 16.0, 15.5)])  # a pillar people pass on its north side
    rows = []
    rng = np.random.default_rng(0)
    for person in range(24):
        y0 = 14.5 + rng.uniform(-0.3, 0.3)
        xs = np.linspace(9.0, 21.0, 49)
        ys = y0 + 2.8 * np.exp(-(((xs - 15.0) / 2.0) ** 2))  # up and over the pillar
        rows += [(f, person, x, y) for f, (x, y) in enumerate(zip(xs, ys, strict=True))]
    pd.DataFrame(rows, columns=["frame", "id", "x", "y"]).to_parquet(tmp_path / "tracks.parquet")
    out = tmp_path / "model"
    argv = ["gscl", "fit-tracks", "--tracks", str(tmp_path / "tracks.parquet"), "--map", str(yaml_path)]
    assert cli.main([*argv, "--out", str(out), "--steps", "60", "--batch-size", "8", "--no-progress"]) == 0
    printed = capsys.readouterr().out
    assert "24 of 24 tracks made demonstrations" in printed
    first, last = (float(v) for v in printed.split("per path ")[1].split(" nats")[0].split(" -> "))
    assert last < first
    assert (out / "demonstrations.png").stat().st_size > 1000
    model = SocialCostModel.load(out)
    assert model.config.objective == "paths" and model(np.zeros((40, 40), np.uint8)).shape == (40, 40)
    with pytest.raises(SystemExit, match="tracks.csv: column 'x' is missing"):
        (tmp_path / "tracks.csv").write_text("frame,id,y\n0,a,1\n")
        cli.main([*argv[:3], str(tmp_path / "tracks.csv"), *argv[4:], "--out", str(tmp_path / "m2")])
    assert not (tmp_path / "m2" / "weights.msgpack").exists()


@pytest.mark.slow
def test_simulated_tracks_keep_variants_apart_and_walkers_make_demonstrations():
    from socialnav.data import DATA_DIR
    from socialnav.jaxsim.scenes.spec import load_scene

    spec = load_scene(DATA_DIR / "scenes" / "casn_crossing.json")
    people, occupancy, resolution, origin = tracks.simulated_tracks(spec, seed=0, variants=3, seconds=8.0)
    variant_frames = {}
    for pid, t in people.items():
        variant_frames.setdefault(pid.split(":")[0], set()).update(t[:, 0].astype(int))
        assert np.all(np.diff(t[:, 0]) > 0) and np.isfinite(t).all()
    assert sorted(variant_frames) == ["0", "1", "2"]
    frames = list(variant_frames.values())
    assert all(not (a & b) for i, a in enumerate(frames) for b in frames[i + 1 :])  # no shared frame
    maps, demos, report = tracks.track_demonstrations(people, occupancy, resolution, origin)
    assert report["used"] >= 3 and len(maps) == report["used"]
    # A walker starts in its window's centre and never stands in a wall cell.
    robot = tuple(int(v) for v in grid.cell_of(0.0, 0.0))
    assert np.all(demos.starts[:, robot[0], robot[1]] == 1)
    assert np.all(demos.moves.sum(1)[maps == grid.WALL] == 0)


def test_fit_tracks_refuses_an_unknown_scene_or_missing_sources_before_writing(tmp_path):
    from socialnav import cli

    out = tmp_path / "m"
    with pytest.raises(SystemExit, match="--scene: no scene .*no_such_scene.json \\(built-in: casn_crossing"):
        cli.main(["gscl", "fit-tracks", "--scene", "no_such_scene", "--out", str(out)])
    with pytest.raises(SystemExit, match="give --tracks and --map, or --recording, or --scene"):
        cli.main(["gscl", "fit-tracks", "--tracks", "t.csv", "--out", str(out)])
    with pytest.raises(SystemExit, match="give --tracks and --map, or --recording, or --scene"):
        cli.main(["gscl", "fit-tracks", "--recording", "students001", "--scene", "casn_crossing", "--out", str(out)])
    with pytest.raises(SystemExit, match="--recording: no shipped run 'students009' \\(shipped: .*students001"):
        cli.main(["gscl", "fit-tracks", "--recording", "students009", "--out", str(out)])
    assert not out.exists()


@pytest.mark.slow
def test_recorded_tracks_are_the_runs_people_on_a_map_with_the_data_walls():
    """An ETH/UCY file: every person a track, in time order, on a map free everywhere and wide
    enough for each track's 16 m window; a Jülich corridor: its walls occupied, its floor free."""
    from socialnav.data import recorded

    people, occupancy, resolution, origin = tracks.recorded_tracks("crowds_zara03")
    rows = recorded.trajectories("crowds_zara03")
    assert len(people) == rows["person"].nunique() and not occupancy.any()
    assert sum(len(t) for t in people.values()) == len(rows)
    assert all(np.all(np.diff(t[:, 0]) > 0) for t in people.values())
    extent = np.array(origin) + np.array(occupancy.shape[::-1]) * resolution
    assert np.all(rows[["x_m", "y_m"]].min().to_numpy() - origin >= grid.HALF_M - 1e-6)
    assert np.all(extent - rows[["x_m", "y_m"]].max().to_numpy() >= grid.HALF_M - 1e-6)
    maps, _, report = tracks.track_demonstrations(people, occupancy, resolution, origin)
    assert report["used"] == report["tracks"] and not (maps == grid.WALL).any()

    people, occupancy, resolution, origin = tracks.recorded_tracks("bi_corr_400_b_03")
    width = recorded.run_info("bi_corr_400_b_03")["geometry"]["corridor_width_m"]
    cell = lambda x, y: occupancy[int((y - origin[1]) / resolution), int((x - origin[0]) / resolution)]
    assert cell(0.0, width / 2) == 0 and cell(0.0, -0.5) == 1 and cell(0.0, width + 0.5) == 1
