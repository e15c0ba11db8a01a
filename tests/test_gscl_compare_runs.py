"""scripts/gscl_compare_runs.py: the table of training runs read from their folders."""

from __future__ import annotations

import json

import pytest
import script_loader

from socialnav.models.config import TrainConfig


def _script():
    return script_loader.load("gscl_compare_runs")


def _run_folder(tmp_path, lines, name="run_a"):
    run = tmp_path / name
    run.mkdir()
    (run / "config.json").write_text(json.dumps(TrainConfig(epochs=2, batch_size=16).to_json()))
    (run / "metrics.jsonl").write_text("".join(json.dumps(line) + "\n" for line in lines))
    return run


def _line(epoch, by_check, meets_quality=True):
    return {
        "epoch": epoch,
        "wall_s": 100.0 * epoch,
        "test_mse": 0.001 / epoch,
        "meets_quality": meets_quality,
        "rules_pass_by_check": by_check,
        "meets_rules": min(by_check.values()) >= 0.95,
    }


def test_rows_list_the_checks_below_the_bar(tmp_path, capsys):
    script = _script()
    run = _run_folder(
        tmp_path,
        [
            _line(1, {"corner/blind_corner": 0.80, "queue/queue_u": 0.96}, False),
            _line(2, {"corner/blind_corner": 0.97}),
        ],
    )
    script.main([str(run)])  # the last epoch only: every check passes
    last = capsys.readouterr().out.splitlines()
    assert len(last) == 2 and "2/2" in last[1] and last[1].split()[-1] == "-" and " yes " in last[1]
    script.main([str(run), "--epochs"])
    rows = capsys.readouterr().out.splitlines()
    assert len(rows) == 3
    assert "1/2" in rows[1] and "corner/blind_corner 80 %" in rows[1] and "queue_u" not in rows[1]
    assert "16" in rows[1].split()  # the run's batch size


def test_a_broken_line_names_the_file_and_line(tmp_path):
    script = _script()
    run = _run_folder(tmp_path, [_line(1, {"corner/blind_corner": 0.9})])
    with (run / "metrics.jsonl").open("a") as f:
        f.write("{not json\n")
    with pytest.raises(SystemExit) as err:
        script.main([str(run)])
    assert err.value.code == 2
    with pytest.raises(ValueError, match=r"metrics.jsonl: line 2 is not JSON"):
        script.epochs_of(run)


def test_a_folder_without_a_run_is_refused(tmp_path, capsys):
    with pytest.raises(SystemExit) as err:
        _script().main([str(tmp_path)])
    assert err.value.code == 2 and "no config.json" in capsys.readouterr().err
