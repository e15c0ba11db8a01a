"""argparse types shared by every subcommand: one clear message for a bad value."""

from __future__ import annotations

import argparse
import math
import pathlib


def _int_at_least(text: str, minimum: int) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if value < minimum:
        raise argparse.ArgumentTypeError(f"must be >= {minimum}, got {value}")
    return value


def positive_int(text: str) -> int:
    """An integer >= 1."""
    return _int_at_least(text, 1)


def non_negative_int(text: str) -> int:
    """An integer >= 0."""
    return _int_at_least(text, 0)


def positive_float(text: str) -> float:
    """A finite number > 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a finite number > 0, got {text}")
    return value


def probability(text: str) -> float:
    """A number in [0, 1]."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not 0 <= value <= 1:  # also false for nan
        raise argparse.ArgumentTypeError(f"must be in [0, 1], got {text}")
    return value


def _each_once(values: list, text: str) -> list:
    """``values`` if none is repeated. A list option names things to run or count (methods, scenes,
    seeds, world ids, models): one given twice would run it twice and count its results twice, which
    narrows a table's intervals with no new data (``--methods navfn,navfn`` reported n = 2 x
    ``--variants`` for NavFn)."""
    seen = set()
    for value in values:
        if value in seen:
            raise argparse.ArgumentTypeError(f"{value!r} is given twice in {text!r}: name each once")
        seen.add(value)
    return values


def comma_ints(text: str) -> list[int]:
    """Comma-separated integers, each once, e.g. ``0,1,3``."""
    try:
        values = [int(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated integers, got {text!r}") from None
    return _each_once(values, text)


def unet_widths(text: str) -> tuple[int, ...]:
    """A U-Net's four widths (3 encoder blocks, bottleneck), e.g. ``16,32,64,128``."""
    try:
        values = tuple(int(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected 4 comma-separated widths, got {text!r}") from None
    if len(values) != 4 or min(values) < 1:
        raise argparse.ArgumentTypeError(f"expected 4 positive comma-separated widths, got {text!r}")
    return values


def comma_names(text: str) -> list[str]:
    """Comma-separated names, each once, e.g. ``S1,S6,S11``."""
    names = [v.strip() for v in text.split(",")]
    if not all(names):
        raise argparse.ArgumentTypeError(f"expected comma-separated names, got {text!r}")
    return _each_once(names, text)


def comma_probabilities(text: str) -> list[float]:
    """Comma-separated probabilities in (0, 1], each once."""
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}") from None
    if any(not 0 < v <= 1 for v in values):
        raise argparse.ArgumentTypeError(f"probabilities must be in (0, 1], got {text}")
    return _each_once(values, text)


def comma_positive_floats(text: str) -> list[float]:
    """Comma-separated finite numbers > 0, each once, e.g. ``0.1,0.3,1`` (a sweep's values)."""
    return _each_once([positive_float(v) for v in text.split(",")], text)


def non_negative_float(text: str) -> float:
    """A finite number >= 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"must be a finite number >= 0, got {text}")
    return value


def output_folder(text: str) -> pathlib.Path:
    """An output folder's path: not empty (``--out ""`` would write into the working folder)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a folder, got an empty path")
    return pathlib.Path(text)


def open_unit_interval(text: str) -> float:
    """A number strictly between 0 and 1 (a significance level)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not 0 < value < 1:  # also false for nan
        raise argparse.ArgumentTypeError(f"must be in (0, 1), got {text}")
    return value


# JAX's random keys keep 32 bits of a seed when 64-bit types are off (its default): seeds 0 and
# 2**40 give the same key, -1 the same as 2**32 - 1. Seeds are therefore the 32-bit range, so that
# different seeds are different streams.
MAX_SEED = 2**32 - 1


def seed_int(text: str) -> int:
    """A random seed: an integer in [0, 2**32 - 1] (JAX's keys keep 32 bits of a seed)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if not 0 <= value <= MAX_SEED:
        raise argparse.ArgumentTypeError(
            f"must be in [0, {MAX_SEED}] (JAX keeps 32 bits of a seed: larger or negative ones would repeat "
            f"another seed's stream), got {text}"
        )
    return value
