"""``socialnav``: the toolkit's command line. One command, one subcommand per job.

    socialnav run --out runs/warehouse                              # simulate, learn, evaluate
    socialnav simulate --worlds 8 --out runs/warehouse              # a full day, 8 worlds
    socialnav learn --logs runs/warehouse                           # causal graph + engine
    socialnav evaluate --tables runs/warehouse/causal/engine_tables.npz --replicas 32
    socialnav ablation --out runs/ablation                          # seed 000 Sec. 6
    socialnav gscl generate|train|evaluate ...                      # GSCL (seed 002)
    socialnav layers --out docs/img                                 # the social cost layers, pictured
    socialnav arena --out runs/arena                                # methods x scenes x variants, closed loop
    socialnav arena-scene my_crowd.csv --out scenes                 # your own recording as arena scenes
    socialnav humans validate --out runs/humans                     # the human models against real pedestrians

Runtime set-up (one XLA host device per core, JAX's persistent compilation cache) happens here,
before JAX is imported; the module of the command asked for (one a command, beside this file) is
imported after it, and only that one (``socialnav simulate`` does not import the arena's or the
causal pipeline's libraries).

Faults of the machine end a command with one line, not a traceback: a full disk (or a quota, a
file-size limit, a file system turned read-only, an I/O error) names the file it was writing,
exit status 2; Ctrl-C says "interrupted", 130; SIGTERM (a batch scheduler's time limit, ``kill``)
is taken as Ctrl-C is, so that the job's cleanup runs (a staged run folder removed, the previous
run kept, the folder's lock released), 143. ``SOCIALNAV_VERBOSE=1`` shows the traceback instead.

The environment a user brings is read here too: ``JAX_ENABLE_X64`` is ignored with a note (the
toolkit runs in float32, :mod:`jaxsim.precision`), and a ``JAX_PLATFORMS`` that JAX cannot start
(``cuda`` on a machine or a JAX without a GPU), or a toolkit variable whose value it cannot use
(``SOCIALNAV_GRID_SOLVER``), ends the command in one line, exit status 2.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import signal
import sys
from collections.abc import Callable

from socialnav import runtime

__all__ = ["COMMAND_MODULES", "MACHINE_FAULTS", "Terminated", "build_parser", "main", "run_command"]


# Each command and the module beside this file that defines it: a command imports its own module
# only (one module's imports are JAX and the libraries its job uses; all of them take seconds).
COMMAND_MODULES = {
    "run": "pipelines",
    "ablation": "pipelines",
    "simulate": "simulate",
    "learn": "learn",
    "evaluate": "evaluate",
    "gscl": "gscl",
    "layers": "layers",
    "arena": "arena",
    "arena-scene": "scene",
    "policy": "policy",
    "referee": "referee",
    "humans": "humans",
}


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser of every subcommand, or of ``command`` alone (importing only its module; an
    unknown name gets every subcommand, so that argparse names the choices). Importing a
    subcommand's module imports JAX."""
    import importlib

    from socialnav.common import __version__

    parser = argparse.ArgumentParser(
        prog="socialnav",
        description="The social-navigation toolkit: one subcommand per job (socialnav COMMAND --help).",
    )
    parser.add_argument("--version", action="version", version=f"socialnav-jax {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    names = [COMMAND_MODULES[command]] if command in COMMAND_MODULES else list(dict.fromkeys(COMMAND_MODULES.values()))
    for name in names:
        module = importlib.import_module(f"socialnav.cli.{name}")
        module.add_parser(sub)
    return parser


def _command(argv: list[str]) -> str | None:
    """The subcommand ``argv`` asks for: its first word that is not an option (the top-level
    parser's options, ``--version`` and ``--help``, take no value)."""
    return next((a for a in argv if not a.startswith("-")), None)


# The errnos of a machine that cannot hold or take what a job writes (not of bad input, not of a
# bug): a full disk, a quota, the file-size limit (ulimit -f), a file system made read-only, a
# device's I/O error.
MACHINE_FAULTS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EROFS, errno.EIO})


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the program is, as Ctrl-C's KeyboardInterrupt is: the ``finally``
    blocks and context managers that remove a job's temporaries run (Python's default for
    SIGTERM ends the process at once, leaving a staged folder and the lock file)."""


def _raise_terminated(signum, frame) -> None:
    raise Terminated(signal.Signals(signum).name)


@contextlib.contextmanager
def _sigterm_as_interrupt():
    """SIGTERM raises :class:`Terminated` inside the block, where no one else handles it (the
    default action, in the main thread); the previous handler is restored after."""
    import threading

    if threading.current_thread() is not threading.main_thread() or signal.getsignal(signal.SIGTERM) != signal.SIG_DFL:
        yield
        return
    signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _command_words(args: argparse.Namespace) -> str:
    """The command a user typed, as its messages name it: ``socialnav gscl rules``."""
    sub = getattr(args, f"{args.command}_command", None)
    return " ".join(["socialnav", args.command, *([sub] if sub else [])])


def main(argv: list[str] | None = None) -> int:
    runtime.request_host_devices()
    runtime.request_wide_vectors()
    runtime.request_compilation_cache()
    runtime.request_float32()
    runtime.repair_compilation_cache()
    runtime.one_line_warnings()
    runtime.quiet_third_party_logs()
    argv = list(sys.argv[1:] if argv is None else argv)
    args = build_parser(_command(argv)).parse_args(argv)
    args.argv = argv  # a run folder records the command that made it
    problem = runtime.jax_platforms_problem() or runtime.variables_problem()
    if problem:
        print(f"{_command_words(args)}: {problem}", file=sys.stderr)
        return 2
    return run_command(_command_words(args), args.handler, args)


def run_command(name: str, handler: Callable[[argparse.Namespace], int], args: argparse.Namespace) -> int:
    """``handler(args)``'s exit status, a fault of the machine ended in one line on stderr naming
    the command ``name`` (see the module's docstring): 2 for a write the machine refused, 130 for
    Ctrl-C, 143 for SIGTERM. Any other error propagates, traceback and all (it is a bug, or the
    handler's own to report); with ``SOCIALNAV_VERBOSE=1`` every error does."""
    verbose = runtime.verbose()
    try:
        with _sigterm_as_interrupt():
            return handler(args)
    except KeyboardInterrupt as e:
        if verbose:
            raise
        terminated = isinstance(e, Terminated)
        print(f"\n{name}: {'terminated (SIGTERM)' if terminated else 'interrupted'}", file=sys.stderr)
        return 128 + int(signal.SIGTERM if terminated else signal.SIGINT)
    except OSError as e:
        if verbose or e.errno not in MACHINE_FAULTS:
            raise
        verb = "cannot read or write" if e.errno == errno.EIO else "cannot write"
        where = f" {e.filename}:" if e.filename else ":"
        print(f"{name}: {verb}{where} {e.strerror or e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
