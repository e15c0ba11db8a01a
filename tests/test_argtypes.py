"""socialnav.cli.argtypes: values parsed, and one clear message naming the bad value."""

from __future__ import annotations

import argparse

import pytest

from socialnav.cli.argtypes import comma_ints, comma_names, comma_positive_floats, comma_probabilities, unet_widths


def test_unet_widths_reads_four_positive_widths():
    assert unet_widths("16,32,64,128") == (16, 32, 64, 128)
    assert unet_widths(" 8, 16,32 ,64") == (8, 16, 32, 64)  # int() strips spaces


@pytest.mark.parametrize("text", ["8,8", "8,16,32,64,128", "0,16,32,64", "8,a,32,64", ""])
def test_unet_widths_refuses_and_names_the_value(text):
    with pytest.raises(argparse.ArgumentTypeError, match=repr(text).replace("(", r"\(")):
        unet_widths(text)


@pytest.mark.parametrize(
    ("parse", "text", "repeated"),
    [
        (comma_names, "navfn,casn, navfn", "'navfn'"),
        (comma_ints, "0,1,0", "0"),
        (comma_positive_floats, "0.1,0.3,0.10", "0.1"),
        (comma_probabilities, "0.5,0.5", "0.5"),
    ],
)
def test_a_list_refuses_a_value_given_twice_and_names_it(parse, text, repeated):
    """Each list option names things to run or count: a repeat would run and count one twice."""
    with pytest.raises(argparse.ArgumentTypeError, match=f"{repeated} is given twice in {text!r}"):
        parse(text)


def test_lists_of_distinct_values_parse_in_their_order():
    assert comma_names("S11, S1,S6") == ["S11", "S1", "S6"]
    assert comma_ints("3,0,1") == [3, 0, 1]
    assert comma_positive_floats("1,0.3") == [1.0, 0.3]
    assert comma_probabilities("0.5,0.1") == [0.5, 0.1]
