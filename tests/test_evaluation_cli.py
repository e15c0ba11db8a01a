"""``socialnav evaluate``: the report it writes, and clear errors for bad input."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from socialnav import cli


@pytest.mark.slow
def test_evaluate_writes_the_report(learned_run, tmp_path, capsys):
    tables = learned_run / "causal" / "engine_tables.npz"
    out = tmp_path / "eval"
    code = cli.main(
        ["evaluate", "--tables", str(tables), "--replicas", "2", "--slots", "S11", "--out", str(out), "--no-progress"]
    )
    assert code == 0
    tasks = pd.read_parquet(out / "tasks.parquet")
    assert len(tasks) == 2 * 2 * 90 and set(tasks["method"]) == {"baseline", "causal"}
    summary = json.loads((out / "summary.json").read_text())
    assert summary["per_method"]["causal"]["success_pct"]["mean"] == 100.0  # nobody in S11
    assert summary["config"]["slots"] == ["S11"] and summary["config"]["replicas"] == 2
    per_slot = pd.read_csv(out / "per_slot.csv")
    assert list(per_slot["slot"]) == ["S11", "S11"]
    for name in ("fig9_efficiency.png", "fig10_safety.png", "fig11_routes.png", "distance_hist.npz"):
        assert (out / name).stat().st_size > 0
    assert "success_pct" in capsys.readouterr().out


def test_evaluate_rejects_bad_input(tmp_path, capsys):
    missing = tmp_path / "none.npz"
    assert cli.main(["evaluate", "--tables", str(missing), "--out", str(tmp_path / "o")]) == 2
    assert "run 'socialnav learn' first" in capsys.readouterr().err
    partial = tmp_path / "partial.npz"
    np.savez(partial, density_ppm2=np.zeros((11, 73)))
    assert cli.main(["evaluate", "--tables", str(partial), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "missing key" in err and str(partial) in err
    other = tmp_path / "other.npz"  # tables of another scenario (3 waypoints)
    np.savez(
        other,
        density_ppm2=np.zeros((11, 3)),
        battery_pct_per_s=np.array([[-0.006, 0.01], [-0.007, 0.0]]),
        speed_edges_mps=np.array([0.0, 0.3, 0.5]),
    )
    assert cli.main(["evaluate", "--tables", str(other), "--out", str(tmp_path / "o")]) == 2
    assert "the scenario has 11 slots and 73 waypoints" in capsys.readouterr().err
    full = tmp_path / "full.npz"
    np.savez(
        full,
        density_ppm2=np.zeros((11, 73)),
        battery_pct_per_s=np.array([[-0.006, 0.01], [-0.007, 0.0]]),
        speed_edges_mps=np.array([0.0, 0.3, 0.5]),
    )
    assert cli.main(["evaluate", "--tables", str(full), "--slots", "S99", "--out", str(tmp_path / "o")]) == 2
    assert "unknown slot" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()  # nothing written on bad input
    with pytest.raises(SystemExit):
        cli.main(["evaluate", "--replicas", "0"])
