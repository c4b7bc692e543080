"""The option parsers every command shares: one grammar for patterns and distances."""

from __future__ import annotations

import pytest

from s2r.cli._common import parse_distances, parse_pattern


@pytest.mark.parametrize(("text", "expected"), [("9x6", (9, 6)), (" 9 X 6 ", (9, 6)), ("8*5", (8, 5)), ("7,4", (7, 4))])
def test_patterns_read(text: str, expected: tuple[int, int]) -> None:
    assert parse_pattern(text) == expected


@pytest.mark.parametrize("text", ["9by6", "9", "1x6", "9x6x2", ""])
def test_bad_patterns_say_inner_corners(text: str) -> None:
    with pytest.raises(ValueError, match="INNER corners"):
        parse_pattern(text)


def test_distances() -> None:
    assert parse_distances("0.5,1, 2,") == (0.5, 1.0, 2.0)
    for bad, needle in (("1,x", "not a list of numbers"), ("0,1", "positive"), ("1,inf", "positive"), ("", "positive")):
        with pytest.raises(ValueError, match=needle):
            parse_distances(bad)
