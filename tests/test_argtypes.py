"""socialnav.cli.argtypes: values parsed, and one clear message naming the bad value."""

from __future__ import annotations

import argparse

import pytest

from socialnav.cli.argtypes import unet_widths


def test_unet_widths_reads_four_positive_widths():
    assert unet_widths("16,32,64,128") == (16, 32, 64, 128)
    assert unet_widths(" 8, 16,32 ,64") == (8, 16, 32, 64)  # int() strips spaces


@pytest.mark.parametrize("text", ["8,8", "8,16,32,64,128", "0,16,32,64", "8,a,32,64", ""])
def test_unet_widths_refuses_and_names_the_value(text):
    with pytest.raises(argparse.ArgumentTypeError, match=repr(text).replace("(", r"\(")):
        unet_widths(text)
