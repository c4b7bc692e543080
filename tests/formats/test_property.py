"""Property: mutated valid files (field deletions, type changes, number perturbations, byte truncations and
flips) make load_any and the CLI raise only s2r's own errors (exit 2, one line), never a traceback."""

from __future__ import annotations

import contextlib
import io
import math
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from s2r.cli import main
from s2r.errors import S2RError
from s2r.formats.detect import load_any
from s2r.formats.kalibr import kalibr_to_yaml
from s2r.formats.ros import camera_info_to_yaml, ros_pair_from_profile
from s2r.formats.s2r_yaml import profile_to_yaml
from s2r.profile import StereoProfile
from tests.formats.rigs import distorted_rotated_rig, with_distortion

DATA = Path(__file__).parent / "data"
RIG = with_distortion(distorted_rotated_rig(), "plumb_bob", (-0.12, 0.05, 0.001, -0.002, 0.0))
_LEFT, _RIGHT = ros_pair_from_profile(RIG)
#: The valid texts that get mutated; for "ros" the mutated file is the left one of a pair.
BASES: dict[str, str] = {
    "s2r": profile_to_yaml(RIG),
    "ros": camera_info_to_yaml(_LEFT),
    "kalibr": kalibr_to_yaml(RIG),
    "echo": (DATA / "gazebo_left_camera_info.txt").read_text(),
    "realsense": (DATA / "rs_enumerate_devices_d435.txt").read_text(),  # text mutations only
}
RIGHT_TEXT = camera_info_to_yaml(_RIGHT)
SETTINGS = settings(max_examples=150, deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.too_slow])

_SAFE_TEXT = st.text(alphabet=st.characters(blacklist_categories=("Cs",)), max_size=8)
ODD_VALUES = st.one_of(
    st.none(), st.booleans(), st.integers(-(10**6), 10**20), st.floats(allow_nan=True, allow_infinity=True),
    _SAFE_TEXT, st.lists(st.floats(allow_nan=False, width=32), max_size=6),
    st.dictionaries(_SAFE_TEXT, st.integers(), max_size=2), st.just("2026-13-45"), st.builds(lambda: [[1, 2], [3]]),
)


def _paths(node: Any, prefix: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    """Every key path into a parsed YAML tree (dict keys and list indexes)."""
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else []
    for key, child in items:
        yield (*prefix, key)
        yield from _paths(child, (*prefix, key))


def _parent(tree: Any, path: tuple[Any, ...]) -> Any:
    for key in path[:-1]:
        tree = tree[key]
    return tree


@st.composite
def structural(draw: st.DrawFn, text: str) -> str:
    """Delete a field, change its type, or perturb a number, then dump the tree back to YAML."""
    tree = next(iter(yaml.safe_load_all(text)))  # the first message of rostopic echo output
    for _ in range(draw(st.integers(1, 3))):
        paths = list(_paths(tree))
        if not paths:
            break
        path = paths[draw(st.integers(0, len(paths) - 1))]
        parent, key = _parent(tree, path), path[-1]
        op = draw(st.sampled_from(["delete", "replace", "perturb"]))
        value = parent[key]
        if op == "delete":
            del parent[key]
        elif op == "perturb" and isinstance(value, (int, float)) and not isinstance(value, bool):
            factor = draw(st.sampled_from([-1.0, 0.0, 1e-9, 0.5, 1.0000001, 3.0, 1e6, math.inf]))
            parent[key] = value * factor + draw(st.sampled_from([0.0, 1e-7, -1.0, 1000.0]))
        else:
            parent[key] = draw(ODD_VALUES)
    return str(yaml.safe_dump(tree, sort_keys=False, allow_unicode=True))


@st.composite
def textual(draw: st.DrawFn, text: str) -> bytes:
    """Truncate, flip a byte, or drop a line of the raw file."""
    raw = text.encode("utf-8")
    op = draw(st.sampled_from(["truncate", "flip", "drop_line"]))
    if op == "truncate":
        return raw[: draw(st.integers(0, len(raw)))]
    if op == "flip":
        where = draw(st.integers(0, len(raw) - 1))
        return raw[:where] + bytes([draw(st.integers(0, 255))]) + raw[where + 1:]
    lines = raw.splitlines(keepends=True)
    drop = draw(st.integers(0, len(lines) - 1))
    return b"".join(lines[:drop] + lines[drop + 1:])


def mutated(kind: str) -> st.SearchStrategy[bytes]:
    text = BASES[kind]
    if kind == "realsense":
        return textual(text)
    return st.one_of(structural(text).map(lambda t: t.encode("utf-8")), textual(text))


def _write(folder: Path, kind: str, content: bytes) -> list[str]:
    path = folder / ("left.yaml" if kind == "ros" else f"{kind}.txt")
    path.write_bytes(content)
    if kind in ("ros", "echo"):
        right = folder / "right.yaml"
        right.write_text(RIGHT_TEXT)
        return [str(path), str(right)]
    return [str(path)]


def _only_s2r_errors(kind: str, content: bytes) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        sources = _write(Path(tmp), kind, content)
        try:
            profile = load_any(sources)
        except S2RError as exc:
            assert "\n" not in str(exc)
        else:
            assert isinstance(profile, StereoProfile)


@pytest.mark.slow
@pytest.mark.parametrize("kind", list(BASES))
def test_mutated_files_raise_only_s2r_errors(kind: str) -> None:
    @SETTINGS
    @given(content=mutated(kind))
    def check(content: bytes) -> None:
        _only_s2r_errors(kind, content)

    check()


@settings(max_examples=60, deadline=None, derandomize=True, database=None, suppress_health_check=[HealthCheck.too_slow])
@given(kind=st.sampled_from(sorted(BASES)), data=st.data())
def test_cli_on_mutated_files_exits_0_or_2_with_one_error_line(kind: str, data: st.DataObject) -> None:
    content = data.draw(mutated(kind))
    with tempfile.TemporaryDirectory() as tmp:
        sources = _write(Path(tmp), kind, content)
        err, out = io.StringIO(), io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
            code = main(["profile", "convert", *sources, "--to", "s2r", "-o", str(Path(tmp) / "out.yaml")])
        lines = err.getvalue().strip().splitlines()
        assert code in (0, 2), err.getvalue()
        assert "Traceback" not in err.getvalue()
        errors = [line for line in lines if line.startswith("error: ")]
        assert len(errors) == (1 if code == 2 else 0), err.getvalue()
        assert all(line.startswith(("error: ", "warning: ")) for line in lines), err.getvalue()
