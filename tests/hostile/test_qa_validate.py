"""QA: ``s2r validate`` options a newcomer may get wrong are refused in one line (exit 2), not exit 3."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest
import yaml

from s2r.cli import main
from s2r.errors import ValidateError
from s2r.profile import StereoProfile
from s2r.validate.run import QUICK, check_distances, distances_in_view

PROFILE = Path(__file__).resolve().parents[2] / "profiles" / "real" / "realsense_d435_848x480.yaml"


def test_negative_seed_is_bad_input(capsys: pytest.CaptureFixture[str]) -> None:
    # numpy's default_rng raised ValueError deep inside the run: "internal error", exit 3
    assert main(["validate", "realsense_d435_848x480", "--quick", "--seed", "-1"]) == 2
    assert capsys.readouterr().err.strip() == "error: --seed: must be 0 or more, got -1 (e.g. 0)"


def test_default_distances_a_short_rig_cannot_see_are_dropped_with_a_warning(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    """A 4 mm baseline sees 0.11-1.7 m: validate used to refuse its own defaults ("not 2.5, 4 m", exit 2)."""
    data = yaml.safe_load(PROFILE.read_text())
    data["extrinsics"]["translation_m"] = [-0.004, 0.0, 0.0]
    short = StereoProfile.model_validate({**data, "name": "b4mm"})
    with caplog.at_level(logging.WARNING):
        kept = distances_in_view([short], "profile", QUICK.distances_m)
    assert kept == (0.75, 1.5)
    assert "validating at 0.75, 1.5 m only, not 2.5, 4 m (b4mm sees 0.11-1.7 m" in caplog.text
    full = StereoProfile.model_validate(yaml.safe_load(PROFILE.read_text()))
    assert distances_in_view([full], "profile", QUICK.distances_m) == QUICK.distances_m
    with pytest.raises(ValidateError, match=r"sees 0\.11-1\.7 m, not 2\.5, 4 m"):  # explicit distances still refused
        check_distances(short, "profile", (0.75, 2.5, 4.0))
