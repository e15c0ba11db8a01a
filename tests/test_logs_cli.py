"""Parquet logs (determinism, atomic writes, pandas without the simulator) and the command line."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from plans import scipy_shortest_plan

from socialnav import cli
from socialnav.common.memory import available_bytes
from socialnav.jaxsim import logs
from socialnav.jaxsim.route_follower import route_follower
from socialnav.jaxsim.scenario import load_scenario
from socialnav.jaxsim.world import build_world


@pytest.fixture(scope="module")
def small():
    return load_scenario(slot_length_s=20.0, n_workers=8)


def _run(scenario, out, **kw):
    args = dict(n_worlds=2, duration_s=40.0, seed=5, sample_interval_s=0.5, progress=False)
    args.update(kw)
    return logs.simulate_to_parquet(
        scenario, out, route_follower(scipy_shortest_plan(scenario), build_world(scenario)), **args
    )


@pytest.mark.slow
def test_logs_open_in_pandas_with_the_documented_columns(small, tmp_path):
    run = _run(small, tmp_path / "a", snapshot_time_s=10.0)
    df = pd.read_parquet(run.log_file)
    assert len(df) == run.rows == 2 * 80
    assert sorted(df.world.unique()) == [0, 1] and (df.seed == 5).all()
    assert (df.slot_length_s == 20.0).all() and (df.n_workers == 8).all()
    for col in (
        "time_s",
        "slot",
        "robot_speed_mps",
        "battery_pct",
        "charging",
        "obstacle",
        "robot_waypoint",
        "tasks_succeeded",
        "density_wa-2-l",
        "dist_worker_7",
    ):
        assert col in df.columns
    assert not any(c.startswith("worker_x_") for c in df.columns)
    t = df[df.world == 0].time_s.to_numpy()
    np.testing.assert_allclose(np.diff(t), 0.5, atol=1e-4)
    assert df.battery_pct.between(0, 100).all()
    meta = json.loads(run.meta_file.read_text())
    assert meta["waypoints"][0] == "parking" and len(meta["slots"]) == 11 and meta["rows"] == run.rows
    assert run.snapshot is not None and run.snapshot["time_s"] == pytest.approx(10.0)


@pytest.mark.slow
def test_same_seed_same_file_whatever_the_chunking(small, tmp_path):
    def read(out, **kw):
        df = pd.read_parquet(_run(small, out, **kw).log_file)
        return df.sort_values(["world", "time_s"], kind="stable").reset_index(drop=True)

    a = read(tmp_path / "a")
    pd.testing.assert_frame_equal(a, read(tmp_path / "a2"), check_exact=True)
    pd.testing.assert_frame_equal(a, read(tmp_path / "b", chunk_budget_bytes=1), check_exact=True)  # 1 sample/chunk
    c = read(tmp_path / "c", seed=6)
    cols = [f"dist_worker_{i}" for i in range(small.params.n_workers)]  # the crowd depends on the seed
    assert not np.array_equal(a[cols].to_numpy(), c[cols].to_numpy(), equal_nan=True)


@pytest.mark.slow
def test_positions_logged_on_request(small, tmp_path):
    df = pd.read_parquet(_run(small, tmp_path / "p", log_positions=True, duration_s=10.0).log_file)
    assert {"worker_x_0", "worker_y_7", "worker_status_3"} <= set(df.columns)


def test_bad_sizes_write_nothing(small, tmp_path):
    with pytest.raises(ValueError, match="multiple of dt_s"):
        _run(small, tmp_path / "x", sample_interval_s=0.05)
    with pytest.raises(ValueError, match="multiple of sample_interval_s"):
        _run(small, tmp_path / "x", duration_s=10.25)
    with pytest.raises(ValueError, match="n_worlds"):
        _run(small, tmp_path / "x", n_worlds=0)
    assert not (tmp_path / "x" / logs.LOG_FILE).exists()


def test_killed_run_leaves_no_half_file(small, tmp_path, monkeypatch):
    out = tmp_path / "k"
    _run(small, out)
    before = (out / logs.LOG_FILE).read_bytes()
    real = logs.record_table
    calls = {"n": 0}

    def fail_on_second_chunk(*a, **k):
        calls["n"] += 1
        if calls["n"] == 2:
            raise KeyboardInterrupt("killed")
        return real(*a, **k)

    monkeypatch.setattr(logs, "record_table", fail_on_second_chunk)
    with pytest.raises(KeyboardInterrupt):
        _run(small, out, chunk_budget_bytes=1, seed=9)
    assert (out / logs.LOG_FILE).read_bytes() == before  # the previous complete run is intact
    assert sorted(f.name for f in out.iterdir()) == [logs.LOG_FILE, logs.META_FILE]  # no temporary left


@pytest.mark.slow
def test_cli_simulate_writes_logs_pictures_and_summary(tmp_path, capsys):
    out = tmp_path / "cli"
    code = cli.main(
        [
            "simulate",
            "--worlds",
            "2",
            "--slots",
            "2",
            "--slot-length-s",
            "20",
            "--out",
            str(out),
            "--sample-interval-s",
            "1",
            "--no-progress",
        ]
    )
    assert code == 0
    for name in ("logs.parquet", "run.json", "snapshot.png", "density_by_slot.png"):
        assert (out / name).stat().st_size > 0
    assert (out / "snapshot.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    text = capsys.readouterr().out
    assert "M agent-steps/s" in text and "most crowded" in text
    assert len(pd.read_parquet(out / "logs.parquet")) == 2 * 40


def test_cli_rejects_bad_input(tmp_path, capsys):
    with pytest.raises(SystemExit):
        cli.main(["simulate", "--worlds", "0"])
    assert cli.main(["simulate", "--scenario", str(tmp_path / "nope"), "--out", str(tmp_path / "o")]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert (
        cli.main(
            [
                "simulate",
                "--slots",
                "1",
                "--slot-length-s",
                "20",
                "--sample-interval-s",
                "0.15",
                "--out",
                str(tmp_path / "o"),
                "--no-progress",
            ]
        )
        == 2
    )
    for option, value in (
        ("--slot-length-s", "inf"),
        ("--sample-interval-s", "nan"),
        ("--obstacle-probability", "1.5"),
        ("--worlds", "2.7"),
    ):
        with pytest.raises(SystemExit):
            cli.main(["simulate", option, value, "--out", str(tmp_path / "o")])
        assert value in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv, words",
    [
        (["--slots", "15"], "the scenario has 11 slots"),
        (["--slots", "1", "--slot-length-s", "60", "--snapshot-time-s", "1e9"], "after the run's end"),
        (["--worlds", "100000000"], "split the run with --shard-worlds"),
    ],
)
def test_cli_refuses_values_that_do_not_fit_the_run_before_any_work(tmp_path, capsys, argv, words):
    assert cli.main(["simulate", "--out", str(tmp_path / "o"), "--no-progress", *argv]) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1
    assert not (tmp_path / "o").exists()


@pytest.mark.skipif(available_bytes() is None, reason="no /proc/meminfo here: no memory check")
def test_the_python_entry_refuses_a_batch_past_the_memory_as_the_command_does(tmp_path):
    """``simulate_to_parquet`` refuses 10^8 worlds (hundreds of GB by its estimate) before it makes
    its folder, as ``socialnav simulate --worlds 100000000`` does; it was killed for memory."""
    scenario = load_scenario(slot_length_s=20.0, n_workers=5)
    driver = route_follower(scipy_shortest_plan(scenario), build_world(scenario))
    with pytest.raises(ValueError, match="n_worlds=100000000: about .* GB at once.*shards") as err:
        logs.simulate_to_parquet(scenario, tmp_path / "o", driver, n_worlds=10**8, duration_s=20.0, progress=False)
    assert "\n" not in str(err.value) and not (tmp_path / "o").exists()
