"""scripts/claims_two_runs.py: two arena runs' claims side by side, the changed verdicts counted."""

from __future__ import annotations

import pandas as pd
import pytest
import script_loader


def _script():
    return script_loader.load("claims_two_runs")


def _run(tmp_path, name, rows, file="directions.csv"):
    folder = tmp_path / name
    folder.mkdir(exist_ok=True)
    columns = ["source", "scene", "metric", "proposed", "baseline", "paper_diff", "ours_diff", "ours_diff_lo",
               "ours_diff_hi", "n_pairs", "verdict"]  # fmt: skip
    pd.DataFrame(rows, columns=columns).to_csv(folder / file, index=False)
    return folder


def test_claims_join_by_claim_and_the_changed_verdicts_are_counted(tmp_path, capsys):
    a = _run(tmp_path, "a", [
        ["s1", "x", "d_min_m", "casn", "snl", 0.3, 0.1, 0.05, 0.15, 100, "reproduced"],
        ["s1", "y", "goal", "gscl", "navfn", 7, 3.0, -1.0, 7.0, 100, "same sign, not significant"],
        ["s1", "z", "goal", "gscl", "navfn", 7, 3.0, 1.0, 5.0, 100, "reproduced"],
    ])  # fmt: skip
    b = _run(tmp_path, "b", [
        ["s1", "y", "goal", "gscl", "navfn", 7, 5.0, 2.0, 8.0, 100, "reproduced"],
        ["s1", "x", "d_min_m", "casn", "snl", 0.3, 0.2, 0.1, 0.3, 100, "reproduced"],
    ])  # fmt: skip
    assert _script().main([str(a), str(b), "--labels", "sf", "steer"]) == 0
    out = capsys.readouterr().out
    assert "| sf | verdict | steer | verdict |" in out
    assert (
        "| s1 | `x` | d_min_m | casn - snl | +0.30 | +0.10 [+0.05, +0.15] | reproduced | +0.20 [+0.10, +0.30] |" in out
    )
    assert "- | not run" in out  # z only in the first run
    assert "2 claims in both runs; the verdict differs in 1:" in out
    assert "- y goal (gscl - navfn): same sign, not significant -> reproduced" in out


def test_a_folder_without_directions_is_named(tmp_path):
    with pytest.raises(SystemExit, match="no directions.csv"):
        _script().main([str(tmp_path), str(tmp_path)])


def test_held_out_reads_the_held_out_claims(tmp_path, capsys):
    row = ["s1", "x", "d_min_m", "casn", "snl", 0.3, 0.1, 0.05, 0.15, 100, "reproduced"]
    held = ["s1", "x", "d_min_m", "casn", "snl", 0.3, -0.1, -0.15, -0.05, 100, "opposite"]
    a = _run(tmp_path, "a", [row])
    b = _run(tmp_path, "b", [row])
    with pytest.raises(SystemExit, match="no directions_held_out.csv .a run made without --held-out"):
        _script().main([str(a), str(b), "--held-out"])
    _run(tmp_path, "a", [held], "directions_held_out.csv")
    _run(tmp_path, "b", [row], "directions_held_out.csv")
    assert _script().main([str(a), str(b), "--held-out"]) == 0
    out = capsys.readouterr().out
    assert "-0.10 [-0.15, -0.05] | opposite | +0.10 [+0.05, +0.15] | reproduced |" in out
    assert "the verdict differs in 1:" in out
