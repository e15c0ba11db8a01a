"""Run folders as units on the command line: a folder holding a run is refused without
``--overwrite``, which replaces it whole; a killed job's temporaries are removed by the next."""

from __future__ import annotations

import json

from socialnav import cli

SHORT = ["--worlds", "1", "--slots", "1", "--slot-length-s", "60", "--no-progress"]


def test_simulate_refuses_a_previous_run_and_overwrite_replaces_it_whole(tmp_path, capsys):
    out = tmp_path / "run"
    assert cli.main(["simulate", "--out", str(out), "--seed", "1", *SHORT]) == 0
    first = (out / "logs.parquet").read_bytes()
    capsys.readouterr()

    assert cli.main(["simulate", "--out", str(out), *SHORT]) == 2
    err = capsys.readouterr().err
    assert "holds a previous run" in err and "--overwrite" in err and err.count("\n") == 1
    assert (out / "logs.parquet").read_bytes() == first  # untouched

    (out / "causal").mkdir()
    (out / "causal" / "report.json").write_text("{}")  # a later step of the old run
    (out / ".tmp-4242-logs.parquet").write_bytes(b"half a file of a killed run")
    assert cli.main(["simulate", "--out", str(out), "--overwrite", *SHORT]) == 0
    assert "removed what a killed job left" in capsys.readouterr().out
    assert json.loads((out / "run.json").read_text())["seed"] == 0
    assert (out / "logs.parquet").read_bytes() != first
    assert not (out / "causal").exists()
    assert sorted(p.name for p in out.iterdir()) == ["density_by_slot.png", "logs.parquet", "run.json", "snapshot.png"]


def test_a_folder_without_run_json_is_an_incomplete_run(tmp_path, capsys):
    out = tmp_path / "run"
    out.mkdir()
    (out / "logs.parquet").write_bytes(b"")
    assert cli.main(["simulate", "--out", str(out), *SHORT]) == 2
    assert "incomplete run (no run.json" in capsys.readouterr().err


def test_learn_and_evaluate_refuse_to_replace_their_results(learned_run, tmp_path, capsys):
    """Both refuse before any work (the learned engine is kept as it is)."""
    report = (learned_run / "causal" / "report.json").read_bytes()
    assert cli.main(["learn", "--logs", str(learned_run), "--no-progress"]) == 2
    assert "causal holds a previous run" in capsys.readouterr().err
    assert (learned_run / "causal" / "report.json").read_bytes() == report

    evaluation = tmp_path / "evaluation"
    evaluation.mkdir()
    (evaluation / "summary.json").write_text("{}")
    tables = learned_run / "causal" / "engine_tables.npz"
    assert cli.main(["evaluate", "--tables", str(tables), "--out", str(evaluation), "--replicas", "1"]) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert (evaluation / "summary.json").read_text() == "{}"
