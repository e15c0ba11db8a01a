"""Fuzzing the inputs a user hands the toolkit: scenario files, logs, engine tables, training
configs and model input maps, corrupted at random (seeded). Each case must end in the reader's
one documented error (naming the file) or in a correct result whose invariants hold, never in
another exception (a traceback for the user) or a silent pass of broken data.

The number of cases per input kind is ``FUZZ_CASES`` (default 40 in the default run; CI sets a
larger number through the slow tier's copy of each test). Each test prints its tally, e.g.
``scenario: 40 cases, 31 refused, 9 accepted``.
"""

from __future__ import annotations

import io
import json
import math
import os
import pathlib
import shutil

import numpy as np
import pytest

from socialnav.causal.extract import LogError, read_run
from socialnav.data import WAREHOUSE_DIR
from socialnav.jaxsim.scenario import ScenarioError, load_scenario
from socialnav.models.config import TrainConfig
from socialnav.planners.warehouse.tables import CausalTables, TablesError

FAST_CASES = int(os.environ.get("FUZZ_CASES", "40"))
SLOW_CASES = 400
SCENARIO_FILES = ("params.json", "waypoints.json", "walls.json", "graph.json", "schedule.json", "tasks.json")
ODD_VALUES = (None, "", "x", -1, 0, 1, 2.7, -1e9, 1e308, [], {}, True, [1, 2], {"a": 1})


def _paths(obj, prefix=()):
    """Every path (tuple of keys) into a JSON tree."""
    yield prefix
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from _paths(v, prefix + (i,))


def _mutate_json(obj, rng):
    """One random change at a random place: a value replaced by an odd one, a key dropped, a
    list item duplicated or dropped, a number scaled or negated, NaN or inf put in."""
    paths = [p for p in _paths(obj) if p and not (isinstance(p[-1], str) and p[-1].startswith("_"))]
    path = paths[rng.integers(len(paths))]
    parent = obj
    for k in path[:-1]:
        parent = parent[k]
    key = path[-1]
    value = parent[key]
    kind = rng.integers(6)
    if kind == 0:
        parent[key] = ODD_VALUES[rng.integers(len(ODD_VALUES))]
    elif kind == 1:
        del parent[key]
    elif kind == 2 and isinstance(value, list) and value:
        value.append(value[rng.integers(len(value))]) if rng.random() < 0.5 else value.pop(rng.integers(len(value)))
    elif kind == 3 and isinstance(value, (int, float)) and not isinstance(value, bool):
        parent[key] = value * float(rng.choice([-1.0, 0.0, 1e-9, 1e9]))
    elif kind == 4:
        parent[key] = float(rng.choice([math.nan, math.inf, -math.inf]))
    else:
        parent[key] = str(value)


def _check_scenario(s) -> None:
    """Invariants of a scenario the loader accepted."""
    s.params.validate()
    assert np.allclose(s.destination_p.sum(axis=1), 1.0)
    assert (s.destination_p >= 0).all()
    assert np.isfinite(s.waypoint_xy_m).all() and (s.waypoint_radius_m > 0).all()
    assert (s.boxes_m[:, 0] < s.boxes_m[:, 1]).all() and (s.boxes_m[:, 2] < s.boxes_m[:, 3]).all()
    assert len(s.robot_goals) == s.n_slots and all(len(g) for g in s.robot_goals)


def fuzz_scenarios(tmp_path: pathlib.Path, n: int, seed: int) -> dict[str, int]:
    rng = np.random.default_rng(seed)
    tally = {"refused": 0, "accepted": 0}
    for case in range(n):
        folder = tmp_path / f"s{case}"
        shutil.copytree(WAREHOUSE_DIR, folder)
        file = folder / SCENARIO_FILES[rng.integers(len(SCENARIO_FILES))]
        mode = rng.integers(10)
        if mode == 0:  # damaged bytes: truncated, or garbage in the middle
            raw = file.read_bytes()
            cut = rng.integers(len(raw))
            file.write_bytes(raw[:cut] if rng.random() < 0.5 else raw[:cut] + bytes(rng.integers(0, 256, 16)))
        else:
            obj = json.loads(file.read_text())
            for _ in range(1 + rng.integers(2)):
                _mutate_json(obj, rng)
            file.write_text(json.dumps(obj))
        try:
            scenario = load_scenario(folder)
        except ScenarioError as e:
            assert str(folder) in str(e) and e.field, f"case {case}: the error names no file or field: {e}"
            tally["refused"] += 1
        else:
            _check_scenario(scenario)
            tally["accepted"] += 1
        shutil.rmtree(folder)
    return tally


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    """One world of two 60 s slots: logs.parquet and run.json."""
    from socialnav.jaxsim.logs import simulate_to_parquet
    from socialnav.jaxsim.route_follower import route_follower
    from socialnav.jaxsim.world import build_world
    from socialnav.planners.warehouse.routes import shortest_path_plan

    run = tmp_path_factory.mktemp("fuzz_run")
    scenario = load_scenario(slot_length_s=60.0)
    simulate_to_parquet(
        scenario,
        run,
        route_follower(shortest_path_plan(scenario), build_world(scenario)),
        n_worlds=2,
        duration_s=120.0,
        progress=False,
    )
    return run


