"""Known answers: synthesise a rig with known parameters, calibrate, and check they come back."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from s2r.calib import calibrate_stereo, find_stereo_pairs
from s2r.profile import StereoProfile


def test_synthetic_rig_recovered_within_tolerances(synthetic_set: tuple[Path, StereoProfile]) -> None:
    folder, truth = synthetic_set
    pairs = find_stereo_pairs(folder)
    result = calibrate_stereo(pairs.left, pairs.right, names=pairs.names, jobs=2)
    p = result.profile
    for cam, true in ((p.left, truth.left), (p.right, truth.right)):
        assert cam.std is not None
        for key, tol in (("fx_px", 0.0015 * true.fx_px), ("fy_px", 0.0015 * true.fy_px), ("cx_px", 0.7),
                         ("cy_px", 0.7)):
            got, want, sd = getattr(cam, key), getattr(true, key), getattr(cam.std, key)
            assert abs(got - want) <= tol, (key, got, want)
            assert sd is not None and sd > 0 and abs(got - want) <= 3 * sd, (key, got, want, sd)
    assert abs(p.baseline_m - truth.baseline_m) <= 0.002 * truth.baseline_m
    b_std = p.extrinsics.baseline_std_m
    assert b_std is not None and abs(p.baseline_m - truth.baseline_m) <= 3 * b_std
    assert np.allclose(p.R, truth.R, atol=2e-3)
    assert p.provenance.origin == "real"
    q = p.provenance.calibration
    assert q is not None and q.views_used >= 20 and q.rms_stereo_px is not None and q.rms_stereo_px < 0.3
    assert q.epipolar_rms_px is not None and q.epipolar_rms_px < 0.3
