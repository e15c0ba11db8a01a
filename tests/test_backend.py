"""Batch jobs cut into shards, run here or as Ray tasks: the same results, retries, resumption.

The Ray tests start a local Ray instance (two CPUs, this machine only) once per module; they are
in the slow tier (CI runs them with the ``ray`` extra installed) and skipped where Ray is absent.
"""

from __future__ import annotations

import json
import os
import pathlib
import sys

import numpy as np
import pandas as pd
import pytest

from socialnav import backend, cli

# Ray's workers run simulate, GSCL and the arena in processes of their own, reading back the
# programs other files compiled: the file starts after those (tests/suite_order.py).
pytestmark = pytest.mark.runs_jobs_elsewhere


def _write_number(shard, result) -> None:
    from socialnav.common.atomic import write_text_atomic

    write_text_atomic(shard.output, json.dumps(result))


def _square(x):
    return x * x


def _shards(tmp_path, n=4):
    return [backend.Shard(name=f"s{k}", output=tmp_path / f"{k}.json", args=(k,)) for k in range(n)]


# ---------------------------------------------------------------- local backend: resumption, errors


def test_local_shards_compute_what_is_missing_and_a_rerun_after_a_killed_driver_skips_the_rest(tmp_path):
    shards = _shards(tmp_path)
    calls = []

    def compute(x):
        calls.append(x)
        return _square(x)

    class Killed(Exception):
        pass

    def save_then_die(shard, result):
        _write_number(shard, result)
        if shard.args[0] == 1:
            raise Killed  # the driver dies after saving shard 1

    with pytest.raises(Killed):
        backend.run_shards(compute, save_then_die, shards, progress=False)
    assert calls == [0, 1] and {p.name for p in tmp_path.iterdir()} == {"0.json", "1.json"}
    assert backend.run_shards(compute, _write_number, shards, progress=False) == 2
    assert calls == [0, 1, 2, 3]  # 0 and 1 were not computed again
    assert [json.loads(s.output.read_text()) for s in shards] == [0, 1, 4, 9]
    assert backend.run_shards(compute, _write_number, shards, progress=False) == 0
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".socialnav-tmp")]  # nothing half written


def test_unknown_backend_and_missing_ray_are_one_line_errors(tmp_path, monkeypatch):
    with pytest.raises(backend.BackendError, match="--backend must be one of local, ray"):
        backend.run_shards(_square, _write_number, _shards(tmp_path), backend="dask", progress=False)
    monkeypatch.setitem(sys.modules, "ray", None)  # "import ray" raises ImportError
    with pytest.raises(backend.BackendError, match=r"pip install 'socialnav-jax\[ray\]'"):
        backend.run_shards(_square, _write_number, _shards(tmp_path), backend="ray", progress=False)


def test_an_unreachable_cluster_is_a_one_line_error_within_seconds(tmp_path):
    pytest.importorskip("ray")
    import socket

    with socket.socket() as sock:  # a port nothing listens on
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    with pytest.raises(backend.BackendError, match=f"cannot reach the Ray cluster at 127.0.0.1:{port}"):
        backend.run_shards(
            _square, _write_number, _shards(tmp_path), backend="ray", address=f"127.0.0.1:{port}", progress=False
        )
    assert not list(tmp_path.iterdir())


def test_the_worker_environment_carries_the_drivers_device_count(monkeypatch):
    import jax

    n = jax.local_device_count()  # the backend starts with the flags it was given
    monkeypatch.setenv("XLA_FLAGS", "--xla_force_host_platform_device_count=7 --xla_cpu_use_thunk_runtime=true")
    env = backend._worker_env()
    assert f"--xla_force_host_platform_device_count={n}" in env["XLA_FLAGS"]
    assert "--xla_cpu_use_thunk_runtime=true" in env["XLA_FLAGS"] and "count=7" not in env["XLA_FLAGS"]


def test_the_worker_environment_carries_the_social_force_switch(monkeypatch):
    monkeypatch.setenv("SOCIALNAV_NATIVE", "off")
    monkeypatch.setenv("SOCIALNAV_NATIVE_CACHE", "/tmp/somewhere")
    env = backend._worker_env()
    assert env["SOCIALNAV_NATIVE"] == "off" and env["SOCIALNAV_NATIVE_CACHE"] == "/tmp/somewhere"
    monkeypatch.delenv("SOCIALNAV_NATIVE")
    assert "SOCIALNAV_NATIVE" not in backend._worker_env()


@pytest.mark.slow
def test_simulate_in_shards_gives_the_worlds_of_one_run_to_float_rounding(tmp_path):
    """Worlds cut into shards are the same worlds (keys by world index); across batch shapes the
    numbers agree to float rounding (the README says so), row order aside."""
    common = ["simulate", "--worlds", "2", "--hours", "0.01", "--no-progress"]
    assert cli.main([*common, "--out", str(tmp_path / "one")]) == 0
    assert cli.main([*common, "--out", str(tmp_path / "two"), "--shard-worlds", "1"]) == 0
    assert (tmp_path / "two" / "logs.parquet").is_dir() and not (tmp_path / "two" / ".shards").exists()
    a = pd.read_parquet(tmp_path / "one" / "logs.parquet").sort_values(["world", "time_s"], ignore_index=True)
    b = pd.read_parquet(tmp_path / "two" / "logs.parquet").sort_values(["world", "time_s"], ignore_index=True)
    assert list(a.columns) == list(b.columns) and len(a) == len(b)
    pd.testing.assert_frame_equal(a, b, check_exact=False, atol=1e-4, rtol=1e-5)
    meta = json.loads((tmp_path / "two" / "run.json").read_text())
    assert meta["n_worlds"] == 2 and meta["rows"] == len(b) and meta["backend"] == "local"
    assert meta["shards"] == [{"first_world": 0, "n_worlds": 1}, {"first_world": 1, "n_worlds": 1}]