def _mutate_frame(frame, rng):
    import pandas as pd

    column = frame.columns[rng.integers(len(frame.columns))]
    kind = rng.integers(7)
    rows = rng.integers(0, len(frame), size=1 + rng.integers(5))
    if kind == 0:
        return frame.drop(columns=[column])
    if kind == 1:
        frame = frame.astype({column: "float64"}) if frame[column].dtype != bool else frame
        frame.loc[frame.index[rows], column] = float(rng.choice([np.nan, np.inf, -np.inf]))
        return frame
    if kind == 2:
        return pd.concat([frame, frame.iloc[rows]])
    if kind == 3:
        return frame.sample(frac=1.0, random_state=int(rng.integers(1 << 31)))
    if kind == 4:
        return frame.astype({column: str})
    if kind == 5:
        return frame.iloc[: rng.integers(len(frame))]
    return frame  # unchanged: must be read back as it is


def _check_frame(frame) -> None:
    assert len(frame) > 0
    for column in frame.columns:
        values = frame[column].to_numpy()
        assert values.dtype == bool or np.isfinite(values).all(), column
    assert (frame.groupby("world")["time_s"].diff().dropna() > 0).all()


def fuzz_logs(small_run: pathlib.Path, tmp_path: pathlib.Path, n: int, seed: int) -> dict[str, int]:
    import pandas as pd

    rng = np.random.default_rng(seed)
    base = pd.read_parquet(small_run / "logs.parquet")
    tally = {"refused": 0, "accepted": 0}
    for case in range(n):
        run = tmp_path / f"r{case}"
        run.mkdir()
        shutil.copy(small_run / "run.json", run / "run.json")
        if rng.random() < 0.15:  # damaged bytes
            raw = (small_run / "logs.parquet").read_bytes()
            (run / "logs.parquet").write_bytes(raw[: rng.integers(len(raw))])
        else:
            _mutate_frame(base.copy(), rng).to_parquet(run / "logs.parquet")
        try:
            frame, _ = read_run(run)
        except LogError as e:
            assert "logs.parquet" in str(e) or "rows" in str(e), f"case {case}: {e}"
            tally["refused"] += 1
        else:
            _check_frame(frame)
            tally["accepted"] += 1
        shutil.rmtree(run)
    return tally


def _tables(rng, scenario) -> dict:
    n_s, n_w = scenario.n_slots, scenario.n_waypoints
    return {
        "density_ppm2": rng.random((n_s, n_w)),
        "speed_edges_mps": np.array([0.0, 0.25, 0.5]),
        "battery_pct_per_s": -rng.random((2, 2)) * 0.01,
        "speed_mps": np.array([0.1, 0.4]),
        "waypoints": np.array(scenario.waypoint_ids),
        "slots": np.array(scenario.slot_names),
    }


def fuzz_tables(tmp_path: pathlib.Path, n: int, seed: int) -> dict[str, int]:
    rng = np.random.default_rng(seed)
    scenario = load_scenario()
    tally = {"refused": 0, "accepted": 0}
    for case in range(n):
        tables = _tables(rng, scenario)
        key = sorted(tables)[rng.integers(len(tables))]
        kind = rng.integers(7)
        if kind == 0:
            tables.pop(key)
        elif kind == 1 and tables[key].dtype.kind == "f":
            tables[key] = tables[key].copy()
            tables[key].flat[rng.integers(tables[key].size)] = rng.choice([np.nan, np.inf, -1.0])
        elif kind == 2:
            tables[key] = tables[key][..., :-1] if tables[key].ndim else tables[key]
        elif kind == 3:
            tables[key] = tables[key][::-1].copy()
        elif kind == 4:
            tables[key] = np.array(["a", "b"])
        path = tmp_path / f"t{case}.npz"
        buf = io.BytesIO()
        np.savez(buf, **tables)
        raw = buf.getvalue()
        path.write_bytes(raw[: rng.integers(len(raw))] if kind == 5 else raw)
        try:
            loaded = CausalTables.load(path)
            loaded.check_against(scenario.waypoint_ids, scenario.slot_names)
        except TablesError as e:
            assert str(path) in str(e), f"case {case}: the error names no file: {e}"
            tally["refused"] += 1
        else:
            d = np.asarray(loaded.density_ppm2)
            assert d.shape == (scenario.n_slots, scenario.n_waypoints)
            assert np.all(np.isnan(d) | (d >= 0))
            assert np.isfinite(np.asarray(loaded.battery_pct_per_s)[~np.isnan(loaded.battery_pct_per_s)]).all()
            tally["accepted"] += 1
        path.unlink()
    return tally


