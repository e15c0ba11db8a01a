"""The files between parts are contracts: what one part writes, the other reads, without
importing each other. The simulator's log through :mod:`common.logschema` into the causal
reader; the causal engine's tables through ``causal.learn.write_tables`` into the planners'
typed reader."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
from plans import scipy_shortest_plan

from socialnav.causal import extract
from socialnav.causal.learn import write_tables
from socialnav.common import logschema
from socialnav.jaxsim import logs
from socialnav.jaxsim.route_follower import route_follower
from socialnav.jaxsim.scenario import load_scenario
from socialnav.jaxsim.world import build_world
from socialnav.planners.warehouse.tables import CausalTables, TablesError


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    scenario = load_scenario(slot_length_s=20.0, n_workers=5)
    out = tmp_path_factory.mktemp("run")
    logs.simulate_to_parquet(
        scenario,
        out,
        route_follower(scipy_shortest_plan(scenario), build_world(scenario)),
        n_worlds=2,
        duration_s=40.0,
        progress=False,
    )
    return scenario, out


@pytest.mark.slow
def test_the_log_has_every_schema_column_with_its_dtype(run):
    scenario, out = run
    schema = pq.read_schema(out / logschema.LOG_FILE)
    want = logschema.required_columns(scenario.waypoint_ids, scenario.params.n_workers)
    assert schema.names == want  # the documented order, nothing else
    df = pd.read_parquet(out / logschema.LOG_FILE)
    for name, dtype in (
        logschema.ID_COLUMNS + logschema.SETTING_COLUMNS + logschema.CLOCK_COLUMNS + logschema.ROBOT_COLUMNS
    ):
        assert df[name].dtype == np.dtype(dtype), name
    meta = json.loads((out / logschema.META_FILE).read_text())
    assert set(logschema.META_KEYS) <= set(meta) and meta["schema_version"] == logschema.SCHEMA_VERSION


@pytest.mark.slow
def test_the_causal_reader_reads_what_the_simulator_writes(run):
    scenario, out = run
    df, meta = extract.read_run(out)
    assert meta["waypoints"] == list(scenario.waypoint_ids) and meta["slots"] == list(scenario.slot_names)
    assert set(extract.LOG_COLUMNS) <= set(logschema.required_columns([]))  # only schema columns are read
    assert len(df) == 2 * 40 and logschema.density_column("wa-2-l") in df.columns
    full = pd.read_parquet(out / logschema.LOG_FILE)
    pd.testing.assert_frame_equal(df, full[df.columns.tolist()])  # the same values, read through the contract


@pytest.mark.slow
def test_the_causal_reader_names_what_is_missing(run, tmp_path):
    _, out = run
    (tmp_path / logschema.META_FILE).write_text((out / logschema.META_FILE).read_text())
    pd.read_parquet(out / logschema.LOG_FILE).drop(columns=["battery_pct"]).to_parquet(tmp_path / logschema.LOG_FILE)
    with pytest.raises(extract.LogError, match="battery_pct"):
        extract.read_run(tmp_path)
    (tmp_path / logschema.META_FILE).write_text("{}")
    with pytest.raises(extract.LogError, match="lacks the waypoint or slot names"):
        extract.read_run(tmp_path)


def test_tables_written_by_causal_are_read_by_the_planners(tmp_path, warehouse):
    tables = {
        "density_ppm2": np.random.default_rng(0).random((11, 73)),
        "battery_pct_per_s": np.array([[-0.005, 0.014], [-0.0069, np.nan]]),
        "speed_mps": np.array([0.1, 0.5]),
        "speed_edges_mps": np.array([0.0, 0.3, 0.51]),
    }
    path = write_tables(
        tmp_path / "engine_tables.npz", list(warehouse.waypoint_ids), list(warehouse.slot_names), tables
    )
    read = CausalTables.load(path)
    read.check_against(warehouse.waypoint_ids, warehouse.slot_names)
    np.testing.assert_array_equal(read.density_ppm2, tables["density_ppm2"])
    np.testing.assert_array_equal(read.battery_pct_per_s, tables["battery_pct_per_s"])
    with pytest.raises(TablesError, match="differ from the scenario's"):
        read.check_against(list(reversed(warehouse.waypoint_ids)), warehouse.slot_names)
