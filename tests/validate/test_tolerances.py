"""Tolerances: defaults, YAML overrides, and one-line errors for bad files."""

from __future__ import annotations

from pathlib import Path

import pytest

from s2r.errors import ValidateError
from s2r.validate.tolerances import Tolerances, load_tolerances


def test_defaults_without_a_file() -> None:
    tol = load_tolerances()
    assert tol == Tolerances()
    assert tol.focal_rel == 0.01 and tol.size_px == 0.0


def test_yaml_overrides_only_named_keys(tmp_path: Path) -> None:
    path = tmp_path / "tol.yaml"
    path.write_text("focal_rel: 0.05\nbaseline_rel: 1\n")
    tol = load_tolerances(path)
    assert tol.focal_rel == 0.05 and tol.baseline_rel == 1.0
    assert tol.fov_deg == Tolerances().fov_deg


def test_empty_file_is_the_defaults(tmp_path: Path) -> None:
    path = tmp_path / "tol.yaml"
    path.write_text("")
    assert load_tolerances(path) == Tolerances()


def test_unknown_keys_give_one_line_listing_valid_keys(tmp_path: Path) -> None:
    path = tmp_path / "tol.yaml"
    path.write_text("focal_rell: 0.05\nfov_deg: 2\nbogus: 1\n")
    with pytest.raises(ValidateError) as info:
        load_tolerances(path)
    text = str(info.value)
    assert "\n" not in text
    assert str(path) in text and "bogus, focal_rell" in text
    assert all(key in text for key in Tolerances.valid_keys())


@pytest.mark.parametrize("body", ["focal_rel: -1\n", "focal_rel: abc\n", "focal_rel: .nan\n", "focal_rel: true\n"])
def test_bad_values_name_the_key(tmp_path: Path, body: str) -> None:
    path = tmp_path / "tol.yaml"
    path.write_text(body)
    with pytest.raises(ValidateError, match="focal_rel: must be a finite non-negative number"):
        load_tolerances(path)


def test_not_a_mapping_and_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "tol.yaml"
    path.write_text("- 1\n- 2\n")
    with pytest.raises(ValidateError, match="expected a mapping"):
        load_tolerances(path)
    with pytest.raises(ValidateError, match="not found"):
        load_tolerances(tmp_path / "absent.yaml")
    path.write_text("a: [1\n")
    with pytest.raises(ValidateError, match="malformed YAML"):
        load_tolerances(path)


@pytest.mark.parametrize("body", ["focal_rel: 2026-13-21\n", "focal_rel: [1,\n", "focal_rel: 0.02\n\tsigma: 3\n"])
def test_malformed_yaml_is_one_line_not_a_traceback(tmp_path: Path, body: str) -> None:
    path = tmp_path / "tol.yaml"
    path.write_text(body)
    with pytest.raises(ValidateError, match="malformed YAML") as info:
        load_tolerances(path)
    assert str(path) in str(info.value) and "\n" not in str(info.value)