def fuzz_configs(n: int, seed: int) -> dict[str, int]:
    rng = np.random.default_rng(seed)
    tally = {"refused": 0, "accepted": 0}
    for case in range(n):
        obj = TrainConfig().to_json()
        for _ in range(1 + rng.integers(2)):
            _mutate_json(obj, rng)
        try:
            config = TrainConfig.from_json(obj, "config.json")
        except ValueError as e:
            assert "config.json" in str(e), f"case {case}: {e}"
            tally["refused"] += 1
        else:
            assert len(config.features) == 4 and min(config.features) >= 1
            assert math.isfinite(config.learning_rate) and config.learning_rate > 0
            assert config.epochs >= 1 and config.batch_size >= 1
            tally["accepted"] += 1
    return tally


def fuzz_maps(n: int, seed: int) -> dict[str, int]:
    from socialnav.models import grid
    from socialnav.models.inference import check_maps

    rng = np.random.default_rng(seed)
    tally = {"refused": 0, "accepted": 0}
    for _ in range(n):
        shape = [(40, 40), (3, 40, 40), (1, 30, 40), (40,), (2, 40, 40, 1)][rng.integers(5)]
        dtype = [np.uint8, np.float32, np.int64, bool, np.float64][rng.integers(5)]
        kind = rng.integers(4)
        if kind == 0:
            values = rng.choice(grid.INPUT_CODES, size=shape)
        elif kind == 1:
            values = rng.random(shape)
        elif kind == 2:
            values = rng.choice(grid.INPUT_CODES, size=shape).astype(np.float64)
            values.flat[rng.integers(values.size)] = np.nan
        else:
            values = rng.integers(0, 256, size=shape)
        maps = values.astype(dtype) if not (kind == 2 and dtype in (np.uint8, np.int64, bool)) else values
        try:
            checked = check_maps(maps)
        except ValueError:
            tally["refused"] += 1
        else:
            out = np.asarray(checked)
            assert out.shape[-2:] == (40, 40) and out.dtype == np.uint8
            assert np.isin(out, grid.INPUT_CODES).all()
            assert np.array_equal(out, np.asarray(maps).astype(np.uint8))
            tally["accepted"] += 1
    return tally


def _report(kind: str, tally: dict, n: int) -> None:
    print(f"{kind}: {n} cases, {tally['refused']} refused, {tally['accepted']} accepted")
    assert tally["refused"] + tally["accepted"] == n


def test_fuzz_scenarios(tmp_path):
    _report("scenario", fuzz_scenarios(tmp_path, FAST_CASES, 0), FAST_CASES)


@pytest.mark.slow
def test_fuzz_logs(small_run, tmp_path):
    _report("logs", fuzz_logs(small_run, tmp_path, FAST_CASES, 0), FAST_CASES)


def test_fuzz_tables(tmp_path):
    _report("tables", fuzz_tables(tmp_path, FAST_CASES, 0), FAST_CASES)


def test_fuzz_configs():
    _report("configs", fuzz_configs(FAST_CASES * 5, 0), FAST_CASES * 5)


def test_fuzz_model_inputs():
    _report("model inputs", fuzz_maps(FAST_CASES * 5, 0), FAST_CASES * 5)


@pytest.mark.slow
def test_fuzz_everything_larger(small_run, tmp_path):
    """CI's larger run: other seeds, SLOW_CASES per kind."""
    _report("scenario", fuzz_scenarios(tmp_path, SLOW_CASES, 1), SLOW_CASES)
    _report("logs", fuzz_logs(small_run, tmp_path, SLOW_CASES, 1), SLOW_CASES)
    _report("tables", fuzz_tables(tmp_path, SLOW_CASES, 1), SLOW_CASES)
    _report("configs", fuzz_configs(SLOW_CASES * 5, 1), SLOW_CASES * 5)
    _report("model inputs", fuzz_maps(SLOW_CASES * 5, 1), SLOW_CASES * 5)
