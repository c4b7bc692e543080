"""Fuzz (seeded, bounded) of issue 23's untrusted inputs: any JSON a corner-cache entry can hold is either a
valid entry or refused with ValueError (never another exception, never a corner outside the image); any YAML
built from anchors and aliases loads or is one S2RError; any text's terminal form holds no control character."""

from __future__ import annotations

import math
import re
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from s2r.calib.detect.cache import validate_entry
from s2r.errors import S2RError, terminal_safe
from s2r.safeparse import parse_yaml

FUZZ = settings(max_examples=60, deadline=None, derandomize=True, database=None)
_JSON = st.recursive(st.none() | st.booleans() | st.integers(-10**12, 10**12) | st.floats() | st.text(max_size=8),
                     lambda inner: st.lists(inner, max_size=6) | st.dictionaries(st.text(max_size=8), inner,
                                                                                   max_size=6), max_leaves=40)
_GOOD_CORNERS = st.lists(st.lists(st.floats(-5.0, 700.0), min_size=2, max_size=2), min_size=1, max_size=6)


@FUZZ
@given(status=st.sampled_from(["ok", "no_board", "unreadable", "x"]) | _JSON, size=_JSON | st.just([640, 480]),
       corners=_JSON | _GOOD_CORNERS, ids=_JSON, extra=st.dictionaries(st.text(max_size=6), _JSON, max_size=3))
def test_cache_entries_are_valid_or_refused(status: Any, size: Any, corners: Any, ids: Any,
                                            extra: dict[str, Any]) -> None:
    data = {**extra, "status": status, "size": size, "corners": corners, "ids": ids}
    try:
        entry = validate_entry(data, corner_count=None, with_ids=False)
    except ValueError:
        return
    if entry["corners"] is not None:
        w, h = entry["size"]
        assert all(math.isfinite(x) and math.isfinite(y) and -1 <= x <= w and -1 <= y <= h
                   for x, y in entry["corners"])


@FUZZ
@given(st.lists(st.tuples(st.integers(0, 4), st.integers(0, 4), st.integers(1, 6)), min_size=1, max_size=8))
def test_alias_graphs_load_or_are_one_error(edges: list[tuple[int, int, int]]) -> None:
    lines = ["a0: &a0 [1.0, 2.0]"]
    for i, (src, _, count) in enumerate(edges, start=1):
        refs = ", ".join([f"*a{min(src, i - 1)}"] * count)
        lines.append(f"a{i}: &a{i} [{refs}]")
    try:
        parse_yaml("\n".join(lines) + "\n", path="f.yaml")
    except S2RError as exc:
        assert "f.yaml" in str(exc) and "\n" not in str(exc)


@FUZZ
@given(st.text(max_size=40))
def test_terminal_form_has_no_control_character(text: str) -> None:
    assert not re.search("[\x00-\x1f\x7f-\x9f\u2028\u2029\u202a-\u202e\u2066-\u2069]", terminal_safe(text))
