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
before JAX is imported; the subcommands' modules (one a command, beside this file) are imported
after it.
"""

from __future__ import annotations

import argparse
import sys

from socialnav import runtime

__all__ = ["build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    """The parser of every subcommand (imports the subcommands' modules, and so JAX)."""
    from socialnav.cli import arena, evaluate, gscl, humans, layers, learn, pipelines, policy, referee, simulate
    from socialnav.common import __version__

    parser = argparse.ArgumentParser(
        prog="socialnav",
        description="The social-navigation toolkit: one subcommand per job (socialnav COMMAND --help).",
    )
    parser.add_argument("--version", action="version", version=f"socialnav-jax {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    pipelines.add_parsers(sub)
    simulate.add_parser(sub)
    learn.add_parser(sub)
    evaluate.add_parser(sub)
    gscl.add_parser(sub)
    layers.add_parser(sub)
    arena.add_parser(sub)
    policy.add_parser(sub)
    referee.add_parser(sub)
    humans.add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    runtime.request_host_devices()
    runtime.request_wide_vectors()
    runtime.request_compilation_cache()
    runtime.quiet_third_party_logs()
    args = build_parser().parse_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)  # a run folder records the command that made it
    return args.handler(args)


if __name__ == "__main__":
    sys.exit(main())
