"""Recovered-against-declared comparison on profiles with known offsets and standard deviations."""

from __future__ import annotations

import pytest

from s2r.profile import CameraUncertainty, Extrinsics, StereoProfile
from s2r.validate.measures.recovery import compare_recovered
from s2r.validate.tolerances import Tolerances
from tests.conftest import make_rig


def _recovered(declared: StereoProfile, *, dfx: float, dcx: float, baseline_m: float,
               std: CameraUncertainty | None) -> StereoProfile:
    left = declared.left.model_copy(update={"fx_px": declared.left.fx_px + dfx, "cx_px": declared.left.cx_px + dcx,
                                            "std": std})
    right = declared.right.model_copy(update={"std": std})
    ext = Extrinsics(translation_m=(-baseline_m, 0.0, 0.0), baseline_std_m=1e-4)
    return declared.model_copy(update={"left": left, "right": right, "extrinsics": ext})


def test_errors_in_sigmas_and_floors() -> None:
    declared = make_rig()
    std = CameraUncertainty(fx_px=0.5, fy_px=0.5, cx_px=0.4, cy_px=0.4)
    rows = {r.name: r for r in compare_recovered(
        declared, _recovered(declared, dfx=1.0, dcx=3.0, baseline_m=0.1002, std=std), Tolerances())}
    assert rows["left fx"].error == pytest.approx(1.0) and rows["left fx"].n_sigma == pytest.approx(2.0)
    assert rows["left fx"].passed  # 2 sigma
    assert rows["left cx"].n_sigma == pytest.approx(7.5) and not rows["left cx"].passed  # 3 px > 1.5 px floor
    assert rows["baseline"].n_sigma == pytest.approx(2.0) and rows["baseline"].passed
    assert rows["right fx"].error == 0.0 and rows["right fx"].passed
    assert rows["rotation error"].recovered == pytest.approx(0.0) and rows["rotation error"].passed


def test_without_predicted_std_only_the_floor_counts() -> None:
    declared = make_rig()
    floor_fx = Tolerances().recovery_focal_rel * declared.left.fx_px  # 0.3 % of fx
    inside = compare_recovered(declared, _recovered(declared, dfx=0.9 * floor_fx, dcx=0.0, baseline_m=0.1, std=None),
                               Tolerances())
    outside = compare_recovered(declared, _recovered(declared, dfx=1.1 * floor_fx, dcx=0.0, baseline_m=0.1,
                                                     std=None), Tolerances())
    assert inside[0].std is None and inside[0].passed
    assert not outside[0].passed
