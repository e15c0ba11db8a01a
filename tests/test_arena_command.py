"""The ``socialnav arena`` command: bad input refused, tables written, a run resumed, other
settings refused."""

import pandas as pd
import pytest


def test_arena_command_refuses_bad_input(tmp_path, capsys):
    from socialnav import cli

    assert cli.main(["arena", "--out", str(tmp_path / "a"), "--methods", "teleport"]) == 2
    assert "unknown teleport" in capsys.readouterr().err
    assert cli.main(["arena", "--out", str(tmp_path / "a"), "--methods", "gscl", "--gscl-run", str(tmp_path)]) == 2
    assert "neither a GSCL training run" in capsys.readouterr().err
    assert cli.main(["arena", "--out", str(tmp_path / "a"), "--scenes", "nowhere"]) == 2
    assert "nowhere.json" in capsys.readouterr().err
    assert not (tmp_path / "a").exists()


@pytest.mark.slow
def test_arena_command_writes_tables_resumes_and_refuses_other_settings(tmp_path, capsys):
    from socialnav import cli

    out = tmp_path / "run"
    args = ["arena", "--out", str(out), "--scenes", "casn_static_person", "--methods", "navfn,casn", "--variants", "2"]
    assert cli.main([*args, "--no-progress", "--keep-trajectories", "1"]) == 0
    episodes = pd.read_parquet(out / "episodes" / "casn_static_person.parquet")
    assert len(episodes) == 4 and set(episodes["method"]) == {"navfn", "casn"}
    assert (out / "pictures" / "casn_static_person_paths.png").exists()
    summary = pd.read_csv(out / "summary.csv")
    assert list(summary["method"]) == ["navfn", "casn"]
    stamp = (out / "episodes" / "casn_static_person.parquet").stat().st_mtime_ns
    assert cli.main([*args, "--no-progress", "--keep-trajectories", "1"]) == 0  # resumed: nothing recomputed
    assert (out / "episodes" / "casn_static_person.parquet").stat().st_mtime_ns == stamp
    assert cli.main([*args[:-1], "3", "--no-progress"]) == 2
    assert "other settings" in capsys.readouterr().err
