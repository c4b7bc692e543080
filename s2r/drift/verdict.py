"""The verdict of a drift check: ``good``, ``drifted`` or ``cannot tell``, in degrees AND in pixels.

Degrees: an axis is drifted when its error is beyond the tolerance and beyond ``significance`` sigmas.
Pixels: the rows of mismatch SGBM would see over the image (median and p95 px, for far points, from the rotation
shrunk towards zero by ``significance`` sigmas per axis: only the part the data is sure of) against
``tolerance_px``. A small angle on a long focal length is many rows; the reasons say which one decided.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["AXES", "Verdict", "judge", "next_steps", "shrunk"]

FloatArray = NDArray[np.float64]
AXES = ("pitch", "yaw", "roll")  # about the right camera's optical x, y, z


@dataclass(frozen=True)
class Verdict:
    """``verdict``, its ``reasons``, and ``decided_by``: "degrees", "pixels", "degrees and pixels" or "" (when
    nothing could be judged); ``unresolved`` lists the axes whose sigma is over half their tolerance."""

    verdict: str
    reasons: list[str]
    decided_by: str
    unresolved: list[str]


def shrunk(omega_deg: FloatArray, sigma_deg: FloatArray, significance: float) -> FloatArray:
    """Each axis moved towards zero by ``significance`` sigmas (zero when that crosses it): degrees."""
    return np.sign(omega_deg) * np.fmax(np.abs(omega_deg) - significance * sigma_deg, 0.0)


def judge(omega_deg: FloatArray, sigma_deg: FloatArray, *, tolerance_deg: Sequence[float], tolerance_px: float,
          significance: float, rows_px: Callable[[FloatArray], dict[str, float]], weak: int = 1) -> Verdict:
    """Verdict of a finite rotation (degrees, about the right camera's axes) and its sigma.

    Args:
        rows_px: the rows of mismatch (``median``, ``p95`` px) that a rotation in degrees leaves over the image.
        weak: the axis (index into :data:`AXES`) that may stay unresolved (yaw: it looks like the p2 lens term).
    """
    tol = np.asarray(tolerance_deg, np.float64)
    by_degrees = [f"{a} {o:+.3f} deg (+/- {s:.3f}) beyond {t:g} deg" for a, o, s, t in
                  zip(AXES, omega_deg, sigma_deg, tol, strict=True) if abs(o) > t and abs(o) > significance * s]
    sure = rows_px(shrunk(omega_deg, sigma_deg, significance))
    by_pixels = [f"rows disagree by at least {sure['median']:.2f} px median, {sure['p95']:.2f} px p95 over the "
                 f"image, beyond {tolerance_px:g} px"] if sure["p95"] > tolerance_px else []
    unresolved = [a for a, s, t in zip(AXES, sigma_deg, tol, strict=True) if s > t / 2.0]
    if by_degrees or by_pixels:
        decided = " and ".join(w for w, hit in (("degrees", by_degrees), ("pixels", by_pixels)) if hit)
        return Verdict("drifted", [*by_degrees, *by_pixels, f"decided by {decided}"], decided, unresolved)
    blocking = [a for a in unresolved if a != AXES[weak]]
    if blocking:
        reasons = [f"{a}: sigma {s:.3f} deg is over half the {t:g} deg tolerance" for a, s, t in
                   zip(AXES, sigma_deg, tol, strict=True) if a in blocking]
        return Verdict("cannot tell", [*reasons, "more frames with texture across the whole image narrow it"],
                       "", unresolved)
    judged = [(a, t) for a, s, t in zip(AXES, sigma_deg, tol, strict=True) if s <= t / 2.0]
    rows = rows_px(omega_deg)
    reasons = [f"{', '.join(a for a, _ in judged)} within tolerance ({', '.join(f'{t:g}' for _, t in judged)} deg)",
               f"rows agree within {tolerance_px:g} px for the part of the rotation the data is sure of (p95 "
               f"{sure['p95']:.2f} px; {rows['p95']:.2f} px at the estimate)", "decided by degrees and pixels"]
    if AXES[weak] in unresolved:  # yaw alone may stay unresolved: it is the p2 pattern of a real lens
        reasons.insert(1, f"{AXES[weak]} not resolved (sigma {sigma_deg[weak]:.3f} deg): on a lens with distortion "
                       "it looks like a tangential-distortion error, and estimators disagree; it scales depth, "
                       "which only a target can check")
    return Verdict("good", reasons, "degrees and pixels", unresolved)


def next_steps(verdict: Verdict, *, profile: str, recording: str, swapped: bool) -> list[str]:
    """What to do after the verdict, as runnable commands or one sentence each."""
    if swapped:
        return ["put the recording right as the reason says and check again; --fix refuses a swapped recording"]
    if verdict.verdict == "drifted":
        steps = []
        if not verdict.unresolved:
            steps.append(f"s2r check {profile} {recording} --fix -o fixed.yaml  (rotation re-estimated, checked "
                         "on frames it did not fit)")
        else:
            steps.append(f"--fix would change {', '.join(verdict.unresolved)}, which the check cannot resolve; it "
                         "corrects only resolved axes")
            steps.append(f"s2r check {profile} {recording} --fix -o fixed.yaml  (resolved axes only)")
        steps.append("or recalibrate with a board (s2r calibrate) if the rig was knocked or its lenses moved")
        return steps
    if verdict.verdict == "cannot tell":
        return ["record more frames of textured scenes at several depths, or recalibrate with a board"]
    return []
