"""Pixel conventions: validate compares the geometry images obey, and says what a sim publishes."""

from __future__ import annotations

import dataclasses

import pytest

from s2r.profile import CENTRE_OFFSET_PX, StereoProfile
from s2r.registry import load_profile
from s2r.validate.run import QUICK, convention_notes, validate


def _as(profile: StereoProfile, convention: str, name: str) -> StereoProfile:
    provenance = profile.provenance.model_copy(update={"convention": convention})
    return profile.model_copy(update={"provenance": provenance, "name": name})


def test_published_offsets_follow_reference() -> None:
    # Gazebo classic publishes (W + 1) / 2, gz-sim W / 2, for an image centred at (W - 1) / 2.
    assert CENTRE_OFFSET_PX == {"gazebo-classic": 1.0, "gz-sim": 0.5, "exact": 0.0, "opencv": 0.0}
    sim = load_profile("gazebo_dual_camera")
    assert (sim.left.cx_px, sim.left.cy_px) == (320.5, 240.5)
    images = sim.in_opencv_pixels()
    assert (images.left.cx_px, images.left.cy_px, images.right.cx_px) == (319.5, 239.5, 319.5)
    assert images.provenance.convention == "opencv" and images.in_opencv_pixels() is images
    assert images.left.fx_px == sim.left.fx_px and images.baseline_m == sim.baseline_m


def test_notes_name_the_offset_of_each_profile() -> None:
    sim = load_profile("gazebo_dual_camera")
    real = _as(sim.in_opencv_pixels(), "opencv", "twin")
    notes = convention_notes(sim, real)
    assert len(notes) == 1 and "gazebo-classic" in notes[0] and "1 px" in notes[0]
    assert convention_notes(real, real) == []


@pytest.mark.slow
def test_a_gazebo_camera_matches_its_opencv_twin() -> None:
    sim = load_profile("gazebo_dual_camera")
    twin = _as(sim.in_opencv_pixels(), "opencv", "twin")
    settings = dataclasses.replace(QUICK, distances_m=(1.0,))
    result = validate(sim, twin, settings=settings, jobs=1)
    cx = {row.name: row.diff for row in result.params}
    assert cx["left cx"] == 0.0 and cx["right cy"] == 0.0
    assert all(diff.mean_px == pytest.approx(0.0, abs=1e-6) for diff in result.projection)
    assert any("declares its principal point 1 px" in note for note in result.notes)
