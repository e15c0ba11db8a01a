"""One job per run folder: the handlers that write a folder hold its lock (:mod:`common.runlock`).

A second job started on a folder another job is writing is refused at once, with one line naming
the holder (command, pid, host, start time), exit code 2; nothing of either run is touched. A job
that reads a run (``learn`` its logs, ``evaluate`` its tables) holds it shared: a job replacing
that run is refused while it reads, and it is refused while one replaces it. An
``--out`` that is a file or cannot be created is refused the same way, before any work. Holding
the lock, a job first removes what a killed job left in the folder (:func:`common.runfolder.clear_leftovers`).
"""

from __future__ import annotations

import contextlib
import functools
import pathlib
import sys
from collections.abc import Callable, Sequence

from socialnav.common import runfolder
from socialnav.common.runlock import RunFolderError, read_lock, run_lock


def locks_folder(
    folder_of: Callable[[object], pathlib.Path | None],
    name: str,
    reads: Callable[[object], Sequence[tuple[str, pathlib.Path]]] | None = None,
):
    """Decorate a subcommand handler ``handler(args) -> int`` so that it runs holding the lock of
    ``folder_of(args)`` (None, "" or "." : no lock, the handler's own checks speak) and a shared
    lock on each run folder it reads, ``reads(args)``: ``(option, folder)`` pairs (``("--logs",
    logs)``), a folder that holds no run left alone."""

    def decorate(handler):
        @functools.wraps(handler)
        def wrapped(args) -> int:
            folder = folder_of(args)
            if folder is None or str(folder) in ("", "."):
                return handler(args)
            try:
                with contextlib.ExitStack() as locks:
                    held = locks.enter_context(run_lock(folder, f"socialnav {name}"))
                    for option, source in reads(args) if reads is not None else ():
                        if not (pathlib.Path(source) / runfolder.MANIFEST).is_file():
                            continue
                        try:
                            locks.enter_context(read_lock(source))
                        except RunFolderError as e:  # being replaced by another job
                            print(f"socialnav {name}: {option}: {e}", file=sys.stderr)
                            return 2
                    warn = lambda message: print(f"socialnav {name}: warning: {message}", file=sys.stderr)
                    gone = runfolder.clear_leftovers(held, warn)  # a killed job's temporaries: nobody else writes here
                    if gone:
                        print(f"socialnav {name}: removed what a killed job left in {folder}: {', '.join(gone)}")
                    return handler(args)
            except RunFolderError as e:  # locked by another job, a file, not writable
                print(f"socialnav {name}: --out: {e}", file=sys.stderr)
                return 2

        return wrapped

    return decorate
