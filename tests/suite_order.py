"""The order the suite starts its test files in (``tests/conftest.py`` sorts the collection by it).

A file runs whole on one worker (``--dist loadfile``), so the order decides two things: how evenly
the workers end (the longest files first leave the short ones to fill in), and which file
compiles a program first and which reads it back from the session's compilation cache.
"""

from __future__ import annotations


def file_order(files: list[str], seconds: dict[str, float], late: set[str] = frozenset()) -> list[str]:
    """``files`` (in pytest's order) longest first by ``seconds`` (each file's seconds in a full
    run, :file:`tests/file_seconds.json`), files it does not name after them in their own order;
    then each file of ``late`` moved back, as far as leaves at least its own seconds of other
    files after it (never forward).

    ``late`` is for files whose tests run the toolkit's jobs in other processes (Ray's workers)
    that read back the programs other files compile in theirs: started first they compile
    everything themselves (docs/testing.md has the figures), started last they would run alone on
    one core while the other worker idles.
    """
    known = sorted((f for f in files if f in seconds), key=lambda f: -seconds[f])
    order = known + [f for f in files if f not in seconds]
    for name in sorted((f for f in order if f in late), key=lambda f: -seconds.get(f, 0.0)):
        earliest = order.index(name)
        order.remove(name)
        after, position = 0.0, len(order)
        while position > earliest and after < seconds.get(name, 0.0):
            position -= 1
            after += seconds.get(order[position], 0.0)
        order.insert(position, name)
    return order
