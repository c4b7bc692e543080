"""Fixtures of the depth tests: an ideal rectified rig matching the synthetic pairs."""

from __future__ import annotations

import pytest

from s2r.profile import StereoProfile
from tests.conftest import make_rig
from tests.depth.synth import SynthPair, make_pair


@pytest.fixture(scope="session")
def pair() -> SynthPair:
    """320x240 synthetic pair: background 12 px, box 30 px."""
    return make_pair()


@pytest.fixture(scope="session")
def small_rig() -> StereoProfile:
    """Ideal 320x240 rig (60 deg HFOV, fx 277.19, 10 cm baseline, cx = (W - 1) / 2): rectification is identity."""
    return make_rig(name="small_rig", width=320, height=240)
