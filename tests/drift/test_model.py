"""The rotation fit's batched rows equal predict_right's, and the fit recovers a known turn from exact matches."""

from __future__ import annotations

import numpy as np
import pytest

from s2r.drift.model import MODELS, _Rows, fit_rotation, predict_right
from s2r.rectification import stereo_rectification
from tests.drift.conftest import rig


def _matches(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(N, 2) rectified left pixels over the image and (N,) disparities (px) of points 0.5-10 m away."""
    profile = rig()
    rect = stereo_rectification(profile)
    rng = np.random.default_rng(seed)
    w, h = rect.image_size
    left = np.column_stack([rng.uniform(0, w - 1, 300), rng.uniform(0, h - 1, 300)])
    disparity = rect.fx_px * rect.baseline_m / rng.uniform(0.5, 10.0, 300) + rect.doffs_px
    return left, disparity


@pytest.mark.parametrize("model", MODELS)
def test_batched_rows_equal_predict_right(model: str) -> None:
    profile = rig()
    rect = stereo_rectification(profile)
    left, disparity = _matches(1)
    omegas = np.radians([[0.0, 0.0, 0.0], [0.3, -0.2, 0.1], [-1.0, 0.5, 0.7], [0.0, 2.0, -0.4]])
    rows = _Rows(profile, rect, left, disparity, model).rows(omegas)
    for k, omega in enumerate(omegas):
        expected = predict_right(profile, rect, left, disparity, omega, model=model)[:, 1]
        np.testing.assert_allclose(rows[:, k], expected, rtol=0, atol=1e-9)


@pytest.mark.parametrize("model", MODELS)
def test_the_fit_recovers_a_turn_from_exact_matches(model: str) -> None:
    """Right rows made by predict_right for a known turn: the fit (without lens terms) returns that turn."""
    profile = rig()
    rect = stereo_rectification(profile)
    left, disparity = _matches(2)
    turn = np.radians([0.2, -0.3, 0.15])
    predicted = predict_right(profile, rect, left, disparity, turn, model=model)
    right = np.column_stack([left[:, 0] - disparity + rect.doffs_px, predicted[:, 1]])
    fit = fit_rotation(profile, rect, left, right, model=model, nuisance=False)
    np.testing.assert_allclose(np.degrees(fit.omega), np.degrees(turn), atol=1e-4)
