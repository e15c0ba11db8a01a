"""``socialnav``: the toolkit's command line. One command, one subcommand per job.

    socialnav run --out runs/warehouse                              # simulate, learn, evaluate
    socialnav simulate --worlds 8 --out runs/warehouse              # a full day, 8 worlds
    socialnav learn --logs runs/warehouse                           # causal graph + engine
    socialnav evaluate --tables runs/warehouse/causal/engine_tables.npz --replicas 32
    socialnav ablation --out runs/ablation                          # seed 000 Sec. 6
    socialnav gscl generate|train|evaluate ...                      # GSCL (seed 002)
    socialnav layers --out docs/img                                 # the social cost layers, pictured
    socialnav arena --out runs/arena                                # methods x scenes x variants, closed loop
    socialnav humans validate --out runs/humans                     # the human models against real pedestrians

Runtime set-up (one XLA host device per core, JAX's persistent compilation cache) happens here,
before JAX is imported; the module of the command asked for (one a command, beside this file) is
imported after it, and only that one (``socialnav simulate`` does not import the arena's or the
causal pipeline's libraries).
"""

from __future__ import annotations

import argparse
import sys

from socialnav import runtime

__all__ = ["COMMAND_MODULES", "build_parser", "main"]


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


def main(argv: list[str] | None = None) -> int:
    runtime.request_host_devices()
    runtime.request_wide_vectors()
    runtime.request_compilation_cache()
    runtime.quiet_third_party_logs()
    argv = list(sys.argv[1:] if argv is None else argv)
    args = build_parser(_command(argv)).parse_args(argv)
    args.argv = argv  # a run folder records the command that made it
    return args.handler(args)


if __name__ == "__main__":
    sys.exit(main())
