"""``socialnav``'s parser: a command imports its own module only, and parses as the whole parser does."""

from __future__ import annotations

import subprocess
import sys

import pytest

from socialnav import cli


def _choices(parser) -> dict:
    (sub,) = [a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction"]
    return sub.choices


def test_every_command_is_mapped_to_the_module_that_defines_it():
    everything = _choices(cli.build_parser())
    assert set(everything) == set(cli.COMMAND_MODULES)
    for command, module in cli.COMMAND_MODULES.items():
        alone = _choices(cli.build_parser(command))
        assert command in alone and set(alone) <= {c for c, m in cli.COMMAND_MODULES.items() if m == module}
        # The command's own parser is the same (its options, defaults and help) either way.
        assert alone[command].format_help() == everything[command].format_help()
    assert set(_choices(cli.build_parser("simulat"))) == set(cli.COMMAND_MODULES)  # argparse names the choices


def test_the_command_word_is_the_first_that_is_not_an_option():
    assert cli._command(["simulate", "--out", "x"]) == "simulate"
    assert cli._command(["--version"]) is None and cli._command([]) is None
    assert cli._command(["gscl", "train", "--out", "x"]) == "gscl"


@pytest.mark.parametrize(
    ("argv", "code", "said"),
    [(["simulat"], 2, "invalid choice: 'simulat'"), ([], 2, "required: COMMAND"), (["--version"], 0, "socialnav-jax")],
)
def test_a_wrong_or_missing_command_is_named_with_the_choices(argv, code, said, capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(argv)
    assert e.value.code == code
    out = capsys.readouterr()
    assert said in out.out + out.err


def test_parsing_simulate_imports_neither_the_arena_nor_the_causal_pipeline():
    code = (
        "import sys; from socialnav import cli; cli.build_parser('simulate').parse_args(['simulate', '--out', 'x']); "
        "print(sorted(m for m in ('socialnav.evaluation.arena', 'socialnav.causal.learn', 'tigramite', "
        "'pyagrum', 'socialnav.cli.arena') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
