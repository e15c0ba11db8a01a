"""The suite's own bookkeeping: the per-file table CI prints (``scripts/test_files.py``), the
order the files start in (``tests/file_seconds.json``, read by ``tests/conftest.py``) and the
compilation cache the sessions keep (``tests/xla_cache.py``)."""

from __future__ import annotations

import json
import os
import pathlib

import pytest
from script_loader import load

TESTS = pathlib.Path(__file__).resolve().parent

REPORT = """<?xml version="1.0" encoding="utf-8"?>
<testsuites><testsuite name="pytest" tests="3">
<testcase classname="tests.test_a" name="test_one" file="tests/test_a.py" line="1" time="2.5">
 <properties><property name="compile_s" value="1.5"/><property name="trace_s" value="0.5"/>
 <property name="xla_s" value="1.0"/><property name="xla_programs" value="3"/>
 <property name="cache_hits" value="1"/></properties></testcase>
<testcase classname="tests.test_a" name="test_two" file="tests/test_a.py" line="9" time="1.0">
 <properties><property name="compile_s" value="0.25"/><property name="xla_programs" value="2"/></properties></testcase>
<testcase classname="tests.test_b" name="test_three" file="tests/test_b.py" line="1" time="7.0"/>
</testsuite></testsuites>
"""


def test_the_files_table_sums_each_files_tests_and_writes_the_longest_first(tmp_path, capsys):
    test_files = load("test_files")
    junit = tmp_path / "junit.xml"
    junit.write_text(REPORT)
    seconds, tests, made = test_files.read(junit)
    assert seconds == {"tests/test_a.py": 3.5, "tests/test_b.py": 7.0}
    assert tests == {"tests/test_a.py": 2, "tests/test_b.py": 1}
    assert made["tests/test_a.py"]["compile_s"] == 1.75 and made["tests/test_a.py"]["xla_programs"] == 5
    assert made["tests/test_b.py"]["compile_s"] == 0
    out = tmp_path / "file_seconds.json"
    assert test_files.main([str(junit), "--write", str(out)]) == 0
    assert list(json.loads(out.read_text()).items()) == [("tests/test_b.py", 7.0), ("tests/test_a.py", 3.5)]
    printed = capsys.readouterr().out
    assert "10 s in all, 3 tests; making programs 2 s" in printed and "5 (    1)  tests/test_a.py" in printed


def test_the_files_the_suite_starts_first_are_its_files():
    """A test file renamed or removed leaves a stale name in the order: write it again
    (``python scripts/test_files.py JUNIT --write tests/file_seconds.json``, docs/testing.md)."""
    order = json.loads((TESTS / "file_seconds.json").read_text())
    stale = [name for name in order if not (TESTS.parent / name).is_file()]
    assert not stale, f"tests/file_seconds.json names files that are gone: {stale}"
    assert list(order.values()) == sorted(order.values(), reverse=True)


def test_files_start_longest_first_and_a_late_file_leaves_its_own_time_to_the_others():
    from suite_order import file_order

    files = ["a", "b", "c", "d", "e", "new"]
    seconds = {"a": 10.0, "b": 50.0, "c": 30.0, "d": 20.0, "e": 25.0}
    assert file_order(files, seconds) == ["b", "c", "e", "d", "a", "new"]
    # b (50 s) goes as far back as leaves 50 s of other files after it: behind c, where e, d, a
    # and new (55 s; a file of unknown time counts as none) follow; behind e only 30 s would.
    assert file_order(files, seconds, late={"b"}) == ["c", "b", "e", "d", "a", "new"]
    # Never forward: d (20 s) has 10 s after it and stays; a (10 s) has none, and none to gain.
    assert file_order(files, seconds, late={"d"}) == ["b", "c", "e", "d", "a", "new"]
    assert file_order(files, seconds, late={"a"}) == ["b", "c", "e", "d", "a", "new"]
    # e (25 s) behind d, where new and a (30 s) cover it; behind new only 10 s would.
    assert file_order(files, {**seconds, "new": 20.0}) == ["b", "c", "e", "d", "new", "a"]
    assert file_order(files, {**seconds, "new": 20.0}, late={"e"}) == ["b", "c", "d", "e", "new", "a"]
    assert file_order(["x", "y"], {}, late={"x"}) == ["y", "x"]  # no time known: short, so last
    assert sorted(file_order(files, seconds, late={"b", "a"})) == sorted(files)


def test_the_conftest_starts_the_files_in_that_order(request):
    """This session's own collection: the files in :func:`suite_order.file_order`'s order."""
    from suite_order import file_order

    items = request.session.items
    names = list(dict.fromkeys(item.nodeid.split("::")[0] for item in items))
    seconds = json.loads((TESTS / "file_seconds.json").read_text())
    late = {item.nodeid.split("::")[0] for item in items if item.get_closest_marker("runs_jobs_elsewhere")}
    assert names == file_order(names, seconds, late)


def test_the_kept_cache_is_one_folder_per_processor_and_is_pruned_oldest_first(tmp_path, monkeypatch):
    import xla_cache

    from socialnav.common import machine

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    folder = xla_cache.kept_folder()
    assert folder.parent == tmp_path / "cache" / "socialnav-jax" / "tests"
    assert machine.cpu_isa().lower().replace("-", "") in folder.name.replace("-", "")
    assert "/" not in folder.name and folder.name == folder.name.lower()
    # Six 100-byte entries written one after another: under the cap nothing goes; over it the
    # oldest go until half the cap is left.
    folder.mkdir(parents=True)
    for k in range(6):
        (folder / f"entry{k}-cache").write_bytes(b"x" * 100)
        os.utime(folder / f"entry{k}-cache", (1000 + k, 1000 + k))
    assert xla_cache.prune(folder, max_bytes=600) == 0 and len(list(folder.iterdir())) == 6
    assert xla_cache.prune(folder, max_bytes=500) == 4
    assert sorted(p.name for p in folder.iterdir()) == ["entry4-cache", "entry5-cache"]
    assert xla_cache.prune(tmp_path / "nowhere") == 0
    assert xla_cache.made_folder() == folder  # there already: kept
    # the pedestrians' measures beside it, one folder per processor too, pruned to their own cap
    humans = xla_cache.made_folder("-humans", max_bytes=250)
    assert humans == folder.parent / f"{folder.name}-humans" and humans.is_dir()
    for k in range(3):
        (humans / f"measure{k}.json").write_bytes(b"x" * 100)
        os.utime(humans / f"measure{k}.json", (1000 + k, 1000 + k))
    assert xla_cache.made_folder("-humans", max_bytes=250) == humans  # 300 bytes: down to 125
    assert [p.name for p in humans.iterdir()] == ["measure2.json"]
    (tmp_path / "file").write_text("not a folder")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "file"))
    with pytest.raises(OSError):  # the conftest then uses a folder of the session's own
        xla_cache.made_folder()