@pytest.mark.slow
def test_gscl_generate_in_shards_is_the_same_dataset_bit_for_bit(tmp_path):
    args = ["gscl", "generate", "--scale", "0.001", "--count", "queue=1500", "--count", "corner=300"]
    assert cli.main([*args, "--out", str(tmp_path / "a.npz")]) == 0
    assert cli.main([*args, "--out", str(tmp_path / "b.npz"), "--shard-samples", "1000", "--no-progress"]) == 0
    a, b = np.load(tmp_path / "a.npz"), np.load(tmp_path / "b.npz")
    assert sorted(a.files) == sorted(b.files)
    for key in a.files:
        np.testing.assert_array_equal(a[key], b[key])
    assert not (tmp_path / ".b.npz.shards").exists()
    made = json.loads((tmp_path / "b.json").read_text())
    assert made["seed"] == 0 and made["shard_samples"] == 1000 and made["backend"] == "local"
    assert made["counts"]["queue"] == 1500


# ---------------------------------------------------------------- Ray (slow tier)


@pytest.fixture(scope="module")
def ray_instance():
    ray = pytest.importorskip("ray")
    backend._connect(None)  # a local instance with this machine's CPUs, the driver's device layout
    ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])  # ship this module's functions
    yield ray
    ray.shutdown()


def _die_once(marker: str, x: int):
    """Kill the worker process the first time (a machine lost mid-shard), succeed the second."""
    path = pathlib.Path(marker)
    if not path.exists():
        path.write_text("died once")
        os._exit(1)
    return x * x


@pytest.mark.slow
def test_ray_retries_a_killed_task_and_saves_each_shard_once(tmp_path, ray_instance):
    marker = tmp_path / "marker"
    shards = [
        backend.Shard(name=f"s{k}", output=tmp_path / f"{k}.json", args=(str(marker) if k == 2 else str(tmp_path), k))
        for k in range(4)
    ]
    saved = []

    def save(shard, result):
        saved.append(shard.name)
        _write_number(shard, result)

    assert backend.run_shards(_die_once, save, shards, backend="ray", progress=False) == 4
    assert marker.read_text() == "died once"  # shard 2's first worker did die
    assert sorted(saved) == ["s0", "s1", "s2", "s3"]  # each saved once, none lost
    assert [json.loads(s.output.read_text()) for s in shards] == [0, 1, 4, 9]


@pytest.mark.slow
def test_ray_and_local_give_the_same_bits_for_simulate_gscl_and_arena(tmp_path, ray_instance):
    sim = ["simulate", "--worlds", "2", "--hours", "0.01", "--shard-worlds", "1", "--no-progress"]
    assert cli.main([*sim, "--out", str(tmp_path / "sim-local")]) == 0
    assert cli.main([*sim, "--out", str(tmp_path / "sim-ray"), "--backend", "ray"]) == 0
    pd.testing.assert_frame_equal(
        pd.read_parquet(tmp_path / "sim-local" / "logs.parquet"), pd.read_parquet(tmp_path / "sim-ray" / "logs.parquet")
    )
    assert json.loads((tmp_path / "sim-ray" / "run.json").read_text())["backend"] == "ray"

    gen = ["gscl", "generate", "--scale", "0.001", "--count", "group=1100", "--shard-samples", "1024", "--no-progress"]
    assert cli.main([*gen, "--out", str(tmp_path / "local.npz")]) == 0
    assert cli.main([*gen, "--out", str(tmp_path / "ray.npz"), "--backend", "ray"]) == 0
    a, b = np.load(tmp_path / "local.npz"), np.load(tmp_path / "ray.npz")
    for key in a.files:
        np.testing.assert_array_equal(a[key], b[key])

    arena = ["arena", "--scenes", "casn_static_person", "--methods", "navfn", "--variants", "4"]
    arena += ["--shard-variants", "2", "--keep-trajectories", "0", "--no-progress"]
    assert cli.main([*arena, "--out", str(tmp_path / "arena-local")]) == 0
    assert cli.main([*arena, "--out", str(tmp_path / "arena-ray"), "--backend", "ray"]) == 0
    name = "episodes/casn_static_person.parquet"
    pd.testing.assert_frame_equal(
        pd.read_parquet(tmp_path / "arena-local" / name), pd.read_parquet(tmp_path / "arena-ray" / name)
    )
    assert not (tmp_path / "arena-ray" / "shards").exists()


@pytest.mark.slow
def test_ray_and_local_evaluate_the_same_replicas(tmp_path, ray_instance, learned_run):
    tables = learned_run / "causal" / "engine_tables.npz"
    ev = ["evaluate", "--tables", str(tables), "--replicas", "2", "--shard-replicas", "1", "--slots", "S11"]
    ev += ["--no-progress"]
    assert cli.main([*ev, "--out", str(tmp_path / "local")]) == 0
    assert cli.main([*ev, "--out", str(tmp_path / "ray"), "--backend", "ray"]) == 0
    a = pd.read_parquet(tmp_path / "local" / "tasks.parquet")
    b = pd.read_parquet(tmp_path / "ray" / "tasks.parquet")
    pd.testing.assert_frame_equal(a, b)
    assert sorted(a["replica"].unique()) == [0, 1]
    one = ["evaluate", "--tables", str(tables), "--replicas", "2", "--slots", "S11", "--no-progress"]
    assert cli.main([*one, "--out", str(tmp_path / "one")]) == 0
    whole = pd.read_parquet(tmp_path / "one" / "tasks.parquet")
    assert len(whole) == len(a) and list(whole["method"]) == list(a["method"])
    assert not (tmp_path / "ray" / ".shards").exists()
