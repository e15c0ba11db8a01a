"""The test suite's files from a pytest JUnit report: their seconds, and what they spent making programs.

    python scripts/test_files.py JUNIT                           # the longest files (what CI prints)
    python scripts/test_files.py JUNIT --write tests/file_seconds.json   # the order the suite runs its files in

A test file runs whole on one worker (``--dist loadfile``), so the file that starts last sets how
long the suite takes; ``tests/conftest.py`` starts the longest files first by
``tests/file_seconds.json`` (each file's seconds in a full run, written here from a report of
``pytest -m "slow or not slow" --junitxml=JUNIT``; the order itself: ``tests/suite_order.py``).
The figures beside each file are the JUnit properties ``tests/conftest.py`` records per test:
seconds spent tracing and lowering (paid again in every process) and in XLA's compile or a read
from the compilation cache, and how many programs went to XLA and how many of them the cache gave
back.
"""

from __future__ import annotations

import argparse
import collections
import json
import pathlib
import xml.etree.ElementTree as ET

from socialnav.common.atomic import write_text_atomic

KEYS = ("compile_s", "trace_s", "xla_s", "xla_programs", "cache_hits")


def read(junit: pathlib.Path) -> tuple[collections.Counter, collections.Counter, dict]:
    """``(seconds per file, tests per file, {file: Counter of KEYS})`` from a JUnit report; a file is
    its path from the repository's root (``tests/test_env.py``)."""
    seconds, tests, made = collections.Counter(), collections.Counter(), collections.defaultdict(collections.Counter)
    for case in ET.parse(junit).getroot().iter("testcase"):
        name = case.get("file") or case.get("classname").replace(".", "/") + ".py"
        seconds[name] += float(case.get("time") or 0)
        tests[name] += 1
        for prop in case.iter("property"):
            if prop.get("name") in KEYS:
                made[name][prop.get("name")] += float(prop.get("value"))
    return seconds, tests, made


def table(seconds: collections.Counter, tests: collections.Counter, made: dict, rows: int = 12) -> str:
    """The whole run's totals and its ``rows`` longest files, as CI prints them."""
    total = sum(made.values(), collections.Counter())
    lines = [
        f"{sum(seconds.values()):8.0f} s in all, {sum(tests.values())} tests; "
        f"making programs {total['compile_s']:.0f} s: "
        f"tracing and lowering {total['trace_s']:.0f} s, XLA {total['xla_s']:.0f} s for {total['xla_programs']:.0f} "
        f"programs ({total['cache_hits']:.0f} read back from the compilation cache)",
        "    time  tests  making programs (tracing, XLA)  XLA programs (cache hits)  file",
    ]
    for name, s in seconds.most_common(rows):
        m = made[name]
        lines.append(
            f"{s:6.0f} s {tests[name]:5d}  {m['compile_s']:6.0f} s ({m['trace_s']:4.0f}, {m['xla_s']:4.0f})  "
            f"{m['xla_programs']:6.0f} ({m['cache_hits']:5.0f})  {name}"
        )
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("junit", type=pathlib.Path, help="a pytest JUnit report (--junitxml)")
    parser.add_argument("--write", type=pathlib.Path, help="write each file's seconds here, longest first")
    parser.add_argument("--rows", type=int, default=12, help="files in the table (default 12)")
    args = parser.parse_args(argv)
    seconds, tests, made = read(args.junit)
    print(table(seconds, tests, made, args.rows))
    if args.write:
        longest_first = {name: round(s, 1) for name, s in seconds.most_common()}
        write_text_atomic(args.write, json.dumps(longest_first, indent=1) + "\n")
        print(f"wrote {args.write} ({len(longest_first)} files)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
